"""Parasitic motion of a constrained machine, solved in closed form (docs/how-to/hybrid.md).

The platform points C_i of the three constraining limbs stay in their planes a_i.C_i = d_i
(kingen.robot.constraints). Given the task coordinates z, roll and pitch of a T6 (mm), write
R = Rz(yaw) Q with Q = Ry(pitch) Rx(roll) = Rz(-yaw_T6) R_T6 and v_i = Q n_i; then plane i is
linear in x, y, cos(yaw) = c and sin(yaw) = s:

    a_ix x + a_iy y + A_i c + B_i s = r_i,  A_i = a_ix v_ix + a_iy v_iy,  B_i = a_iy v_ix - a_ix v_iy,
    r_i = d_i - a_iz (v_iz + z).

With w the left null vector of the planes' (x, y) columns, alpha c + beta s = gamma
(alpha = w.A, beta = w.B, gamma = w.r), so (c, s) = (gamma (alpha, beta) +/- sqrt(rho^2 - gamma^2)
(-beta, alpha)) / rho^2 (rho^2 = alpha^2 + beta^2), the sign whose yaw is nearer the
verification home's; then (x, y) = (N^T N)^-1 N^T (r - A c - B s). D = (rho^2 - gamma^2) / rho^2
is the normalised radicand: below zero no pose has these task coordinates (unreachable), near
zero the two yaw branches meet (a constraint singularity). The generated C does the same
operations in the same order (templates/routine_helpers.c.j2, ``parasitic``).

A T6 whose x or y differ from the solved ones by more than manifold_tolerance_mm (a fraction
MANIFOLD_TOLERANCE of the machine's size) or whose yaw (rotation, for the 'axes' and 'tube'
families) differs by more than MANIFOLD_TOLERANCE_RAD asks for a pose the machine cannot take: it
is *off the manifold*. Both tolerances hold a pose copied from a drawing: coordinates rounded to
4 decimals of a mm and angles to 3 decimals of a degree.
"""

from dataclasses import dataclass

import numpy as np

from ...conventions import angle_difference, pose_from_t6, t6_from_pose
from ...robot.constraints import TASK, constraint_table, family
from .parasitic_axes import axes_wrenches, solve_axes
from .parasitic_tube import solve_tube, tube_residuals, tube_wrenches

MANIFOLD_TOLERANCE = 1e-5
"""How far a T6's x and y may be from the machine's before the routine calls the pose off the
manifold, as a fraction of the machine's size (Robot.size_mm): 0.005 mm on a machine of 500 mm,
a hundred times the 5e-5 mm a coordinate rounded to 4 decimals may be off."""
MANIFOLD_TOLERANCE_RAD = 3e-5
"""How far a T6's yaw (rad; for the 'axes' and 'tube' families, any entry of its rotation) may be
from the machine's before the routine calls the pose off the manifold: 0.0017 degrees, above the
1.5e-5 rad three angles each rounded to 3 decimals of a degree may turn the rotation by."""
OFF_MANIFOLD_EVERY = 8
"""verify leaves one drawn pose in this many as drawn (off the manifold), to exercise the warning."""


@dataclass(frozen=True)
class Parasitic:
    """Over n T6: ``t6`` (n, 4, 4) each with its x, y and yaw replaced by the machine's (the task
    coordinates kept), ``radicand`` (n,) D, ``off`` (n,) bool: the T6 was off the manifold."""

    t6: np.ndarray
    radicand: np.ndarray
    off: np.ndarray


def manifold_tolerance_mm(robot):
    """How far (mm) a T6's x and y may be from ``robot``'s before its routine calls the pose off
    the manifold: MANIFOLD_TOLERANCE of its size."""
    return MANIFOLD_TOLERANCE * robot.size_mm


def home_yaw(robot):
    """(cos, sin) of the verification home's yaw: the yaw branch the machine is assembled in."""
    yaw = np.radians(robot.verification.home[5])
    return np.cos(yaw), np.sin(yaw)


def solve_parasitic(robot, t6):
    """The machine's pose for each T6 (n, 4, 4), mm: see the module docstring (an Exechon-type
    machine's: kingen.kinematics.hybrid.parasitic_axes, a Tricept-type one's: kingen.kinematics.hybrid.parasitic_tube,
    its T6's position kept). Non-finite T6 give
    non-finite results (the caller's finite test catches them)."""
    if family(robot) in ("axes", "tube"):
        return _solve_rotation(robot, t6, solve_axes if family(robot) == "axes" else solve_tube)
    table = constraint_table(robot)
    t6 = np.asarray(t6, dtype=float)
    rotation = np.swapaxes(t6[:, :3, :3], 1, 2)
    yaw = np.arctan2(t6[:, 0, 1], t6[:, 0, 0])
    c0, s0 = np.cos(yaw), np.sin(yaw)
    tilt = np.stack([c0[:, None] * rotation[:, 0] + s0[:, None] * rotation[:, 1],
                     c0[:, None] * rotation[:, 1] - s0[:, None] * rotation[:, 0], rotation[:, 2]], axis=1)
    v = np.einsum("nij,kj->nki", tilt, table.points)  # (n, 3 limbs, 3)
    ax, ay, az = table.axes[:, 0], table.axes[:, 1], table.axes[:, 2]
    a = ax * v[..., 0] + ay * v[..., 1]
    b = ay * v[..., 0] - ax * v[..., 1]
    r = table.offsets - az * (v[..., 2] + t6[:, 3, 2, None])
    alpha, beta, gamma = a @ table.null, b @ table.null, r @ table.null
    rho2 = alpha * alpha + beta * beta
    radicand = (rho2 - gamma * gamma) / rho2
    root = np.sqrt(np.where(radicand > 0.0, rho2 - gamma * gamma, 0.0))
    hc, hs = home_yaw(robot)
    candidates = [((gamma * alpha - sign * root * beta) / rho2, (gamma * beta + sign * root * alpha) / rho2)
                  for sign in (-1.0, 1.0)]
    nearer = candidates[1][0] * hc + candidates[1][1] * hs > candidates[0][0] * hc + candidates[0][1] * hs
    c = np.where(nearer, candidates[1][0], candidates[0][0])
    s = np.where(nearer, candidates[1][1], candidates[0][1])
    rest = r - a * c[:, None] - b * s[:, None]
    x, y = rest @ table.pseudo_inverse[0], rest @ table.pseudo_inverse[1]
    fixed = t6.copy()
    fixed[:, :3, 0] = c[:, None] * tilt[:, 0] - s[:, None] * tilt[:, 1]
    fixed[:, :3, 1] = s[:, None] * tilt[:, 0] + c[:, None] * tilt[:, 1]
    fixed[:, :3, 2] = tilt[:, 2]
    fixed[:, 3, 0], fixed[:, 3, 1] = x, y
    turn = np.arctan2(s * c0 - c * s0, c * c0 + s * s0)
    tolerance = manifold_tolerance_mm(robot)
    off = ~((np.abs(x - t6[:, 3, 0]) <= tolerance) & (np.abs(y - t6[:, 3, 1]) <= tolerance)
            & (np.abs(turn) <= MANIFOLD_TOLERANCE_RAD))
    return Parasitic(t6=fixed, radicand=radicand, off=off)


def _solve_rotation(robot, t6, solve):
    """solve_parasitic for the 'axes' and 'tube' families (``solve``: their rotation's closed
    form): the rotation replaced, off where any entry of it moved by more than MANIFOLD_TOLERANCE_RAD."""
    t6 = np.asarray(t6, dtype=float)
    rotation, radicand = solve(robot, t6)
    fixed = t6.copy()
    fixed[:, :3, :3] = np.swapaxes(rotation, 1, 2)
    off = ~(np.max(np.abs(fixed[:, :3, :3] - t6[:, :3, :3]), axis=(1, 2)) <= MANIFOLD_TOLERANCE_RAD)
    return Parasitic(t6=fixed, radicand=radicand, off=off)


def constraint_residuals(robot, t6):
    """(n, 3) mm: each constraint equation's residual at the machine's pose for each T6 (n, 4, 4)
    (solve_parasitic; pose_constraint_residuals there), and (n,) the radicand D (where D < 0 no
    pose closes them)."""
    machine = solve_parasitic(robot, t6)
    return pose_constraint_residuals(robot, machine.t6), machine.radicand


def pose_constraint_residuals(robot, t6):
    """(n, 3) mm: each constraint equation's residual with the platform at T6 (n, 4, 4) as given
    (not moved onto the manifold), computed forward from the constraints' own statement:
    a_i.(C_i - c_i) for revolute axes fixed in the base, (R e).(b - p) - e.n for axes fixed in
    the platform, the tube's (kingen.kinematics.hybrid.parasitic_tube.tube_residuals) for a passive leg."""
    t6 = np.asarray(t6, dtype=float)
    if family(robot) == "tube":
        return tube_residuals(robot, t6)
    rotation, position = np.swapaxes(t6[:, :3, :3], 1, 2), t6[:, 3, :3]
    residuals = []
    for limb in robot.limbs:
        if family(robot) == "axes":
            axis, base, point = limb.platform_constraint()
            residuals.append(np.sum((rotation @ axis) * (base - position), -1) - np.dot(axis, point))
        else:
            axis, point = limb.constraint_plane()
            platform = rotation @ np.asarray(limb.platform_point, dtype=float) + position
            residuals.append((platform - point) @ axis)
    return np.stack(residuals, axis=1)


def on_manifold(robot, poses):
    """Poses (n, 6) (mm, degrees) with x, y and yaw replaced by the machine's for their task
    coordinates (those without a solution keep their closest approach)."""
    with np.errstate(all="ignore"):
        return pose_from_t6(solve_parasitic(robot, t6_from_pose(poses)).t6)


def task_twists(robot, t6):
    """(n, 6, 3) the platform twist [v; omega] (v: the velocity of the point at the base origin,
    mm; omega rad) per unit rate of each task coordinate (robot.task), moving on the manifold,
    at T6 (n, 4, 4) on it: the solution t of G t = 0 (each plane's row [a_i, C_i x a_i], or each
    platform axis's, kingen.kinematics.hybrid.parasitic_axes) and S t = e_k (S: task_rows); NaN at a
    pose where that system is singular (the constraints and the task coordinates dependent
    there: the manifold has no tangent of the task's dimension)."""
    t6 = np.asarray(t6, dtype=float)
    rows = np.zeros((len(t6), 6, 6))
    rows[:, :3] = constraint_rows(robot, t6)
    rows[:, 3:] = task_rows(t6, robot.task)
    right = np.zeros((len(t6), 6, len(TASK)))
    right[:, 3:, :] = np.eye(len(TASK))
    try:
        return np.linalg.solve(rows, right)
    except np.linalg.LinAlgError:  # some pose's system is singular: those answer NaN, the others as above
        return np.array([_solved_or_nan(matrix, column) for matrix, column in zip(rows, right)])


def constraint_rows(robot, t6):
    """(n, 3, 6) the constraints' rows G at T6 (n, 4, 4) on the manifold: a twist t [v; omega]
    (v: the velocity of the point at the base origin) keeps them while G t = 0 (each plane's row
    [a_i, C_i x a_i], or each platform axis's, kingen.kinematics.hybrid.parasitic_axes)."""
    if family(robot) in ("axes", "tube"):
        return (axes_wrenches if family(robot) == "axes" else tube_wrenches)(robot, t6)
    table = constraint_table(robot)
    points = np.einsum("nji,kj->nki", t6[:, :3, :3], table.points) + t6[:, 3, None, :3]
    return np.concatenate([np.broadcast_to(table.axes, points.shape), np.cross(points, table.axes)], axis=-1)


def _solved_or_nan(matrix, right):
    """The solution x of ``matrix`` x = ``right``, or NaN of its shape when ``matrix`` is singular."""
    try:
        return np.linalg.solve(matrix, right)
    except np.linalg.LinAlgError:
        return np.full(right.shape, np.nan)


def task_rows(t6, task=TASK):
    """(n, 3, 6) the rates of the task coordinates per unit twist at T6 (n, 4, 4), in the
    order x, y, z, roll, pitch, yaw: x' = v_x + (omega x p)_x = v_x + omega.(p x e_x) (so
    for y, z); roll' and pitch' from omega = E (roll', pitch', yaw'), E's columns Rz Ry e_x,
    Rz e_y, e_z."""
    t6 = np.asarray(t6, dtype=float)
    count = len(t6)
    _, pitch, yaw = np.radians(pose_from_t6(t6)[:, 3:]).T
    cy, sy, cp, sp = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch)
    euler = np.zeros((count, 3, 3))
    euler[:, :, 0] = np.stack([cy * cp, sy * cp, -sp], -1)
    euler[:, :, 1] = np.stack([-sy, cy, np.zeros(count)], -1)
    euler[:, 2, 2] = 1.0
    rates = np.linalg.inv(euler)
    rows = np.zeros((count, 6, 6))
    for axis in range(3):
        rows[:, axis, axis] = 1.0
        rows[:, axis, 3:] = np.cross(t6[:, 3, :3], np.eye(3)[axis])
    rows[:, 3:, 3:] = rates
    names = ("x", "y", "z", "roll", "pitch", "yaw")
    return rows[:, [index for index, name in enumerate(names) if name in task]]


def off_manifold_words(robot, pose):
    """(how far, where) when ``pose`` (6,) mm and degrees is off ``robot``'s manifold, else None
    (also for a robot without task coordinates, and where no pose has its task coordinates):
    'by 0.054 mm in y (tolerance ...)', the parasitic coordinate farthest beyond its tolerance,
    and 'x y z roll pitch yaw = ...', the machine's pose for the task coordinates."""
    if not robot.task:
        return None
    with np.errstate(all="ignore"):
        machine = solve_parasitic(robot, t6_from_pose(np.asarray([pose], dtype=float)))
        if not machine.off[0] or not np.all(np.isfinite(machine.t6)):
            return None
        taken = pose_from_t6(machine.t6)[0]
        deviation = np.abs(np.asarray(pose, dtype=float) - taken)
        deviation[3:] = np.degrees(np.abs(angle_difference(np.radians(pose[3:]), np.radians(taken[3:]))))
    names = ("x", "y", "z", "roll", "pitch", "yaw")
    limits = [manifold_tolerance_mm(robot)] * 3 + [np.degrees(MANIFOLD_TOLERANCE_RAD)] * 3
    worst = max((index for index, name in enumerate(names) if name not in robot.task),
                key=lambda index: deviation[index] / limits[index])
    unit = "mm" if worst < 3 else "degrees"
    size = f", {MANIFOLD_TOLERANCE:g} of its {robot.size_mm:g} mm size" if worst < 3 else ""
    return (f"by {deviation[worst]:.3g} {unit} in {names[worst]} (tolerance {limits[worst]:.3g} {unit}{size})",
            f"x y z roll pitch yaw = {' '.join(f'{value:.9g}' for value in taken)} (mm, degrees)")
