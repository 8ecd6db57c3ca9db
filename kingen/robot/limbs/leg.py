"""Leg (S-P-S, U-P-S): a prismatic leg from base point b to platform point t.

q = |R t + p - b| - L0 (mm). One branch, always reachable (docs/explanation/conventions.md, 'Leg'). With
L0 = 0 the joint is the leg's absolute length.
"""

from typing import Literal, Optional

import numpy as np

from ...conventions import PRISMATIC
from ..schema import ReferenceLength, UnitVec3, Vec3
from .base import LimbModel, LimbSolution, c_double, c_vector


class Leg(LimbModel):
    """S-P-S / U-P-S leg: q = |R t + p - b| - L0 (mm). One branch."""

    model: Literal["leg"]
    base_point: Vec3
    reference_length: ReferenceLength
    """mm; 0: the joint is the leg's absolute length (as LinuxCNC's genhexkins reports it)."""
    revolute_axis: Optional[UnitVec3] = None
    """The axis (unit, base frame) of a revolute joint at the base point, fixed in the base (an
    R-P-S leg): the leg then turns only in the plane through base_point normal to it, and the
    platform point stays in that plane. Absent: a spherical or universal joint (S-P-S, U-P-S)."""
    platform_revolute_axis: Optional[UnitVec3] = None
    """The axis (unit, platform frame) of a revolute joint at the platform point, fixed in the
    platform (an S-P-R or U-P-R leg, the Exechon's): the leg stays perpendicular to it, so the
    base point stays in the plane through the platform point normal to it. Absent: a spherical
    joint at the platform."""

    joint_type = PRISMATIC
    calibratable = {"reference_length": "mm"}
    calibration_parameters = (("base_point", "base", "vector"), ("platform_point", "platform", "vector"),
                              ("reference_length", "length", "mm"))
    length_fields = ("base_point", "platform_point", "reference_length")
    joint_words = ("the leg's extension from its reference length (positive extends it; with a reference "
                   "length of 0, the leg's whole length)")
    c_columns = ("joint, base point b (mm, base frame), platform point t (mm, platform frame), "
                 "reference length L0 (mm), its dialog field")

    def solve(self, platform_point):
        length = np.linalg.norm(platform_point - np.asarray(self.base_point), axis=-1)
        q = length - self.reference_length
        return LimbSolution(values=np.stack([q, q], axis=-1))

    link_length_rate = 1.0
    passive_radius = "leg_radius"

    def base_side_point(self, platform_point, joint):
        return np.broadcast_to(np.asarray(self.base_point, dtype=float), np.shape(platform_point))

    def passive_length(self, joint):
        return self.reference_length + np.asarray(joint)

    def actuator_part_gain(self, distance):
        """None: the cylinder turns with the leg about its base joint."""
        return None

    def constraint_plane(self):
        if self.revolute_axis is None:
            return None
        return np.asarray(self.revolute_axis, dtype=float), np.asarray(self.base_point, dtype=float)

    def platform_constraint(self):
        if self.platform_revolute_axis is None:
            return None
        return (np.asarray(self.platform_revolute_axis, dtype=float), np.asarray(self.base_point, dtype=float),
                np.asarray(self.platform_point, dtype=float))

    def c_row(self):
        return {"base_point": c_vector(self.base_point), "platform_point": c_vector(self.platform_point),
                "reference_length": c_double(self.reference_length)}

    def explain_offset(self, offset):
        if self.reference_length > 0 and abs(offset - self.reference_length) <= 1e-9 * max(1.0, self.reference_length):
            return (f"the routine reports the leg's absolute strut length, not its extension from the reference "
                    f"length {self.reference_length:g} mm (as LinuxCNC's genhexkins does): to verify it, set "
                    "reference_length: 0")
        return (f"a wrong reference length (the routine behaves as if L0 = "
                f"{self.reference_length - offset:.6g} mm; the robot says {self.reference_length:g} mm)")
