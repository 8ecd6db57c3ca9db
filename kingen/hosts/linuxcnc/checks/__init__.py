"""LinuxCNC's own verify checks, one module each: the inverse refuses what it cannot answer
(:mod:`.refusal`), the forward returns the sampled pose from seeds near and far and never
another assembly mode (:mod:`.forward`); and ``CHECKS``: every check a LinuxCNC module gets,
in report order."""

from ....verify.checks import Closure, Definition, Determinism, Golden, Jacobian, Machine, RoundTrip, Values, Warnings
from .forward import Forward
from .refusal import Refusal

CHECKS = (Definition(), Refusal(), Values(), Warnings(), Closure(), Jacobian(), RoundTrip(), Forward(),
          Determinism(), Machine(), Golden())
"""Every check a LinuxCNC module gets, in report order."""

__all__ = ["CHECKS", "Forward", "Refusal"]
