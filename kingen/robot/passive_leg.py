"""A passive constraining leg (the Tricept's central tube; docs/how-to/hybrid.md).

The tube runs from the centre c of a universal joint in the base to the platform frame's
origin p, through a passive prismatic joint, and is rigidly fixed to the platform. The
universal joint's first axis a is fixed in the base; its second axis is fixed in the tube (so
in the platform: b_p, platform frame) and perpendicular to a and to the tube. With the tube's
direction in the platform frame t_p (``tube_axis``), the platform's rotation R follows from p
alone: R t_p = d = (p - c) / |p - c| and R b_p = (a x d) / |a x d|. The three actuated legs
(U-P-S, plain ``leg`` limbs) then read p = x, y, z, the task coordinates. b_p is the machine's
as assembled at the verification home: R0^T (a x d0) / |a x d0|.
"""

from dataclasses import dataclass

import numpy as np

from ..conventions import t6_from_pose
from ..units import LENGTH_UNITS
from .schema import Strict, UnitVec3, Vec3

POSITION = ("x", "y", "z")
ALIGNED = 1e-6
"""|a x d| at the verification home below this: the tube lies along the universal joint's first axis (refused)."""
ON_TUBE = 1e-9
"""How far the verification home's tube direction may be from R0 t_p (unit vectors)."""


class PassiveLegFile(Strict):
    """A passive constraining leg (a Tricept's central tube): a universal joint at ``base_point``,
    a passive prismatic joint, the tube fixed to the platform and running to the platform
    frame's origin. The robot declares task: [x, y, z] and three actuated legs; the universal
    joint's second axis is the machine's as assembled at the verification home, which must hold
    the tube along ``tube_axis``."""

    base_point: Vec3
    """The universal joint's centre c (base frame, the file's length unit)."""
    first_axis: UnitVec3
    """The universal joint's first axis a (unit, base frame), fixed in the base."""
    tube_axis: UnitVec3
    """The tube's direction from c toward the platform origin, in the platform frame (unit)."""


@dataclass(frozen=True, eq=False)
class PassiveLeg:
    """The tube in mm: ``base_point`` c (3,), ``first_axis`` a (3,), ``tube_axis`` t_p (3,),
    ``second_axis`` b_p (3,), platform frame; ``frame`` (3, 3) columns t_p, b_p, t_p x b_p."""

    base_point: np.ndarray
    first_axis: np.ndarray
    tube_axis: np.ndarray
    second_axis: np.ndarray
    frame: np.ndarray

    @classmethod
    def of(cls, base_point, first_axis, tube_axis, second_axis):
        """The PassiveLeg with these ``base_point`` c (3,) mm, ``first_axis`` a (3,) base frame,
        ``tube_axis`` t_p and ``second_axis`` b_p (3,) platform frame, unit and perpendicular;
        its ``frame`` built from t_p and b_p."""
        frame = np.stack([tube_axis, second_axis, np.cross(tube_axis, second_axis)], axis=1)
        return cls(base_point=np.asarray(base_point, dtype=float), first_axis=first_axis, tube_axis=tube_axis,
                   second_axis=second_axis, frame=frame)


def passive_leg_of(document, locate):
    """The PassiveLeg of a validated robot file (mm; its verification home already in mm), or
    None; a located error when the home does not hold the tube (its direction is not R0 t_p)
    or holds it along the first axis."""
    section = document.passive_leg
    if section is None:
        return None
    base = np.asarray(section.base_point, dtype=float) * LENGTH_UNITS[document.units]
    axis, tube = np.asarray(section.first_axis, dtype=float), np.asarray(section.tube_axis, dtype=float)
    home = t6_from_pose(np.asarray([document.verification.home], dtype=float))[0]
    rotation, offset = home[:3, :3].T, home[3, :3] - base
    length = np.linalg.norm(offset)
    if not length > 0.0 or np.linalg.norm(rotation @ tube - offset / length) > ON_TUBE:
        raise locate.error(["passive_leg", "tube_axis"],
                           "at the verification home the tube (from base_point to the platform origin) does not run "
                           "along tube_axis (platform frame): the home must be a pose the machine takes")
    across = np.cross(axis, offset / length)
    if not np.linalg.norm(across) > ALIGNED:
        raise locate.error(["passive_leg", "first_axis"], "at the verification home the tube lies along the "
                                                          "universal joint's first axis (its singularity)")
    second = rotation.T @ (across / np.linalg.norm(across))
    return PassiveLeg.of(base, axis, tube, second)


def check_tube(robot, locate):
    """Raise a located error unless a machine with a passive leg is one kingen solves: task
    x, y, z and three limbs, none with a revolute axis (each a U-P-S or S-P-S leg)."""
    if not robot.task:
        raise locate.error(["passive_leg"], f"a passive leg constrains the platform: declare the task coordinates "
                                            f"(task: [{', '.join(POSITION)}])")
    if tuple(sorted(robot.task)) != tuple(sorted(POSITION)) or len(robot.task) != len(POSITION):
        raise locate.error(["task"], f"a machine with a passive_leg has the task coordinates of its platform "
                                     f"origin: give task: [{', '.join(POSITION)}]")
    if len(robot.limbs) != len(POSITION):
        raise locate.error(["limbs"], f"a machine with a passive_leg has {len(POSITION)} actuated limbs; this one "
                                      f"has {len(robot.limbs)}")
    for index, limb in enumerate(robot.limbs):
        for field, found in (("revolute_axis", limb.constraint_plane()),
                             ("platform_revolute_axis", limb.platform_constraint())):
            if found is not None:
                raise locate.error(["limbs", index, field], "the passive_leg alone constrains the platform: its "
                                                            "actuated legs end in spherical or universal joints")
