"""Where a robot's base frame and mount-plate (T6) frame go on the machine, and what each
branch of its two-branch limbs looks like there: words for the hosts' setup sheets, derived
from the limbs' geometry (their base joints, joint axes and platform joints), never written
per robot. The branch words are the limb models' own (``LimbModel.branch_labels``), taken
with the platform at the verification home."""

import math

import numpy as np

from ..conventions import matrix_from_pose
from .limbs.base import axis_words
from ..units import LENGTH_UNITS

ANGLE_TOLERANCE = 0.01
"""Degrees within which a joint counts as on an axis, or two as mirror images."""


def _number(value):
    return f"{round(float(value), 6) + 0.0:.10g}"


def _rounded(value):
    """A derived length or angle to 0.001 of its unit."""
    return f"{round(float(value), 3) + 0.0:g}"


def _point(point, scale=1.0):
    return "(" + ", ".join(_number(value / scale) for value in point) + ")"


def _home(robot):
    return matrix_from_pose(np.asarray(robot.verification.home, dtype=float))


def home_platform_points(robot):
    """(dof, 3) each limb's platform joint in the base frame, mm, with the platform at the
    verification home."""
    home = _home(robot)
    return np.array([home[:3, :3] @ limb.platform_point + home[:3, 3] for limb in robot.limbs])


def base_joints(robot):
    """(dof, 3) each limb's actuated joint on the base, mm, base frame (``LimbModel.base_joint``)."""
    return np.array([limb.base_joint() for limb in robot.limbs], dtype=float)


def branch_words(robot):
    """Per limb: (branch 0, branch 1) in machine words, each true with the platform at the
    verification home (centre: the base joints' centroid); () for one-branch limbs."""
    centre = base_joints(robot).mean(axis=0)
    return [limb.branch_labels(point, centre) for limb, point in zip(robot.limbs, home_platform_points(robot))]


def frames(robot, units="mm"):
    """The setup sheet's frames, lengths in ``units``: {"base": sentences placing the base
    frame by the base joints, "platform": sentences placing the mount-plate (T6) frame by
    the platform joints, "joints": per limb {name, base (its base joint, base frame), axis
    (its joint axis in words, or "-"), platform (its platform joint, platform frame)}}."""
    scale = LENGTH_UNITS[units]
    base, platform = base_joints(robot), np.array([limb.platform_point for limb in robot.limbs], dtype=float)
    home = _home(robot)
    base_in_platform = home[:3, :3].T @ (base.mean(axis=0) - home[:3, 3])
    rows = [{"name": name, "base": _point(joint, scale), "platform": _point(point, scale),
             "axis": "-" if limb.joint_axis() is None else axis_words(limb.joint_axis())}
            for name, joint, point, limb in zip(robot.joint_names, base, platform, robot.limbs)]
    placed = _describe(base, robot.joint_names, "base joints", home_platform_points(robot).mean(axis=0),
                       "platform", scale, units)
    axes = {row["axis"] for row in rows}
    if len(axes) == 1 and "-" not in axes:
        placed.append(f"Every actuated joint {'turns about' if robot.revolute[0] else 'moves along'} {axes.pop()}.")
    return {"base": placed,
            "platform": _describe(platform, robot.joint_names, "platform joints", base_in_platform, "base", scale, units),
            "joints": rows}


def _describe(points, names, what, other, other_name, scale, units):
    """Sentences placing a frame by ``points`` (n, 3) in it, mm: its origin against their
    centroid, its Z axis against their plane and the side ``other`` (a point in this frame)
    lies on, its X axis against the joints' bearings about their centre."""
    centre = points.mean(axis=0)
    tolerance = 1e-6 * max(1.0, float(np.max(np.linalg.norm(points - centre, axis=1))))
    if np.linalg.norm(centre) <= tolerance:
        origin = f"at the centre (centroid) of the {what}"
    elif math.hypot(centre[0], centre[1]) <= tolerance:
        origin = (f"on the Z axis through the centre of the {what}, {_rounded(abs(centre[2]) / scale)} {units} "
                  f"on its {'-Z' if centre[2] > 0 else '+Z'} side")
    else:
        origin = f"placed so that the centre of the {what} is at ({', '.join(_rounded(v / scale) for v in centre)}) {units}"
    sentences = [f"Origin {origin}."]
    side = other[2] - centre[2]
    toward = f"points toward the {other_name}" if side > tolerance else (
        f"points away from the {other_name}" if side < -tolerance else "")
    if np.ptp(points[:, 2]) <= tolerance:
        sentences.append(f"+Z is normal to their plane{' and ' + toward if toward else ''}.")
    else:
        spread = f"they span Z {_rounded(points[:, 2].min() / scale)} to {_rounded(points[:, 2].max() / scale)} {units}"
        sentences.append(f"+Z {toward}; {spread}." if toward else f"Along Z {spread}.")
    sentences.append(_bearing(points - centre, names, tolerance, scale, units))
    return sentences


def _bearing(offsets, names, tolerance, scale, units):
    """Where the X axis points among the joints at ``offsets`` (n, 3) from their centre: +X,
    -X, +Y or -Y (the first that fits) toward one joint or midway between a mirror pair, else
    +X at an angle from the nearest joint; joints at one place are named together."""
    groups = {}
    for offset, name in zip(offsets, names):
        groups.setdefault(tuple(np.round(offset / tolerance)), (offset, []))[1].append(name)
    bearings = [(math.degrees(math.atan2(offset[1], offset[0])), math.hypot(offset[0], offset[1]),
                 " and ".join(f"{name}'s" for name in grouped) + " joint" + ("s" if len(grouped) > 1 else ""))
                for offset, grouped in groups.values() if math.hypot(offset[0], offset[1]) > tolerance]
    if not bearings:
        return "The joints lie on the Z axis: X is free."
    radii = [radius for _, radius, _ in bearings]
    circle = (f" They lie on a circle of radius {_rounded(radii[0] / scale)} {units} about it."
              if max(radii) - min(radii) <= tolerance and len(bearings) > 2 else "")
    for axis, direction in (("+X", 0.0), ("-X", 180.0), ("+Y", 90.0), ("-Y", -90.0)):
        turned = [((angle - direction + 180.0) % 360.0 - 180.0, radius, label) for angle, radius, label in bearings]
        on_axis = [label for angle, _, label in turned if abs(angle) <= ANGLE_TOLERANCE]
        if on_axis:
            return f"{axis} points from their centre toward {on_axis[0]}.{circle}"
        pairs = sorted((a, first, second) for a, ra, first in turned for b, rb, second in turned
                       if 0.0 < a < 180.0 - ANGLE_TOLERANCE and abs(a + b) <= ANGLE_TOLERANCE and abs(ra - rb) <= tolerance)
        if pairs:
            angle, first, second = pairs[0]
            return (f"{axis} points from their centre midway between {first} and {second} "
                    f"({_rounded(angle)} degrees either side).{circle}")
    angle, _, label = min(bearings, key=lambda bearing: abs(bearing[0]))
    sense = "clockwise" if angle > 0 else "counterclockwise"
    return f"+X points from their centre {_rounded(abs(angle))} degrees {sense} (about +Z) of {label}.{circle}"
