"""check-path's actuator power: each actuator's load as the program moves the machine (the
payload and the limbs' parts under gravity and their d'Alembert forces, kingen.kinematics.loads)
times its joint's speed, in W, against the limb's ``max_power``.

The platform's (a wrist machine's tool's) motion at the regular samples comes from finite
differences along the path, as the joints' speeds do (kingen.paths.timing.joint_rates): the
origin's velocity and acceleration from its position, the angular velocity and acceleration from
the rotation matrix, [omega] = R' R^T and [alpha] = the skew part of R'' R^T (base frame)."""

import numpy as np

from ..kinematics.loads import Motion, loads_of, machine_solution
from .timing import joint_rates

W_PER_N_MM_PER_S = 1e-3
"""W per N mm/s: a prismatic actuator's power from its force (N) and speed (mm/s)."""


def power_limited(robot):
    """Whether the robot file gives some limb a ``max_power``."""
    return any(limb.max_power is not None for limb in robot.limbs)


def _vee(matrices):
    """(n, 3) the vectors of the skew parts of (n, 3, 3) matrices."""
    skew = 0.5 * (matrices - np.swapaxes(matrices, 1, 2))
    return np.stack([skew[:, 2, 1], skew[:, 0, 2], skew[:, 1, 0]], axis=1)


def platform_motion(t6, s, runs, rate, change):
    """The :class:`Motion` (velocity and acceleration (n, 6): mm/s, rad/s; mm/s^2, rad/s^2, base
    frame) of the frame at T6 (n, 4, 4) sampled at path coordinates ``s`` in runs ``runs`` with
    the path's speed ``rate`` and its change ``change`` (kingen.paths.timing.joint_rates' arguments)."""
    rotation = np.swapaxes(t6[:, :3, :3], 1, 2)
    values = np.concatenate([t6[:, 3, :3], rotation.reshape(-1, 9)], axis=1)
    first, second = joint_rates(values, s, runs, np.zeros(12, dtype=bool), rate, change)
    back = np.swapaxes(rotation, 1, 2)
    omega = _vee(first[:, 3:].reshape(-1, 3, 3) @ back)
    alpha = _vee(second[:, 3:].reshape(-1, 3, 3) @ back)
    return Motion(velocity=np.concatenate([first[:, :3], omega], axis=1),
                  acceleration=np.concatenate([second[:, :3], alpha], axis=1))


def actuator_power(robot, t6, motion, speeds):
    """((n, m), (n, m)) W: each limb's actuator power at T6 (n, 4, 4) (``robot`` held at one
    posture) moving with ``motion`` at joint ``speeds`` (n, joints; mm/s or rad/s), and the part
    of it its load at rest gives (NaN where a sample is not timed or not reachable)."""
    count = len(robot.limbs)
    scale = np.where(robot.revolute[:count], 1.0, W_PER_N_MM_PER_S) * speeds[:, :count]
    t6, solution = machine_solution(robot, t6)  # solved once, for both
    with np.errstate(invalid="ignore"):
        moving = loads_of(robot, t6, solution, motion=motion).forces[:, 0, :count] * scale
        resting = loads_of(robot, t6, solution).forces[:, 0, :count] * scale
    return moving, resting


def fitting_feed(power, resting, limit):
    """The largest feed override k (0 < k < 1) up to which |k P_r + k^3 (P - P_r)| stays within
    ``limit`` W: at feed k the speeds scale by k and the accelerations (the load's part beyond
    ``resting``'s, P - P_r) by k^2. None where ``power`` is not beyond the limit."""
    if not abs(power) > limit:
        return None
    roots = np.concatenate([np.roots([power - resting, 0.0, resting, -sign * limit]) for sign in (1.0, -1.0)])
    real = roots[np.abs(roots.imag) <= 1e-9 * np.maximum(1.0, np.abs(roots))].real
    return float(np.min(real[real > 0.0]))
