"""The limb models: one module and one template partial each, found through this registry.

``MODELS`` maps each YAML tag (``model: rail``) to its class. Everything that works per
model (schema, reference solver, C tables, setup sheet words, diagnoses, verify's
conditioning bound, loads' limits, calibration's parameters, the closed-form forward, the
design judge's geometry) asks the class; nothing else in kingen names a model but this
registry and the layouts (kingen.robot.layouts), tests/test_architecture.py checks. ``register``
adds a model at run time (tests do, with a toy model); the robot-file schema follows
the registry's content (:func:`kingen.robot.model.robot_file_schema`).
"""

from .base import LimbModel, LimbSolution, c_double, c_vector, model_name, partial_path
from .crank import Crank
from .leg import Leg
from .rail import Rail

MODELS = {}


def register(cls):
    """Add limb model class ``cls`` (a LimbModel subclass with a ``model`` literal)."""
    MODELS[model_name(cls)] = cls
    return cls


def unregister(cls):
    """Remove limb model class ``cls`` again."""
    MODELS.pop(model_name(cls), None)


for _cls in (Leg, Rail, Crank):
    MODELS[model_name(_cls)] = _cls

__all__ = ["MODELS", "LimbModel", "LimbSolution", "register", "unregister", "c_double", "c_vector", "model_name", "partial_path",
           "Leg", "Rail", "Crank"]
