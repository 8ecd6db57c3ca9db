"""Rail (P-S-S, Gantry-Tau, Hexaglide, linear Delta): a carriage on a rail drives a link
of fixed length to a platform point.

With w = R n + p - s - d: q = u.w -/+ sqrt(l^2 - |w|^2 + (u.w)^2) - origin (mm), branch 0
the minus sign; D = radicand / l^2 = cos^2 of the link-to-rail angle (docs/explanation/conventions.md, 'Rail').
"""

from typing import Literal, Optional

import numpy as np

from ...conventions import PRISMATIC
from pydantic import model_validator

from ..schema import UNIT_TOLERANCE, Coordinate, Length, UnitVec3, Vec3
from .base import LimbSolution, TwoBranchModel, axis_words, c_double, c_vector, components_last


class Rail(TwoBranchModel):
    """P-S-S carriage on a rail: q = u.w -/+ sqrt(l^2 - |w|^2 + (u.w)^2) (mm). Two branches."""

    model: Literal["rail"]
    rail_point: Vec3
    direction: UnitVec3
    carriage_offset: Vec3
    link_length: Length
    origin: Coordinate = 0.0
    """Carriage position reported as 0 (mm along the direction from rail_point): q -= origin."""
    revolute_axis: Optional[UnitVec3] = None
    """The axis (unit, base frame) of a revolute joint between carriage and link, fixed in the
    carriage, perpendicular to the rail (a P-R-S limb): the link then turns only in the plane
    through rail_point + carriage_offset normal to it, and the platform point stays in that plane.
    Absent: a spherical or universal joint (P-S-S), no constraint."""

    joint_type = PRISMATIC
    joint_words = ("the carriage's position along its rail, 0 at the origin's distance from the rail point "
                   "(positive moves it along the rail's direction); the link keeps its length")
    calibratable = {"origin": "mm", "link_length": "mm"}
    calibration_parameters = (("rail_point", "base", "vector"), ("direction", "direction", "tilt"),
                              ("platform_point", "platform", "vector"), ("link_length", "length", "mm"),
                              ("origin", "zero", "mm"))
    """The carriage offset moves the carriage as the rail point does: it is kept as written and the
    rail point stands for both."""
    revolute_axis_turns_about = "direction"
    closed_form_forward = True
    length_fields = ("rail_point", "carriage_offset", "platform_point", "link_length", "origin")
    c_columns = ("joint, rail point s (mm, base frame), direction u (unit), carriage offset d (mm), "
                 "platform point n (mm, platform frame), link length l (mm), origin (mm), "
                 "dialog fields of l and origin")

    def solve(self, platform_point):
        direction = np.asarray(self.direction)
        w = platform_point - np.asarray(self.rail_point) - np.asarray(self.carriage_offset)
        along = w @ direction
        link_squared = self.link_length * self.link_length
        radicand = link_squared - np.sum(w * w, axis=-1) + along * along
        root = np.sqrt(np.where(radicand > 0.0, radicand, 0.0))
        return LimbSolution(values=np.stack([along - root, along + root], axis=-1) - self.origin,
                            radicand=radicand / link_squared)

    @model_validator(mode="after")
    def _axis_across_rail(self):
        """A revolute axis within UNIT_TOLERANCE of perpendicular to the rail (as written to 4
        decimals) is made exactly perpendicular (its part along the rail removed, normalised)."""
        if self.revolute_axis is None:
            return self
        across = np.dot(self.revolute_axis, self.direction)
        if abs(across) > UNIT_TOLERANCE:
            raise ValueError("revolute_axis must be perpendicular to the rail's direction (the carriage "
                             "moves in the plane the joint keeps its link in)")
        axis = np.asarray(self.revolute_axis) - across * np.asarray(self.direction)
        object.__setattr__(self, "revolute_axis", [float(value) for value in axis / np.linalg.norm(axis)])  # frozen
        return self

    def constraint_plane(self):
        if self.revolute_axis is None:
            return None
        return np.asarray(self.revolute_axis, dtype=float), np.add(self.rail_point, self.carriage_offset)

    def base_side_point(self, platform_point, joint):
        start = np.asarray(self.rail_point) + np.asarray(self.carriage_offset)
        along = np.asarray(joint) + self.origin
        return components_last([start[axis] + along * self.direction[axis] for axis in range(3)])

    def passive_length(self, joint):
        return np.full(np.shape(joint), self.link_length)

    def base_side_velocity(self, joint):
        return np.broadcast_to(np.asarray(self.direction, dtype=float), np.shape(joint) + (3,))

    def c_row(self):
        return {"rail_point": c_vector(self.rail_point), "direction": c_vector(self.direction),
                "carriage_offset": c_vector(self.carriage_offset), "platform_point": c_vector(self.platform_point),
                "link_length": c_double(self.link_length), "origin": c_double(self.origin)}

    def joint_axis(self):
        return np.asarray(self.direction, dtype=float)

    def branch_labels(self, platform_point, centre):
        """Branch 0 puts the carriage's joint on the -u side of its link's platform joint
        (along the rail), branch 1 on the +u side, wherever the platform is."""
        return tuple(f"carriage on the {axis_words(sign * np.asarray(self.direction))} side of its link's platform joint"
                     for sign in (-1.0, 1.0))

    def singular_scale(self):
        return self.link_length

    def explain_offset(self, offset):
        return "a wrong rail origin or carriage offset along the rail"
