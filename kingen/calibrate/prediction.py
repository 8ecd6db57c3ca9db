"""What a parameter vector predicts: the joints a measured pose needs (the limbs' closure at the
pose, through each limb model's inverse), the measurement that read joints give (kingen's
forward kinematics, Newton from a nearby pose), and the errors between prediction and
measurement. Frames: a measured pose M is in the device's frame, the platform's pose
T = F M Tg^-1 in the base frame (kingen.calibrate.parameters); mm, degrees in and out,
radians for revolute joints. On a machine with a serial wrist the target is on the tool: T is
the tool's pose, the platform's is T W(q)^-1 for the wrist's read joints q
(kingen.calibrate.wrist), and the legs' closure and constraints are the parallel part's there.
"""

import numpy as np

from ..conventions import (matrix_from_pose, matrix_from_t6, pose_from_t6, rotation_from_rpy, t6_from_matrix,
                           t6_from_pose, wrap_angle)
from ..kinematics.forward import free_mask, newton
from ..kinematics.hybrid.parasitic import on_manifold, pose_constraint_residuals
from ..kinematics.reference import platform_points_in_base, solve
from .wrist import platform_of_tool, tool_of_platform

CLOSED = 1e-7
"""Forward kinematics reached the joints where no limb misses its length by more than this
fraction of the robot's size."""


def matrix_radians(poses):
    """Matrices H (n, 4, 4) of poses (n, 6) in mm and radians."""
    poses = np.asarray(poses, dtype=float)
    return matrix_from_pose(np.concatenate([poses[:, :3], np.degrees(poses[:, 3:])], axis=1))


def platform_of_measured(parameters, values, measured):
    """The platform's (with a wrist: the tool's) poses H (n, 4, 4), base frame, that measured
    poses (n, 6; mm, degrees, device frame) put it at: T = F M Tg^-1."""
    return parameters.frame(values) @ matrix_from_pose(measured) @ np.linalg.inv(parameters.target(values))


def measured_platform(parameters, values, measurements):
    """(robot of ``values``, the platform's poses H (n, 4, 4), base frame) at the measured poses
    of ``measurements`` (with a wrist: the tool's poses carried back by the read wrist joints)."""
    robot = parameters.robot_of(values)
    body = platform_of_measured(parameters, values, measurements.measured)
    return robot, body if robot.wrist is None else platform_of_tool(robot, body, measurements.joints)


def measured_of_platform(parameters, values, platform):
    """What the device measures (n, 6; mm, degrees) or (n, 3; mm) with the platform (with a
    wrist: the tool) at H (n, 4, 4)."""
    inverse = np.linalg.inv(parameters.frame(values))
    if parameters.measure == "pose":
        return pose_from_t6(t6_from_matrix(inverse @ platform @ parameters.target(values)))
    point = platform[:, :3, :3] @ parameters.target(values) + platform[:, :3, 3]
    return point @ inverse[:3, :3].T + inverse[:3, 3]


def inverse_joints(robot, platform):
    """Both branches' joints (n, dof, 2; mm, radians) and radicands (n, dof) of ``robot`` with
    the platform at H (n, 4, 4)."""
    points = platform_points_in_base(t6_from_matrix(platform), [limb.platform_point for limb in robot.limbs])
    joints = np.empty(points.shape[:2] + (2,))
    radicands = np.full(points.shape[:2], np.inf)
    for index, limb in enumerate(robot.limbs):
        solution = limb.solve(points[:, index])
        joints[:, index] = solution.values
        if solution.radicand is not None:
            radicands[:, index] = solution.radicand
    return joints, radicands


def joint_residuals(parameters, values, measurements):
    """Predicted minus read joints (n, dof) in mm-equivalents (radians times the robot's size)
    at the measured poses, each limb on the branch nearer its read joint; for a machine with
    task coordinates, then its constraint equations' residuals there (n, 3; mm,
    kingen.kinematics.hybrid.parasitic.pose_constraint_residuals): the built machine's pose keeps them,
    so a measured pose lies on the real machine's manifold. With a wrist, the legs' and the
    parallel part's constraints at the platform pose the measured tool pose and the read wrist
    joints give (:func:`measured_platform`)."""
    whole, platform = measured_platform(parameters, values, measurements)
    robot = whole.parallel
    joints, _ = inverse_joints(robot, platform)
    difference = joints - measurements.joints[:, :robot.dof, None]
    revolute = robot.revolute
    difference[:, revolute] = wrap_angle(difference[:, revolute])
    nearer = np.take_along_axis(difference, np.argmin(np.abs(difference), axis=2)[..., None], axis=2)[..., 0]
    nearer = nearer * np.where(revolute, parameters.lever, 1.0)
    if not robot.task:
        return nearer
    return np.concatenate([nearer, pose_constraint_residuals(robot, t6_from_matrix(platform))], axis=1)


def residuals_per_pose(robot, measure):
    """How many residuals one measured pose gives: the joints and, for a machine with task
    coordinates, its constraint equations (pose measurements); 3 for positions."""
    if measure != "pose":
        return 3
    return robot.dof + (3 if robot.parallel.task else 0)


def forward_poses(robot, joints, start):
    """Forward kinematics of ``robot`` for joints (n, dof) by Newton from poses ``start`` (n, 6;
    mm, radians): (poses (n, 6), closed (n,) bool: every limb within CLOSED of its length)."""
    poses, residuals = newton(robot, start, joints, free_mask(robot))
    return poses, residuals <= CLOSED * robot.size_mm


def predicted_measurements(parameters, values, joints, start):
    """(measured (n, 6 or 3), platform poses (n, 6; mm, radians), closed (n,)) that read joints
    (n, joint_count) give with ``values``, forward kinematics of the legs (the parallel part)
    started at ``start`` (n, 6), then with a wrist the wrist's forward."""
    robot = parameters.robot_of(values)
    poses, closed = forward_poses(robot.parallel, joints[:, :robot.dof], start)
    body = matrix_radians(poses)
    if robot.wrist is not None:
        body = tool_of_platform(robot, body, joints)
    return measured_of_platform(parameters, values, body), poses, closed


def errors(predicted, measured):
    """(position error (n,) mm, orientation error (n,) degrees or None) between predicted and
    measured poses (n, 6) or points (n, 3)."""
    position = np.linalg.norm(predicted[:, :3] - measured[:, :3], axis=1)
    if measured.shape[1] == 3:
        return position, None
    relative = np.swapaxes(_rotation(predicted), 1, 2) @ _rotation(measured)
    cosine = np.clip((np.trace(relative, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0)
    return position, np.degrees(np.arccos(cosine))


def _rotation(poses):
    angles = np.radians(poses[:, 3:])
    return rotation_from_rpy(angles[:, 0], angles[:, 1], angles[:, 2])


def synthesize(parameters, values, poses, posture):
    """(joints (n, dof; mm, radians), measured (n, 6 or 3)) a robot with ``values`` reads and
    the device measures with the platform at ``poses`` (n, 6; mm, degrees, base frame), in
    ``posture``: measurements made from the parameters' own model (for plans and tests); a
    machine with task coordinates at its own poses for the poses' task coordinates (on_manifold);
    a machine with a wrist at the tool poses the reference reaches for ``poses`` (tool poses;
    with two wrist joints the turn about the tool axis is the machine's)."""
    robot = parameters.robot_of(values)
    if robot.wrist is not None:
        solution = solve(robot, t6_from_pose(poses))
        joints = solution.joints[:, :, posture]
        tool = tool_of_platform(robot, matrix_from_t6(solution.platform), joints)
        return joints, measured_of_platform(parameters, values, tool)
    platform = matrix_from_pose(on_manifold(robot, poses) if robot.task else poses)
    joints, _ = inverse_joints(robot, platform)
    branches = np.array(robot.posture_branches(posture))
    chosen = np.take_along_axis(joints, np.broadcast_to(branches[None, :, None], joints.shape[:2] + (1,)), 2)[..., 0]
    return chosen, measured_of_platform(parameters, values, platform)
