"""Forward kinematics of a machine with a wrist (kingen.robot.wrist), numpy only: the parallel
part's forward (kingen.kinematics.forward's Newton, along the manifold of a machine with task
coordinates) from the legs' joints, then the wrist's forward (kingen.kinematics.hybrid.wrist.tool_t6)
from the wrist's; and the joint rates per tool twist from central differences of that map,
independent of the inverse's closed form (what verify's ``jacobian`` check compares with).
Every assembly mode of such a machine: kingen.kinematics.forward.assemblies.

Poses are (x, y, z) mm and (roll, pitch, yaw) rad here, as in kingen.kinematics.forward.
"""

import numpy as np

from ..forward import free_mask, newton, t6_of
from .wrist import orientation_rows, tool_t6


def tool_forward(robot, joints, near):
    """The whole machine's forward for ``joints`` (n, joint_count) (mm, rad): (tool T6 (n, 4, 4),
    the platform's pose (n, 6) mm and rad, the legs' largest closure residual (n,) mm). Newton
    starts each platform at ``near`` (n, 6) and converges to the assembly mode nearest it."""
    parallel = robot.parallel
    joints = np.asarray(joints, dtype=float)
    platform, residual = newton(parallel, near, joints[:, :robot.dof], free_mask(parallel))
    return tool_t6(robot, t6_of(platform), joints[:, robot.dof:]), platform, residual


def tool_rates(robot, joints, near, step_mm, step_rad):
    """(n, joint_count, 6) the joint rates per unit tool twist (translations along base x, y,
    z, mm; rotations about base x, y, z through the base origin, rad: the twists of
    kingen.kinematics.singularity.twist_poses) at ``joints`` (n, joint_count), the platform
    near ``near`` (n, 6). The forward map's derivative with respect to each joint, of the tool
    tip and the tool axis, by Richardson-extrapolated central differences (steps ``step_mm``
    for the legs, ``step_rad`` for the wrist, and half of them), is solved by least squares for
    the tip's rate v + omega x tip and the axis's rate omega x axis: the five driven directions;
    the twist about the tool axis asks neither and gets zero rates. With three wrist joints
    every tool axis's rate is asked (kingen.kinematics.hybrid.wrist.orientation_rows): all six twists."""
    joints = np.asarray(joints, dtype=float)
    count, total = joints.shape
    rows = (3, *orientation_rows(robot.wrist))
    steps = np.where(np.arange(total) < robot.dof, step_mm, step_rad)
    derivatives = []
    for halving in (1.0, 2.0):
        moved = np.repeat(joints[:, None, None], 2, axis=2).repeat(total, axis=1)  # (n, joint, sign, joint)
        for joint in range(total):
            moved[:, joint, 0, joint] -= steps[joint] / halving
            moved[:, joint, 1, joint] += steps[joint] / halving
        tool, _, _ = tool_forward(robot, moved.reshape(-1, total), np.repeat(near, 2 * total, axis=0))
        tool = tool.reshape(count, total, 2, 4, 4)
        motion = np.concatenate([tool[..., row, :3] for row in rows], axis=-1)  # tip and axes
        derivatives.append((motion[:, :, 1] - motion[:, :, 0]) / (2.0 * steps[None, :, None] / halving))
    derivative = np.swapaxes((4.0 * derivatives[1] - derivatives[0]) / 3.0, 1, 2)  # (n, 3 rows, joint)
    tool, _, _ = tool_forward(robot, joints, near)
    tip = tool[:, 3, :3]
    omega = np.eye(3)
    asked = np.zeros((count, 3 * len(rows), 6))  # (n, tip and axes rates, twist)
    asked[:, :3, :3] = np.eye(3)
    asked[:, :3, 3:] = np.swapaxes(np.cross(omega[None], tip[:, None]), 1, 2)
    for index, row in enumerate(rows[1:], start=1):
        asked[:, 3 * index:3 * index + 3, 3:] = np.swapaxes(np.cross(omega[None], tool[:, row, None, :3]), 1, 2)
    # The axes' rows as mm of arc at the robot's size, so that all weigh alike; the pseudo-inverse
    # solves them exactly (the derivative has full column rank away from the machine's singularities).
    weights = np.array([1.0] * 3 + [robot.size_mm] * (3 * len(rows) - 3))[:, None]
    return np.linalg.pinv(derivative * weights) @ (asked * weights)
