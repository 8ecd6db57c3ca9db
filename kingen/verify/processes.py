"""How a verification's poses are compared: in chunks of flat memory, shared among forked
comparing processes (one per core by default), each drawing its own chunks' poses and
sending back only a chunk's totals. The report is the same whatever the process count."""

import multiprocessing
from contextlib import contextmanager, nullcontext
from dataclasses import dataclass, replace

import numpy as np

from ..conventions import t6_from_pose
from ..runtime.cores import usable_cores
from ..runtime.household import die_with_parent
from ..runtime.isolation import captured_output
from ..kinematics.poses import PoseStream
from ..kinematics.reference import CERTIFY_PROBE_POSES, certificate_settles, solve
from .report import Report
from ..kinematics.routine import VALUE_TOLERANCE_RAD, WARNINGS
from ..kinematics.singularity import PACKED, partial_sum_split
from .options import value_tolerance_mm
from .tally import Tally, accumulate, compares_by_branch

CHUNK_ENTRIES = 2000000
"""Joint entries (poses x dof x postures) per batch, within 1000 and MAX_CHUNK_POSES poses:
large enough for numpy to work in long runs, small enough for flat memory."""
MAX_CHUNK_POSES = 8192


PROBE_SEED = 0
"""The seed of the region's poses chunk_size probes the certificate on (any would do: the
chunk size depends on the robot alone, whatever a verification's seed)."""


def chunk_size(robot):
    """Poses per batch for ``robot``: about CHUNK_ENTRIES joint entries, fewer when the direct
    index's packed 6 x 6 matrices (21 entries per limb line and per partial sum, each pose)
    are computed too; its per-posture ones take a fixed block (reference.BLOCK_POSTURES).
    They are not where the certificate settles the index (reference.certificate_settles on
    the region's first poses of PROBE_SEED: CEART's 64 postures, whose chunks then hold
    5,208 poses instead of 2,057: 8 to 13 % less processor time, measured)."""
    entries = robot.dof * robot.postures
    if robot.direct_index_min is not None and not certificate_settles(
            robot, t6_from_pose(PoseStream(robot, PROBE_SEED).draw(CERTIFY_PROBE_POSES))):
        low_bits, low_limbs, _ = partial_sum_split(robot)
        partial_sums = (robot.postures >> low_bits) + ((1 << low_bits) if low_limbs else 0)
        entries += len(PACKED) * (2 * robot.dof + partial_sums)
    return min(MAX_CHUNK_POSES, max(1000, CHUNK_ENTRIES // entries))


def process_count(options, chunks):
    """How many processes compare ``chunks`` chunks: ``options.processes`` (None:
    usable_cores()), at most one per chunk; one where processes cannot be forked."""
    if "fork" not in multiprocessing.get_all_start_methods():
        return 1
    return max(1, min(chunks, usable_cores() if options.processes is None else options.processes))


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


def set_chunk_job(robot, calibrated, plugin, options):
    """What compare_poses compares in this process: ``robot``'s reference (``calibrated``: with
    the options' fields applied) against the loaded routine ``plugin``."""
    global _chunk_job
    _chunk_job = (robot, calibrated, plugin, options)


def _compare_chunk(poses, first=False):
    """One of the sample's chunks: compare_poses (tests count and fail these)."""
    return compare_poses(poses, first)


def compare_poses(poses, first=False, captured=True):
    """Call the routine on ``poses`` (m, 6; mm, degrees), solve the reference and compare: a
    _Part (with the poses kept for diagnoses only for the ``first`` chunk; nothing else
    heavy, so that it travels between processes cheaply), for set_chunk_job's routine.
    What the call prints is counted when ``captured`` (a routine run here, not its answers)."""
    robot, calibrated, plugin, options = _chunk_job
    report = empty_report(robot, plugin.routine, options)
    tally = Tally.start(calibrated)
    printed = Printed()
    t6 = t6_from_pose(poses)
    plugin.reset_host()
    # A host that can summarise the solutions by limb branch as it calls (kingen.verify.tally uses it).
    summarises = getattr(plugin, "summarises_branches", False) and compares_by_branch(robot)
    summary = {"branches_of": robot} if summarises else {}
    with printed.capture() if captured else nullcontext():
        calls = plugin.call(t6, options.link_lengths, options.link_offsets, **summary)
    expected = in_vocabulary(solve(robot, t6, options.link_lengths, options.link_offsets), plugin)
    accumulate(robot, report, tally, robot.revolute, t6, calls, expected, keep_first=first)
    counts = {name: getattr(report, name) for name in REPORT_COUNTS + REPORT_WORST}
    tally.calibrated = None
    return _Part(counts, tally, printed.bytes, printed.first_line)


def compared_chunks(robot, calibrated, plugin, options, bounds, processes, phase, deaths):
    """(first index, pose count, _Part) chunk by chunk, in order, for the chunks ``bounds``
    (chunk_bounds) of PoseStream's poses. With ``processes`` (process_count) above 1, the
    other comparing processes (_Helpers, forked before chunk 0) each compare the chunks
    _taker gives them, ahead of this one, which draws and compares only its own. If one dies
    (the routine crashed or exited there, or something outside killed it: the out-of-memory
    killer, say), its chunks are drawn and compared here again, so that a crash is named by
    this process's stage as always; if they run to the end here, (first index, pose count,
    exit code) of the chunk it died in is appended to ``deaths``, for the ``crash`` check to
    tell which of those it was (kingen.runtime.isolation.killed_from_outside)."""
    set_chunk_job(robot, calibrated, plugin, options)
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


def merge(report, tally, printed, part):
    """Add one chunk's _Part to the verification's report, totals and printed output."""
    for name in REPORT_COUNTS:
        setattr(report, name, getattr(report, name) + part.counts[name])
    for name in REPORT_WORST:
        setattr(report, name, max(getattr(report, name), part.counts[name]))
    tally.add(part.tally)
    printed.bytes += part.printed_bytes
    printed.first_line = printed.first_line or part.printed_first_line


class Printed:
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


def in_vocabulary(expected, plugin):
    """The reference's solution with the warnings ``plugin`` cannot give (its optional
    ``warning_vocabulary``: a LinuxCNC module without a status pin tells only good from
    unreachable) read as WARN_GOOD_SOLUTION, but a limb's singular band where its radicand is
    negative as WARN_UNREACHABLE: what such a routine is judged by."""
    vocabulary = getattr(plugin, "warning_vocabulary", None)
    if vocabulary is None:
        return expected
    codes = [WARNINGS[name] for name in vocabulary]
    warnings = expected.warnings
    if WARNINGS["WARN_SINGULAR_SOLUTION"] not in codes:
        # Inside a limb's singular band a routine without that warning may call the pose
        # unreachable where the radicand is negative: the reference's closest approach there.
        past = np.any(expected.radicands < 0, axis=1)[:, None] & (warnings == WARNINGS["WARN_SINGULAR_SOLUTION"])
        warnings = np.where(past, WARNINGS["WARN_UNREACHABLE"], warnings)
    warnings = np.where(np.isin(warnings, codes), warnings, WARNINGS["WARN_GOOD_SOLUTION"])
    return replace(expected, warnings=warnings.astype(expected.warnings.dtype))


def empty_report(robot, routine, options):
    return Report(robot=robot.name, routine=routine, samples=options.samples, seed=options.seed,
                  postures=robot.postures, tolerance_mm=value_tolerance_mm(robot),
                  tolerance_rad=VALUE_TOLERANCE_RAD)
