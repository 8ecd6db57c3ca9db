"""Identification: the parameters that best explain the measurements, by nonlinear least squares
(scipy's ``least_squares``, Levenberg-Marquardt) on parameters scaled to mm-equivalents.

Residuals: with pose measurements, each limb's joint predicted at the measured pose (the
limbs' closure there) minus the joint read, and for a machine with task coordinates its
constraint equations' residuals there; with positions, the point forward kinematics puts the
target at for the read joints minus the measured point (mm). Steps:

1. the measurements checked against the nominal robot and the measuring frame's first estimate
   (kingen.calibrate.alignment); each pose's residuals whitened by the covariance the stated
   noise gives them (kingen.calibrate.noise: generalised least squares);
2. the measuring frame and target alone by least squares: the residuals *before*;
3. the Jacobian there; the identifiable parameters (kingen.calibrate.identifiability), the
   rest kept nominal; all of them by least squares: the residuals *after*, the standard
   deviations (with redundancy), the variance factor and observability indices at the
   solution; a pose the leave-one-out test marks an outlier is left out, named, and the fit
   made again.
"""

import math
import time
from dataclasses import dataclass, replace

import numpy as np

from ..conventions import t6_from_matrix, t6_from_pose
from ..errors import KingenError
from ..kinematics.forward import free_mask, poses_of
from ..kinematics.hybrid.parasitic import on_manifold
from ..kinematics.poses import sample_poses
from ..kinematics.reference import solve
from . import identifiability, noise
from .measurements import Measurements
from .prediction import (errors, joint_residuals, measured_platform, predicted_measurements, residuals_per_pose,
                         synthesize)
from .alignment import align

STEP = 1e-4
"""Central differences' step, mm-equivalents."""
MAX_EVALUATIONS = 5000
"""Residual evaluations a least-squares stage may take: far beyond what a fit that converges needs
(tens to a few hundred)."""
TOLERANCE = 1e-12
"""Levenberg-Marquardt stops when a step changes the cost or the parameters by less than this share."""
MAX_OUTLIER_SHARE = 0.2
"""The share of the poses that may be left out as outliers; beyond it the fit is refused."""
VARIANCE_LIMIT = 100.0
"""A variance factor beyond this (residuals over ten times the stated noise) refuses the fit."""
STRUCTURE_POSES = 60
"""Seeded poses of the verification region the structural rank (how many poses are needed) is taken on."""


class Problem:
    """The residuals and their Jacobian for Parameters ``parameters`` and Measurements
    ``measurements``; ``start`` (n, 6; mm, radians) the poses forward kinematics starts from
    (position measurements), kept at the last solution; ``factor`` (n, k, k) each pose's
    residuals' covariance factor L_i (kingen.calibrate.noise.factors; None: the residuals as they
    are), whose inverse, ``whitener``, whitens them."""

    def __init__(self, parameters, measurements, start, factor=None):
        self.parameters, self.measurements, self.start = parameters, measurements, start
        self.factor = factor
        self.whitener = None if factor is None else np.linalg.inv(factor)

    def raw(self, values, measurements, keep=False):
        """(n, k) each pose's residuals (see the module docstring) in mm-equivalents, unwhitened."""
        if self.parameters.measure == "pose":
            return joint_residuals(self.parameters, values, measurements)
        predicted, poses, _ = predicted_measurements(self.parameters, values, measurements.joints, self.start)
        if keep:
            self.start = poses
        return predicted - measurements.measured

    def residuals(self, values, keep=True):
        """(m,) the residuals at ``values``, each pose's whitened."""
        raw = self.raw(values, self.measurements, keep)
        return raw.ravel() if self.whitener is None else noise.whiten(self.whitener, raw)

    def whitened(self, values, stated):
        """This Problem with each pose's residuals whitened by the covariance the Noise ``stated``
        gives them at ``values`` (kingen.calibrate.noise.covariances)."""
        def residual_of(measured, joints):
            return self.raw(values, replace(self.measurements, measured=measured, joints=joints))

        data = self.measurements
        covariance = noise.covariances(residual_of, data.measured, data.joints, self.parameters.robot.revolute, stated)
        return Problem(self.parameters, data, self.start, noise.factors(covariance))

    def without(self, row):
        """This Problem without measurement ``row`` (0-based)."""
        keep = np.arange(len(self.measurements.joints)) != row
        data = self.measurements
        data = replace(data, joints=data.joints[keep], measured=data.measured[keep],
                       lines=tuple(np.asarray(data.lines)[keep].tolist()))
        return Problem(self.parameters, data, self.start[keep], None if self.factor is None else self.factor[keep])

    def jacobian(self, values, columns):
        """d(residuals)/dx (m, len(columns)) by central differences."""
        steps = self.parameters.step
        out = []
        for column in columns:
            shift = np.zeros(len(values))
            shift[column] = STEP * steps[column]
            out.append((self.residuals(values + shift, False) - self.residuals(values - shift, False)) / (2 * STEP))
        return np.column_stack(out) if out else np.zeros((len(self.residuals(values, False)), 0))

    def unwhitened(self, jacobian):
        """A whitened Jacobian (m, r) of this Problem's residuals back in mm-equivalents."""
        if self.factor is None:
            return jacobian
        blocks = jacobian.reshape(len(self.factor), -1, jacobian.shape[1])
        return np.einsum("nij,njc->nic", self.factor, blocks).reshape(jacobian.shape)

    def predicted(self, values):
        """(predicted (n, 6 or 3), closed (n,)): what ``values`` predict the device measures
        (mm, degrees, the device's frame) from the read joints, forward kinematics started at
        the measured poses (position measurements: at the last solution)."""
        if self.parameters.measure == "pose":
            start = poses_of(t6_from_matrix(measured_platform(self.parameters, values, self.measurements)[1]))
        else:
            start = self.start
        predicted, _, closed = predicted_measurements(self.parameters, values, self.measurements.joints, start)
        return predicted, closed

    def errors(self, values):
        """(position error (n,) mm, orientation error (n,) degrees or None, closed (n,)): what
        ``values`` predict from the read joints against what was measured."""
        predicted, closed = self.predicted(values)
        position, angle = errors(predicted, self.measurements.measured)
        return position, angle, closed


@dataclass
class Fit:
    """An identification: ``values`` identified, ``before`` (frame and target fitted alone),
    ``selected`` and ``chosen`` (identifiable) masks, ``std`` (NaN where not identified or
    without redundancy), observability ``indices``, ``unidentifiable`` in words, ``converged``
    and ``message``, ``evaluations``, ``seconds``, the Problem it solved (without the outliers),
    the Noise ``stated``, the ``inference`` at the solution (kingen.calibrate.noise.Inference),
    the identified parameters' ``covariance`` (mm and degrees, in the order of the parameters),
    the ``outliers`` left out (each {line, position_mm, angle_deg, noise_ratio}) and ``refusal``:
    why the result is not a calibration (None: it is)."""

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
    stated: noise.Noise
    inference: noise.Inference
    covariance: np.ndarray
    outliers: list
    refusal: str = None


def region_poses(robot, count, seed):
    """``count`` seeded poses (mm, degrees) of the robot's verification region, the coordinates
    forward kinematics does not solve for (a translating platform's angles) held at home; a
    machine with task coordinates at its nominal poses for the drawn task coordinates (on its
    manifold, kingen.kinematics.hybrid.parasitic.on_manifold); a machine with a wrist: tool poses of
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
                           jac=lambda x: problem.jacobian(full(x), columns), method="lm", max_nfev=max_evaluations,
                           xtol=TOLERANCE, ftol=TOLERANCE)
    return full(result.x), result


def identify(parameters, measurements, selected, stated=None, max_evaluations=None):
    """The Fit of ``parameters`` to ``measurements`` over the ``selected`` (mask) parameters with
    the Noise ``stated`` (default: kingen.calibrate.noise.Noise()), each least-squares stage
    stopped after ``max_evaluations`` residual evaluations (default MAX_EVALUATIONS). A pose whose
    leave-one-out statistic marks it an outlier (kingen.calibrate.noise.outlier) is left out and
    the fit made again, the worst first, up to MAX_OUTLIER_SHARE of the poses."""
    began = time.perf_counter()
    stated = stated or noise.Noise()
    max_evaluations = max_evaluations or MAX_EVALUATIONS
    values, start = align(parameters, measurements)
    selected, words = _translating(parameters, selected)
    rank, needed = needed_poses(parameters, values, selected)
    if len(measurements.joints) < needed:
        raise KingenError(f"{measurements.path}:{measurements.lines[-1]}: poses: {len(measurements.joints)} "
                          f"measurements for {rank} identifiable parameters: at least {needed} poses are needed "
                          f"(kingen calibrate plan chooses them)")
    problem = Problem(parameters, measurements, start).whitened(values, stated)
    evaluations = 0
    frame_columns = np.flatnonzero(selected & np.isin(parameters.groups, ("frame", "target")))
    if len(frame_columns):
        values, result = least_squares_fit(problem, values, frame_columns, max_evaluations)
        evaluations += result.nfev
    before = values.copy()
    order, _, taken, chosen = identifiable_columns(problem, values, parameters, selected)
    per_pose = residuals_per_pose(parameters.robot, parameters.measure)
    whole, kept, left_out, refusal = problem, np.arange(len(measurements.joints)), [], None
    while True:
        values, result = least_squares_fit(problem, values, np.flatnonzero(chosen), max_evaluations)
        evaluations += result.nfev
        final = problem.jacobian(values, order)
        inference = noise.infer(final[:, taken], problem.residuals(values), per_pose)
        found = noise.outlier(inference, per_pose) if result.status > 0 else None
        if found is None:
            break
        if len(left_out) + 1 > MAX_OUTLIER_SHARE * len(measurements.joints):
            refusal = (f"more than {MAX_OUTLIER_SHARE:.0%} of the poses are outliers (the next: line "
                       f"{problem.measurements.lines[found[0]]}): the measurements do not fit one machine")
            break
        left_out.append((int(kept[found[0]]), found[1]))
        kept = np.delete(kept, found[0])
        problem = problem.without(found[0])
    std = np.full(len(parameters), np.nan)
    identified = np.array(order)[taken]
    sorting = np.argsort(identified)
    covariance = inference.covariance[np.ix_(sorting, sorting)] * np.outer(*[parameters.step[identified[sorting]]] * 2)
    if inference.redundancy >= per_pose:
        std[identified[sorting]] = np.sqrt(np.diag(covariance))
    full = np.zeros((final.shape[0], len(parameters)))
    full[:, order] = final
    words += identifiability.combinations(full, parameters.names, chosen, selected)
    if refusal is None and inference.variance_factor > VARIANCE_LIMIT:
        refusal = (f"the residuals are {math.sqrt(inference.variance_factor):.3g} times the stated noise: the model "
                   "does not explain the measurements (or state the noise: --noise-mm, --noise-deg, --noise-joint-mm, "
                   "--noise-joint-deg)")
    return Fit(values=values, before=before, selected=selected, chosen=chosen, std=std,
               indices=identifiability.indices(problem.unwhitened(final[:, taken])), unidentifiable=words,
               converged=bool(result.status > 0), message=result.message, evaluations=int(evaluations),
               seconds=time.perf_counter() - began, problem=problem, stated=stated, inference=inference,
               covariance=covariance,
               outliers=_outliers(whole, values, left_out, per_pose), refusal=refusal)


def _outliers(problem, values, left_out, per_pose):
    """[{line, position_mm, angle_deg, noise_ratio}] of the measurements ``left_out`` ((row of
    ``problem``, leave-one-out statistic) each): its line, its errors with the parameters
    ``values`` identified without it, and its leave-one-out residuals' RMS in stated standard
    deviations."""
    if not left_out:
        return []
    position, angle, _ = problem.errors(values)
    return [{"line": int(problem.measurements.lines[row]), "position_mm": float(position[row]),
             "angle_deg": None if angle is None else float(angle[row]),
             "noise_ratio": math.sqrt(max(statistic, 0.0) / per_pose)} for row, statistic in left_out]


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
