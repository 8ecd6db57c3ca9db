"""LinuxCNC's own verify checks, one module each: the inverse refuses what it cannot answer
(:mod:`.refusal`), the forward returns the sampled pose from seeds near and far and never
another assembly mode (:mod:`.forward`), the load pins hold kingen's static loads
(:mod:`.loads`); and ``CHECKS``: every check a LinuxCNC module gets,
in report order."""

from ....verify.checks import Closure, Definition, Determinism, Golden, Jacobian, Machine, RoundTrip, Values, Warnings
from .five_axis import FiveAxisForward
from .forward import Forward
from .loads import HalLoads
from .refusal import Refusal

CHECKS = (Definition(), Refusal(), Values(), Warnings(), Closure(), Jacobian(), RoundTrip(), Forward(),
          HalLoads(), Determinism(), Machine(), Golden())
"""Every check a LinuxCNC module gets, in report order."""
WRIST_CHECKS = (Definition(), Refusal(), Values(), Warnings(), FiveAxisForward(), HalLoads(), Determinism(), Golden())
"""The checks of a five-axis module (a robot with a wrist): its forward is judged by
:class:`.five_axis.FiveAxisForward` (tool tip and axis, then the inverse of what it returns)."""

__all__ = ["CHECKS", "FiveAxisForward", "Forward", "HalLoads", "Refusal", "WRIST_CHECKS"]
