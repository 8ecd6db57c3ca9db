"""Reference inverse kinematics in numpy, written from docs/explanation/conventions.md's equations.

Independent of the C templates: neither is generated from the other. Each limb
model's numpy solver lives with its model (:mod:`kingen.robot.limbs`); this module maps
poses to platform points, assembles postures and decides warnings. Vectorised
over poses. Inputs are T6 arrays (n, 4, 4) in the base frame, mm; outputs
are every posture's joint values (mm, radians in (-pi, pi]) and warning.

Warnings follow the generated C exactly (docs/explanation/warnings.md):
``WARN_UNREACHABLE`` when some limb has no real solution, ``WARN_SINGULAR_SOLUTION``
when some limb's normalised radicand D (rails, cranks) is within ``routine.SINGULAR_TOLERANCE``
of zero or the posture's direct index is at most the robot's ``direct_index_min``, ``WARN_JOINT_LIMITS_EXCEEDED`` when a joint is outside its travel limits;
unreachable wins over singular, singular over joint limits. A limb without a
real solution reports the value at the clamped radicand (closest approach), so
values are always finite. Non-finite T6: all postures unreachable, all joints 0. A limb
whose value overflows (a T6 of 1e300 mm) is unreachable with joints 0. A machine with task
coordinates (kingen.robot.constraints) is solved at the pose its constraints give for the T6's
z, roll and pitch (kingen.kinematics.hybrid.parasitic): a T6 off that manifold (for a routine that
reads x, y and yaw: ``parasitic_given``), or one whose task coordinates no pose has, is
unreachable with the joints of that pose. A robot with a serial wrist is solved from the tool
pose by kingen.kinematics.hybrid.wrist.
"""

import functools
from dataclasses import dataclass

import numpy as np

from .certificate import certified_above
from .hybrid.parasitic import solve_parasitic
from .routine import SINGULAR_TOLERANCE, warning_codes
from .hybrid.wrist import solve_tool
from .singularity import (EXACT_WINDOW, branch_table, direct_index_of_entries, direct_index_side, gram_entries_of,
                          gram_partial_sums, limb_wrenches, posture_values)


@dataclass(frozen=True)
class Solution:
    """Every posture over n poses.

    branch_joints: (n, dof, 2) each limb's joint in its branch 0 and 1 (the same twice for
    one-branch limbs), mm or rad; ``joints`` spreads them over the postures.
    warnings: (n, postures) WARN_* codes.
    radicands: (n, dof) normalised radicand D per limb (+inf for legs).
    finite: (n,) whether the T6 was finite.
    """

    branch_joints: np.ndarray
    warnings: np.ndarray
    radicands: np.ndarray
    finite: np.ndarray
    posture_branches: tuple
    """Per posture, the branch each joint takes (kingen.kinematics.singularity.branch_table as tuples)."""
    constraint: np.ndarray = None
    """(n,) a machine with task coordinates: the normalised radicand D of its parasitic yaw
    (kingen.kinematics.hybrid.parasitic), -inf off the manifold where its routine reads x, y and yaw;
    None for other robots. Its warnings count it as a limb's."""
    points: np.ndarray = None
    """(n, dof, 3) each limb's platform point in the base frame, mm (0 for a non-finite T6)."""
    platform: np.ndarray = None
    """(n, 4, 4) a robot with a wrist: the parallel part's T6 (the platform's pose the machine
    takes for each tool T6, kingen.kinematics.hybrid.wrist); None for other robots."""
    parallel: object = None
    """A robot with a wrist: the parallel part's own Solution at ``platform``; None for other robots."""
    machine: np.ndarray = None
    """(n, 4, 4) a machine with task coordinates: the T6 it takes for each T6 asked (its pose
    on its manifold for the task coordinates, kingen.kinematics.hybrid.parasitic); None for other robots."""
    direct_index: np.ndarray = None
    """(n, postures) the direct index in mm (NaN where unreachable), or None when not computed
    (robots without six force lines, or not asked for). Computed for the warnings only (not
    ``indices``), it is exact within EXACT_WINDOW of direct_index_min and elsewhere only says
    its side, +inf or -inf (kingen.kinematics.singularity.direct_index_side; +inf also where
    kingen.kinematics.certificate proves it above the window)."""

    @functools.cached_property
    def joints(self):
        """(n, dof, postures) every posture's joints, mm or rad."""
        table = np.array(self.posture_branches)
        return np.swapaxes(self.branch_joints[:, np.arange(table.shape[1]), table], 1, 2)

    @property
    def min_inverse_index(self):
        """(n,) the smallest normalised radicand D over the limbs (inf: no limb has one)."""
        return np.min(self.radicands, axis=1)


def platform_points_in_base(t6, points):
    """Platform-frame points (m, 3) mapped to the base frame for each T6: shape (n, m, 3), mm.

    The result is a view of (m, 3, n) memory, so that every coordinate of a point is one
    contiguous row over the poses: numpy's element-wise operations on it (the limb models',
    the force lines') keep that layout and run along the poses."""
    return _points_from_rows(_t6_rows(t6), points)


def _t6_rows(t6):
    """(4, 3, n) a new array: T6[r][i] of every pose as one contiguous row over the poses."""
    return np.ascontiguousarray(np.moveaxis(np.asarray(t6, dtype=float)[:, :, :3], 0, -1))


def _points_from_rows(rows, points):
    """platform_points_in_base from T6 as _t6_rows gives it."""
    points = np.asarray(points, dtype=float)
    # Written out in the generated C's order: T6[0][i] x + T6[1][i] y + T6[2][i] z + T6[3][i].
    base = (rows[None, 0] * points[:, 0, None, None] + rows[None, 1] * points[:, 1, None, None]
            + rows[None, 2] * points[:, 2, None, None]) + rows[None, 3]
    return np.moveaxis(base, -1, 0)


def solve(robot, t6, link_lengths=None, link_offsets=None, indices=False):
    """Every posture of ``robot`` for T6 arrays (n, 4, 4); see the module docstring.

    ``link_lengths`` / ``link_offsets`` (6 each, the calibration fields length i / offset i) replace
    the parameters the robot marks as calibrated, where non-zero. The direct index is
    computed when the robot's warnings need it (``direct_index_min``) or ``indices`` asks
    for it, for robots with six force lines."""
    with np.errstate(all="ignore"):
        robot, t6 = robot.calibrated(link_lengths, link_offsets), np.asarray(t6, dtype=float).reshape(-1, 4, 4)
        if robot.wrist is not None:
            return solve_tool(robot, t6, lambda parallel, machine: _solve(parallel, machine, indices), Solution)
        return _solve(robot, t6, indices)


BLOCK_POSTURES = 8192
"""Postures whose direct index is computed at once: about 20 arrays of them stay in the cache."""


def _blocks(count, postures):
    """Slices of ``count`` poses holding about BLOCK_POSTURES postures each."""
    step = max(1, BLOCK_POSTURES // postures)
    return [slice(begin, begin + step) for begin in range(0, count, step)]


CERTIFY_PROBE_POSES = 32
"""The certificate (kingen.kinematics.certificate) is tried on this many poses first, per call of solve
for robots with more than one posture (it forms all 64 branch combinations' determinants,
of which a one-posture robot uses one)..."""
CERTIFY_SETTLED = 0.5
"""...and used for all of them only where it settled at least this fraction of the probe's
postures: it settles every CEART posture in the verification region and (being loose by 19
to 350 times there) none of IWF's or the hexapod's, where it would only cost time."""


def _direct_index(robot, points, branch_joints, indices):
    """(n, postures) the direct index (mm): exact (``indices``), or as direct_index_side gives
    it for robot.direct_index_min, +inf where kingen.kinematics.certificate proves it above the window,
    the rest from each posture's M (built only where some posture of a block needs it)."""
    count = points.shape[0]
    wrenches, lines = _force_lines(robot, points, branch_joints)
    index = np.empty((count, robot.postures))
    threshold = robot.direct_index_min
    settled = None
    probe = _settling_probe(robot, lines) if not indices else None
    if probe is not None:
        rest = certified_above(robot, lines[..., CERTIFY_PROBE_POSES:], _window_top(robot))
        settled = np.concatenate([probe, rest])
    partial_sums = None
    for block in _blocks(count, robot.postures):
        if settled is not None and np.all(settled[block]):
            index[block] = np.inf
            continue
        if partial_sums is None:
            partial_sums = gram_partial_sums(robot, wrenches)
        entries = gram_entries_of(partial_sums, block)
        index[block] = (direct_index_of_entries(entries) if indices else direct_index_side(entries, threshold))
        if settled is not None:
            np.copyto(index[block], np.inf, where=settled[block])
    return index


def _force_lines(robot, points, branch_joints):
    """(wrenches (n, dof, 2, 6), lines (dof, 2, 6, n)): the limbs' unit line wrenches
    (kingen.kinematics.singularity.limb_wrenches) for platform points (n, dof, 3) and joints per branch
    (n, dof, 2), and the same memory in its own layout, poses last, as the certificate reads it."""
    wrenches, _ = limb_wrenches(robot, points, branch_joints, with_transmissions=False)
    return wrenches, np.moveaxis(wrenches, 0, -1)


def _settling_probe(robot, lines):
    """kingen.kinematics.certificate on the first CERTIFY_PROBE_POSES poses of the limbs' ``lines``
    (dof, 2, 6, n): (m, postures) where it settles at least CERTIFY_SETTLED of their postures,
    else None (and always for robots it is not tried for: no threshold, or one posture)."""
    if robot.direct_index_min is None or robot.postures <= 1 or lines.shape[-1] == 0:
        return None
    probe = certified_above(robot, lines[..., :CERTIFY_PROBE_POSES], _window_top(robot))
    return probe if np.mean(probe) >= CERTIFY_SETTLED else None


def _window_top(robot):
    """Above this (mm) direct_index_side says only "above": what the certificate must prove."""
    return robot.direct_index_min * (1.0 + EXACT_WINDOW)


def certificate_settles(robot, t6):
    """Whether solve, called on the poses ``t6`` (n, 4, 4; mm), settles their direct index by
    kingen.kinematics.certificate, as it decides on its first CERTIFY_PROBE_POSES poses (and then builds
    no posture's M). False for robots it does not try it for."""
    if not robot.has_direct_index:
        return False
    t6 = np.asarray(t6, dtype=float).reshape(-1, 4, 4)[:CERTIFY_PROBE_POSES]
    with np.errstate(all="ignore"):
        points, branch_joints, *_ = _limb_solutions(robot.calibrated(), t6)
        return _settling_probe(robot, _force_lines(robot, points, branch_joints)[1]) is not None


def limb_solution(robot, t6):
    """The limbs' part of solve for T6 arrays (n, 4, 4), for searches that decide their own
    warnings (about ten times cheaper on CEART): a Solution whose ``warnings`` and
    ``direct_index`` are None, and whose ``finite`` is also False where a limb's value overflows.
    A robot with a wrist gets solve's whole answer (its legs stand at the platform's pose, not the tool's)."""
    if robot.wrist is not None:
        return solve(robot, t6)
    with np.errstate(all="ignore"):
        points, branch_joints, radicands, finite, overflow, *_ = _limb_solutions(
            robot, np.asarray(t6, dtype=float).reshape(-1, 4, 4))
    return Solution(branch_joints=branch_joints, warnings=None, radicands=radicands, finite=finite & ~np.any(overflow, axis=1),
                    posture_branches=tuple(map(tuple, branch_table(robot).tolist())), points=points)


def _limb_solutions(robot, t6):
    """(points (n, dof, 3), branch_joints (n, dof, 2), radicands (n, dof), finite (n,),
    overflow (n, dof), constraint (n,) or None: Solution.constraint, machine: Solution.machine) of every limb for T6 arrays (n, 4, 4): joints 0 where the T6 is not
    finite or the limb's value overflows (see the module docstring)."""
    count = t6.shape[0]
    finite = np.all(np.isfinite(t6[:, :, :3].reshape(count, 12)), axis=1)
    constraint, machine = None, None
    if robot.task:  # the machine's pose for the task coordinates; off the manifold or unsolvable: unreachable
        parasitic = solve_parasitic(robot, t6)
        t6, constraint = parasitic.t6, np.where(parasitic.off & robot.parasitic_given, -np.inf, parasitic.radicand)
        machine = t6
    rows = _t6_rows(t6)
    if not np.all(finite):
        rows[:, :, ~finite] = 0.0
    points = _points_from_rows(rows, [limb.platform_point for limb in robot.limbs])

    branch_joints = np.empty((count, robot.dof, 2))
    radicands = np.full((count, robot.dof), np.inf)
    for index, limb in enumerate(robot.limbs):
        limb_solution = limb.solve(points[:, index])
        branch_joints[:, index, :] = limb_solution.values
        if limb_solution.radicand is not None:
            radicands[:, index] = limb_solution.radicand
    overflow = ~(np.isfinite(branch_joints[..., 0]) & np.isfinite(branch_joints[..., 1]))  # (n, dof)
    branch_joints[overflow | ~finite[:, None]] = 0.0
    return points, branch_joints, radicands, finite, overflow, constraint, machine


def _solve(robot, t6, indices):
    count = t6.shape[0]
    points, branch_joints, radicands, finite, overflow, constraint, machine = _limb_solutions(robot, t6)

    lower, upper = robot.travel_limits()
    limited = np.isfinite(lower) | np.isfinite(upper)
    if np.any(limited):  # each limb's branches against its limits, then spread over the postures
        beyond = (branch_joints < lower[None, :, None]) | (branch_joints > upper[None, :, None])
        outside = np.any(posture_values(robot, beyond), axis=2)
    else:
        outside = np.zeros((count, robot.postures), dtype=bool)
    unreachable = np.any(~(radicands >= -SINGULAR_TOLERANCE) | overflow, axis=1)
    singular = np.any(np.abs(radicands) <= SINGULAR_TOLERANCE, axis=1)
    if constraint is not None:  # no pose has these task coordinates, or the T6 is off the manifold
        unreachable |= ~(constraint >= -SINGULAR_TOLERANCE)
        singular |= np.abs(constraint) <= SINGULAR_TOLERANCE

    unreachable = unreachable[:, None] | ~finite[:, None]
    singular = np.broadcast_to(singular[:, None], outside.shape)
    index = None
    if robot.has_direct_index and (indices or robot.direct_index_min is not None):
        index = _direct_index(robot, points, branch_joints, indices)
        np.copyto(index, np.nan, where=unreachable)
        if robot.direct_index_min is not None:
            singular = singular | (index <= robot.direct_index_min)

    return Solution(branch_joints=branch_joints, warnings=warning_codes(outside, singular, unreachable), radicands=radicands, constraint=constraint,
                    finite=finite, posture_branches=tuple(map(tuple, branch_table(robot).tolist())), points=points,
                    direct_index=index, machine=machine)
