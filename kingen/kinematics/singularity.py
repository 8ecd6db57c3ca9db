"""Force lines, the direct (platform) singularity index and the analytic Jacobian, in numpy.

Every limb transmits a pure force to the platform along its passive link, through its
platform point C (base frame): from the base point (leg), the carriage joint (rail) or the
crank tip (crank) to C. Its unit wrench is w = [f; C x f], f the unit direction, moments in
mm. The line depends on the posture through the limb's branch. docs/explanation/conventions.md
('Force lines and the direct index') states the definitions; the limb models give the
geometry (``base_side_point``, ``transmission``), so nothing here names a model.

- Direct index: with M = sum_i w_i w_i^T split into force (v) and moment (w) blocks, the
  square root of the smallest eigenvalue of the Schur complement M_ww - M_wv M_vv^-1 M_vw,
  in mm: the least power sum_i (w_i . t)^2 over twists t = [v; omega] with |omega| = 1.
  Frame-independent; 0 at a direct singularity, and 0 when M_vv is singular (a
  pure-translation singularity). Defined for robots with six force lines only.
- Jacobian: joint rates from a platform twist [v; omega] (v: the velocity of the platform
  point at the base origin, mm/s; omega: rad/s, base frame): row i is w_i^T / t_i with
  t_i the limb's transmission (f . dP/dq + dl/dq), derived from the closure, not from the
  inverse-kinematics formula.
"""

import functools

import numpy as np

from ..conventions import SIX, branch_of_posture

TRANSLATION_SINGULAR = 1e-12
"""M_vv (force block) counts as singular when its determinant is at most this fraction of
(trace / 3)^3, the determinant it would have with equal eigenvalues."""


def branch_table(robot):
    """(postures, joint_count) int array (read-only): the branch each joint takes in each
    posture: each limb's, then (a robot with a wrist) each wrist joint's, the posture's last bit
    (0 where a one-posture view holds the wrist on one branch: its joints are that branch's in
    both columns, kingen.kinematics.hybrid.wrist)."""
    held = robot.wrist is not None and robot.wrist.branch is not None
    return _branch_table(robot.branch_bits, robot.joint_count - robot.dof, held)


@functools.lru_cache(maxsize=64)
def _branch_table(branch_bits, wrist_joints=0, held=False):
    postures = np.arange(2 ** sum(1 for bit in branch_bits if bit >= 0))
    table = np.stack([branch_of_posture(postures, bit) if bit >= 0 else np.zeros_like(postures)
                      for bit in branch_bits], axis=1)
    if wrist_joints and held:
        table = np.concatenate([table, np.zeros((len(postures), wrist_joints), dtype=table.dtype)], axis=1)
    elif wrist_joints:  # posture = 2 * the parallel part's posture + the wrist's branch
        table = np.concatenate([np.repeat(table, 2, axis=0), np.tile([[0], [1]], (len(postures), wrist_joints))], axis=1)
    table.flags.writeable = False
    return table


EXACT_WINDOW = 1e-4
"""Around a threshold the closed-form eigenvalue is replaced by LAPACK's: far wider than the
closed form's error (at most about 1e-7 relative on the shipped robots)."""


def representative_postures(robot):
    """(joint_count, 2) int array (read-only): for each joint (branch_table), the first posture
    taking its branch 0 and its branch 1 (branch 0's again for one-branch limbs). A routine's
    value there stands for that branch."""
    held = robot.wrist is not None and robot.wrist.branch is not None
    return _representative_postures(robot.branch_bits, robot.joint_count - robot.dof, held)


@functools.lru_cache(maxsize=64)
def _representative_postures(branch_bits, wrist_joints=0, held=False):
    table = _branch_table(branch_bits, wrist_joints, held)
    bits = branch_bits + (-1 if held else 0,) * wrist_joints
    first = [[int(np.argmax(table[:, index] == branch)) for branch in range(2)] for index in range(len(bits))]
    representative = np.array([row if bit >= 0 else [row[0], row[0]] for row, bit in zip(first, bits)])
    representative.flags.writeable = False
    return representative


def branch_values(robot, per_posture):
    """(..., k, 2) each joint's value in its branch 0 and 1 from values per posture
    (..., k, postures), read at representative_postures: k the limbs (dof) or every joint
    (joint_count)."""
    count = per_posture.shape[-2]
    return np.take_along_axis(per_posture, np.broadcast_to(
        representative_postures(robot)[:count], per_posture.shape[:-1] + (2,)), axis=-1)


def posture_values(robot, per_branch):
    """(n, postures, k, ...) each posture's value of each joint, from values per branch
    (n, k, 2, ...) (k the limbs, dof, or every joint, joint_count): the inverse of
    branch_values, postures before joints."""
    count = per_branch.shape[1]
    return per_branch[:, np.arange(count), branch_table(robot)[:, :count]]


def limb_wrenches(robot, points, branch_joints, with_transmissions=True):
    """Unit wrenches (n, dof, 2, 6) and transmissions (n, dof, 2; None unless
    ``with_transmissions``) of each limb's two force lines (branch 0 and 1; the same twice
    for one-branch limbs), from platform points (n, dof, 3) and each limb's joint per branch
    (n, dof, 2; see branch_values). A limb has at most two lines: everything per posture
    is assembled from these. Both are views of memory with the poses last (dof, 2, 6, n), so
    that each component is one contiguous row over the poses."""
    count = points.shape[0]
    wrenches = np.empty((robot.dof, 2, 6, count))
    transmissions = np.empty((robot.dof, 2, count)) if with_transmissions else None
    for index, limb in enumerate(robot.limbs):
        point = points[:, index]
        for branch in range(limb.branches):
            joint = branch_joints[:, index, branch]
            direction = limb.force_direction(point, joint)
            wrench = wrenches[index, branch]
            wrench[:3] = direction.T
            for axis in range(3):  # C x f, written out: numpy.cross is several times slower on rows
                first, second = (axis + 1) % 3, (axis + 2) % 3
                np.subtract(point[:, first] * direction[:, second], point[:, second] * direction[:, first],
                            out=wrench[3 + axis])
            if with_transmissions:
                transmissions[index, branch] = limb.transmission(direction, joint)
        if limb.branches == 1:
            wrenches[index, 1] = wrenches[index, 0]
            if with_transmissions:
                transmissions[index, 1] = transmissions[index, 0]
    return np.moveaxis(wrenches, -1, 0), None if transmissions is None else np.moveaxis(transmissions, -1, 0)


def posture_wrenches(robot, points, joints):
    """Unit wrenches (n, postures, dof, 6) and transmissions (n, postures, dof) of every
    limb in every posture, from platform points (n, dof, 3) and joints (n, dof, postures)."""
    wrenches, transmissions = limb_wrenches(robot, points, branch_values(robot, joints))
    return posture_values(robot, wrenches), posture_values(robot, transmissions)


PACKED = [(i, j) for i in range(SIX) for j in range(i + 1)]
"""The entries of a symmetric 6 x 6 matrix in packed order (lower triangle, row by row)."""
_PACKED_INDEX = {pair: k for k, pair in enumerate(PACKED)}


def partial_sum_split(robot):
    """(low_bits, low limbs, high limbs): how a posture's M is split in two partial sums,
    one over the limbs whose posture digit is below low_bits (half the two-branch limbs),
    one over all others; posture k's M is high[k >> low_bits] + low[k & (2^low_bits - 1)].
    The generated C and posture_gram_entries both sum this way."""
    low_bits = sum(1 for bit in robot.branch_bits if bit >= 0) // 2
    low_limbs = [i for i, bit in enumerate(robot.branch_bits) if 0 <= bit < low_bits]
    return low_bits, low_limbs, [i for i in range(robot.dof) if i not in low_limbs]


def posture_gram_entries(robot, wrenches):
    """M of every posture as its 21 packed entries (21, n, postures), from the limbs' line
    wrenches (n, dof, 2, 6): each line's w w^T once, summed in the two partial sums of
    partial_sum_split, as the generated C does. The result is a view of memory with the
    poses last (21, postures, n)."""
    return gram_entries_of(gram_partial_sums(robot, wrenches))


def gram_partial_sums(robot, wrenches):
    """(high, low): the two partial sums of partial_sum_split as packed entries with the poses
    last, high (21, postures >> low_bits, n) and low (21, 2^low_bits, n) (None when no limb
    is split off), from the limbs' line wrenches (n, dof, 2, 6): each line's w w^T once.
    Per pose, not per posture: gram_entries_of adds them up for the postures."""
    count = wrenches.shape[0]
    lines = {}
    for index, limb in enumerate(robot.limbs):
        for branch in range(limb.branches):
            rates = np.ascontiguousarray(wrenches[:, index, branch].T)  # (6, n)
            product = np.empty((len(PACKED), count))
            for row in range(SIX):  # packed row ``row``: entries (row, 0) .. (row, row)
                start = row * (row + 1) // 2
                np.multiply(rates[row], rates[:row + 1], out=product[start:start + row + 1])
            lines[index, branch] = product
    table = branch_table(robot)
    low_bits, low_limbs, high_limbs = partial_sum_split(robot)

    def partial_sums(limbs, postures):
        """(21, len(postures), n): per posture, the sum over ``limbs`` of their branch's w w^T."""
        sums = np.empty((len(PACKED), len(postures), count))
        for column, posture in enumerate(postures):
            first, *others = limbs
            total = sums[:, column]
            np.copyto(total, lines[first, table[posture, first]])
            for limb in others:
                total += lines[limb, table[posture, limb]]
        return sums

    high = partial_sums(high_limbs, range(0, robot.postures, 1 << low_bits))
    return high, partial_sums(low_limbs, range(1 << low_bits)) if low_limbs else None


def gram_entries_of(partial_sums, poses=slice(None)):
    """M of every posture (21, m, postures) for the poses ``poses`` (a slice) of the partial
    sums from gram_partial_sums, posture k's high[k >> low_bits] + low[k & (2^low_bits - 1)]:
    a view of memory with the poses last (21, postures, m)."""
    high, low = partial_sums
    high = high[..., poses]
    if low is not None:
        high = (high[:, :, None, :] + low[:, None, :, poses]).reshape(len(PACKED), -1, high.shape[-1])
    return np.moveaxis(high, -1, 1)


def direct_index(gram, exact_near=None):
    """The direct index (mm) from M (..., 6, 6): see the module docstring and
    direct_index_of_entries."""
    gram = np.asarray(gram, dtype=float)
    return direct_index_of_entries(np.stack([gram[..., i, j] for i, j in PACKED]), exact_near)


def direct_index_of_entries(entries, exact_near=None):
    """The direct index (mm) from M given as its 21 packed entries (21, ...).

    Computed component by component (vectorised): the Schur complement from the force
    block's LDL^T, then its smallest eigenvalue in closed form (relative error about eps x
    its largest eigenvalue). Where that value lies within EXACT_WINDOW (relative) of
    ``exact_near`` (mm; everywhere when None) it is recomputed with numpy.linalg.eigvalsh,
    so every decision at a threshold rests on LAPACK."""
    entries, single = _packed_columns(entries)
    schur, translation_singular = _schur_complement(entries)
    with np.errstate(all="ignore"):
        smallest = _smallest_eigenvalue(schur)
        near = np.ones(smallest.shape, dtype=bool) if exact_near is None else (
            np.abs(np.sqrt(np.maximum(smallest, 0.0)) - exact_near) <= EXACT_WINDOW * exact_near)
    near &= ~translation_singular
    if np.any(near):
        smallest[near] = _exact_smallest_eigenvalue(schur, near)
    index = np.sqrt(np.maximum(smallest, 0.0))
    np.copyto(index, 0.0, where=translation_singular)
    return index[0] if single else index


def direct_index_side(entries, threshold):
    """The direct index (mm) from M's 21 packed entries (21, ...) where it lies within
    EXACT_WINDOW (relative) of ``threshold`` (mm), from numpy.linalg.eigvalsh; elsewhere only
    its side: +inf above, -inf below (0 where M_vv is singular, as direct_index_of_entries).
    All a warning needs, and cheaper: the side is decided by Sylvester's criterion on
    S - (threshold (1 +/- EXACT_WINDOW))^2 I (positive definite exactly when the index lies
    above), whose rounding is far below the window, with no eigenvalue computed."""
    entries, single = _packed_columns(entries)
    schur, translation_singular = _schur_complement(entries)
    with np.errstate(all="ignore"):
        above = _positive_definite(schur, (threshold * (1.0 + EXACT_WINDOW)) ** 2)
        index = np.where(above, np.inf, -np.inf)
        undecided = ~above & ~translation_singular
        if np.any(undecided):
            subset = {key: value[undecided] for key, value in schur.items()}
            near = _positive_definite(subset, (threshold * (1.0 - EXACT_WINDOW)) ** 2)
            if np.any(near):
                values = index[undecided]
                values[near] = np.sqrt(np.maximum(_exact_smallest_eigenvalue(subset, near), 0.0))
                index[undecided] = values
    np.copyto(index, 0.0, where=translation_singular)
    return index[0] if single else index


def _packed_columns(entries):
    """(entries as a float array (21, ...) with at least one column, whether it had none)."""
    entries = np.asarray(entries, dtype=float)
    return (entries[:, None], True) if entries.ndim == 1 else (entries, False)


def _schur_complement(entries):
    """(S, translation_singular) from M's packed entries (21, ...): the Schur complement
    M_ww - M_wv M_vv^-1 M_vw as {(i, j): array} for i <= j, and where M_vv is singular
    (or M not finite), there S is meaningless."""
    def entry(i, j):
        return entries[_PACKED_INDEX[max(i, j), min(i, j)]]

    force_trace = entry(0, 0) + entry(1, 1) + entry(2, 2)
    # Every entry is finite when the trace is: |M_ij| <= (M_ii + M_jj) / 2, and each M_ii a sum
    # of squares. The entries are at most 6 (size)^2, so the trace cannot overflow.
    finite = np.isfinite(force_trace + entry(3, 3) + entry(4, 4) + entry(5, 5))
    if not np.all(finite):
        entries = np.where(finite, entries, 0.0)
        force_trace = np.where(finite, force_trace, 0.0)
    with np.errstate(all="ignore"):  # a zero pivot is a translation singularity, decided below
        # M_vv = L D L^T (L unit lower triangular, pivots d), so that
        # S = M_ww - M_wv M_vv^-1 M_vw = M_ww - sum_k y_k^T y_k / d_k with the rows y_k of L^-1 M_vw.
        pivot0 = entry(0, 0)
        l10, l20 = entry(1, 0) / pivot0, entry(2, 0) / pivot0
        pivot1 = entry(1, 1) - l10 * entry(1, 0)
        reduced21 = entry(2, 1) - l20 * entry(1, 0)
        l21 = reduced21 / pivot1
        pivot2 = entry(2, 2) - l20 * entry(2, 0) - l21 * reduced21
        rows = [[entry(0, 3 + j) for j in range(3)]]
        rows.append([entry(1, 3 + j) - l10 * rows[0][j] for j in range(3)])
        rows.append([entry(2, 3 + j) - l20 * rows[0][j] - l21 * rows[1][j] for j in range(3)])
        scaled = [[value / pivot for value in row] for row, pivot in zip(rows, (pivot0, pivot1, pivot2))]
        schur = {(i, j): entry(3 + i, 3 + j) - (scaled[0][i] * rows[0][j] + scaled[1][i] * rows[1][j]
                                                + scaled[2][i] * rows[2][j]) for i in range(3) for j in range(i, 3)}
        translation_singular = ~finite | ~(pivot0 * pivot1 * pivot2 > TRANSLATION_SINGULAR * (force_trace / 3.0) ** 3)
    return schur, translation_singular


def _shifted(a, shift):
    """(diagonal of A - shift I as three arrays, det(A - shift I)) for symmetric 3x3 matrices
    {(i, j): array}, the determinant expanded along the first row."""
    d0, d1, d2 = a[0, 0] - shift, a[1, 1] - shift, a[2, 2] - shift
    determinant = (d0 * (d1 * d2 - a[1, 2] * a[1, 2]) - a[0, 1] * (a[0, 1] * d2 - a[1, 2] * a[0, 2])
                   + a[0, 2] * (a[0, 1] * a[1, 2] - d1 * a[0, 2]))
    return (d0, d1, d2), determinant


def _positive_definite(a, shift):
    """Whether A - shift I is positive definite, for symmetric 3x3 matrices {(i, j): array}:
    Sylvester's criterion, its three leading principal minors positive (False for NaN)."""
    (d0, d1, _), minor3 = _shifted(a, shift)
    minor2 = d0 * d1 - a[0, 1] * a[0, 1]
    return (d0 > 0.0) & (minor2 > 0.0) & (minor3 > 0.0)


def _exact_smallest_eigenvalue(a, where):
    """numpy.linalg.eigvalsh's smallest eigenvalue of the symmetric 3x3 matrices
    {(i, j): array} at the True entries of ``where``."""
    matrix = np.stack([np.stack([a[min(i, j), max(i, j)][where] for j in range(3)], -1) for i in range(3)], -2)
    return np.linalg.eigvalsh(matrix)[..., 0]


def _smallest_eigenvalue(a):
    """Smallest eigenvalue of symmetric 3x3 matrices {(i, j): array}, in closed form:
    mean + 2 spread cos(acos(det(B) / 2) / 3 + 2 pi / 3), B = (A - mean I) / spread."""
    off = a[0, 1] ** 2 + a[0, 2] ** 2 + a[1, 2] ** 2
    mean = (a[0, 0] + a[1, 1] + a[2, 2]) / 3.0
    (b00, b11, b22), determinant = _shifted(a, mean)
    spread = np.sqrt((b00 * b00 + b11 * b11 + b22 * b22 + 2.0 * off) / 6.0)
    with np.errstate(all="ignore"):
        half_determinant = determinant / (2.0 * spread * spread * spread)
    # A multiple of the identity (spread 0) gives 0 / 0 above: fmin/fmax turn the NaN into 1,
    # so that the cosine stays finite and the result is the mean.
    angle = np.arccos(np.fmax(np.fmin(half_determinant, 1.0), -1.0)) / 3.0
    return mean + 2.0 * spread * np.cos(angle + 2.0 * np.pi / 3.0)


def jacobian(wrenches, transmissions):
    """Joint rates per unit twist (..., dof, 6): row i = w_i / t_i; inf where t_i = 0."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return wrenches / transmissions[..., None]


def twist_poses(t6, step_mm, step_rad):
    """T6 (n, 12, 4, 4): each pose moved by -/+ one step along each unit twist: translations
    along base x, y, z (``step_mm``), then rotations about base x, y, z through the base
    origin (``step_rad``). Order: twist 0 minus, twist 0 plus, twist 1 minus, ..."""
    t6 = np.asarray(t6, dtype=float)
    moved = np.repeat(t6[:, None], 12, axis=1)
    for axis in range(3):
        for sign, column in ((-1.0, 2 * axis), (1.0, 2 * axis + 1)):
            moved[:, column, 3, axis] += sign * step_mm
            rotation = _axis_rotation(axis, sign * step_rad)
            # H' = Rot H: rows of T6 (n, o, a, p) are columns of H, each rotated.
            moved[:, 6 + column, :, :3] = t6[:, :, :3] @ rotation.T
    return moved


def _axis_rotation(axis, angle):
    c, s = np.cos(angle), np.sin(angle)
    i, j = (axis + 1) % 3, (axis + 2) % 3
    rotation = np.eye(3)
    rotation[i, i] = rotation[j, j] = c
    rotation[i, j], rotation[j, i] = -s, s
    return rotation


def finite_difference_jacobian(joints_of, t6, step_mm, step_rad, wraps):
    """Central differences (n, dof, postures, 6) of ``joints_of(t6)`` (a function of (m, 4, 4)
    T6 giving (m, dof, postures) joints) along the six unit twists; ``wraps`` (dof,) marks
    angles, differenced modulo 2 pi."""
    count = len(t6)
    moved = twist_poses(t6, step_mm, step_rad).reshape(-1, 4, 4)
    joints = joints_of(moved)
    joints = joints.reshape(count, 6, 2, *joints.shape[1:])
    difference = joints[:, :, 1] - joints[:, :, 0]
    difference[:, :, wraps] = difference[:, :, wraps] - 2 * np.pi * np.rint(difference[:, :, wraps] / (2 * np.pi))
    steps = np.array([step_mm] * 3 + [step_rad] * 3)
    return np.moveaxis(difference / (2.0 * steps[None, :, None, None]), 1, -1)


def posture_direct_index(robot, points, branch_joints, postures):
    """(n,) the exact direct index (mm) of one posture per pose: ``postures`` (n,) for
    platform points (n, dof, 3) and each limb's joint per branch (n, dof, 2), from that
    posture's M = W^T W (W: its six unit line wrenches as rows), as direct_index computes it."""
    wrenches, _ = limb_wrenches(robot, points, branch_joints, with_transmissions=False)  # (n, dof, 2, 6)
    branches = branch_table(robot)[np.asarray(postures)]  # (n, dof)
    lines = np.take_along_axis(wrenches, branches[:, :, None, None], axis=2)[:, :, 0]  # (n, dof, 6)
    return direct_index(np.einsum("nki,nkj->nij", lines, lines))
