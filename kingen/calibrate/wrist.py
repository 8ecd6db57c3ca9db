"""A serial wrist's geometry as calibration parameters, and the wrist's part of the prediction
(docs/how-to/calibrate.md, 'A machine with a serial wrist').

A machine with a wrist (kingen.robot.wrist) is measured on its tool: the measured frame (or the
reflector) is on the tool, ``target`` in the tool frame. It adds per wrist joint its
``zero_offset`` (degrees, group 'zero') and its axis's two tilts across itself (degrees, 0
nominal, group 'axis', as kingen.calibrate.constraints tilts the constraints' axes), then the
tool's reach (mm, group 'length'): the tool frame's origin moved along the tool's z axis.

The wrist's joints are read, like the legs'. The tool frame in the platform frame for readings
q is W(q) = Rot(a1, q1 + z1) Rot(a2, q2 + z2) ... H0 (H0 the tool frame at zero, column-form
homogeneous matrices, kingen.kinematics.hybrid.wrist.tool_t6): a tool at B puts the platform at
B W(q)^-1, and the platform at P puts the tool at P W(q).
"""

import math
from dataclasses import replace

import numpy as np

from ..conventions import matrix_from_t6
from ..kinematics.hybrid.wrist import tool_t6
from .constraints import TILTS, tilted

TOOL = "tool"
"""The ``wrist`` mark of the tool's reach (the others are wrist joint indices)."""


def entries(robot):
    """[((name, group, unit, nominal), (wrist, field, component))] of the wrist's parameters of
    ``robot`` (a Robot with a wrist; none without one): the zero offsets first (where a zero and
    an axis's tilt move the tool alike, the identification keeps the zero), then the axes' tilts,
    then the tool's reach."""
    if robot.wrist is None:
        return []
    wrist = robot.wrist
    found = [((f"{name}.zero_offset", "zero", "deg", math.degrees(wrist.zero[index])), (index, "zero_offset", None))
             for index, name in enumerate(wrist.names)]
    for index, name in enumerate(wrist.names):
        found += [((f"{name}.axis.tilt_{part}", "axis", "deg", 0.0), (index, "axis", part)) for part in TILTS]
    found.append(((f"{TOOL}.reach", "length", "mm", wrist.reach), (TOOL, "reach", None)))
    return found


def calibrated_wrist(wrist, placed):
    """The Wrist ``wrist`` with ``placed`` [((wrist, field, component), value (mm, degrees))]
    put in: zero offsets, axes tilted across themselves, the tool's origin moved along its z
    axis to the reach."""
    zero, axes, tool = wrist.zero.copy(), wrist.axes.copy(), wrist.tool.copy()
    tilts = {}
    reach = wrist.reach
    for (index, field, component), value in placed:
        if field == "zero_offset":
            zero[index] = math.radians(value)
        elif field == "axis":
            tilts.setdefault(index, {})[component] = math.radians(value)
        else:
            reach = float(value)
    for index, angles in tilts.items():
        axes[index] = tilted(wrist.axes[index], angles)
    tool[:3, 3] += (reach - wrist.reach) * wrist.tool[:3, 2]
    return replace(wrist, zero=zero, axes=axes, tool=tool, reach=reach)


def tool_in_platform(robot, wrist_joints):
    """(n, 4, 4) W(q): the tool frame in the platform frame (column form, mm) of ``robot``'s
    wrist for its readings ``wrist_joints`` (n, k) rad."""
    identity = np.tile(np.eye(4), (len(wrist_joints), 1, 1))
    return matrix_from_t6(tool_t6(robot, identity, np.asarray(wrist_joints, dtype=float)))


def platform_of_tool(robot, tool, joints):
    """(n, 4, 4) the platform's pose (column form, base frame) with the tool at ``tool`` (n, 4,
    4) and the machine's joints ``joints`` (n, joint_count; the wrist's read)."""
    return tool @ np.linalg.inv(tool_in_platform(robot, joints[:, robot.dof:]))


def tool_of_platform(robot, platform, joints):
    """(n, 4, 4) the tool's pose (column form, base frame) with the platform at ``platform`` (n,
    4, 4) and the machine's joints ``joints`` (n, joint_count)."""
    return platform @ tool_in_platform(robot, joints[:, robot.dof:])
