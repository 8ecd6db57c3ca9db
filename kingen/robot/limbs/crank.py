"""Crank (R-U-S, R-S-S, 6-RUS, rotary Delta): a crank turning about a horizontal axis
drives a rod of fixed length to a platform point.

Tip B = A + r (cos(theta) cos(beta), cos(theta) sin(beta), -sin(theta)); with
g = R c + p - A, a = g.(cos beta, sin beta, 0), b = -g_z, K = (|g|^2 + r^2 - L^2) / (2 r),
rho^2 = a^2 + b^2: theta = atan2(b, a) +/- acos(K / rho) - zero_offset (rad, (-pi, pi]),
branch 0 the plus sign; D = (rho^2 - K^2) / rho^2 = sin^2 of the crank-to-rod angle
(docs/explanation/conventions.md, 'Crank').
"""

import math
from typing import Literal

import numpy as np

from ...conventions import REVOLUTE, wrap_angle
from ..schema import Angle, Length, Vec3
from .base import LimbSolution, TwoBranchModel, c_double, c_vector, components_last


class Crank(TwoBranchModel):
    """R-U-S crank: theta = phi +/- acos(K / rho) (radians). Two branches.

    ``crank_direction`` (beta) is in degrees in the YAML.
    """

    model: Literal["crank"]
    pivot: Vec3
    crank_direction: Angle
    crank_length: Length
    rod_length: Length
    zero_offset: Angle = 0.0
    """Geometric crank angle (degrees) reported as joint 0: theta -= zero_offset."""

    joint_type = REVOLUTE
    calibratable = {"zero_offset": "degrees", "crank_length": "mm", "rod_length": "mm"}
    calibration_parameters = (("pivot", "base", "vector"), ("crank_direction", "direction", "deg"),
                              ("crank_length", "length", "mm"), ("rod_length", "length", "mm"),
                              ("zero_offset", "zero", "deg"), ("platform_point", "platform", "vector"))
    length_fields = ("pivot", "crank_length", "rod_length", "platform_point")
    joint_words = ("the crank's angle from the horizontal less its zero offset (positive turns its tip "
                   "down, toward -Z); the rod keeps its length")
    c_columns = ("joint, pivot A (mm, base frame), cos(beta), sin(beta), crank length r (mm), "
                 "rod length L (mm), platform point c (mm, platform frame), zero offset (rad), "
                 "dialog fields of zero offset, r and L")

    def solve(self, platform_point):
        beta = math.radians(self.crank_direction)
        g = platform_point - np.asarray(self.pivot)
        a = g[:, 0] * math.cos(beta) + g[:, 1] * math.sin(beta)
        b = -g[:, 2]
        r, rod = self.crank_length, self.rod_length
        k = (np.sum(g * g, axis=-1) + r * r - rod * rod) / (2.0 * r)
        rho_squared = a * a + b * b
        with np.errstate(divide="ignore", invalid="ignore"):
            radicand = np.where(rho_squared > 0.0, (rho_squared - k * k) / rho_squared, -1.0)
            cosine = np.where(rho_squared > 0.0, k / np.sqrt(rho_squared), 1.0)
        half = np.arccos(np.clip(cosine, -1.0, 1.0))
        phi = np.arctan2(b, a)
        zero = math.radians(self.zero_offset)
        return LimbSolution(values=wrap_angle(np.stack([phi + half - zero, phi - half - zero], axis=-1)),
                            radicand=radicand)

    def base_side_point(self, platform_point, joint):
        """The crank tip B(theta): pivot + r (cos theta cos beta, cos theta sin beta, -sin theta)."""
        return np.asarray(self.pivot) + self.crank_length * self._direction(joint, derivative=False)

    def _direction(self, joint, derivative):
        """(c cos beta, c sin beta, s) (..., 3) with c, s = cos theta, -sin theta (or, for the
        derivative, -sin theta, -cos theta), theta = joint + zero offset (components_last)."""
        beta = math.radians(self.crank_direction)
        theta = np.asarray(joint) + math.radians(self.zero_offset)
        cosine, sine = np.cos(theta), np.sin(theta)
        first, third = (-sine, -cosine) if derivative else (cosine, -sine)
        return components_last([first * math.cos(beta), first * math.sin(beta), third])

    def base_joint(self):
        """The crank's pivot."""
        return np.asarray(self.pivot, dtype=float)

    def joint_axis(self):
        """(-sin beta, cos beta, 0): a positive angle turns the crank from beta down toward -z."""
        beta = math.radians(self.crank_direction)
        return np.array([-math.sin(beta), math.cos(beta), 0.0])

    def branch_labels(self, platform_point, centre):
        """Knee out / knee in: which branch puts the crank's tip (the knee) farther from the
        Z axis through ``centre`` with the rod at ``platform_point``; where both knees are as
        far (the limb singular there), which branch turns the crank further."""
        joints = self.solve(np.asarray(platform_point, dtype=float)[None]).values[0]
        knees = self.base_side_point(None, joints) - np.asarray(centre, dtype=float)
        reach = np.hypot(knees[:, 0], knees[:, 1])
        if abs(reach[0] - reach[1]) <= 1e-9 * self.crank_length:
            return ("crank turned further in the joint's positive sense", "crank turned less far")
        words = ("knee out (farther from the centre axis)", "knee in (nearer the centre axis)")
        return words if reach[0] > reach[1] else words[::-1]

    def actuator_segment(self, joint):
        """The crank itself, from its pivot to its tip."""
        tip = self.base_side_point(None, joint)
        return np.broadcast_to(np.asarray(self.pivot, dtype=float), tip.shape), tip

    def passive_length(self, joint):
        return np.full(np.shape(joint), self.rod_length)

    def base_side_velocity(self, joint):
        return self.crank_length * self._direction(joint, derivative=True)

    def base_side_acceleration(self, joint):
        """-r (cos theta cos beta, cos theta sin beta, -sin theta): the tip's second derivative."""
        return -self.crank_length * self._direction(joint, derivative=False)

    def actuator_part_gain(self, distance):
        """A point of the crank ``distance`` mm from its pivot moves as its tip times distance / r."""
        return distance / self.crank_length

    def c_row(self):
        beta = math.radians(self.crank_direction)
        return {"pivot": c_vector(self.pivot), "cos_direction": c_double(math.cos(beta)),
                "sin_direction": c_double(math.sin(beta)), "crank_length": c_double(self.crank_length),
                "rod_length": c_double(self.rod_length), "platform_point": c_vector(self.platform_point),
                "zero_offset": c_double(math.radians(self.zero_offset))}

    def tilt_judge_row(self):
        """The pivot, the crank direction's cosine and sine, the crank and rod lengths and the
        platform point: the six-crank judge's geometry."""
        beta = np.radians(self.crank_direction)
        return {"pivot": list(map(float, self.pivot)), "cos_direction": float(np.cos(beta)),
                "sin_direction": float(np.sin(beta)), "crank_length": self.crank_length,
                "rod_length": self.rod_length, "platform": list(map(float, self.platform_point))}

    def explain_offset(self, offset):
        return f"a wrong crank zero ({math.degrees(offset):+.6g} deg)"
