"""The comparison of one chunk of poses and the running totals over a verification: every
joint of every posture against the reference (by limb branch where the routine allows it),
warnings with their tolerance bands, return values, buffer faults, closure residuals and
per-posture statistics. The checks (:mod:`kingen.verify.checks`) judge these totals."""

from dataclasses import dataclass, fields, replace

import numpy as np

from ..conventions import joint_errors
from ..kinematics.hybrid.parasitic import constraint_residuals, pose_constraint_residuals
from ..kinematics.routine import INPUTS_MODIFIED, SINGULAR_TOLERANCE, UNWRITTEN_WARNING, WARNING_BAND, WARNINGS
from ..kinematics.singularity import branch_table, branch_values, posture_values, representative_postures
from ..kinematics.hybrid.wrist import tool_miss, tool_t6
from .options import CONDITIONING_FACTOR

DIAGNOSIS_POSES = 2000
"""The first this many compared poses are kept for diagnoses and the per-pose checks."""
UNREACHABLE = WARNINGS["WARN_UNREACHABLE"]
WARNING_KINDS = tuple(WARNINGS)


def singular_bounds(robot, reference_solution, fixed=None):
    """(n, dof) error bound for ill-conditioned joints; 0 where the fixed limits apply. A joint
    is ill-conditioned in its limb's singular band, and wherever its conditioning bound
    CONDITIONING_FACTOR * scale / sqrt(|D|) exceeds its fixed bound ``fixed`` ((dof,), mm or
    rad; when given): just outside the band of a long link the square root is as
    ill-conditioned as inside it, so the bound does not drop there. For a prismatic joint
    the scale is the larger of its link's length and reach^2 / that length (reach: the
    larger of the robot's size_mm and the joint's own magnitude): the radicand's rounding
    grows with the coordinates it is computed from."""
    radicands = reference_solution.radicands
    if not np.any(np.isfinite(radicands)):  # legs only (D = +inf): no joint is ill-conditioned
        return np.zeros(radicands.shape)
    # A wrist joint (an angle, from its own radicand) at the scale of one radian.
    scale = np.array([limb.singular_scale() for limb in robot.limbs] + [1.0] * (robot.joint_count - robot.dof))
    # A length's radicand is computed from coordinates as large as the robot or the joint
    # (a carriage far along its rail): its rounding grows with (that / link)^2.
    # np.fmax ignores a NaN as np.nanmax would; over the axis of two branches, several times faster.
    magnitude = np.abs(reference_solution.branch_joints)
    reach = np.fmax(robot.size_mm, np.fmax(magnitude[..., 0], magnitude[..., 1]))
    scale = np.where(robot.revolute, scale, np.maximum(scale, reach ** 2 / scale))
    in_band = np.abs(radicands) <= SINGULAR_TOLERANCE + WARNING_BAND
    eps = np.finfo(float).eps
    with np.errstate(invalid="ignore"):
        bound = CONDITIONING_FACTOR * scale / np.sqrt(np.maximum(np.abs(radicands), eps))
    if fixed is not None:
        in_band = in_band | (bound > fixed)
    return np.where(in_band, bound, 0.0)


def warnings_in_band(robot, reference_solution):
    """(n, postures) True where the reference's warning is within WARNING_BAND of a threshold:
    a radicand within it of +/-SINGULAR_TOLERANCE, a joint within it of a travel limit (mm or
    rad), or a direct index within WARNING_BAND relative of the robot's direct_index_min."""
    radicands = reference_solution.radicands
    near_radicand = np.any(
        (np.abs(radicands - SINGULAR_TOLERANCE) < WARNING_BAND) | (np.abs(radicands + SINGULAR_TOLERANCE) < WARNING_BAND),
        axis=1,
    )
    near = np.broadcast_to(near_radicand[:, None], reference_solution.warnings.shape)
    lower, upper = robot.travel_limits()
    if np.any(np.isfinite(lower) | np.isfinite(upper)):
        joints = reference_solution.branch_joints  # (n, dof, 2): each limb's branches, then spread over the postures
        near_limit = ((np.abs(joints - lower[None, :, None]) < WARNING_BAND)
                      | (np.abs(joints - upper[None, :, None]) < WARNING_BAND))
        if np.any(near_limit):
            near = near | np.any(posture_values(robot, near_limit), axis=2)
    if robot.direct_index_min is not None:
        with np.errstate(invalid="ignore"):
            near = near | (np.abs(reference_solution.direct_index - robot.direct_index_min)
                           <= WARNING_BAND * robot.direct_index_min)
    return near


@dataclass
class Tally:
    """Running totals over the chunks of one verification."""

    calibrated: object = None
    """The robot with the calibration fields applied, for the closure check."""
    returns_wrong: int = 0
    reachable_poses: int = 0
    """Poses at which the reference reaches at least one posture."""
    warning_counts: np.ndarray = None
    """(WARNING_KINDS,) how many postures the reference gave each warning, in WARNING_KINDS order."""
    aborted: int = 0
    closure_worst: float = 0.0
    closure_checked: int = 0
    constraint_worst: float = 0.0
    constraint_checked: int = 0
    """A machine with task coordinates: the largest |constraint residual| (mm) at the machine's
    pose of the poses that have one, and how many poses were judged."""
    wrist_worst: float = 0.0
    wrist_checked: int = 0
    """A robot with a wrist: the largest miss (wrist_error) of the asked tool tip (mm) or axis,
    and how many (pose, posture) pairs were judged."""
    posture_counts: np.ndarray = None
    """(4, postures): right, wrong, unreachable wrongly, missed."""
    posture_worst: list = None
    """[mm (postures,), rad (postures,)] worst errors where both solve."""

    faulty_calls: int = 0
    fault_bits: int = 0
    first: tuple = None
    boundary_reachable: int = 0
    """Of ``reachable_poses``, those beside warnings' boundaries (not drawn in the region)."""
    boundary_first: tuple = None
    """As ``first``, for the poses beside warnings' boundaries (kingen.verify.boundaries)."""
    direct_index_below: int = 0
    """Postures the reference reaches with a direct index at most the robot's
    direct_index_min: those that exercise its threshold from below."""

    @classmethod
    def start(cls, calibrated):
        """Empty totals for ``calibrated`` (the robot with the calibration fields applied)."""
        postures = calibrated.postures
        return cls(calibrated=calibrated, posture_counts=np.zeros((4, postures), dtype=np.int64),
                   posture_worst=[np.zeros(postures), np.zeros(postures)],
                   warning_counts=np.zeros(len(WARNING_KINDS), dtype=np.int64))

    def add(self, other):
        """Add the totals of a later chunk (its ``first`` counts only when none is kept yet)."""
        self.warning_counts = self.warning_counts + other.warning_counts
        for name in ("returns_wrong", "reachable_poses", "aborted", "closure_checked", "faulty_calls",
                     "direct_index_below", "constraint_checked", "wrist_checked"):
            setattr(self, name, getattr(self, name) + getattr(other, name))
        self.fault_bits |= other.fault_bits
        self.closure_worst = max(self.closure_worst, other.closure_worst)
        self.constraint_worst = max(self.constraint_worst, other.constraint_worst)
        self.wrist_worst = max(self.wrist_worst, other.wrist_worst)
        self.posture_counts += other.posture_counts
        self.posture_worst = [np.maximum(mine, theirs) for mine, theirs in zip(self.posture_worst, other.posture_worst)]
        if self.first is None:
            self.first = other.first


def accumulate(robot, report, tally, revolute, t6, calls, expected, keep_first=True):
    """Add one chunk's comparison to ``report``'s counters and ``tally``'s totals: the routine's
    ``calls`` on the poses ``t6`` against the reference's ``expected``. Its first
    DIAGNOSIS_POSES poses become ``tally.first`` when ``keep_first`` and none are kept yet."""
    tally.faulty_calls += int(np.count_nonzero(calls.faults))
    tally.fault_bits |= int(np.bitwise_or.reduce(calls.faults)) if len(calls.faults) else 0
    aborted = (calls.faults & ~INPUTS_MODIFIED) != 0
    if np.any(aborted):  # judged by the buffers check; its outputs are partial
        tally.aborted += int(np.count_nonzero(aborted))
        t6, expected, calls = t6[~aborted], _rows(expected, ~aborted), _rows(calls, ~aborted)
        if not len(t6):
            return
    columns = compared_columns(robot, calls, expected)
    errors = joint_errors(columns.plugin, columns.reference, revolute)
    errors = np.where(~columns.reference_solves[:, None, :] & np.isfinite(columns.plugin), 0.0, errors)
    bounds = singular_bounds(robot, expected, np.where(revolute, report.tolerance_rad, report.tolerance_mm))[:, :, None]
    singular = np.broadcast_to(bounds > 0, errors.shape)
    report.singular_entries += int(np.count_nonzero(bounds)) * robot.postures
    report.singular_out_of_bound += columns.postures_of(singular & (errors > bounds))
    regular = np.where(singular, 0.0, errors)
    _count_postures(tally, report, revolute, calls, expected, columns, errors, singular, bounds)
    if np.any(~revolute):
        report.max_abs_error_mm = max(report.max_abs_error_mm, float(regular[:, ~revolute].max()))
    if np.any(revolute):
        report.max_abs_error_rad = max(report.max_abs_error_rad, float(regular[:, revolute].max()))
    differ = calls.warnings != expected.warnings
    excused = differ & warnings_in_band(robot, expected) & (calls.warnings != UNWRITTEN_WARNING)
    report.warning_mismatches += int(np.count_nonzero(differ & ~excused))
    report.warnings_in_band += int(np.count_nonzero(excused))
    none_reachable = np.all(expected.warnings == UNREACHABLE, axis=1)
    tally.returns_wrong += int(np.count_nonzero(calls.returned != np.where(none_reachable, 1, 0)))
    tally.reachable_poses += int(np.count_nonzero(~none_reachable))
    tally.warning_counts += np.array([np.count_nonzero(expected.warnings == WARNINGS[kind]) for kind in WARNING_KINDS])
    if expected.direct_index is not None and robot.direct_index_min is not None:
        with np.errstate(invalid="ignore"):  # NaN where unreachable: not counted
            tally.direct_index_below += int(np.count_nonzero(expected.direct_index <= robot.direct_index_min))
    closure_worst, closure_checked = closure_error(tally.calibrated, expected, calls.solutions)
    tally.closure_worst = max(tally.closure_worst, closure_worst)
    tally.closure_checked += closure_checked
    if robot.parallel.task:  # with a wrist: at the platform's pose the reference solves the tool pose at
        parallel = tally.calibrated.parallel
        with np.errstate(all="ignore"):  # that pose is on the manifold: not solved again
            if robot.wrist is None:
                residuals, radicand = constraint_residuals(parallel, t6)
            else:
                residuals, radicand = pose_constraint_residuals(parallel, expected.platform), expected.constraint
        judged = radicand > SINGULAR_TOLERANCE
        tally.constraint_checked += int(np.count_nonzero(judged))
        worst = np.where(np.isfinite(residuals), np.abs(residuals), np.inf)[judged]
        tally.constraint_worst = max(tally.constraint_worst, float(worst.max()) if worst.size else 0.0)
    if robot.wrist is not None:
        worst, judged = wrist_error(tally.calibrated, t6, expected, calls.solutions)
        tally.wrist_worst, tally.wrist_checked = max(tally.wrist_worst, worst), tally.wrist_checked + judged
    if keep_first and tally.first is None:
        keep = slice(0, DIAGNOSIS_POSES)
        tally.first = (t6[keep], calls.solutions[keep], calls.warnings[keep], expected.joints[keep],
                       expected.warnings[keep])


@dataclass
class _Columns:
    """The joints one chunk compares, column by column: every posture, or, when the routine's
    postures repeat each limb's branch values bit for bit and it reaches exactly the postures
    the reference reaches, each limb's two branches, each standing for the postures taking it.
    Either way every entry the routine wrote is judged; the second way is cheaper by the
    posture count over two."""

    plugin: np.ndarray
    """(n, dof, columns) the routine's joints."""
    reference: np.ndarray
    """(n, dof, columns) the reference's joints."""
    reference_solves: np.ndarray
    """(n, columns) where the reference reaches the column's postures."""
    both_solve: np.ndarray
    """(n, columns) where the reference and the routine both reach them."""
    column_of: np.ndarray
    """(postures, dof) the column holding each posture's joint of each limb."""
    weights: np.ndarray
    """(dof, columns) how many postures each column stands for."""

    def postures_of(self, flags):
        """How many (pose, limb, posture) entries the (n, dof, columns) ``flags`` stand for."""
        return int(np.sum(np.count_nonzero(flags, axis=0) * self.weights))

    def per_posture(self, flags):
        """(n, postures) whether any limb's column of each posture is flagged in ``flags`` (n, dof, columns)."""
        if not np.any(flags):
            return np.zeros((flags.shape[0], self.column_of.shape[0]), dtype=bool)
        return np.any(flags[:, np.arange(self.column_of.shape[1]), self.column_of], axis=2)


def compares_by_branch(robot):
    """Whether compared_columns may compare ``robot``'s joints by limb branch: robots with more
    than two postures and no wrist (see _repeats_branches); the host's summary is asked for those only."""
    return robot.postures > 2 and robot.wrist is None


def compared_columns(robot, calls, expected):
    """The _Columns of one chunk: by branch when the routine allows it and the robot has more
    than two postures, else by posture. Whether it allows it, and its values by branch, come
    from the host's summary of the calls where it made one (Calls.repeats), else from
    _repeats_branches and kingen.kinematics.singularity.branch_values: the same test and values."""
    reference_solves = expected.warnings != UNREACHABLE
    same_reach = (np.array_equal(calls.warnings != UNREACHABLE, reference_solves)
                  and np.array_equal(reference_solves, np.broadcast_to(reference_solves[:, :1], reference_solves.shape)))
    table = branch_table(robot)
    summarised = calls.repeats is not None
    if compares_by_branch(robot) and same_reach and (np.all(calls.repeats) if summarised
                                               else _repeats_branches(robot, calls.solutions)):
        weights = np.array([[np.count_nonzero(table[:, index] == branch) for branch in range(2)]
                            for index in range(robot.dof)])
        reach = np.repeat(reference_solves[:, :1], 2, axis=1)
        values = calls.branch_values if summarised else branch_values(robot, calls.solutions)
        return _Columns(values, expected.branch_joints, reach, reach, table, weights)
    postures = np.arange(robot.postures)
    return _Columns(calls.solutions, expected.joints, reference_solves,
                    reference_solves & (calls.warnings != UNREACHABLE),
                    np.repeat(postures[:, None], robot.joint_count, axis=1),
                    np.ones((robot.joint_count, robot.postures), dtype=int))


def _repeats_branches(robot, solutions):
    """Whether each limb's joint (solutions (n, dof, postures)) is, in every posture, equal to
    its value in the first posture taking the same branch (NaN never is), for robots with
    more than two postures (the only ones compared by branch: there every entry takes part
    in a comparison). Posture k takes branch (k >> bit) & 1 of the limb with that digit, in
    runs of 2^bit postures: compared through shifted views (contiguous, no gather), each
    run's entries with their neighbour and each posture with the one two runs before it."""
    for index, bit in enumerate(robot.branch_bits):
        values = solutions[:, index, :]
        run = robot.postures if bit < 0 else 1 << bit
        period = 2 * run
        if not (np.array_equal(values[:, 1:run], values[:, :run - 1])
                and np.array_equal(values[:, run + 1:period], values[:, run:period - 1])
                and np.array_equal(values[:, period:], values[:, :-period])):
            return False
    return True


def _count_postures(tally, report, revolute, calls, expected, columns, errors, singular, bounds):
    """Per posture: poses solved right, solved wrong, unreachable wrongly, missed; worst errors."""
    tolerance = np.where(revolute, report.tolerance_rad, report.tolerance_mm)[None, :, None]
    bad = columns.per_posture(np.where(singular, errors > bounds, errors > tolerance))
    reference_solves = expected.warnings != UNREACHABLE
    plugin_solves = calls.warnings != UNREACHABLE
    both = reference_solves & plugin_solves
    outcomes = (both & ~bad, both & bad, reference_solves & ~plugin_solves, ~reference_solves & plugin_solves)
    # Counted along the poses, which (4, postures, n) puts last.
    tally.posture_counts += np.count_nonzero(np.stack([flags.T for flags in outcomes]), axis=2)
    if not len(errors):
        return
    solved = np.where(columns.both_solve[:, None, :] & ~singular, errors, 0.0).max(axis=0)  # (dof, columns)
    per_posture = solved[np.arange(solved.shape[0]), columns.column_of]  # (postures, dof)
    for unit, mask in ((0, ~revolute), (1, revolute)):
        if np.any(mask):
            tally.posture_worst[unit] = np.maximum(tally.posture_worst[unit], per_posture[:, mask].max(axis=1))


def posture_statistics(robot, tally):
    has = {0: bool(np.any(~robot.revolute)), 1: bool(np.any(robot.revolute))}
    return [{"posture": k, "right": int(tally.posture_counts[0, k]), "wrong": int(tally.posture_counts[1, k]),
             "unreachable_wrongly": int(tally.posture_counts[2, k]), "missed": int(tally.posture_counts[3, k]),
             "worst_error_mm": float(tally.posture_worst[0][k]) if has[0] else None,
             "worst_error_rad": float(tally.posture_worst[1][k]) if has[1] else None}
            for k in range(robot.postures)]


def _rows(result, keep):
    """A copy of ``result`` (a Solution or Calls) with only the poses ``keep`` (n,) selects."""
    count = len(keep)
    return replace(result, **{item.name: getattr(result, item.name)[keep] for item in fields(result)
                              if isinstance(getattr(result, item.name), np.ndarray)
                              and getattr(result, item.name).shape[:1] == (count,)})


ZERO_LENGTH = 1e-9
"""A passive link shorter than this fraction of the robot's size has no direction: singular."""


def closure_error(robot, expected, solutions):
    """(largest |closure residual| / passive-link length, joints judged): each limb's joint
    of each of its branches, as the routine returned it in the first posture taking that
    branch, put back into the limb's geometry (``robot`` calibrated as for the call); the
    values check holds every other posture to the same reference. Only postures the
    reference calls reachable count; NaN joints count as infinitely wrong. Limbs in their
    singular band are left out: there, with -1e-5 <= D < 0, the joint is the limb's closest
    approach, which misses closing by design (by up to D l / 2); so are links of no length
    (at most ZERO_LENGTH of the robot's size)."""
    representative = representative_postures(robot)
    reachable = expected.warnings != UNREACHABLE
    closing = np.abs(expected.radicands) > SINGULAR_TOLERANCE + WARNING_BAND
    worst, judged_count = 0.0, 0
    for index, limb in enumerate(robot.limbs):
        point = expected.points[:, index]
        for posture in representative[index, :limb.branches]:
            miss, length = closure_miss(limb, point, solutions[:, index, posture])
            with np.errstate(all="ignore"):
                relative = miss / length
            relative = np.where(np.isfinite(relative), relative, np.inf)
            # A link of no length (a leg whose ends meet) is singular: nothing to close.
            judged = reachable[:, posture] & closing[:, index] & ~(length <= ZERO_LENGTH * robot.size_mm)
            judged_count += int(np.count_nonzero(judged))
            if np.any(judged):
                worst = max(worst, float(np.max(np.where(judged, relative, 0.0))))
    return worst, judged_count


def wrist_error(robot, t6, expected, solutions):
    """(largest miss, (pose, posture) pairs judged) of a robot with a wrist: the wrist's forward
    (kingen.kinematics.hybrid.wrist.tool_t6) from the reference's platform pose and the routine's wrist
    joints of each posture (``solutions`` (n, joint_count, postures)) against the asked tool T6
    ``t6`` (n, 4, 4): the larger of the tool tip's distance (mm) and the tool axes' (unit
    vectors; with two wrist joints the tool's z axis only, the turn about it free; with three
    every axis: the whole pose, kingen.kinematics.hybrid.wrist.tool_miss). Judged: postures the reference reaches,
    outside the wrist's singular bands (where its closest approach misses by design); inside the
    parallel part's constraint's band too (its platform's rotation is still a rotation, with the
    wrist centre where asked); NaN joints count as infinitely wrong."""
    reachable = expected.warnings != UNREACHABLE
    regular = np.all(np.abs(expected.radicands[:, robot.dof:]) > SINGULAR_TOLERANCE + WARNING_BAND, axis=1)
    judged = reachable & regular[:, None]
    worst = 0.0
    for posture in range(robot.postures):
        rows = judged[:, posture]
        if not np.any(rows):
            continue
        with np.errstate(all="ignore"):
            tool = tool_t6(robot, expected.platform[rows], solutions[rows, robot.dof:, posture])
            miss = np.fmax(*tool_miss(robot.wrist, tool, t6[rows]))
        worst = max(worst, float(np.max(np.where(np.isfinite(miss), miss, np.inf))))
    return worst, int(np.count_nonzero(judged))


def closure_miss(limb, points, joints):
    """(|closure residual|, |passive-link length|) (n,) (n,), mm, of ``limb`` at its platform
    points (n, 3) and joints (n,): by how much the joints miss closing the limb (NaN for NaN joints)."""
    with np.errstate(all="ignore"):
        return np.abs(limb.closure_residual(points, joints)), np.abs(limb.passive_length(joints))
