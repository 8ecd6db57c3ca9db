"""What a robot file says about the machine's loads: the payload it carries, gravity, and per
limb its actuator's force or torque limit, its stiffness and its passive joints' limits
(all optional; documented in docs/how-to/loads.md and docs/explanation/loads.md).

Units are fixed whatever the file's length unit: kg, kg m^2, m/s^2, N, N m, N/mm and N m/rad,
degrees; only the payload's centre is a length in the file's unit."""

from dataclasses import dataclass
from typing import Annotated, Optional, Union

import numpy as np
from pydantic import AfterValidator, Field

from ..defaults import MAX_MM
from .schema import Strict, Vec3

MAX_MASS_KG = 1e6
MAX_FORCE_N = 1e9
"""Forces and torques (N, N m) and stiffnesses (N/mm, N m/rad) a file may state at most."""
MAX_GRAVITY = 1000.0
"""m/s^2: a gravity vector's components at most (100 g)."""
MAX_INERTIA = 1e9
"""kg m^2: an inertia entry's magnitude at most."""
SYMMETRY_TOLERANCE = 1e-9
"""How far (relative to the largest entry) a 3 x 3 inertia may be from symmetric."""

Mass = Annotated[float, Field(gt=0, le=MAX_MASS_KG)]
ForceLimit = Annotated[float, Field(gt=0, le=MAX_FORCE_N)]
ConeAngle = Annotated[float, Field(gt=0, lt=180)]
"""Degrees: a passive joint's largest angle from its neutral axis, above 0 and below 180."""
InertiaEntry = Annotated[float, Field(ge=-MAX_INERTIA, le=MAX_INERTIA)]


def _as_matrix(value):
    """(3, 3) kg m^2 from principal moments [Ixx, Iyy, Izz] or a whole matrix."""
    return np.diag(value) if not isinstance(value[0], list) else np.array(value, dtype=float)


def _inertia_matrix(value):
    """The payload's inertia as a 3 x 3 symmetric positive-definite matrix (kg m^2), from its
    principal moments [Ixx, Iyy, Izz] or a whole matrix."""
    matrix = _as_matrix(value)
    scale = max(float(np.max(np.abs(matrix))), 1e-300)
    if np.max(np.abs(matrix - matrix.T)) > SYMMETRY_TOLERANCE * scale:
        raise ValueError("the inertia matrix must be symmetric")
    if np.min(np.linalg.eigvalsh(0.5 * (matrix + matrix.T))) <= 0.0:
        raise ValueError("the inertia must be positive definite (every principal moment above 0)")
    return value


Inertia = Annotated[Union[Annotated[list[InertiaEntry], Field(min_length=3, max_length=3)],
                          Annotated[list[Annotated[list[InertiaEntry], Field(min_length=3, max_length=3)]],
                                    Field(min_length=3, max_length=3)]],
                    AfterValidator(_inertia_matrix)]


def refuse_wrong_limit(joint_type, max_force, max_torque):
    """ValueError unless a prismatic joint's actuator limit is max_force and a revolute one's max_torque."""
    wrong = "max_force" if joint_type.wraps else "max_torque"
    if (max_force if joint_type.wraps else max_torque) is not None:
        right = "max_torque" if joint_type.wraps else "max_force"
        kind = "revolute" if joint_type.wraps else "prismatic"
        raise ValueError(f"a {kind} joint's actuator limit is {right}, not {wrong}")


class PayloadFile(Strict):
    """``payload:`` in a robot file: the rigid body the platform carries."""

    mass: Mass
    """kg, above 0."""
    centre: Vec3 = [0.0, 0.0, 0.0]
    """Its centre of mass in the platform frame (in the file's length unit)."""
    inertia: Optional[Inertia] = None
    """kg m^2 about its centre along the platform axes: [Ixx, Iyy, Izz] or a symmetric positive-definite
    3 x 3 matrix; absent: a point mass."""


def _check_gravity(vector):
    """each component within ±1000 m/s^2 (100 g)"""
    if any(abs(component) > MAX_GRAVITY for component in vector):
        raise ValueError(f"gravity's components must be within +/-{MAX_GRAVITY:g} m/s^2")
    return vector


Gravity = Annotated[list[float], Field(min_length=3, max_length=3), AfterValidator(_check_gravity)]
"""m/s^2, base frame."""


class JointLimits(Strict):
    """``joint_limits:`` of a limb: the largest angle (degrees) between its passive link and each
    passive joint's neutral axis."""

    base: Optional[ConeAngle] = None
    """The base-side passive joint's largest angle (degrees) from its neutral axis (``base_axis``)."""
    platform: Optional[ConeAngle] = None
    """The platform joint's largest angle (degrees) from its neutral axis (``platform_axis``)."""


@dataclass(frozen=True)
class Payload:
    """The payload as kingen computes with it: ``mass`` kg, ``centre`` (3,) mm in the platform
    frame, ``inertia`` (3, 3) kg m^2 about the centre along the platform axes."""

    mass: float
    centre: tuple
    inertia: tuple

    @property
    def inertia_matrix(self):
        return np.array(self.inertia, dtype=float)


class Part(Strict):
    """One moving part of a limb, a point mass: ``mass`` kg and ``centre``, its distance (in the
    file's length unit) along the part from the joint it is measured from."""

    mass: Mass
    """kg, above 0."""
    centre: Annotated[float, Field(ge=0, le=MAX_MM)] = 0.0
    """The distance of its centre of mass from the joint it is measured from (in the file's length unit)."""


class LimbParts(Strict):
    """``parts:`` of a limb: the masses it moves (docs/explanation/loads.md, 'The limbs' parts')."""

    actuator: Optional[Part] = None
    """The part the actuator moves: a leg's cylinder (its centre measured from the base joint along
    the leg), a crank (from its pivot along the crank), a rail's carriage (the carriage moves
    rigidly: its centre does not matter)."""
    link: Optional[Part] = None
    """The passive link: a leg's rod, a crank's or a carriage's rod (its centre measured from the
    platform joint along the link toward the base side)."""

    def scaled(self, scale):
        """These parts with their centres multiplied by ``scale`` (mm per the file's unit)."""
        return self.model_copy(update={name: part.model_copy(update={"centre": part.centre * scale})
                                       for name, part in (("actuator", self.actuator), ("link", self.link))
                                       if part is not None})


def payload_of(document, mm_per_unit):
    """The file's payload (kingen's units), or None."""
    section = document.payload
    if section is None:
        return None
    inertia = np.zeros((3, 3)) if section.inertia is None else _as_matrix(section.inertia)
    inertia = 0.5 * (inertia + inertia.T)
    return Payload(mass=section.mass, centre=tuple(float(v) * mm_per_unit for v in section.centre),
                   inertia=tuple(map(tuple, inertia.tolist())))
