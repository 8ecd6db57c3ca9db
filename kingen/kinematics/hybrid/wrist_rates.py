"""The joint rates per tool twist of a machine with a wrist (kingen.robot.wrist) in closed
form, numpy only: what the C library's Jacobian answers (kingen/hosts/c, ``c jacobian``).

Twists are [v; omega] (base frame; v the velocity of the point at the base origin, mm; omega
rad), as in kingen.kinematics.singularity.twist_poses. The tool tip q moves at v + omega x q,
the tool axis w at omega x w; the wrist centre p = q - reach w at v + omega x p. The legs
follow the platform's twist on the parallel part's manifold for that wrist-centre velocity
(kingen.kinematics.hybrid.parasitic.task_twists); the wrist's two joints turn the tool axis by the
rest of omega, (t1' A1 + t2' B2) x w = (omega - omega_platform) x w, solved by least squares.
A twist about the tool axis through the tip moves neither p nor w: zero rates (the five-axis
reading). A three-axis wrist turns by all of it: t1' A1 + t2' A2 + t3' A3 = omega -
omega_platform, with p = q - R t moving at v + omega x p as well (all six twists).
"""

import numpy as np

from .parasitic import task_twists
from .wrist import rotation_about


def centre_rates(platform):
    """(n, 3, 6) the wrist centre's velocity (mm) per unit tool twist, the centre the origin of
    the platform's T6 (n, 4, 4): v + omega x p = v - p x omega."""
    p = np.asarray(platform, dtype=float)[:, 3, :3]
    rates = np.zeros((len(p), 3, 6))
    rates[:, :, :3] = np.eye(3)
    for axis in range(3):
        rates[:, :, 3 + axis] = np.cross(np.eye(3)[axis], p)
    return rates


def _spherical_rates(wrist, rotation, angles, platform_twist):
    """(n, 3, 6) a three-axis ``wrist``'s rates per unit tool twist: (t1' A1 + t2' A2 + t3' A3) =
    omega - omega_platform, A_i its axes in the base frame at ``angles`` (n, 3) rad on the
    platform's ``rotation`` (n, 3, 3, column form); NaN where they are dependent (the gimbal lock)."""
    carried, axes = rotation, []
    for index, joint_axis in enumerate(wrist.axes):
        axes.append(carried @ joint_axis)
        carried = carried @ rotation_about(joint_axis, angles[:, index])
    directions = np.stack(axes, axis=2)  # (n, 3, 3)
    spin = -platform_twist[:, 3:]
    spin[:, :, 3:] += np.eye(3)
    rates = np.full((len(rotation), 3, 6), np.nan)
    regular = np.abs(np.linalg.det(directions)) > 1e-12
    rates[regular] = np.linalg.solve(directions[regular], spin[regular])
    return rates


def tool_jacobian(robot, tool, platform, joints, leg_rows):
    """(n, joint_count, 6) the joint rates (mm or rad) per unit tool twist of ``robot`` (with a
    wrist): ``tool`` its tool T6 (n, 4, 4), ``platform`` the machine's platform T6 there (n, 4,
    4, kingen.kinematics.reference.solve's ``platform``), ``joints`` (n, joint_count) one
    posture's joints (the wrist's readings, rad), ``leg_rows`` (n, dof, 6) the legs' rates per
    platform twist in that posture (kingen.kinematics.singularity.jacobian). NaN where the
    wrist is singular (its rates' directions dependent)."""
    tool, platform = np.asarray(tool, dtype=float), np.asarray(platform, dtype=float)
    wrist, dof = robot.wrist, robot.dof
    platform_twist = task_twists(robot.parallel, platform) @ centre_rates(platform)  # (n, 6, 6)
    legs = np.asarray(leg_rows, dtype=float) @ platform_twist
    rotation = np.swapaxes(platform[:, :3, :3], 1, 2)
    angles = np.asarray(joints, dtype=float)[:, dof:] + wrist.zero  # geometric, from the readings
    if wrist.whole_pose:
        return np.concatenate([legs, _spherical_rates(wrist, rotation, angles, platform_twist)], axis=1)
    axis = tool[:, 2, :3]
    first = rotation @ wrist.axes[0]
    second = np.einsum("nij,nj->ni", rotation @ rotation_about(wrist.axes[0], angles[:, 0]), np.broadcast_to(
        wrist.axes[1], first.shape))
    directions = np.stack([np.cross(first, axis), np.cross(second, axis)], axis=2)  # (n, 3, 2)
    spin = np.zeros((len(tool), 3, 6))
    spin[:, :, 3:] = np.eye(3)
    spin -= platform_twist[:, 3:]
    target = np.cross(spin, axis[:, :, None], axisa=1, axisb=1, axisc=1)  # (n, 3, 6)
    rates = np.full((len(tool), 2, 6), np.nan)
    for index in range(len(tool)):
        solution, _, rank, _ = np.linalg.lstsq(directions[index], target[index], rcond=None)
        if rank == 2:
            rates[index] = solution
    return np.concatenate([legs, rates], axis=1)
