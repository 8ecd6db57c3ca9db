"""Choosing the poses to measure: greedy D-optimal design among seeded candidates.

Candidates are seeded poses of the robot's verification region (the coordinates forward
kinematics does not solve for held at home; a machine with task coordinates on its nominal
manifold; a machine with a wrist: tool poses, the parallel part's forward judged at the
platform's pose the reference gives, the wrist's singularity by the same margin) that kingen's reference judges good in the
working posture (reachable, within travel, away from singularities by the robot's
``direct_index_min``, and by MARGIN of the limbs' and forward kinematics' conditioning) and, where the robot file gives ``collision`` radii, whose links keep
clear of each other. Each candidate's rows of the identification Jacobian (at the nominal
parameters) are whitened by the covariance the stated noise gives its residuals
(kingen.calibrate.noise), as identification whitens them;
poses are then added one at a time: first each the one that most increases log det of the
information matrix J^T W J over the identifiable parameters (D-optimal, until it is regular
and a few poses beyond), then each the one that most decreases the sum of the logarithms of
the limb parameters' variances (their geometric mean: each deviation counts by its ratio, so
the typical one falls, by which a plan is judged). The predicted standard deviations are sqrt(diag((J^T W J)^-1)). A plan's rows hold the pose the
machine takes (with a two-axis wrist, its own turn about the tool axis), not the pose drawn.
"""

from dataclasses import dataclass

import numpy as np

from ..conventions import pose_from_t6, t6_from_pose
from ..errors import KingenError
from ..kinematics.collision import clearances
from ..kinematics.forward import closure, free_mask, scaled_closure_derivative
from ..kinematics.reference import solve
from ..kinematics.routine import WARNINGS
from . import identifiability
from .identification import identifiable_columns, region_poses, synthetic_problem

CANDIDATES = 5000
MARGIN = 0.01
"""Away from singularities: a candidate's least normalised radicand D (rails, cranks) and the
ratio of the smallest to the largest singular value of its closure Jacobian over the free
pose coordinates (angles per robot size) must be at least this; D-optimal designs otherwise
crowd where the joints or the pose are ill-conditioned, and the fit with them."""


@dataclass
class Candidates:
    """The candidate poses drawn (n, 6; mm, degrees), their nominal joints (n, joint_count; mm,
    radians), what the device measures there with the measuring frame and target at nominal
    (``measured``, n, 6 or 3: the pose the machine takes, mm, degrees), the whitened Jacobian
    blocks (n, rows per pose, identifiable parameters), the unwhitened ones, and which
    parameters are identifiable (``chosen``, a mask over all)."""

    poses: np.ndarray
    joints: np.ndarray
    measured: np.ndarray
    weighted: np.ndarray
    blocks: np.ndarray
    chosen: np.ndarray


def candidates(parameters, selected, stated, count=CANDIDATES, seed=1):
    """The Candidates for Parameters ``parameters`` at their nominal values, ``selected``
    (mask) the parameters to identify, the Noise ``stated`` (kingen.calibrate.noise)."""
    robot = parameters.robot
    posture = robot.working_posture
    poses = region_poses(robot, count, seed)
    solution = solve(robot, t6_from_pose(poses))
    good = solution.warnings[:, posture] == WARNINGS["WARN_GOOD_SOLUTION"]
    legs = solution.joints[:, :robot.dof, posture]
    if robot.collision is not None:
        rods, cranks = clearances(robot.parallel, solution.points, legs)
        good &= ~(rods < 0.0) & ~(cranks < 0.0)
    good &= solution.min_inverse_index >= MARGIN
    platform = poses if robot.wrist is None else pose_from_t6(solution.platform)  # poses are then the tool's
    good[good] = _regular(robot.parallel, platform[good], legs[good])
    poses = poses[good]
    if not len(poses):
        raise KingenError(f"{robot.path}: verification: no pose of the verification region is reachable, within "
                          "travel and away from singularities and collisions")
    values = parameters.nominal
    problem, data = synthetic_problem(parameters, values, poses, posture)
    _, jacobian, taken, chosen = identifiable_columns(problem, values, parameters, selected)
    blocks = jacobian[:, taken].reshape(len(poses), -1, int(np.count_nonzero(taken)))
    whitener = problem.whitened(values, stated).whitener
    return Candidates(poses=poses, joints=data.joints, measured=data.measured,
                      weighted=np.einsum("nij,njc->nic", whitener, blocks), blocks=blocks, chosen=chosen)


def _regular(robot, poses, joints):
    """(n,) bool: whether forward kinematics is well-conditioned at poses (n, 6; mm, degrees)
    for joints (n, dof): the closure Jacobian's singular values' ratio at least MARGIN (for a
    machine with task coordinates, along its manifold: per unit rate of each task coordinate)."""
    radians = np.concatenate([poses[:, :3], np.radians(poses[:, 3:])], axis=1)
    _, wrenches = closure(robot, radians, joints)
    free = free_mask(robot)
    values = np.linalg.svd(scaled_closure_derivative(robot, wrenches, radians, free), compute_uv=False)
    return values[:, -1] >= MARGIN * values[:, 0]


D_OPTIMAL_EXTRA = 3
"""Poses chosen by D-optimality beyond the fewest that make the information matrix regular."""


def greedy(weighted, count, limbs=None):
    """Indices of ``count`` candidates chosen one at a time from the weighted blocks (n, rows,
    parameters): first, each the one that most increases log det of the information matrix
    (D-optimal) until D_OPTIMAL_EXTRA more poses than its rank needs are chosen; then each the
    one that most decreases the sum of the logarithms of the variances of the parameters
    ``limbs`` (a mask over the columns; None: all): the typical deviation the plan is judged by."""
    count = min(count, len(weighted))
    rows, parameters = weighted.shape[1], weighted.shape[2]
    limbs = np.ones(parameters, dtype=bool) if limbs is None else limbs
    scale = float(np.mean(np.einsum("nij,nij->j", weighted, weighted))) / len(weighted)
    information = 1e-9 * scale * np.eye(parameters)
    chosen = []
    available = np.ones(len(weighted), dtype=bool)
    d_optimal = min(count, -(-parameters // rows) + D_OPTIMAL_EXTRA)
    while len(chosen) < count:
        inverse = np.linalg.inv(information)
        projected = weighted @ inverse
        growth = np.eye(rows) + projected @ np.swapaxes(weighted, 1, 2)
        if len(chosen) < d_optimal:
            gain = np.linalg.slogdet(growth)[1]
        else:
            variance = np.diag(inverse)[limbs]
            reduction = np.einsum("nij,nij->nj", np.linalg.solve(growth, projected)[:, :, limbs], projected[:, :, limbs])
            gain = -np.sum(np.log(np.maximum(variance - reduction, 1e-300 * variance)), axis=1)
        gain[~available] = -np.inf
        best = int(np.argmax(gain))
        chosen.append(best)
        available[best] = False
        information += weighted[best].T @ weighted[best]
    return np.array(chosen)


def limb_columns(candidates_, parameters):
    """(identifiable parameters,) bool: which of the candidates' columns are the machine's own
    parameters (the limbs' and the constraints'; not the measuring frame or the target)."""
    return ~np.isin(parameters.groups, ("frame", "target"))[candidates_.chosen]


def predicted(candidates_, rows, parameters):
    """(predicted standard deviations (len(parameters),) in mm and degrees, NaN where not
    identified; the observability indices) of measuring the candidates ``rows``."""
    weighted = candidates_.weighted[rows].reshape(-1, candidates_.weighted.shape[2])
    std = np.full(len(parameters), np.nan)
    columns = np.flatnonzero(candidates_.chosen)
    std[columns] = identifiability.predicted_deviations(weighted, np.ones(len(weighted))) * parameters.step[columns]
    return std, identifiability.indices(candidates_.blocks[rows].reshape(-1, candidates_.blocks.shape[2]))
