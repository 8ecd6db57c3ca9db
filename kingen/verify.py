"""Verification: a compiled routine (kingen's or hand-written) against the numpy
reference, the golden values and the interface contract (docs: README, 'What verify proves').

Everything is compared, nothing sampled away: every joint of every posture of
every pose, and every warning. Where the reference calls a posture unreachable the
interface asks only for finite joints, so only finiteness is checked there (the
warning itself is compared as everywhere). A warning may differ only inside the documented
tolerance band (``WARNING_BAND``): where the reference's decision quantity (a
normalised radicand or a joint value) lies that close to its threshold, both
answers are right within floating-point rounding. Each clause is a named check;
failed value checks carry diagnoses (:mod:`kingen.diagnose`).

``verify`` runs in the calling process (for tests and kingen's own code);
``verify_library`` loads and verifies a library in a child process
(:mod:`kingen.isolation`), so that a crash, an ``exit()`` or a hang in foreign code
becomes a failed check instead of a dead, silent or stuck kingen.
"""

import math
import multiprocessing
import os
import time
from contextlib import contextmanager
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import Optional

import numpy as np

from . import abi
from .defaults import DEFAULT_TIMEOUT, MAX_PROCESSES
from .conventions import joint_errors, pose_from_t6, t6_from_pose
from .diagnose import diagnose, diagnose_warnings
from .forward import closure_derivative, free_mask, newton, t6_of
from .errors import PluginDefect
from .host import Plugin, captured_output, host_state
from .isolation import die_with_parent, ending, keep_freed_memory, run_in_child
from .library_info import build_info
from .abi import SINGULAR_TOLERANCE, UNWRITTEN_WARNING, VALUE_TOLERANCE_MM, VALUE_TOLERANCE_RAD, WARNING_BAND
from .reference import solve
from .singularity import (PACKED, branch_table, branch_values, finite_difference_jacobian, jacobian,
                          partial_sum_split, posture_values, posture_wrenches, representative_postures)
from .snapshot import check as snapshot_check
from .report import Check, GoldenResult, Report

RELATIVE_TOLERANCE = 256 * np.finfo(float).eps
"""For robots larger than about 17 m the prismatic bound grows with size: 256 eps x size."""
CONDITIONING_FACTOR = 16.0 * np.finfo(float).eps
"""Inside a limb's singular band its joint is ill-conditioned (a square root of a radicand
near 0): there it is compared within CONDITIONING_FACTOR * scale / sqrt(max(|D|, eps)),
scale = link length (mm) for rails, 1 rad for cranks. Everywhere else the fixed limits hold."""
CHUNK_ENTRIES = 2000000
"""Joint entries (poses x dof x postures) per batch, within 1000 and MAX_CHUNK_POSES poses:
large enough for numpy to work in long runs, small enough for flat memory."""
MAX_CHUNK_POSES = 8192
DIAGNOSIS_POSES = 2000
DETERMINISM_POSES = 1000
CLOSURE_TOLERANCE = 1e-9
"""Relative to the passive link's length."""
JACOBIAN_POSES = 200
ROUND_TRIP_POSES = 1000
ROUND_TRIP_POSTURES = 4096
"""At most about this many regular (pose, posture) pairs of those poses go round: every one for
robots with few postures, a diagonal selection covering every posture for many (CEART: 64)."""
ROUND_TRIP_MIN_CONDITIONING = 1e-4
"""Postures whose closure derivative with respect to the free pose coordinates (rotations per
mm of arc at the robot's size) has a smallest singular value below this are near a
singularity: their pose is not determined by the joints (pose_conditioning)."""
JACOBIAN_STEP = 1e-6
"""Central-difference steps: this fraction of the robot's size (mm), and this many radians:
small enough for the curvature near (not in) a singular band, large against rounding."""
JACOBIAN_TOLERANCE = 1e-6
"""Relative to the largest entry of the joint's Jacobian row (rotations weighed as mm of arc
at the robot's size); Richardson-extrapolated central differences with these steps agree
with the analytic Jacobian to about 1e-9 on every shipped robot."""
JACOBIAN_MIN_TRANSMISSION = 0.05
JACOBIAN_MIN_RADICAND = 1e-3
"""Only regular postures are compared: away from limb singularities, where differences
of an ill-conditioned joint would measure the conditioning, not the formula."""
UNREACHABLE = abi.WARNINGS["WARN_UNREACHABLE"]


@dataclass(frozen=True)
class VerifyOptions:
    """What a verification is asked to do: poses, seed, the dialog's fields, time limit (s)."""

    samples: int = 10000
    seed: int = 0
    link_lengths: tuple = None
    link_offsets: tuple = None
    timeout: float = DEFAULT_TIMEOUT
    snapshot: object = None
    """A loaded kingen.snapshot.Snapshot to check the routine against (check ``snapshot``)."""
    processes: Optional[int] = 1
    """Processes comparing the sampled poses: 1 keeps everything in the calling process, more
    fork the others (compared_chunks); None: comparing_processes(), one per core."""


def report_tolerance_mm(robot):
    """The prismatic bound verify reports for ``robot`` (see value_tolerance_mm)."""
    return value_tolerance_mm(robot)


def value_tolerance_mm(robot):
    """The bound on prismatic joints: 1e-9 mm, or 256 eps x the robot's size (mm) when larger."""
    return max(VALUE_TOLERANCE_MM, RELATIVE_TOLERANCE * robot.size_mm)


class PoseStream:
    """The seeded poses of a verification, in order: uniform in the robot's verification
    region (mm, degrees), from one generator, drawn or skipped a run at a time. Skipping
    moves the generator past the poses as if they had been drawn (each uniform double takes
    one 64-bit output of PCG64), so the poses after them are the same, bit for bit."""

    def __init__(self, robot, seed):
        region = robot.verification
        self._home, self._half_widths = np.asarray(region.home), np.asarray(region.range)
        self._generator = np.random.default_rng(seed)

    def draw(self, count):
        """The next ``count`` poses (count, 6)."""
        return self._home + self._generator.uniform(-1.0, 1.0, size=(count, 6)) * self._half_widths

    def skip(self, count):
        """Move past the next ``count`` poses without drawing them."""
        self._generator.bit_generator.advance(6 * count)


def chunk_bounds(count, chunk):
    """(first index, pose count) of each chunk of ``count`` poses, ``chunk`` at a time."""
    return [(begin, min(chunk, count - begin)) for begin in range(0, count, chunk)]


def pose_chunks(robot, count, seed, chunk):
    """(first index, poses (m, 6)) chunk by chunk: ``count`` poses of PoseStream, so the poses
    are the same, bit for bit, whatever the chunk size; memory stays that of one chunk."""
    stream = PoseStream(robot, seed)
    for begin, size in chunk_bounds(count, chunk):
        yield begin, stream.draw(size)


CPU_QUOTA_FILES = (("/sys/fs/cgroup/cpu.max", None),
                   ("/sys/fs/cgroup/cpu/cpu.cfs_quota_us", "/sys/fs/cgroup/cpu/cpu.cfs_period_us"))
"""Where Linux control groups (v2, then v1) state a container's CPU time quota and period."""


def comparing_processes():
    """Processes a verification compares with by default: one per core this process may run
    on, no more than its container's CPU quota allows, at most MAX_PROCESSES."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        cores = os.cpu_count() or 1
    quota = cpu_quota()
    if quota is not None:
        cores = min(cores, quota)
    return max(1, min(MAX_PROCESSES, cores))


def cpu_quota():
    """The cores a control group's CPU quota amounts to (rounded up), or None without one."""
    for quota_file, period_file in CPU_QUOTA_FILES:
        try:
            words = Path(quota_file).read_text().split()
            if period_file is not None:
                words.append(Path(period_file).read_text().strip())
            quota, period = float(words[0]), float(words[1])
        except (OSError, ValueError, IndexError):  # no such file, "max" (v2) or unreadable
            continue
        if quota > 0 and period > 0:
            return math.ceil(quota / period)
    return None


def process_count(options, chunks):
    """How many processes compare ``chunks`` chunks: ``options.processes`` (None:
    comparing_processes()), at most one per chunk; one where processes cannot be forked."""
    if "fork" not in multiprocessing.get_all_start_methods():
        return 1
    return max(1, min(chunks, comparing_processes() if options.processes is None else options.processes))


def _taker(number, processes):
    """Which of ``processes`` comparing processes compares chunk ``number`` (0, 1, ...):
    0 is the one that merges them all (and takes chunk 0)."""
    return number % processes


REPORT_COUNTS = ("singular_entries", "singular_out_of_bound", "warning_mismatches", "warnings_in_band")
REPORT_WORST = ("max_abs_error_mm", "max_abs_error_rad")
_chunk_job = None
"""(robot, calibrated robot, plugin, options) of the comparing processes: set before the
others are forked, so that nothing but results travels between them."""


@dataclass
class _Part:
    """One chunk's comparison: the report's counters, the running totals, what was printed."""

    counts: dict
    tally: object
    printed_bytes: int
    printed_first_line: str


def _compare_chunk(poses, first=False):
    """Call the routine on ``poses`` (m, 6), solve the reference and compare: a _Part (with
    the poses kept for diagnoses only for the ``first`` chunk; nothing else heavy, so
    that it travels between processes cheaply)."""
    robot, calibrated, plugin, options = _chunk_job
    report = _empty_report(robot, plugin.routine, options)
    tally = _Tally.start(calibrated)
    printed = _Printed()
    t6 = t6_from_pose(poses)
    plugin.reset_host()
    with printed.capture():
        calls = plugin.call(t6, options.link_lengths, options.link_offsets)
    expected = solve(robot, t6, options.link_lengths, options.link_offsets)
    _accumulate(robot, report, tally, robot.revolute, t6, calls, expected)
    counts = {name: getattr(report, name) for name in REPORT_COUNTS + REPORT_WORST}
    tally.calibrated = None
    if not first:
        tally.first = None
    return _Part(counts, tally, printed.bytes, printed.first_line)


def compared_chunks(robot, calibrated, plugin, options, bounds, processes, phase, deaths):
    """(first index, pose count, _Part) chunk by chunk, in order, for the chunks ``bounds``
    (chunk_bounds) of PoseStream's poses. With ``processes`` (process_count) above 1, the
    other comparing processes (_Helpers, forked before chunk 0) each compare the chunks
    _taker gives them, ahead of this one, which draws and compares only its own. If one dies (the routine crashed or exited there), its chunks are drawn
    and compared here again, so that a crash is named by this process's stage as always;
    if they run to the end here, (first index, pose count, exit code) of the chunk it died
    in is appended to ``deaths``: the routine crashed all the same."""
    global _chunk_job
    _chunk_job = (robot, calibrated, plugin, options)
    stream = PoseStream(robot, options.seed)
    helpers = _Helpers(robot, options, bounds, processes) if processes > 1 else None
    try:
        for number, (begin, size) in enumerate(bounds):
            phase(f"poses {begin} to {begin + size - 1} of seed {options.seed}")
            part = helpers.result(number) if helpers is not None and _taker(number, processes) != 0 else None
            if part is None:
                part = _compare_chunk(stream.draw(size), first=begin == 0)
            else:
                stream.skip(size)
            yield begin, size, part
    finally:
        if helpers is not None:
            helpers.stop()
            deaths.extend((*bounds[number], code) for number, code in helpers.deaths)


class _Helpers:
    """Forked processes 1 .. processes - 1 that compare the chunks _taker gives them, ahead of
    this one: each draws its own poses, so only results travel (through a pipe each, which
    also holds a process back when it runs far ahead). They die with this process.
    ``deaths``: (the chunk number it was awaited for, exit code) of each that died."""

    def __init__(self, robot, options, bounds, processes):
        context = multiprocessing.get_context("fork")
        self._processes = processes
        self._receivers, self._children = {}, {}
        self.deaths = []
        try:
            for taker in range(1, processes):
                receiver, sender = context.Pipe(duplex=False)
                child = context.Process(target=_compare_taken_chunks,
                                        args=(sender, robot, options, bounds, taker, processes), daemon=True)
                self._receivers[taker], self._children[taker] = receiver, child
                child.start()
                sender.close()
        except BaseException:  # out of processes or memory: none is left running
            self.stop()
            raise

    def result(self, number):
        """Chunk ``number``'s _Part from the process that takes it, or None once that one has
        died (then this process compares its chunks)."""
        taker = _taker(number, self._processes)
        receiver = self._receivers.get(taker)
        if receiver is None:
            return None
        try:
            return receiver.recv()
        except (EOFError, OSError):
            receiver.close()
            del self._receivers[taker]
            self._children[taker].join()
            self.deaths.append((number, self._children[taker].exitcode))
            return None

    def stop(self):
        for receiver in self._receivers.values():
            receiver.close()
        for child in self._children.values():
            if child.pid is not None:  # started
                child.kill()
                child.join()


def _compare_taken_chunks(sender, robot, options, bounds, taker, processes):
    die_with_parent()
    stream = PoseStream(robot, options.seed)
    for number, (_, size) in enumerate(bounds):
        if _taker(number, processes) == taker:
            sender.send(_compare_chunk(stream.draw(size)))
        else:
            stream.skip(size)


def _merge(report, tally, printed, part):
    """Add one chunk's _Part to the verification's report, totals and printed output."""
    for name in REPORT_COUNTS:
        setattr(report, name, getattr(report, name) + part.counts[name])
    for name in REPORT_WORST:
        setattr(report, name, max(getattr(report, name), part.counts[name]))
    tally.add(part.tally)
    printed.bytes += part.printed_bytes
    printed.first_line = printed.first_line or part.printed_first_line


def sample_poses(robot, count, seed):
    """``count`` poses (mm, degrees) uniform in the robot's verification region, seeded."""
    return np.concatenate([poses for _, poses in pose_chunks(robot, count, seed, max(count, 1))])


def chunk_size(robot):
    """Poses per batch for ``robot``: about CHUNK_ENTRIES joint entries, fewer when the direct
    index's packed 6 x 6 matrices (21 entries per limb line and per partial sum, each pose)
    are computed too; its per-posture ones take a fixed block (reference.BLOCK_POSTURES)."""
    entries = robot.dof * robot.postures
    if robot.direct_index_min is not None:
        low_bits, low_limbs, _ = partial_sum_split(robot)
        partial_sums = (robot.postures >> low_bits) + ((1 << low_bits) if low_limbs else 0)
        entries += len(PACKED) * (2 * robot.dof + partial_sums)
    return min(MAX_CHUNK_POSES, max(1000, CHUNK_ENTRIES // entries))


def singular_bounds(robot, reference_solution):
    """(n, dof) error bound for joints in their singular band; 0 where the fixed limits apply."""
    radicands = reference_solution.radicands
    scale = np.array([limb.singular_scale() for limb in robot.limbs])
    in_band = np.abs(radicands) <= SINGULAR_TOLERANCE + WARNING_BAND
    eps = np.finfo(float).eps
    with np.errstate(invalid="ignore"):
        bound = CONDITIONING_FACTOR * scale / np.sqrt(np.maximum(np.abs(radicands), eps))
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
class _Tally:
    """Running totals over the chunks of one verification."""

    calibrated: object = None
    """The robot with the dialog's fields applied, for the closure check."""
    returns_wrong: int = 0
    aborted: int = 0
    closure_worst: float = 0.0
    closure_checked: int = 0
    posture_counts: np.ndarray = None
    """(4, postures): right, wrong, unreachable wrongly, missed."""
    posture_worst: list = None
    """[mm (postures,), rad (postures,)] worst errors where both solve."""

    faulty_calls: int = 0
    fault_bits: int = 0
    first: tuple = None

    @classmethod
    def start(cls, calibrated):
        """Empty totals for ``calibrated`` (the robot with the dialog's fields applied)."""
        postures = calibrated.postures
        return cls(calibrated=calibrated, posture_counts=np.zeros((4, postures), dtype=np.int64),
                   posture_worst=[np.zeros(postures), np.zeros(postures)])

    def add(self, other):
        """Add the totals of a later chunk (its ``first`` counts only when none is kept yet)."""
        for name in ("returns_wrong", "aborted", "closure_checked", "faulty_calls"):
            setattr(self, name, getattr(self, name) + getattr(other, name))
        self.fault_bits |= other.fault_bits
        self.closure_worst = max(self.closure_worst, other.closure_worst)
        self.posture_counts += other.posture_counts
        self.posture_worst = [np.maximum(mine, theirs) for mine, theirs in zip(self.posture_worst, other.posture_worst)]
        if self.first is None:
            self.first = other.first


class _Printed:
    """What the routine printed on stdout/stderr over several captured blocks."""

    def __init__(self):
        self.bytes = 0
        self.first_line = ""

    @contextmanager
    def capture(self):
        with captured_output() as printed:
            yield
        self.bytes += printed["bytes"]
        if not self.first_line and printed["text"].strip():
            self.first_line = printed["text"].strip().splitlines()[0]


def verify(robot, plugin, options=VerifyOptions(), progress=None, phase=None, on_check=None):
    """Check ``plugin`` against ``robot``'s reference on ``options.samples`` seeded poses,
    its golden values and the interface contract. ``progress(done)`` is called after each
    chunk, ``phase(text)`` before each stage and ``on_check(check)`` as each check is
    decided (all optional). The dialog fields of ``options`` are passed to the routine
    and the reference alike; golden values are checked with empty fields (the published
    geometry). What the routine prints on stdout/stderr is reported as a notice."""
    report = _empty_report(robot, plugin.routine, options)
    phase = phase or (lambda text: None)
    printed = _Printed()

    def decided(checks):
        for check in checks:
            report.checks.append(check)
            if on_check is not None:
                on_check(check)

    phase("the interface checks")
    with printed.capture():
        decided(check_interface(robot, plugin))
    if (plugin.dof, plugin.postures) == (robot.dof, robot.postures):
        decided(_compare_samples(robot, plugin, report, options, progress, printed, phase))
        phase("the golden values")
        with printed.capture():
            report.golden = check_golden(robot, plugin)
        decided(Check(f"golden[{i}]", result.passed, _golden_detail(result)) for i, result in enumerate(report.golden))
        if options.snapshot is not None:
            phase("the snapshot")
            with printed.capture():
                decided([snapshot_check(robot, options.snapshot, _calls(plugin, options))])
    else:
        decided([Check("values", False, "not compared: the routine's joint or posture count differs")])
    if printed.bytes:
        report.notices.append(
            f"the routine printed {printed.bytes} bytes on stdout/stderr (first line: {printed.first_line!r}); "
            "debug printing slows the host by orders of magnitude"
        )
    return report


def _empty_report(robot, routine, options):
    return Report(robot=robot.name, routine=routine, samples=options.samples, seed=options.seed,
                  postures=robot.postures, tolerance_mm=value_tolerance_mm(robot),
                  tolerance_rad=VALUE_TOLERANCE_RAD)


def verify_library(robot, library, routine, options=VerifyOptions(), progress=None):
    """Load ``library`` and verify its ``routine`` in a child process. A plugin that crashes,
    exits or stops making progress for ``options.timeout`` seconds, at load time or in any
    call, gives a report whose last check is ``crash`` or ``timeout`` naming the stage;
    a plugin that breaks the interface before it can be called fails ``get_kin_config``.
    Bad input (no such file, not a library, unknown routine) raises KingenError."""
    checks = [definition_check(robot, library)]

    def on_message(kind, value):
        if kind == "progress" and progress is not None:
            progress(value)
        elif kind == "check":
            checks.append(value)

    try:
        report, failure = run_in_child(_verify_job, (robot, library, routine, options), options.timeout, on_message)
    except PluginDefect as defect:
        report, failure = None, None
        checks = [Check(defect.check, False, str(defect))]
    if report is not None:
        report.checks.insert(0, checks[0])
        return report
    report = _empty_report(robot, routine, options)
    report.checks.extend(checks)
    if failure is not None:
        report.checks.append(Check(failure.kind, False, failure.detail))
    return report


def _calls(plugin, options):
    def call(t6):
        plugin.reset_host()
        calls = plugin.call(t6, options.link_lengths, options.link_offsets)
        return calls.solutions, calls.warnings

    return call


def definition_check(robot, library):
    """``definition``: whether the library was built from this robot file (the sha256 it
    carries), from another one, or not by kingen (then the check passes, saying so)."""
    info = build_info(library)
    if info is None:
        return Check("definition", True, "the library carries no kingen build information (not built by kingen): "
                                         "its definition cannot be traced")
    if info.get("sha256") == robot.sha256:
        return Check("definition", True, f"built by kingen {info.get('kingen', '?')} from this robot file "
                                         f"(sha256 {robot.sha256[:16]})")
    return Check("definition", False, f"built by kingen {info.get('kingen', '?')} from another definition of "
                                      f"'{info.get('robot', '?')}': the library says sha256 "
                                      f"{info.get('sha256', '?')[:16]}, {robot.path.name} has {robot.sha256[:16]}: "
                                      "rebuild it from the reviewed file")


def _verify_job(channel, robot, library, routine, options):
    keep_freed_memory()
    printed = _Printed()
    with printed.capture():
        plugin = Plugin(library, routine)
    report = verify(robot, plugin, options, progress=lambda done: channel.send("progress", done),
                    phase=channel.stage, on_check=lambda check: channel.send("check", check))
    if printed.bytes:
        report.notices.insert(0, f"loading the library printed {printed.bytes} bytes on stdout/stderr "
                                 f"(first line: {printed.first_line!r})")
    return report


def _compare_samples(robot, plugin, report, options, progress, printed, phase):
    tally = _Tally.start(robot.calibrated(options.link_lengths, options.link_offsets))
    start = time.perf_counter()
    bounds = chunk_bounds(options.samples, chunk_size(robot))
    report.processes = process_count(options, len(bounds))
    deaths = []
    for begin, count, part in compared_chunks(robot, tally.calibrated, plugin, options, bounds, report.processes,
                                              phase, deaths):
        _merge(report, tally, printed, part)
        if progress is not None:
            progress(begin + count)
    report.seconds = time.perf_counter() - start
    report.posture_statistics = _posture_statistics(robot, tally)
    crashes = [Check("crash", False, f"a comparing process ended ({ending(code)}) during poses {begin} to "
                                     f"{begin + count - 1} of seed {options.seed}, which ran to the end when compared "
                                     "again in the first process: the routine crashed or exited all the same "
                                     "(--processes 1 compares every pose in one process)")
               for begin, count, code in deaths]
    phase("the determinism check")
    with printed.capture():
        return crashes + _sample_checks(robot, plugin, report, options, tally)


def _accumulate(robot, report, tally, revolute, t6, calls, expected):
    tally.faulty_calls += int(np.count_nonzero(calls.faults))
    tally.fault_bits |= int(np.bitwise_or.reduce(calls.faults)) if len(calls.faults) else 0
    aborted = (calls.faults & ~abi.WROTE_INPUTS) != 0
    if np.any(aborted):  # judged by the buffers check; its outputs are partial
        tally.aborted += int(np.count_nonzero(aborted))
        t6, expected, calls = t6[~aborted], _rows(expected, ~aborted), _rows(calls, ~aborted)
        if not len(t6):
            return
    columns = _compared_columns(robot, calls, expected)
    errors = joint_errors(columns.plugin, columns.reference, revolute)
    errors = np.where(~columns.reference_solves[:, None, :] & np.isfinite(columns.plugin), 0.0, errors)
    bounds = singular_bounds(robot, expected)[:, :, None]
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
    closure_worst, closure_checked = closure_error(tally.calibrated, expected, calls.solutions)
    tally.closure_worst = max(tally.closure_worst, closure_worst)
    tally.closure_checked += closure_checked
    if tally.first is None:
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


def _compared_columns(robot, calls, expected):
    """The _Columns of one chunk: by branch when the routine allows it and the robot has more
    than two postures, else by posture."""
    reference_solves = expected.warnings != UNREACHABLE
    same_reach = (np.array_equal(calls.warnings != UNREACHABLE, reference_solves)
                  and np.array_equal(reference_solves, np.broadcast_to(reference_solves[:, :1], reference_solves.shape)))
    table = branch_table(robot)
    if robot.postures > 2 and same_reach and _repeats_branches(robot, calls.solutions):
        weights = np.array([[np.count_nonzero(table[:, index] == branch) for branch in range(2)]
                            for index in range(robot.dof)])
        reach = np.repeat(reference_solves[:, :1], 2, axis=1)
        return _Columns(branch_values(robot, calls.solutions), expected.branch_joints, reach, reach, table, weights)
    postures = np.arange(robot.postures)
    return _Columns(calls.solutions, expected.joints, reference_solves,
                    reference_solves & (calls.warnings != UNREACHABLE),
                    np.repeat(postures[:, None], robot.dof, axis=1), np.ones((robot.dof, robot.postures), dtype=int))


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


def _posture_statistics(robot, tally):
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


def closure_error(robot, expected, solutions):
    """(largest |closure residual| / passive-link length, joints judged): each limb's joint
    of each of its branches, as the routine returned it in the first posture taking that
    branch, put back into the limb's geometry (``robot`` calibrated as for the call); the
    values check holds every other posture to the same reference. Only postures the
    reference calls reachable count; NaN joints count as infinitely wrong. Limbs in their
    singular band are left out: there, with -1e-5 <= D < 0, the joint is the limb's closest
    approach, which misses closing by design (by up to D l / 2)."""
    representative = representative_postures(robot)
    reachable = expected.warnings != UNREACHABLE
    closing = np.abs(expected.radicands) > SINGULAR_TOLERANCE + WARNING_BAND
    worst, judged_count = 0.0, 0
    for index, limb in enumerate(robot.limbs):
        point = expected.points[:, index]
        for posture in representative[index, :limb.branches]:
            miss, length = _closure_miss(limb, point, solutions[:, index, posture])
            with np.errstate(all="ignore"):
                relative = miss / length
            relative = np.where(np.isfinite(relative), relative, np.inf)
            judged = reachable[:, posture] & closing[:, index]
            judged_count += int(np.count_nonzero(judged))
            if np.any(judged):
                worst = max(worst, float(np.max(np.where(judged, relative, 0.0))))
    return worst, judged_count


def _closure_miss(limb, points, joints):
    """(|closure residual|, |passive-link length|) (n,) (n,), mm, of ``limb`` at its platform
    points (n, 3) and joints (n,): by how much the joints miss closing the limb (NaN for NaN joints)."""
    with np.errstate(all="ignore"):
        return np.abs(limb.closure_residual(points, joints)), np.abs(limb.passive_length(joints))


def jacobian_check(robot, plugin, options, t6):
    """Finite differences of the routine's own joints along the six unit twists, against
    the analytic Jacobian of the limbs' constraint geometry (kingen.singularity), on the
    reachable, regular postures of ``t6``: catches a formula mistake the routine and the
    reference share."""
    calibrated = robot.calibrated(options.link_lengths, options.link_offsets)
    expected = solve(robot, t6, options.link_lengths, options.link_offsets)
    plugin.reset_host()
    center = plugin.call(t6, options.link_lengths, options.link_offsets).solutions
    wrenches, transmissions = posture_wrenches(calibrated, expected.points, center)
    analytic = np.swapaxes(jacobian(wrenches, transmissions), 1, 2)

    def joints_of(moved):
        plugin.reset_host()
        return plugin.call(moved, options.link_lengths, options.link_offsets).solutions

    # Richardson's extrapolation of central differences at h and h/2: truncation error O(h^4).
    coarse, fine = (finite_difference_jacobian(joints_of, t6, JACOBIAN_STEP * robot.size_mm / halving,
                                               JACOBIAN_STEP / halving, robot.revolute) for halving in (1, 2))
    numeric = (4.0 * fine - coarse) / 3.0
    regular = ((expected.warnings == abi.WARNINGS["WARN_GOOD_SOLUTION"])[:, None, :]
               & (np.abs(np.swapaxes(transmissions, 1, 2)) > JACOBIAN_MIN_TRANSMISSION)
               & np.all(expected.radicands > JACOBIAN_MIN_RADICAND, axis=1)[:, None, None])
    # Rotations in mm of arc at the robot's size, so that all six twists weigh alike.
    units = np.array([1.0] * 3 + [1.0 / robot.size_mm] * 3)
    with np.errstate(all="ignore"):
        relative = (np.max(np.abs(numeric - analytic) * units, axis=-1)
                    / np.max(np.abs(analytic) * units, axis=-1))
    relative = np.where(regular, np.where(np.isfinite(relative), relative, np.inf), 0.0)
    worst, compared = float(relative.max(initial=0.0)), int(np.count_nonzero(regular))
    passed = worst <= JACOBIAN_TOLERANCE
    detail = (f"finite differences of the routine's joints against the analytic Jacobian on {compared} "
              f"regular joint-postures of {len(t6)} poses: max relative difference {worst:.3g} "
              f"(at most {JACOBIAN_TOLERANCE:g})")
    return Check("jacobian", passed, detail)


def round_trip_check(robot, plugin, options, t6):
    """Forward kinematics seeded at each sampled pose, from the routine's joints of its
    regular postures (about ROUND_TRIP_POSTURES in all), must return that pose: within the
    value bound (mm) and 1e-9 rad, or within what the joints explain through the posture's
    conditioning (pose_conditioning): their closure residual at that pose, as far as the
    closure check accepts it (CLOSURE_TOLERANCE), plus rounding (CONDITIONING_FACTOR x
    size), over the conditioning. Joints a few units in the last place from the reference's
    thus go round as well as its own; joints the closure check refuses do not."""
    if not robot.has_forward:
        return Check("round trip", True, f"not available: forward kinematics needs free pose coordinates for a "
                                         f"robot with {robot.dof} limbs (forward: {{free: [...]}})")
    calibrated = robot.calibrated(options.link_lengths, options.link_offsets)
    expected = solve(robot, t6, options.link_lengths, options.link_offsets)
    plugin.reset_host()
    joints = plugin.call(t6, options.link_lengths, options.link_offsets).solutions
    wrenches, transmissions = posture_wrenches(calibrated, expected.points, joints)
    candidates = ((expected.warnings == abi.WARNINGS["WARN_GOOD_SOLUTION"])
                  & np.all(np.abs(transmissions) > JACOBIAN_MIN_TRANSMISSION, axis=2)
                  & np.all(expected.radicands > JACOBIAN_MIN_RADICAND, axis=1)[:, None])
    # About ROUND_TRIP_POSTURES of them, along diagonals of (pose, posture), so that every posture takes part.
    stride = max(1, -(-int(np.count_nonzero(candidates)) // ROUND_TRIP_POSTURES))
    pose_number, posture_number = np.indices(candidates.shape)
    pose_index, posture = np.nonzero(candidates & ((pose_number + posture_number) % stride == 0))
    sampled = pose_from_t6(t6)
    start = np.concatenate([sampled[:, :3], np.radians(sampled[:, 3:])], axis=1)[pose_index]
    free = free_mask(calibrated)
    conditioning = pose_conditioning(robot, wrenches[pose_index, posture], start, free)
    regular = conditioning > ROUND_TRIP_MIN_CONDITIONING
    pose_index, posture, conditioning, start = (kept[regular] for kept in (pose_index, posture, conditioning, start))
    if not len(pose_index):
        return Check("round trip", True, "no regular posture among the sampled poses to go round")
    routine_joints = joints[pose_index, :, posture]
    residual = np.zeros(len(pose_index))  # the joints' closure residual, as far as the closure check accepts it
    for index, limb in enumerate(calibrated.limbs):
        miss, length = _closure_miss(limb, expected.points[pose_index, index], routine_joints[:, index])
        residual = np.fmax(residual, np.fmin(miss, CLOSURE_TOLERANCE * length))
    found, _ = newton(calibrated, start, routine_joints, free)
    position = np.max(np.abs(found[:, :3] - start[:, :3]), axis=1)
    rotation = np.max(np.abs(t6_of(found)[:, :3, :3] - t6_of(start)[:, :3, :3]), axis=(1, 2))
    explained_mm = 2.0 * (np.sqrt(robot.dof) * residual + CONDITIONING_FACTOR * robot.size_mm) / conditioning
    allowed_mm = np.maximum(report_tolerance_mm(robot), explained_mm)
    allowed_rad = np.maximum(VALUE_TOLERANCE_RAD, explained_mm / robot.size_mm)
    passed = bool(np.all(position <= allowed_mm) and np.all(rotation <= allowed_rad))
    worst_mm, worst_rad = float(np.max(position)), float(np.max(rotation))
    return Check("round trip", passed,
                 f"forward kinematics from the routine's joints of {len(pose_index)} regular postures of {len(t6)} "
                 f"poses returns each pose within {worst_mm:.3g} mm and {worst_rad:.3g} rad (bounds "
                 f"{report_tolerance_mm(robot):.3g} mm, {VALUE_TOLERANCE_RAD:g} rad, or what the joints' closure "
                 f"residual and rounding explain through the posture's conditioning; postures near a singularity, "
                 f"where the pose is ill-conditioned, are left out)")


def pose_conditioning(robot, wrenches, poses, free):
    """The smallest singular value (m,) of the closure's derivative with respect to the free
    pose coordinates (what forward kinematics solves for) at poses (m, 6) (mm, radians):
    forward.closure_derivative of the limbs' unit wrenches (m, dof, 6), the matrix Newton
    solves with, rotations per mm of arc at the robot's size. Dimensionless (mm of closure per mm of pose); 0 at a singularity and
    where the free coordinates are not all determined; non-finite counts as 0."""
    scale = np.array([1.0] * 3 + [1.0 / robot.size_mm] * 3)[free]
    with np.errstate(all="ignore"):
        matrix = closure_derivative(wrenches, poses, free) * scale
    finite = np.all(np.isfinite(matrix), axis=(1, 2))
    matrix = np.where(finite[:, None, None], matrix, 0.0)
    return np.where(finite, np.linalg.svd(matrix, compute_uv=False)[:, -1], 0.0)


def _sample_checks(robot, plugin, report, options, tally):
    buffers = buffers_check(tally.faulty_calls, tally.fault_bits)
    if tally.first is None:
        return [Check(name, False, "not compared: every call was stopped at a write outside its buffers")
                for name in ("values", "warnings", "return value")] + [buffers]
    t6, solutions, warnings, reference_joints, reference_warnings = tally.first
    values_ok = (report.max_abs_error_mm <= report.tolerance_mm and report.max_abs_error_rad <= report.tolerance_rad
                 and report.singular_out_of_bound == 0)
    aborted = f" ({tally.aborted} calls stopped at a write outside their buffers left out)" if tally.aborted else ""
    values = Check("values", values_ok,
                   f"max |error| {report.max_abs_error_mm:.3g} mm, {report.max_abs_error_rad:.3g} rad over "
                   f"{report.samples - tally.aborted} poses x {report.postures} postures{aborted}; "
                   f"{report.singular_entries} entries in a singular band, {report.singular_out_of_bound} beyond "
                   f"their bound (bounds {report.tolerance_mm:.3g} mm, {report.tolerance_rad:.3g} rad)")
    if not values_ok:
        values.diagnoses = diagnose(robot, t6, solutions, reference_joints, reference_warnings)
    warnings_check = Check("warnings", report.warning_mismatches == 0,
                           f"{report.warning_mismatches} mismatches, {report.warnings_in_band} inside the tolerance band")
    if not warnings_check.passed:
        warnings_check.diagnoses = diagnose_warnings(warnings, reference_warnings, abi.WARNING_NAMES)
    checks = [values, warnings_check]
    checks.append(Check("return value", tally.returns_wrong == 0,
                        f"{tally.returns_wrong} calls return other than 1 when no posture is reachable, 0 otherwise"))
    checks.append(buffers)
    checks.append(Check("closure", tally.closure_worst <= CLOSURE_TOLERANCE,
                        f"each limb's joint of each branch put back into the limb geometry: worst relative "
                        f"residual {tally.closure_worst:.3g} over {tally.closure_checked} joints "
                        f"(at most {CLOSURE_TOLERANCE:g} of the link length)"))
    checks.append(jacobian_check(robot, plugin, options, t6[:JACOBIAN_POSES]))
    checks.append(round_trip_check(robot, plugin, options, t6[:ROUND_TRIP_POSES]))
    plugin.reset_host()
    again = plugin.call(t6[:DETERMINISM_POSES], options.link_lengths, options.link_offsets)
    same = (np.array_equal(again.solutions, solutions[:DETERMINISM_POSES], equal_nan=True)
            and np.array_equal(again.warnings, warnings[:DETERMINISM_POSES]))
    checks.append(Check("determinism", same, "the same T6 gives the same output" if same
                        else "calling again with the same T6 gives different output (state kept between calls?)"))
    return checks


def buffers_check(faulty_calls, fault_bits):
    """The ``buffers`` check from the guarded driver's per-call fault bits."""
    if not faulty_calls:
        return Check("buffers", True, "no call wrote outside solutions/warnings (each against an "
                                      "inaccessible page) and inputs stayed untouched")
    what = "; ".join(text for bit, text in abi.GUARD_FAULTS.items() if fault_bits & bit)
    return Check("buffers", False, f"{faulty_calls} calls: the routine {what}")


def _golden_detail(result):
    return (f"{result.source}: pose {result.pose} posture {result.posture}: expected {result.expected}, "
            f"plugin {[round(v, 6) for v in result.plugin]}, reference {[round(v, 6) for v in result.reference]}, "
            f"tolerance {result.tolerance:g}")


def check_golden(robot, plugin):
    """Each golden value of the robot against the plugin and the reference, in YAML units."""
    results = []
    scale = robot.joint_scale()
    for golden in robot.golden:
        t6 = t6_from_pose(np.asarray([golden.pose]))
        plugin.reset_host()
        from_plugin = plugin.call(t6).solutions[0, :, golden.posture] / scale
        from_reference = solve(robot, t6).joints[0, :, golden.posture] / scale
        expected = np.asarray(golden.joints)
        passed = bool(
            np.all(np.abs(from_plugin - expected) <= golden.tolerance)
            and np.all(np.abs(from_reference - expected) <= golden.tolerance)
        )
        results.append(GoldenResult(
            source=" ".join(golden.source.split()), pose=list(golden.pose), posture=golden.posture,
            expected=list(golden.joints), plugin=[float(v) for v in from_plugin],
            reference=[float(v) for v in from_reference], tolerance=golden.tolerance, passed=passed,
        ))
    return results


def check_interface(robot, plugin):
    """The interface contract of docs/delmia-abi.md as named checks, each failure in one sentence."""
    config = plugin.config
    problems = []
    if (config.dof, config.solutions) != (robot.dof, robot.postures):
        problems.append(f"answers {config.dof} joints and {config.solutions} solutions; "
                        f"the robot has {robot.dof} and {robot.postures}")
    if config.data_hint not in (abi.CONSTANTS["USR_KIN_DATA_NULL"], abi.CONSTANTS["USR_KIN_DATA_KINSTAT"]):
        problems.append(f"answers an unknown data hint {config.data_hint}")
    if plugin.kin_config(plugin.routine + "_unknown").status == 0:
        problems.append(f"accepts a routine name that is not '{plugin.routine}'")
    checks = [Check("get_kin_config", not problems, "; ".join(problems) or
                    f"answers '{plugin.routine}' with {config.dof} joints, {config.solutions} solutions, "
                    f"hint {config.data_hint}; refuses other names")]
    home = t6_from_pose(np.asarray([robot.verification.home]))

    plugin.reset_host()
    plugin.call(home)
    calls, dof, solutions = host_state()
    expected = (1, plugin.dof, plugin.postures)
    checks.append(Check("kin_check_definition", (calls, dof, solutions) == expected,
                        f"called {calls} times, last with ({dof}, {solutions}); expected once with "
                        f"({plugin.dof}, {plugin.postures})"))

    plugin.reset_host(refuse=True)
    refused = plugin.call(home)
    plugin.reset_host()
    problems = []
    if refused.returned[0] != 1:
        problems.append(f"returns {refused.returned[0]}, not 1")
    if not (np.all(np.isnan(refused.solutions)) and np.all(refused.warnings == UNWRITTEN_WARNING)):
        problems.append("writes solutions or warnings")
    checks.append(Check("refusal", not problems, "when kin_check_definition refuses, the routine " +
                        (" and ".join(problems) if problems else "returns 1 and writes nothing")))

    problems = []
    for bad in (np.nan, np.inf):
        t6 = home.copy()
        t6[0, 3, 0] = bad
        result = plugin.call(t6)
        if not (result.returned[0] == 1 and np.all(np.isfinite(result.solutions))
                and np.all(result.warnings == abi.WARNINGS["WARN_UNREACHABLE"])):
            problems.append(f"a T6 holding {bad} gives return {result.returned[0]}, "
                            f"{'finite' if np.all(np.isfinite(result.solutions)) else 'non-finite'} joints, "
                            f"warnings {sorted(set(result.warnings[0].tolist()))}")
    checks.append(Check("non-finite T6", not problems, "; ".join(problems) or
                        "NaN and inf give return 1, finite joints, WARN_UNREACHABLE everywhere"))
    return checks


