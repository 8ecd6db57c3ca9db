"""Identification: the parameters that best explain the measurements, by nonlinear least squares
(scipy's ``least_squares``, Levenberg-Marquardt) on parameters scaled to mm-equivalents.

Residuals: with pose measurements, each limb's joint predicted at the measured pose (the
limbs' closure there) minus the joint read, and for a machine with task coordinates its
constraint equations' residuals there, each weighted by one over the deviation the measured
pose's noise gives it (``pose_weights``); with positions, the point forward kinematics
puts the target at for the read joints minus the measured point (mm). Steps:

1. the nominal robot's forward kinematics of every read joint set, in the working posture and
   within forward kinematics' search region around the verification home (its failures, a spread of
   positions that looks like metres or inches, a measured pose the nominal robot cannot
   reach: KingenError naming file, line and column); the measuring frame's first estimate
   fitted to those poses (rigid, closed form);
2. the measuring frame and target alone by least squares: the residuals *before*;
3. the Jacobian there; the identifiable parameters (kingen.calibrate.identifiability), the
   rest kept nominal; all of them by least squares: the residuals *after*, the standard
   deviations and observability indices at the solution.
"""

import math
import time
from dataclasses import dataclass

import numpy as np

from ..conventions import matrix_from_pose, pose_from_t6, t6_from_matrix, t6_from_pose
from ..errors import KingenError
from ..kinematics.forward import assemblies, free_mask, poses_of, search_region
from ..kinematics.parasitic import on_manifold
from ..kinematics.poses import sample_poses
from ..kinematics.reference import solve
from ..kinematics.routine import SINGULAR_TOLERANCE
from . import identifiability
from .measurements import Measurements
from .prediction import (CLOSED, errors, forward_poses, inverse_joints, joint_residuals, matrix_radians,
                         measured_platform, predicted_measurements, residual_sigma, residuals_per_pose, synthesize)
from .wrist import tool_of_platform

STEP = 1e-4
"""Central differences' step, mm-equivalents."""
MAX_EVALUATIONS = 100
STRUCTURE_POSES = 60
"""Seeded poses of the verification region the structural rank (how many poses are needed) is taken on."""
UNITS = {"metres": 1e-3, "inches": 1.0 / 25.4}
"""Units measurements are mistaken for: their spread is this fraction of the poses' in mm."""


class Problem:
    """The residuals and their Jacobian for Parameters ``parameters`` and Measurements
    ``measurements``; ``start`` (n, 6; mm, radians) the poses forward kinematics starts from
    (position measurements), kept at the last solution; ``weights`` (m,) each pose residual's
    weight (pose measurements; None: all 1)."""

    def __init__(self, parameters, measurements, start, weights=None):
        self.parameters, self.measurements, self.start = parameters, measurements, start
        self.weights = 1.0 if weights is None else weights

    def residuals(self, values, keep=True):
        """(m,) mm-equivalents (see the module docstring), pose residuals times their weights."""
        if self.parameters.measure == "pose":
            return joint_residuals(self.parameters, values, self.measurements).ravel() * self.weights
        predicted, poses, _ = predicted_measurements(self.parameters, values, self.measurements.joints, self.start)
        if keep:
            self.start = poses
        return (predicted - self.measurements.measured).ravel()

    def jacobian(self, values, columns):
        """d(residuals)/dx (m, len(columns)) by central differences."""
        steps = self.parameters.step
        out = []
        for column in columns:
            shift = np.zeros(len(values))
            shift[column] = STEP * steps[column]
            out.append((self.residuals(values + shift, False) - self.residuals(values - shift, False)) / (2 * STEP))
        return np.column_stack(out) if out else np.zeros((len(self.residuals(values, False)), 0))

    def errors(self, values):
        """(position error (n,) mm, orientation error (n,) degrees or None, closed (n,)): what
        ``values`` predict from the read joints against what was measured."""
        if self.parameters.measure == "pose":
            start = poses_of(t6_from_matrix(measured_platform(self.parameters, values, self.measurements)[1]))
        else:
            start = self.start
        predicted, _, closed = predicted_measurements(self.parameters, values, self.measurements.joints, start)
        position, angle = errors(predicted, self.measurements.measured)
        return position, angle, closed


@dataclass
class Fit:
    """An identification: ``values`` identified, ``before`` (frame and target fitted alone),
    ``selected`` and ``chosen`` (identifiable) masks, ``std`` (NaN where not identified),
    observability ``indices``, ``unidentifiable`` in words, ``converged`` and ``message``,
    ``evaluations``, ``seconds``, and the Problem it solved."""

    values: np.ndarray
    before: np.ndarray
    selected: np.ndarray
    chosen: np.ndarray
    std: np.ndarray
    indices: dict
    unidentifiable: list
    converged: bool
    message: str
    evaluations: int
    seconds: float
    problem: Problem


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


def region_poses(robot, count, seed):
    """``count`` seeded poses (mm, degrees) of the robot's verification region, the coordinates
    forward kinematics does not solve for (a translating platform's angles) held at home; a
    machine with task coordinates at its nominal poses for the drawn task coordinates (on its
    manifold, kingen.kinematics.parasitic.on_manifold); a machine with a wrist: tool poses of
    its region (kingen.calibrate.prediction.synthesize takes the machine's turn about the tool axis)."""
    poses = sample_poses(robot, count, seed)
    if robot.wrist is not None:
        return poses
    if robot.task:
        return on_manifold(robot, poses)
    fixed = ~free_mask(robot)
    poses[:, fixed] = np.asarray(robot.verification.home)[fixed]
    return poses


def synthetic_problem(parameters, values, poses, posture):
    """(Problem, Measurements): exact measurements of the robot of ``values`` at ``poses`` (n, 6;
    mm, degrees) in ``posture``, and the identification problem started at those poses."""
    joints, measured = synthesize(parameters, values, poses, posture)
    data = Measurements("", parameters.measure, joints, measured, tuple(range(len(poses))), ())
    start = np.concatenate([poses[:, :3], np.radians(poses[:, 3:])], axis=1)
    if parameters.robot.wrist is not None:  # the platform's, not the tool's
        start = poses_of(solve(parameters.robot_of(values), t6_from_pose(poses)).platform)
    return Problem(parameters, data, start), data


def identifiable_columns(problem, values, parameters, selected):
    """(order, jacobian, taken, chosen): the ``selected`` parameters in identifiability.priority's
    order, ``problem``'s Jacobian over them at ``values``, which of them (taken, over order)
    are identifiable, and those as a mask over all parameters (chosen)."""
    order = [i for i in identifiability.priority(parameters) if selected[i]]
    jacobian = problem.jacobian(values, order)
    taken = identifiability.identifiable(jacobian, range(len(order)))
    chosen = np.zeros(len(parameters), dtype=bool)
    chosen[np.array(order)[taken]] = True
    return order, jacobian, taken, chosen


def needed_poses(parameters, values, selected):
    """(identifiable parameters, poses needed): the rank of the selected parameters' Jacobian
    on STRUCTURE_POSES seeded poses of the verification region, and the poses that many
    parameters need (each pose gives residuals_per_pose equations)."""
    robot = parameters.robot
    poses = region_poses(robot, STRUCTURE_POSES, seed=1)
    problem, _ = synthetic_problem(parameters, values, poses, robot.working_posture)
    jacobian = problem.jacobian(values, np.flatnonzero(selected))
    rank = int(np.count_nonzero(identifiability.identifiable(jacobian, range(jacobian.shape[1]))))
    return rank, -(-rank // residuals_per_pose(robot, parameters.measure))


def least_squares_fit(problem, values, columns, max_evaluations):
    """scipy's least_squares over ``columns`` from ``values``: (values, result)."""
    from scipy.optimize import least_squares

    def full(x):
        out = values.copy()
        out[columns] = problem.parameters.nominal[columns] + x * problem.parameters.step[columns]
        return out

    start = problem.parameters.deviations(values)[columns]
    result = least_squares(lambda x: problem.residuals(full(x)), start,
                           jac=lambda x: problem.jacobian(full(x), columns), method="lm", max_nfev=max_evaluations)
    return full(result.x), result


def identify(parameters, measurements, selected, max_evaluations=None):
    """The Fit of ``parameters`` to ``measurements`` over the ``selected`` (mask) parameters, each
    least-squares stage stopped after ``max_evaluations`` (default MAX_EVALUATIONS)."""
    began = time.perf_counter()
    max_evaluations = max_evaluations or MAX_EVALUATIONS
    values, start = align(parameters, measurements)
    selected, words = _translating(parameters, selected)
    rank, needed = needed_poses(parameters, values, selected)
    if len(measurements.joints) < needed:
        raise KingenError(f"{measurements.path}:{measurements.lines[-1]}: poses: {len(measurements.joints)} "
                          f"measurements for {rank} identifiable parameters: at least {needed} poses are needed "
                          f"(kingen calibrate plan chooses them)")
    problem = Problem(parameters, measurements, start, pose_weights(parameters, values, measurements))
    evaluations = 0
    frame_columns = np.flatnonzero(selected & np.isin(parameters.groups, ("frame", "target")))
    if len(frame_columns):
        values, result = least_squares_fit(problem, values, frame_columns, max_evaluations)
        evaluations += result.nfev
    before = values.copy()
    order, _, taken, chosen = identifiable_columns(problem, values, parameters, selected)
    columns = np.flatnonzero(chosen)
    values, result = least_squares_fit(problem, values, columns, max_evaluations)
    evaluations += result.nfev
    final = problem.jacobian(values, order)
    residuals = problem.residuals(values)
    std = np.full(len(parameters), np.nan)
    identified = np.array(order)[taken]
    std[identified] = identifiability.deviations(final[:, taken], residuals) * parameters.step[identified]
    full = np.zeros((final.shape[0], len(parameters)))
    full[:, order] = final
    words += identifiability.combinations(full, parameters.names, chosen, selected)
    return Fit(values=values, before=before, selected=selected, chosen=chosen, std=std,
               indices=identifiability.indices(final[:, taken]), unidentifiable=words,
               converged=bool(result.status > 0), message=result.message, evaluations=int(evaluations),
               seconds=time.perf_counter() - began, problem=problem)


def pose_weights(parameters, values, measurements):
    """(m,) each pose residual's weight, or None for positions: one over the standard deviation
    the measured pose's noise gives it (prediction.residual_sigma at ``values``, the noise taken
    alike in every coordinate in mm-equivalents: 1 mm, and 1 mm over the robot's size in
    radians), so that residuals that move more with the measured pose (a steep rail's carriage)
    count less and the deviations' pooled variance holds for every residual."""
    if parameters.measure != "pose":
        return None
    sigma = residual_sigma(parameters, values, measurements, 1.0, math.degrees(1.0 / parameters.lever))
    return 1.0 / sigma


def _translating(parameters, selected):
    """(selected, words): for pose measurements of a platform that does not rotate (forward
    kinematics solves for no angle, and no angle is parasitic), the target's angles deselected,
    with the words why."""
    robot = parameters.robot
    if parameters.measure != "pose" or robot.task or not robot.forward_free or set(robot.forward_free) & {"roll", "pitch", "yaw"}:
        return selected, []
    angles = selected & (parameters.groups == "target") & np.array([entry.unit == "deg" for entry in parameters.entries])
    if not np.any(angles):
        return selected, []
    names = ", ".join(np.array(parameters.names)[angles])
    return selected & ~angles, [f"{names}: the platform does not rotate, so the measured orientation fixes only the "
                                "measuring frame's and the target's rotations together: the target's cannot be "
                                "identified from pose measurements (kept at its nominal value)"]


def validation_problem(parameters, values, measurements):
    """A Problem for held-out ``measurements`` (its errors at ``values``): forward kinematics
    started at the nominal robot's poses for them (the checks of :func:`align` applied)."""
    _, start = align(parameters, measurements)
    return Problem(parameters, measurements, start)
