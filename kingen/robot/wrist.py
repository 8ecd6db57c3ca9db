"""A serial wrist on the platform of a machine with task x, y, z (docs/how-to/hybrid.md).

A robot file's ``wrist:`` section lists the wrist's joints in chain order, each with its axis
and origin in the platform frame with every wrist joint at 0, and ``tool:`` places the tool
frame in the platform frame with every wrist joint at 0 (mm, degrees). kingen solves two or
three revolute joints whose axes meet at the platform frame's origin (the wrist centre, the
parallel part's task point): two with the tool tip on the tool's z axis through that centre (a
five-axis machine: tool tip and tool axis), three anywhere (a spherical wrist: the whole tool
pose); the inverse from the tool pose is then in closed form (kingen.kinematics.hybrid.wrist). Anything
else (prismatic joints, axes off the centre) is refused in one located line. :func:`with_wrist` makes the whole machine's Robot from its parallel part's:
its joints are the legs' then the wrist's, its postures the parallel part's times the wrist's
two branches (the branch the last bit), its verification region and golden values over the
tool pose, and it has no task coordinates: every tool tip and tool axis is the machine's (with
two joints the turn about the tool axis is free; with three the whole pose is read), and its
parallel part (``Robot.parallel``) keeps them.
"""

from dataclasses import dataclass, replace
from typing import Literal, Optional

import numpy as np
from pydantic import Field

from ..conventions import REVOLUTE, matrix_from_pose, pose_from_t6, t6_from_matrix
from .schema import Identifier, Strict, Travel, UnitVec3, Vec3

ALIGNED = 1e-6
"""|a x b| below this: two unit axes are parallel (refused)."""
ON_AXIS = 1e-9
"""How far (mm) the tool tip may be from the tool's z axis through the wrist centre (two joints)."""
SOLVED = ("kingen solves two or three revolute wrist joints whose axes pass through the wrist centre "
          "(the platform frame's origin)")
"""What every refusal of a wrist kingen does not solve says is solved."""


class WristJoint(Strict):
    """One wrist joint: its unit axis and a point on it (mm), platform frame, every wrist joint at 0."""

    name: Identifier
    type: Literal["revolute", "prismatic"] = "revolute"
    axis: UnitVec3
    origin: Vec3 = [0.0, 0.0, 0.0]
    travel: Optional[Travel] = None
    """Degrees, of the joint's reading (its geometric angle less ``zero_offset``)."""
    zero_offset: float = Field(0.0, ge=-180.0, le=180.0, description=(
        "Degrees: the geometric angle at which the joint reads 0 (as a crank's zero_offset): the joint reads its "
        "geometric angle (0 where 'axis' and 'tool' are given) less this, wrapped to (-180, 180]; its travel "
        "limits the reading. What `kingen calibrate` identifies."))


@dataclass(frozen=True, eq=False)
class Wrist:
    """The wrist in internal units: ``names`` (k,), ``axes`` (k, 3) unit, platform frame at zero,
    ``lower``/``upper`` (k,) rad (-inf/+inf without travel) of the joints' readings, ``zero``
    (k,) rad each joint's geometric angle at reading 0 (reading = geometric - zero, wrapped to
    (-pi, pi]), ``tool`` (4, 4) the tool frame in
    the platform frame at zero as a column-form homogeneous matrix H (conventions.matrix_from_pose:
    ``tool[:3, 3]`` its origin, mm; not a transposed T6), ``reach`` the signed distance (mm) from the wrist centre to the
    tool tip along the tool's z axis; ``branch`` None (the wrist's two branches are postures) or
    the one branch (0 or 1) a one-posture view holds it on (kingen.robot.one_posture)."""

    names: tuple
    axes: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    tool: np.ndarray
    reach: float
    zero: np.ndarray
    branch: Optional[int] = None

    @property
    def whole_pose(self):
        """Whether the wrist has three joints (a spherical wrist): the tool pose is read whole,
        six coordinates; False for two joints (a five-axis reading, the turn about the tool axis free)."""
        return len(self.names) == 3

    @property
    def tip(self):
        """(3,) the tool tip's offset (mm) from the wrist centre in the tool frame: R0^T tool[:3, 3],
        constant as the wrist turns (its axes pass through the centre)."""
        return self.tool[:3, :3].T @ self.tool[:3, 3]


def wrist_of(section, robot, locate):
    """The Wrist of a validated robot file's ``wrist`` and ``tool`` (mm and degrees) for the
    parallel part ``robot``; a located error for what this version does not solve."""
    if section.wrist is None:
        raise locate.error(["tool"], "a tool frame needs a wrist: give the wrist's joints in 'wrist', or leave 'tool' out")
    if section.tool is None:
        raise locate.error(["tool"], "required with a wrist: the tool frame in the platform frame, wrist joints at 0")
    if robot.task != ("x", "y", "z") or robot.length_unit != "mm":
        raise locate.error(["wrist"], "a wrist needs a parallel part in mm with task: [x, y, z] (the wrist centre)")
    names = list(robot.joint_names)
    for index, joint in enumerate(section.wrist):
        if joint.name in names:
            raise locate.error(["wrist", index, "name"], f"joint name '{joint.name}' is used twice")
        names.append(joint.name)
        if joint.type != "revolute":
            raise locate.error(["wrist", index, "type"], f"a prismatic wrist joint is not solved: {SOLVED}")
        if any(joint.origin):
            raise locate.error(["wrist", index, "origin"], f"off the wrist centre: {SOLVED}, origin [0, 0, 0]")
    if len(section.wrist) == 1:
        raise locate.error(["wrist"], f"a wrist of one joint is not solved: {SOLVED}")
    axes = np.array([joint.axis for joint in section.wrist])
    tool = matrix_from_pose(section.tool)
    for index in range(1, len(axes)):
        if np.linalg.norm(np.cross(axes[index - 1], axes[index])) < ALIGNED:
            raise locate.error(["wrist", index, "axis"], "parallel to the joint's before it: the wrist would lose a turn")
    reach = float(tool[:3, 3] @ tool[:3, 2])
    if len(axes) == 2:
        if np.linalg.norm(np.cross(axes[1], tool[:3, 2])) < ALIGNED:
            raise locate.error(["tool"], "the tool's z axis lies along the last joint's axis, which would not tilt it")
        if np.linalg.norm(tool[:3, 3] - reach * tool[:3, 2]) > ON_AXIS:
            raise locate.error(["tool"], "a two-joint wrist is solved with the tool tip on the tool's z axis through "
                                         "the wrist centre (three joints take any tool frame)")
    scale = REVOLUTE.yaml_scale
    travel = [joint.travel or [-np.inf, np.inf] for joint in section.wrist]
    return Wrist(names=tuple(joint.name for joint in section.wrist), axes=axes,
                 lower=np.array([t[0] for t in travel]) * scale, upper=np.array([t[1] for t in travel]) * scale,
                 tool=tool, reach=reach, zero=np.radians([joint.zero_offset for joint in section.wrist]))


def with_wrist(parallel, document, locate):
    """The whole machine's Robot: ``parallel`` (a Robot, its region the platform's, no golden
    entries) with the validated robot file ``document``'s wrist and tool. Its verification region
    is centred on the tool pose at the platform's home with every wrist joint at 0 (the same
    half-widths); its golden entries are the file's, over the tool pose. Its parallel part's
    working posture is the whole machine's without the wrist's branch (the last bit)."""
    wrist = wrist_of(document, parallel, locate)
    home = matrix_from_pose(parallel.verification.home) @ wrist.tool
    region = parallel.verification.model_copy(update={"home": pose_from_t6(t6_from_matrix(home)).tolist()})
    return replace(parallel, wrist=wrist, verification=region, golden=tuple(document.golden), task=(), forward_free=(),
                   parallel_part=replace(parallel, working_posture=parallel.working_posture // 2))
