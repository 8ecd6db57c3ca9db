"""The constraints' geometry of a machine with task coordinates as calibration parameters
(docs/how-to/calibrate.md, 'Machines with task coordinates').

A direction is calibrated by small turns across it (degrees, 0 nominal, each one mm-equivalent
like the other angles): the unit vector d becomes (d + a u + b v) / |d + a u + b v|, with u and
v the two unit vectors across d (``across``). What each family of constrained machine
(kingen.robot.constraints) gains:

- revolute axes fixed in the base ('planes'): a limb's ``revolute_axis`` two turns, or one turn
  about the direction its model names in ``revolute_axis_turns_about`` (a rail's: the axis must stay
  perpendicular to the rail, so that the carriage moves in its plane: the other way is not a
  parameter of that model);
- revolute axes fixed in the platform ('axes', the Exechon's): the pair's shared
  ``platform_revolute_axis`` two turns (both legs of the pair keep one axis, as their common
  part holds them), the third leg's two turns;
- a passive leg ('tube', the Tricept's): its ``base_point`` (3, mm), its ``first_axis`` and its
  ``tube_axis`` two turns each; the universal joint's second axis stays the nominal one turned
  with the tube (projected across the new tube axis).
"""

import math

import numpy as np

from ..robot.constraints import axes_table, family
from ..robot.passive_leg import PassiveLeg

TILTS = ("a", "b")
TURN = "turn"
AXIS_GROUP = ("axis", "the constraints' axes (revolute axes fixed in the base or the platform, a passive "
                      "leg's universal joint and tube axes)")
"""The group --identify names the constraints' directions by, and its words."""


def across(direction):
    """Two unit vectors across ``direction`` (3,), right-handed with it: the tilt axes."""
    unit = np.asarray(direction, dtype=float) / np.linalg.norm(direction)
    helper = np.eye(3)[int(np.argmin(np.abs(unit)))]
    first = np.cross(unit, helper)
    first /= np.linalg.norm(first)
    return first, np.cross(unit, first)


def tilted(direction, angles):
    """The unit vector ``direction`` (3,) tilted by ``angles`` ({'a', 'b'}: radians) across itself."""
    first, second = across(direction)
    unit = np.asarray(direction, dtype=float) / np.linalg.norm(direction)
    moved = unit + angles.get("a", 0.0) * first + angles.get("b", 0.0) * second
    return moved / np.linalg.norm(moved)


def turned_about(vector, axis, angle):
    """``vector`` (3,) made perpendicular to the unit ``axis`` (3,), unit, then turned by ``angle``
    (radians) about it (right-handed)."""
    normal = np.asarray(vector, dtype=float) - np.dot(vector, axis) * np.asarray(axis)
    normal /= np.linalg.norm(normal)
    return math.cos(angle) * normal + math.sin(angle) * np.cross(axis, normal)


def entries(robot):
    """[(name, group, unit, nominal, limb, field, component)] of the constraints' parameters of
    ``robot`` (none without task coordinates); ``limb`` None for the passive leg's."""
    kind, names = family(robot), robot.joint_names
    found = []
    if kind == "planes":
        for index, limb in enumerate(robot.limbs):
            parts = (TURN,) if type(limb).revolute_axis_turns_about else TILTS
            found += [(f"{names[index]}.revolute_axis.{_word(part)}", AXIS_GROUP[0], "deg", 0.0, index,
                       "revolute_axis", part) for part in parts]
    elif kind == "axes":
        first, second, third = axes_table(robot).pair
        for owner, label in ((first, f"{names[first]}+{names[second]}"), (third, names[third])):
            found += [(f"{label}.platform_revolute_axis.tilt_{part}", AXIS_GROUP[0], "deg", 0.0, owner,
                       "platform_revolute_axis", part) for part in TILTS]
    elif kind == "tube":
        leg = robot.passive_leg
        found += [(f"passive_leg.base_point.{axis}", "base", "mm", float(leg.base_point[n]), None, "base_point", n)
                  for n, axis in enumerate("xyz")]
        for field in ("first_axis", "tube_axis"):
            found += [(f"passive_leg.{field}.tilt_{part}", AXIS_GROUP[0], "deg", 0.0, None, field, part)
                      for part in TILTS]
    return found


def _word(part):
    return TURN if part == TURN else f"tilt_{part}"


def partners(robot):
    """{limb index: limb index whose constraint axis it shares}: an 'axes' machine's pair."""
    if family(robot) != "axes":
        return {}
    first, second, _ = axes_table(robot).pair
    return {second: first}


def limb_axis(limb, field, angles, direction):
    """The limb's constraint axis ``field`` turned by ``angles`` ({'a', 'b'} or {'turn'}: radians);
    ``direction`` (3,) the calibrated direction of the model's ``revolute_axis_turns_about`` (for a
    'turn') or None."""
    nominal = np.asarray(getattr(limb, field), dtype=float)
    if TURN in angles:
        return turned_about(nominal, direction, angles[TURN])
    return tilted(nominal, angles)


def passive_leg_of(leg, base_point, angles):
    """The PassiveLeg ``leg`` with ``base_point`` (3,) mm and its axes turned by ``angles``
    ({field: {'a', 'b'}: radians}); the second axis the nominal one across the new tube axis."""
    first_axis = tilted(leg.first_axis, angles.get("first_axis", {}))
    tube_axis = tilted(leg.tube_axis, angles.get("tube_axis", {}))
    second = turned_about(leg.second_axis, tube_axis, 0.0)
    return PassiveLeg.of(base_point, first_axis, tube_axis, second)
