"""Actuator loads, passive-joint angles and the platform's deflection at poses, in numpy
(docs/explanation/loads.md derives them).

Frames and units. Poses are T6 (n, 4, 4), base frame, mm. A twist t = [v; omega] is the
velocity v of the platform point at the base origin (mm/s) and the angular velocity omega
(rad/s), base frame; a wrench W = [F; M] is a force F (N) and its moment M about the base
origin (N mm), base frame: W . t is a power (N mm/s). Limb i's row J_i = w_i / t_i (its unit
force line over its transmission, kingen.kinematics.singularity) gives its joint rate per twist.

The platform moves in d free directions, the columns of T (6, d): a basis of the twists along
a constrained machine's manifold (any basis gives the same loads; _task_tangents), otherwise the
twists per unit rate of the robot's ``forward.free`` coordinates with the others held (all six
for a six-limb machine). Virtual work over those motions gives the actuators' generalized forces
tau (N for a prismatic joint; N mm per rad for a revolute one, reported in N m) that hold the
platform against the wrench W applied to it (gravity on the payload, an external wrench, minus
the payload's rate of change of momentum, d'Alembert):

    (J T)^T tau = -T^T W.

Positive tau is the force or torque the actuator exerts in the direction that increases its
joint. The constraints (passive joints, a machine's held coordinates) carry the rest,
-(W + J^T tau). With each actuator's stiffness k_i, the platform's deflection under W is
T ds with ds = ((J T)^T K (J T))^-1 T^T W (the passive joints rigid). The limbs' parts add
their weight and d'Alembert forces to W (kingen.kinematics.limb_parts).
"""

import itertools
from dataclasses import dataclass

import numpy as np

from ..conventions import t6_from_pose
from .forward import free_mask, pose_jacobian, poses_of
from .hybrid.parasitic import constraint_rows, solve_parasitic, task_twists
from .limb_parts import MM_PER_M, with_parts
from .reference import solve
from .routine import WARNINGS
from .singularity import branch_table, branch_values, limb_wrenches


@dataclass(frozen=True)
class Motion:
    """The platform frame origin's motion, base frame: ``velocity`` (6,) [mm/s, rad/s] and
    ``acceleration`` (6,) [mm/s^2, rad/s^2]."""

    velocity: np.ndarray
    acceleration: np.ndarray


@dataclass(frozen=True)
class Loads:
    """Loads over n poses and every posture (p postures, m limbs).

    ``machine`` (n, 4, 4): the T6 the machine takes (a constrained machine's, on its manifold).
    ``forces`` (n, p, m): each actuator's generalized force, N (prismatic) or N m (revolute);
    NaN where the posture is singular for loads (J T not invertible) or the pose unreachable.
    ``constraint`` (n, p, 6): the wrench the constraints carry, N and N m about the platform origin, base frame.
    ``base_angles``, ``platform_angles`` (n, p, m): each passive joint's angle from its neutral axis, rad.
    ``deflection`` (n, p, 6): the platform origin's displacement (mm) and rotation vector (rad) under
    the static wrench (gravity and the external wrench), or None where a limb has no stiffness.
    ``warnings`` (n, p): the reference's WARN_* codes at the machine's pose.
    """

    machine: np.ndarray
    forces: np.ndarray
    constraint: np.ndarray
    base_angles: np.ndarray
    platform_angles: np.ndarray
    deflection: object
    warnings: np.ndarray


def all_free(robot):
    """Whether the platform moves in all six pose coordinates (then T is a change of basis)."""
    return not robot.task and bool(free_mask(robot).all())


def free_twists(robot, t6):
    """(n, 6, d) a basis of the platform's free twists at T6 (n, 4, 4) the machine takes: a task
    machine's along its manifold (_task_tangents), else the twists per unit rate of its ``forward.free``
    coordinates (all six when none are declared) with the other pose coordinates held
    (kingen.kinematics.forward.pose_jacobian), in pose order."""
    if robot.task:
        return _task_tangents(robot, t6)
    if _translating(robot):
        return np.broadcast_to(np.eye(6)[:, free_mask(robot)], (len(t6), 6, int(free_mask(robot).sum())))
    return pose_jacobian(poses_of(t6))[:, :, free_mask(robot)]


def _translating(robot):
    """Whether the platform's free coordinates are translations only (no task coordinates):
    each column of T is then a constant unit twist [e_k; 0]."""
    return not robot.task and not free_mask(robot)[3:].any()


def payload_wrench(robot, t6, motion=None):
    """(n, 6) the wrench [N; N mm about the base origin] the payload applies to the platform at
    T6 (n, 4, 4): its weight, minus its rate of change of momentum when ``motion`` is given.
    Zero without a payload."""
    t6 = np.asarray(t6, dtype=float)
    wrench = np.zeros((len(t6), 6))
    payload = robot.payload
    if payload is None:
        return wrench
    rotation, origin = np.swapaxes(t6[:, :3, :3], 1, 2), t6[:, 3, :3]
    arm = rotation @ np.asarray(payload.centre, dtype=float)  # origin to centre, mm
    force = payload.mass * np.broadcast_to(np.asarray(robot.gravity, dtype=float), arm.shape)
    moment = np.zeros_like(arm)
    if motion is not None:
        velocity = np.broadcast_to(np.asarray(motion.velocity, dtype=float), (len(t6), 6))
        acceleration = np.broadcast_to(np.asarray(motion.acceleration, dtype=float), (len(t6), 6))
        omega, alpha = velocity[:, 3:], acceleration[:, 3:]
        centre_acceleration = acceleration[:, :3] + np.cross(alpha, arm) + np.cross(omega, np.cross(omega, arm))
        force = force - payload.mass * centre_acceleration / MM_PER_M
        inertia = rotation @ payload.inertia_matrix @ np.swapaxes(rotation, 1, 2)  # kg m^2, base axes
        spin = np.einsum("nij,nj->ni", inertia, omega)
        moment = -(np.einsum("nij,nj->ni", inertia, alpha) + np.cross(omega, spin)) * MM_PER_M
    wrench[:, :3] = force
    wrench[:, 3:] = np.cross(origin + arm, force) + moment
    return wrench


def external_wrench(t6, wrench):
    """(n, 6) [N; N mm about the base origin] of a wrench ``wrench`` (6,) [N; N m] applied at the
    platform origin of T6 (n, 4, 4), base frame."""
    t6 = np.asarray(t6, dtype=float)
    wrench = np.asarray(wrench, dtype=float)
    force = np.broadcast_to(wrench[:3], (len(t6), 3))
    return np.concatenate([force, np.cross(t6[:, 3, :3], force) + wrench[3:] * MM_PER_M], axis=1)


def applied_wrenches(robot, t6, wrench=None, motion=None):
    """((n, 6), (n, 6)) [N; N mm about the base origin]: the wrench applied at T6 (n, 4, 4) at rest
    (the payload's weight and the external ``wrench``, (6,) [N, N m] at the frame's origin) and
    with ``motion`` (the payload's momentum's rate too; the same as at rest without a motion)."""
    external = external_wrench(t6, wrench) if wrench is not None else 0.0
    static = payload_wrench(robot, t6) + external
    return static, (static if motion is None else payload_wrench(robot, t6, motion) + external)


def platform_loads(robot, machine, solution, chosen, static, applied, motion=None):
    """:class:`Loads` of ``robot`` (no wrist) at the T6 ``machine`` (n, 4, 4) it takes, from the
    reference's ``solution`` there, in postures ``chosen``, holding the wrenches ``static`` (at
    rest) and ``applied`` (n, 6) [N; N mm about the base origin] applied to the platform, and
    the limbs' parts under gravity and, with ``motion`` (the platform origin's), moving."""
    static, applied = with_parts(robot, machine, solution, chosen, static, applied, motion)  # (n, 1 or p, 6)
    lines, transmissions = _force_lines(robot, solution, chosen)
    with np.errstate(divide="ignore", invalid="ignore"):
        rows = lines / transmissions[..., None]
    twists = None if all_free(robot) else free_twists(robot, machine)
    if twists is None:  # six free coordinates: J^T tau = -W
        reduced, generalized = rows, -applied
    elif _translating(robot):  # T's columns are unit twists: J T and T^T W pick their components
        columns = np.flatnonzero(free_mask(robot))
        reduced, generalized = rows[..., columns], -applied[..., columns]
    else:
        reduced, generalized = rows @ twists[:, None], -np.einsum("nkd,npk->npd", twists, applied)
    forces = _solve_each(np.swapaxes(reduced, 2, 3), generalized)  # (n, p, m)
    carried = -applied
    for limb in range(robot.dof):  # minus J^T tau, limb by limb (a matmul of tiny stacks is slower)
        carried = carried - rows[..., limb, :] * forces[..., limb, None]
    constraint = about_origin(carried, machine)
    scale = np.where(np.array([t.wraps for t in robot.joint_types[:robot.dof]]), 1.0 / MM_PER_M, 1.0)
    warnings = solution.warnings[:, chosen]
    unreachable = warnings == WARNINGS["WARN_UNREACHABLE"]
    forces = np.where(unreachable[..., None], np.nan, forces * scale)
    base_angles, platform_angles = _angles(robot, lines[..., :3], machine)
    return Loads(machine=machine, forces=forces, constraint=np.where(unreachable[..., None], np.nan, constraint),
                 base_angles=base_angles, platform_angles=platform_angles,
                 deflection=_deflection(robot, machine, reduced, twists, static), warnings=warnings)


def _force_lines(robot, solution, chosen):
    """((n, p, m, 6), (n, p, m)): each limb's unit force line [f; C x f] and its transmission in
    each posture of ``chosen`` (p,), from the reference's ``solution``; one posture: from its own
    joints, one line per limb; else from both branches' lines (kingen.kinematics.singularity)."""
    if len(chosen) == 1:
        count = len(solution.points)
        lines, transmissions = np.empty((count, 1, robot.dof, 6)), np.empty((count, 1, robot.dof))
        for index, limb in enumerate(robot.limbs[:robot.dof]):
            point, joint = solution.points[:, index], solution.joints[:, index, chosen[0]]
            direction = limb.force_direction(point, joint)
            lines[:, 0, index, :3] = direction
            for axis in range(3):  # C x f, into place
                first, second = (axis + 1) % 3, (axis + 2) % 3
                np.subtract(point[:, first] * direction[:, second], point[:, second] * direction[:, first],
                            out=lines[:, 0, index, 3 + axis])
            transmissions[:, 0, index] = limb.transmission(direction, joint)
        return lines, transmissions
    wrenches, transmissions = limb_wrenches(robot, solution.points, branch_values(robot, solution.joints))
    table = branch_table(robot)[chosen, :robot.dof]  # (p, m): each chosen posture's branch of each limb
    limbs = np.arange(robot.dof)
    return wrenches[:, limbs, table], transmissions[:, limbs, table]


HADAMARD_FLOOR = 1e-13
"""A matrix counts as singular (loads undefined, NaN) where |det| is at most this fraction of
the product of its rows' norms (Hadamard's bound)."""


def _solve_each(matrices, right):
    """Solutions x of matrices (..., d, d) x = right (..., d), NaN where a matrix is not finite
    or singular (HADAMARD_FLOOR)."""
    if matrices.shape[-2:] == (3, 3):
        return _solve_each_3(matrices, right)
    matrices, right = np.broadcast_arrays(matrices, right[..., None])
    out = np.full(right.shape[:-1], np.nan)
    if matrices.shape[-2] != matrices.shape[-1]:
        return out
    finite = np.all(np.isfinite(matrices), axis=(-2, -1))
    bound = np.prod(np.linalg.norm(np.where(finite[..., None, None], matrices, 0.0), axis=-1), axis=-1)
    good = finite & (np.abs(np.linalg.det(np.where(finite[..., None, None], matrices, 0.0))) > HADAMARD_FLOOR * bound)
    out[good] = np.linalg.solve(matrices[good], right[good])[..., 0]
    return out


def _cofactors(matrices):
    """(cofactors, det, bound) of 3 x 3 matrices (..., 3, 3), written out over the stacks:
    cofactors[i][j] (...), det (...) and Hadamard's bound, the product of the rows' norms."""
    m = [[matrices[..., row, column] for column in range(3)] for row in range(3)]
    cofactor = [[m[(i + 1) % 3][(j + 1) % 3] * m[(i + 2) % 3][(j + 2) % 3]
                 - m[(i + 1) % 3][(j + 2) % 3] * m[(i + 2) % 3][(j + 1) % 3] for j in range(3)] for i in range(3)]
    determinant = m[0][0] * cofactor[0][0] + m[0][1] * cofactor[0][1] + m[0][2] * cofactor[0][2]
    bound = np.ones_like(determinant)
    for row in m:
        bound = bound * np.sqrt(row[0] * row[0] + row[1] * row[1] + row[2] * row[2])
    return cofactor, determinant, bound


def _solve_each_3(matrices, right):
    """_solve_each for 3 x 3 matrices, in closed form (x = adj(M) right / det M); NaN where a
    matrix is not finite or singular (HADAMARD_FLOOR)."""
    cofactor, determinant, bound = _cofactors(matrices)
    r = [right[..., row] for row in range(3)]
    with np.errstate(invalid="ignore", divide="ignore"):
        inverse = np.where(np.abs(determinant) > HADAMARD_FLOOR * bound, 1.0 / determinant, np.nan)  # NaN: not finite
        return np.stack([(cofactor[0][i] * r[0] + cofactor[1][i] * r[1] + cofactor[2][i] * r[2]) * inverse
                         for i in range(3)], axis=-1)


WELL_CONDITIONED = 1e-6
"""How well conditioned (|det| over the whole rows' Hadamard bound) a task machine's constraint
block must be to give its tangents in closed form; elsewhere
kingen.kinematics.hybrid.parasitic.task_twists solves for them."""


def _task_tangents(robot, t6):
    """(n, 6, 3) a basis of the twists along a task machine's manifold at T6 (n, 4, 4) on it: with
    its constraints' rows G (kingen.kinematics.hybrid.parasitic.constraint_rows) split into three twist
    components A and the other three B, G t = 0 gives t_A = -G_A^-1 G_B t_B (t_B free); A is the
    split best conditioned on average over the first poses (SAMPLED), and task_twists answers where G_A is poorly
    conditioned (WELL_CONDITIONED; loads do not depend on the basis)."""
    rows = constraint_rows(robot, t6)
    squared = np.einsum("nij,nij->ni", rows, rows)
    norms = np.sqrt(squared[:, 0] * squared[:, 1] * squared[:, 2])  # Hadamard's bound of any split, from the whole rows
    sample = rows[:SAMPLED]
    splits = [np.array(columns) for columns in itertools.combinations(range(6), 3)]
    chosen = max(splits, key=lambda columns: np.mean(_quality(_cofactors(sample[:, :, columns])[1], norms[:SAMPLED])))
    others = np.setdiff1d(np.arange(6), chosen)
    cofactor, determinant, _ = _cofactors(rows[:, :, chosen])
    basis = np.zeros((len(t6), 6, 3))
    with np.errstate(invalid="ignore", divide="ignore"):
        inverse = 1.0 / determinant
        for i, k in itertools.product(range(3), range(3)):  # -(G_A^-1 G_B)[i, k], G_A^-1[i, j] = cofactor[j][i] / det
            basis[:, chosen[i], k] = -sum(cofactor[j][i] * rows[:, j, others[k]] for j in range(3)) * inverse
    basis[:, others, np.arange(3)] = 1.0
    poor = _quality(determinant, norms) < WELL_CONDITIONED
    if np.any(poor):
        basis[poor] = task_twists(robot, t6[poor])
    return basis


SAMPLED = 16
"""The poses whose constraint rows choose _task_tangents' split."""


def _quality(determinant, norms):
    """|det G_A| over the whole rows' Hadamard bound ``norms`` (0 to 1; 0 where not finite): a
    row whose part in the split A is tiny beside its whole makes the split poor, however that
    part is shaped."""
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.nan_to_num(np.abs(determinant) / norms)


def about_origin(wrench, t6):
    """Wrenches (n, p, 6) [N; N mm about the base origin] as [N; N m about the platform origin]."""
    force = wrench[..., :3]
    moment = wrench[..., 3:] - np.cross(t6[:, None, 3, :3], force)
    return np.concatenate([force, moment / MM_PER_M], axis=-1)


def _stiffness(robot):
    """(m,) each actuator's stiffness in N/mm or N mm/rad, or None where a limb has none."""
    values = [limb.stiffness for limb in robot.limbs]
    if any(value is None for value in values):
        return None
    return np.array([value * (MM_PER_M if limb.joint_type.wraps else 1.0)
                     for value, limb in zip(values, robot.limbs)])


def _deflection(robot, t6, reduced, twists, static):
    """(n, p, 6) the platform origin's displacement (mm) and rotation vector (rad) under the
    static wrench (n, 1 or p, 6) (module docstring), or None without every limb's stiffness; ``twists`` None:
    the six coordinates free (T the identity's change of basis, left out)."""
    stiffness = _stiffness(robot)
    if stiffness is None or reduced.shape[-1] != reduced.shape[-2]:
        return None
    matrix = np.swapaxes(reduced, 2, 3) @ (stiffness[:, None] * reduced)
    if twists is None:
        twist = _solve_each(matrix, static)  # (n, p, 6)
    else:
        moves = _solve_each(matrix, np.einsum("nkd,npk->npd", twists, static))  # (n, p, d)
        twist = np.einsum("nkd,npd->npk", twists, moves)
    displacement = twist[..., :3] + np.cross(twist[..., 3:], t6[:, None, 3, :3])
    return np.concatenate([displacement, twist[..., 3:]], axis=-1)


def neutral_axes(robot):
    """((m, 3), (m, 3)): each limb's base joint axis (base frame) and platform joint axis
    (platform frame): the file's ``base_axis``/``platform_axis``, else the link's direction at
    the verification home in the working posture."""
    at_home = machine_t6(robot, np.asarray(robot.verification.home, dtype=float)[None])
    solution = solve(robot, at_home)
    wrenches, _ = limb_wrenches(robot, solution.points, branch_values(robot, solution.joints), with_transmissions=False)
    table = branch_table(robot)[[robot.working_posture], :robot.dof]
    base = wrenches[:, np.arange(robot.dof), table][..., :3]  # (1, 1, m, 3) unit, base side to platform point
    platform = (at_home[:, None, None, :3, :3] @ base[..., None])[..., 0]  # R^T f, R = t6[:3, :3]^T
    bases = np.array([limb.base_axis if limb.base_axis is not None else base[0, 0, index]
                      for index, limb in enumerate(robot.limbs)], dtype=float)
    platforms = np.array([limb.platform_axis if limb.platform_axis is not None else platform[0, 0, index]
                          for index, limb in enumerate(robot.limbs)], dtype=float)
    return bases, platforms


def machine_t6(robot, poses):
    """T6 (n, 4, 4) the machine takes for poses (n, 6) (mm, degrees)."""
    t6 = t6_from_pose(poses)
    return solve_parasitic(robot, t6).t6 if robot.task else t6


def _angles(robot, directions, t6):
    """((n, p, m), (n, p, m)) rad: each limb's base and platform passive joint's angle between its
    link's direction (n, p, m, 3) (unit, base frame) at T6 (n, 4, 4) and its neutral axis
    (neutral_axes; the platform's turned into the base frame, R a, rather than every link into the
    platform's), the products written out over the components (faster than reductions here)."""
    base_axes, platform_axes = neutral_axes(robot)
    t6 = np.asarray(t6, dtype=float)
    turned = [sum(t6[:, None, None, j, i] * platform_axes[:, j] for j in range(3)) for i in range(3)]  # R a
    angles = []
    for axes in ([base_axes[:, i] for i in range(3)], turned):
        cosine = directions[..., 0] * axes[0] + directions[..., 1] * axes[1] + directions[..., 2] * axes[2]
        angles.append(np.arccos(np.clip(cosine, -1.0, 1.0, out=cosine), out=cosine))
    return tuple(angles)
