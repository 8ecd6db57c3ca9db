"""Calibration's noise model and what it gives: each pose's residual covariance, the whitening
that makes the least squares generalised ones, the parameters' covariance, the residuals' check
against the stated noise and the poses that fail it (outliers).

The model: the device measures each coordinate with independent normal noise, ``device_mm`` (x,
y, z) and ``device_deg`` (roll, pitch, yaw, or none for positions), and the controller reads
each joint with independent normal noise, ``joint_mm`` (prismatic) and ``joint_deg`` (revolute).
A pose's residuals r_i (k of them: its joints, constraints, or its point) all depend on that
pose's measurement and joints, so their covariance is

    C_i = G_i S_m G_i^T + Q_i S_q Q_i^T

with G_i = dr_i/d(measured) and Q_i = dr_i/d(joints read) (central differences at the
parameters the fit starts from) and S_m, S_q the diagonal variances: a pose's residuals are
correlated, different poses' are not. Each pose's residuals are whitened by L_i^-1 (C_i = L_i
L_i^T), so that the least squares are generalised least squares and the whitened residuals are
of unit variance when the stated noise is right. With the whitened Jacobian A (m equations, r
identified parameters) at the fit, the parameters' covariance is max(1, s^2) (A^T A)^-1, s^2
the variance factor chi^2 / (m - r) (the residuals' sum of squares over the redundancy: 1 when
the noise is as stated): the stated noise's covariance, scaled up when the residuals say the
noise is larger. A standard deviation is reported only with redundancy (m - r at least one
pose's k).
"""

import math
from dataclasses import dataclass

import numpy as np

from ..defaults import CALIBRATION_NOISE

STEP = 1e-4
"""Central differences' step for the residuals' derivatives by the measurement (mm, degrees) and
the joints read (mm, radians)."""
OUTLIER_ALPHA = 0.01
"""A pose is an outlier when its leave-one-out statistic would be exceeded by chance with this
probability among all poses (Bonferroni: each pose's tail probability below OUTLIER_ALPHA / n)."""


@dataclass(frozen=True)
class Noise:
    """The stated noise, one standard deviation per coordinate: the device's positions
    (``device_mm``, mm) and angles (``device_deg``, degrees), the joints read (``joint_mm``, mm
    for prismatic joints; ``joint_deg``, degrees for revolute ones)."""

    device_mm: float = CALIBRATION_NOISE["device_mm"]
    device_deg: float = CALIBRATION_NOISE["device_deg"]
    joint_mm: float = CALIBRATION_NOISE["joint_mm"]
    joint_deg: float = CALIBRATION_NOISE["joint_deg"]


def covariances(residual_of, measured, joints, revolute, noise):
    """(n, k, k): each pose's residual covariance C_i (module docstring) in the residuals' units
    squared. ``residual_of(measured, joints)`` gives the residuals (n, k) for measurements (n, 6
    or 3; mm, degrees) and joints read (n, joint_count; mm, radians); ``revolute`` (joint_count,)
    which joints are angles."""
    sources = [(measured, column, noise.device_mm if column < 3 else noise.device_deg)
               for column in range(measured.shape[1])]
    sources += [(joints, column, math.radians(noise.joint_deg) if revolute[column] else noise.joint_mm)
                for column in range(joints.shape[1])]
    total = 0.0
    for array, column, sigma in sources:
        shifted = []
        for sign in (1.0, -1.0):
            moved = array.copy()
            moved[:, column] += sign * STEP
            shifted.append(residual_of(moved, joints) if array is measured else residual_of(measured, moved))
        gradient = (shifted[0] - shifted[1]) / (2 * STEP) * sigma
        total = total + gradient[:, :, None] * gradient[:, None, :]
    return total


def factors(covariance):
    """(n, k, k): L_i of each pose's covariance C_i = L_i L_i^T (its inverse whitens the pose's
    residuals), a covariance with no noise at all in some direction given a floor of 1e-12 of its
    trace there."""
    k = covariance.shape[1]
    floor = 1e-12 * np.trace(covariance, axis1=1, axis2=2)[:, None, None] + np.finfo(float).tiny
    return np.linalg.cholesky(covariance + floor * np.eye(k))


def whiten(whitener, residuals):
    """Whitened residuals (n * k,) of residuals (n, k)."""
    return np.einsum("nij,nj->ni", whitener, residuals).ravel()


@dataclass
class Inference:
    """What the whitened Jacobian ``jacobian`` (m, r) and residuals (m,) at a fit give:
    ``redundancy`` m - r, ``variance_factor`` s^2 (NaN without redundancy), ``covariance`` (r, r)
    of the identified parameters in mm-equivalents (max(1, s^2) (A^T A)^-1), ``leave_out`` (n,) each
    pose's leave-one-out statistic (its whitened residuals e_i weighed by (I - H_ii)^-1, H the hat
    matrix: chi^2 with k degrees of freedom times s^2 when the pose fits the rest)."""

    redundancy: int
    variance_factor: float
    covariance: np.ndarray
    leave_out: np.ndarray


def infer(jacobian, residuals, per_pose):
    """The Inference of whitened ``jacobian`` (m, r) and ``residuals`` (m,), ``per_pose`` residuals
    a pose."""
    rows, columns = jacobian.shape
    redundancy = rows - columns
    inverse = np.linalg.pinv(jacobian.T @ jacobian)
    chi2 = float(residuals @ residuals)
    factor = chi2 / redundancy if redundancy > 0 else float("nan")
    blocks = jacobian.reshape(-1, per_pose, columns)
    hat = np.einsum("nic,cd,njd->nij", blocks, inverse, blocks)
    kept = np.eye(per_pose) - hat
    errors = residuals.reshape(-1, per_pose)
    solved = np.einsum("nij,nj->ni", np.linalg.pinv(kept, hermitian=True), errors)
    return Inference(redundancy=redundancy, variance_factor=factor, covariance=max(1.0, factor) * inverse,
                     leave_out=np.einsum("ni,ni->n", errors, solved))


def outlier(inference, per_pose):
    """(pose index, its statistic) of the worst pose when it is an outlier, else None: its
    leave-one-out statistic beyond the chi^2 (k degrees of freedom) quantile 1 - OUTLIER_ALPHA / n,
    scaled by the poses' median statistic over chi^2's median when that is above 1 (so that
    noise stated too small makes no pose an outlier: the variance factor says so)."""
    from scipy.stats import chi2

    statistic = inference.leave_out
    if inference.redundancy < 2 * per_pose or not len(statistic):
        return None
    scale = max(1.0, float(np.median(statistic)) / chi2.median(per_pose))
    worst = int(np.argmax(statistic))
    limit = scale * chi2.isf(OUTLIER_ALPHA / len(statistic), per_pose)
    return (worst, float(statistic[worst])) if statistic[worst] > limit else None
