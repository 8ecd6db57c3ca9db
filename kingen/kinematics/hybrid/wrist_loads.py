"""Loads of a machine with a serial wrist (docs/explanation/loads.md, 'A serial wrist'): the
payload on the tool, its wrench carried through the wrist to the platform, the parallel part's
loads there (kingen.kinematics.platform_loads) and each wrist joint's torque.

The wrist's axes pass through its centre, the platform frame's origin. The tool side of wrist
joint j (the tool, the payload and the joints after j; their own masses not modelled) is held
by the joint's reaction, which has no moment along the joint's axis z_j, and by its actuator:
its torque is tau_j = -z_j . M_c, M_c the applied wrench's moment about the centre (N m; positive
turns the joint's reading up). The platform, with the wrist on it, receives the whole applied
wrench; the legs' parts are weighed, their inertia left out (the platform's motion is not the tool's)."""

import numpy as np

from ..platform_loads import Loads, about_origin, applied_wrenches, platform_loads
from ..reference import solve
from ..routine import WARNINGS
from .wrist import rotation_about, tool_t6


def wrist_axes(robot, platform, wrist_joints):
    """(n, k, 3) each wrist joint's unit axis in the base frame, for the platform's T6 (n, 4, 4)
    and the wrist's readings (n, k) rad: R_p Rot(a_1, theta_1) ... Rot(a_(j-1), theta_(j-1)) a_j."""
    turned = np.swapaxes(platform[:, :3, :3], 1, 2)
    axes = []
    for index, joint_axis in enumerate(robot.wrist.axes):
        axes.append(turned @ joint_axis)
        turned = turned @ rotation_about(joint_axis, wrist_joints[:, index] + robot.wrist.zero[index])
    return np.stack(axes, axis=1)


def wrist_loads(robot, t6, wrench, motion, chosen):
    """:class:`Loads` of ``robot`` (with a wrist) at tool T6 (n, 4, 4) in postures ``chosen``: the
    payload (centre and inertia in the tool frame the wrist reaches), ``motion`` the tool frame
    origin's, ``wrench`` (6,) [N, N m] at the tool frame origin. ``forces`` holds the legs' then
    the wrist joints' (N m); ``machine`` the platform's T6; the angles, constraint and deflection
    are the parallel part's."""
    parallel, dof = robot.parallel, robot.dof
    solution = solve(robot, t6)
    platform = solution.platform
    legs = solution.parallel
    parts = []
    for posture in chosen:
        readings = solution.joints[:, dof:, posture]
        tool = tool_t6(robot, platform, readings)
        static, applied = applied_wrenches(robot, tool, wrench, motion)
        branch = posture // 2 if robot.wrist.branch is None else posture
        held = platform_loads(parallel, platform, legs, np.array([branch]), static, applied)
        centre_moment = about_origin(applied[:, None], platform)[:, 0, 3:]  # N m about the wrist centre
        torques = -np.einsum("nki,ni->nk", wrist_axes(robot, platform, readings), centre_moment)
        unreachable = solution.warnings[:, posture] == WARNINGS["WARN_UNREACHABLE"]
        forces = np.concatenate([held.forces[:, 0], np.where(unreachable[:, None], np.nan, torques)], axis=1)
        parts.append((held, forces, solution.warnings[:, posture]))
    deflections = [held.deflection for held, _, _ in parts]
    return Loads(machine=platform, forces=np.stack([forces for _, forces, _ in parts], axis=1),
                 constraint=np.concatenate([held.constraint for held, _, _ in parts], axis=1),
                 base_angles=np.concatenate([held.base_angles for held, _, _ in parts], axis=1),
                 platform_angles=np.concatenate([held.platform_angles for held, _, _ in parts], axis=1),
                 deflection=None if deflections[0] is None else np.concatenate(deflections, axis=1),
                 warnings=np.stack([warnings for _, _, warnings in parts], axis=1))
