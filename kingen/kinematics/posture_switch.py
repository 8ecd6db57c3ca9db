"""A posture switch predicted: what a host that recomputes the TCP from a routine's joints
may do when the routine answers posture B after posture A at the same commanded pose.

The routine's joints for B close the robot at the commanded pose, but forward kinematics
from them has every assembly mode those joints admit (:mod:`kingen.kinematics.forward`);
a host that recomputes the TCP may land on any of them, so the TCP may jump by up to the
largest distance from the commanded pose. Poses are (x, y, z) in mm and (roll, pitch, yaw)
in radians, in the robot's base frame.
"""

from dataclasses import dataclass
from typing import Optional

import numpy as np

from ..conventions import pose_from_t6, wrap_angle
from .forward import assemblies
from .routine import WARNINGS


@dataclass(frozen=True)
class PostureSwitch:
    """A switch from posture ``first`` (A) to ``second`` (B) at one commanded pose.

    ``unreachable``: A or B (A first) when it is unreachable at the pose; then nothing is
    predicted and the other fields are None. ``change`` (dof,): B's joints minus A's, mm or
    rad (revolute differences wrapped into (-pi, pi]). ``commanded`` (6,): the commanded pose,
    mm and rad. ``modes``: B's joints' assembly modes (forward.Assembly, nearest the
    commanded pose first), None when the robot has no forward kinematics (``forward.free``
    not declared); ``distances_mm``: each mode's TCP distance from the commanded one."""

    first: int
    second: int
    unreachable: Optional[int] = None
    change: Optional[np.ndarray] = None
    commanded: Optional[np.ndarray] = None
    modes: Optional[list] = None
    distances_mm: Optional[list] = None

    @property
    def jump_mm(self):
        """The largest TCP jump (mm) a host that recomputes the TCP from B's joints may make;
        None when B's joints admit no pose or nothing was predicted."""
        return max(self.distances_mm) if self.distances_mm else None


def predict_switch(robot, t6, joints, warnings, first, second):
    """The PostureSwitch from posture ``first`` to ``second`` at the commanded ``t6`` (4, 4;
    mm), given the reference's ``joints`` (dof, postures; mm or rad) and
    ``warnings`` (postures,) there. Both postures must be below ``robot.postures``."""
    unreachable = [k for k in (first, second) if warnings[k] == WARNINGS["WARN_UNREACHABLE"]]
    if unreachable:
        return PostureSwitch(first, second, unreachable=unreachable[0])
    pose = pose_from_t6(t6)
    commanded = np.concatenate([pose[:3], np.radians(pose[3:])])
    change = joints[:, second] - joints[:, first]
    change = np.where(robot.revolute, wrap_angle(change), change)
    if not robot.has_forward:
        return PostureSwitch(first, second, change=change, commanded=commanded)
    modes = assemblies(robot, joints[:, second], commanded).found
    distances = [float(np.linalg.norm(mode.pose[:3] - commanded[:3])) for mode in modes]
    return PostureSwitch(first, second, change=change, commanded=commanded, modes=modes, distances_mm=distances)
