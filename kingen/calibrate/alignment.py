"""The measuring frame's first estimate and the checks of the measurements against the nominal
robot: the nominal robot's forward kinematics of every read joint set, in the working posture
and within forward kinematics' search region around the verification home (its failures, a
spread of positions that looks like metres or inches, a measured pose the nominal robot cannot
reach: KingenError naming file, line and column); the measuring frame fitted to those poses
(rigid, closed form). Frames and units as kingen.calibrate.prediction's."""

import math

import numpy as np

from ..conventions import matrix_from_pose, pose_from_t6, t6_from_matrix
from ..errors import KingenError
from ..kinematics.forward import assemblies, search_region
from ..kinematics.routine import SINGULAR_TOLERANCE
from .prediction import CLOSED, forward_poses, inverse_joints, matrix_radians, measured_platform
from .wrist import tool_of_platform

UNITS = {"metres": 1e-3, "inches": 1.0 / 25.4}
"""Units measurements are mistaken for: their spread is this fraction of the poses' in mm."""


def align(parameters, measurements):
    """(values, start): the nominal values with the measuring frame fitted to the nominal
    robot's forward kinematics of the read joints (rigid, closed form), and those poses (n, 6;
    mm, radians). KingenError for joints the nominal robot cannot close, positions that look
    like another unit, and measured poses it cannot reach. With a wrist: the parallel part's
    forward kinematics of the legs' joints, the measurements on the tool (the wrist's forward)."""
    whole = parameters.robot
    robot, legs = whole.parallel, measurements.joints[:, :whole.dof]
    home, half = search_region(robot)
    poses, closed = forward_poses(robot, legs, np.tile(home, (len(legs), 1)))
    closed &= _in_working_posture(robot, poses, legs) & np.all(np.abs(poses - home) <= half, axis=1)
    for row in np.flatnonzero(~closed):
        poses[row], closed[row] = _working_assembly(robot, legs[row], home, half)
    if not np.all(closed):
        row = int(np.flatnonzero(~closed)[0])
        raise KingenError(f"{measurements.where(row, 'q1')}: the nominal robot reaches no pose "
                          f"with these joints in its working posture (forward kinematics finds none)")
    platform = matrix_radians(poses)
    if whole.wrist is not None:
        platform = tool_of_platform(whole, platform, measurements.joints)
    _check_units(measurements, platform[:, :3, 3])
    values = parameters.nominal.copy()
    frame = _fitted_frame(parameters, values, measurements, platform)
    values[parameters.groups == "frame"] = pose_from_t6(t6_from_matrix(frame))
    if parameters.measure == "pose":
        _check_reachable(parameters, values, measurements)
    return values, poses


def _in_working_posture(robot, poses, joints):
    """(n,) bool: whether the reference's working posture at poses (n, 6; mm, radians) gives
    the joints (n, dof): the assembly mode the machine is built in."""
    platform = matrix_radians(poses)
    branches, _ = inverse_joints(robot, platform)
    chosen = np.take_along_axis(branches, np.array(robot.posture_branches(robot.working_posture))[None, :, None]
                                .repeat(len(poses), 0), axis=2)[..., 0]
    difference = np.abs(chosen - joints) * np.where(robot.revolute, robot.size_mm, 1.0)
    return np.all(difference <= CLOSED * robot.size_mm, axis=1)


def _working_assembly(robot, joints, home, half):
    """(pose (6,), found): the assembly mode of ``joints`` (dof,) in the working posture within
    ``half`` (6,) of ``home`` (forward kinematics' search region), nearest home first."""
    for assembly in assemblies(robot, joints, home).found:
        if (_in_working_posture(robot, assembly.pose[None], joints[None])[0]
                and np.all(np.abs(assembly.pose - home) <= half)):
            return assembly.pose, True
    return home, False


def _fitted_frame(parameters, values, measurements, platform):
    """The measuring frame F (4, 4) that best maps the measurements onto the platform poses (for
    positions on a line, its rotation is left to the least squares that follow: identity)."""
    if parameters.measure == "pose":
        each = platform @ parameters.target(values) @ np.linalg.inv(matrix_from_pose(measurements.measured))
        rotation = _nearest_rotation(np.sum(each[:, :3, :3], axis=0))
        translation = np.mean(each[:, :3, 3], axis=0)
    else:
        points = platform[:, :3, :3] @ parameters.target(values) + platform[:, :3, 3]
        measured = measurements.measured
        cross = (measured - measured.mean(0)).T @ (points - points.mean(0))
        spread = np.linalg.svd(points - points.mean(0), compute_uv=False)
        rotation = _nearest_rotation(cross.T) if spread[min(1, len(spread) - 1)] > 1e-3 * spread[0] else np.eye(3)
        translation = points.mean(0) - rotation @ measured.mean(0)
    frame = np.eye(4)
    frame[:3, :3], frame[:3, 3] = rotation, translation
    return frame


def _nearest_rotation(matrix):
    """The rotation nearest ``matrix`` (3, 3) (its polar factor, determinant +1)."""
    left, _, right = np.linalg.svd(matrix)
    return left @ np.diag([1.0, 1.0, np.sign(np.linalg.det(left @ right))]) @ right


def _spread(points):
    return float(np.sqrt(np.mean(np.sum((points - points.mean(0)) ** 2, axis=1))))


def _check_units(measurements, positions):
    """KingenError when the measured positions spread over a metre's or an inch's share of
    what the joints' poses spread over (in mm)."""
    expected = _spread(positions)
    if len(positions) < 3 or expected < 1.0:
        return
    ratio = _spread(measurements.measured[:, :3]) / expected
    for unit, share in UNITS.items():
        if abs(math.log(ratio / share)) < math.log(1.5):
            raise KingenError(f"{measurements.where(0, 'x')}: the measured positions spread over "
                              f"{ratio * expected:.4g} against {expected:.4g} mm for the joints' poses: they look "
                              f"like {unit}; give them in mm")


def _check_reachable(parameters, values, measurements):
    """KingenError at the first measured pose some limb of the nominal robot cannot reach."""
    _, radicands = inverse_joints(parameters.robot.parallel, measured_platform(parameters, values, measurements)[1])
    unreachable = radicands < -SINGULAR_TOLERANCE
    if np.any(unreachable):
        row, limb = (int(i) for i in np.argwhere(unreachable)[0])
        raise KingenError(f"{measurements.where(row, 'x')}: the nominal robot cannot reach this measured pose "
                          f"({parameters.robot.joint_names[limb]} has no solution there)")
