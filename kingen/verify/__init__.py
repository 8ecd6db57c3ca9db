"""Verification: a compiled routine (kingen's or hand-written) against the numpy
reference, the golden values and the interface contract (docs/explanation/verify.md).

Everything is compared, nothing sampled away: every joint of every posture of
every pose, and every warning. Where the reference calls a posture unreachable the
interface asks only for finite joints, so only finiteness is checked there (the
warning itself is compared as everywhere). A warning may differ only inside the documented
tolerance band (``WARNING_BAND``): where the reference's decision quantity (a
normalised radicand or a joint value) lies that close to its threshold, both
answers are right within floating-point rounding. Each clause is a named check;
failed value checks carry diagnoses (:mod:`kingen.verify.diagnose`).

This module orchestrates only: the poses are drawn and compared in chunks over processes
by :mod:`kingen.verify.processes`, tallied by :mod:`kingen.verify.tally`, and judged by the
checks of :mod:`kingen.verify.checks`, each in its own module; a routine's host composes
which checks it gets (its ``checks`` tuple), verify runs them in that order.

``verify`` runs in the calling process (for tests and kingen's own code);
``verify_library`` loads and verifies a library in a child process
(:mod:`kingen.runtime.isolation`), so that a crash, an ``exit()`` or a hang in foreign code
becomes a failed check instead of a dead, silent or stuck kingen.
"""

import functools
import platform
import time
from dataclasses import asdict

from ..errors import KingenError, PluginDefect
from ..runtime.isolation import ending, keep_freed_memory, killed_from_outside, killer, run_in_child
from ..kinematics.poses import chunk_bounds
from .report import Report
from ..runtime.wire import typed
from .checks import PHASES, Check, Context, by_need
from .options import VerifyOptions, report_tolerance_mm, value_tolerance_mm
from .boundaries import boundary_poses
from .cluster import ClusterChunks
from .processes import Printed, chunk_size, compare_poses, compared_chunks, empty_report, merge, process_count
from .tally import Tally, posture_statistics
from .evidence import answers, decoder, unconfirmed

__all__ = ["VerifyOptions", "chunk_size", "report_tolerance_mm", "value_tolerance_mm", "verify", "verify_library"]


def verify(robot, plugin, options=VerifyOptions(), progress=None, phase=None, on_check=None, loaded_from=None):
    """Check the loaded routine ``plugin`` against ``robot``'s reference on ``options.samples``
    seeded poses, its golden values and its host's contract: the checks of ``plugin.checks``
    but those that need the library file. ``progress(done)`` is called after each chunk,
    ``phase(text)`` before each stage and ``on_check(check)`` as each check is decided (all
    optional). The calibration fields of ``options`` are passed to the routine and the
    reference alike; golden values are checked with empty fields (the published geometry).
    What the routine prints on stdout/stderr is reported as a notice. ``loaded_from`` (host,
    library path, routine name) is where ``plugin`` came from: what the workers of a cluster
    load (``options.scheduler``)."""
    report = empty_report(robot, plugin.routine, options)
    report.interface_checks = _interface_names(plugin.checks)
    phase = phase or (lambda text: None)
    printed = Printed()
    context = Context(robot=robot, options=options, routine=plugin, report=report)

    def decided(checks):
        for check in checks:
            report.checks.append(check)
            if on_check is not None:
                on_check(check)

    def run(need):
        phase(PHASES[need])
        with printed.capture():
            decided([result for check in by_need(plugin.checks, need) for result in check.run(context)])

    run("routine")
    if (plugin.dof, plugin.postures) == (robot.joint_count, robot.postures):
        decided(_compare_samples(context, progress, printed, phase, loaded_from))
        run("golden values")
        if options.snapshot is not None:
            run("snapshot")
    else:
        decided([Check("values", False, "not compared: the routine's joint or posture count differs")])
    if printed.bytes:
        report.notices.append(
            f"the routine printed {printed.bytes} bytes on stdout/stderr (first line: {printed.first_line!r}); "
            "debug printing slows the host by orders of magnitude"
        )
    report.notices.extend(robot.left_out)
    return report


def verify_library(robot, library, routine, options=VerifyOptions(), progress=None, *, host):
    """Load ``library`` through ``host`` (a kingen.hosts.Host) and verify its ``routine`` in a
    child process, after the checks that read only the library file (``definition``). A
    library that crashes, exits or stops making progress for ``options.timeout`` seconds, at
    load time or in any call, gives a report whose last check is ``crash`` or ``timeout``
    naming the stage; one that breaks the host's interface before it can be called fails the
    check the host names. Bad input (no such file, not a library, unknown routine) raises
    KingenError."""
    context = Context(robot=robot, options=options, library=library)
    checks = [result for check in by_need(host.checks, "library") for result in check.run(context)]
    on_file = len(checks)
    isolation, evidence = [], []

    def on_message(kind, value):
        if kind == "progress" and progress is not None:
            progress(value)
        elif kind == "check":
            checks.append(value)
        elif kind == "evidence":
            evidence.append(value)

    host.prepare_load()
    if options.scheduler is not None:
        # Dask's client asks for the processor's name, which runs uname(1): a program the
        # sandbox would refuse; asked here, it is cached for the child.
        platform.uname().processor
    try:
        report, failure = run_in_child(_verify_job, (robot, library, routine, host, options), options.timeout,
                                       on_message, first_stage=host.loading_stage,
                                       decoders={**REPORT_DECODERS, "evidence": decoder(options)},
                                       network=options.scheduler is not None, on_isolation=isolation.append)
    except PluginDefect as defect:
        report, failure = None, None
        checks = [Check(defect.check, False, str(defect))]
    if report is not None:
        report.checks[:0] = checks[:on_file]
        report.isolation = "".join(isolation[:1])
        forged = unconfirmed(robot, options, report, evidence[0] if evidence else None)
        report.checks.extend([forged] if forged is not None else [])
        return report
    report = empty_report(robot, routine, options)
    report.isolation = "".join(isolation[:1])
    report.interface_checks = _interface_names(host.checks)
    report.checks.extend(checks)
    if failure is not None:
        report.checks.append(Check(failure.kind, False, failure.detail))
    return report


REPORT_DECODERS = {"result": functools.partial(typed, Report), "check": functools.partial(typed, Check),
                   "progress": functools.partial(typed, int)}
"""What verify's child sends, checked field by field before use (kingen.runtime.wire): the report is
only data here, and its verdict (Report.passed) is computed from its checks in this process."""


def _interface_names(checks):
    """The names of the checks run on the loaded routine before any pose: its interface."""
    return tuple(check.name for check in by_need(checks, "routine"))


def _verify_job(channel, robot, library, routine, host, options):
    keep_freed_memory()
    printed = Printed()
    with printed.capture():
        plugin = host.load(library, routine, robot)
    report = verify(robot, plugin, options, progress=lambda done: channel.send("progress", done),
                    phase=channel.stage, on_check=lambda check: channel.send("check", check),
                    loaded_from=(host, library, routine))
    if printed.bytes:
        report.notices.insert(0, f"loading the library printed {printed.bytes} bytes on stdout/stderr "
                                 f"(first line: {printed.first_line!r})")
    if (plugin.dof, plugin.postures) == (robot.joint_count, robot.postures):
        with printed.capture():
            channel.send("evidence", answers(robot, plugin, options))
    return report


def _compare_samples(context, progress, printed, phase, loaded_from):
    """Compare the sampled poses chunk by chunk, then run the checks that judge them."""
    robot, plugin, report, options = context.robot, context.routine, context.report, context.options
    tally = Tally.start(robot.calibrated(options.link_lengths, options.link_offsets))
    start = time.perf_counter()
    bounds = chunk_bounds(options.samples, chunk_size(robot))
    deaths = []
    for begin, count, part in _sample_parts(context, tally.calibrated, bounds, loaded_from, phase, deaths):
        merge(report, tally, printed, part)
        if progress is not None:
            progress(begin + count)
    phase("the warnings' boundary poses")
    boundary, found, searched = boundary_poses(robot, options.seed, options.link_lengths, options.link_offsets,
                                               getattr(plugin, "warning_vocabulary", None))
    report.boundary_poses = {"poses": len(boundary), "boundaries_found": found,
                             "searched": {kind: asdict(descent) for kind, descent in searched.items()}}
    if len(boundary):
        part = compare_poses(boundary, first=True)
        tally.boundary_first, part.tally.first = part.tally.first, None  # for the warnings' diagnoses
        tally.boundary_reachable = part.tally.reachable_poses
        merge(report, tally, printed, part)
    report.seconds = time.perf_counter() - start
    report.posture_statistics = posture_statistics(robot, tally)
    crashes = [Check("crash", False, _death(begin, count, code, options.seed)) for begin, count, code in deaths]
    context.tally = tally
    phase(PHASES["compared poses"])
    with printed.capture():
        return crashes + _sample_checks(context)


def _sample_parts(context, calibrated, bounds, loaded_from, phase, deaths):
    """(first index, pose count, _Part) of the chunks ``bounds``, in order: compared by local
    processes (compared_chunks), or by a cluster's workers with ``options.scheduler``
    (kingen.verify.cluster); sets the report's ``processes``; failed ones go to ``deaths``."""
    robot, plugin, report, options = context.robot, context.routine, context.report, context.options
    if options.scheduler is None:
        report.processes = process_count(options, len(bounds))
        yield from compared_chunks(robot, calibrated, plugin, options, bounds, report.processes, phase, deaths)
        return
    if loaded_from is None:
        raise KingenError("--scheduler: the routine must be verified from its library file")
    with ClusterChunks(robot, calibrated, plugin, options, bounds, loaded_from, phase) as cluster:
        report.processes = cluster.count
        yield from cluster.parts()
    deaths.extend(cluster.deaths)


def _death(begin, count, code, seed):
    """What the ``crash`` check says of a comparing process that died during poses ``begin``
    .. ``begin + count - 1`` (which then ran to the end in the first process): the routine
    crashed or exited there, or, for a process killed_from_outside, something outside killed
    it, which is no crash of the routine but leaves the run disturbed. ``code`` is a text for
    a cluster's job (kingen.verify.cluster)."""
    where = f"during poses {begin} to {begin + count - 1} of seed {seed}"
    if isinstance(code, str):  # a cluster's job: what failed, not an exit code
        return (f"a cluster worker's job failed ({code}) {where}, which ran to the end when compared again in this "
                "process: the routine crashed or exited on the worker, or the cluster lost it: run it again")
    if killed_from_outside(code):
        return (f"a comparing process was {killer(code)} {where}, not ended by the routine; those poses ran to the "
                "end when compared again in the first process, but the run was disturbed: run it again "
                "(--processes 1 needs the least memory)")
    return (f"a comparing process ended ({ending(code)}) {where}, which ran to the end when compared again in the "
            "first process: the routine crashed or exited all the same (--processes 1 compares every pose in one "
            "process)")


def _sample_checks(context):
    """The checks that judge the sampled calls, in order: those that need compared poses
    report their ``uncompared`` failure, or are left out, when every call was stopped."""
    results = []
    for check in context.routine.checks:
        if check.needs == "sampled calls":
            results.extend(check.run(context))
        elif check.needs == "compared poses":
            if context.tally.first is not None:
                results.extend(check.run(context))
            elif check.uncompared is not None:
                results.append(Check(check.name, False, check.uncompared))
    return results
