"""Benchmarks: nanoseconds per routine call through the C batch driver and through one
cffi call per pose, and the reference's and verify's poses per second. Figures are
printed, never asserted: speed targets live here, not in unit tests.

The routine is timed through the runners its host's loaded routine offers
(``batch_runner`` and ``each_runner``, as DELMIA's plugin does), and, where it offers
``call_times(t6, calls)`` (each call timed singly), the median and the worst call.

Memory is bounded whatever the call count: the routine is timed over a pool of at most
``POOL_POSES`` distinct poses, passed over repeatedly until ``calls`` calls are made."""

import statistics
import time

from typing_extensions import NotRequired, TypedDict

from ..conventions import t6_from_pose
from ..errors import PluginDefect
from ..runtime.isolation import captured_output
from ..kinematics.poses import sample_poses
from ..kinematics.reference import solve
from ..runtime.text import shorten
from . import VerifyOptions, verify, verify_library

PER_CALL_LIMIT = 20000
"""The per-call cffi path is slow; it is timed on at most this many poses."""
POOL_POSES = 20000
ROUNDS = 9
"""Rounds of timings in turns when routines are compared."""
VERIFY_LIMIT = 200000
"""verify's poses per second are measured on at most this many poses."""
FLOOR_SAMPLES = 2000
"""Poses a floor is verified on before it is timed."""


class Timings(TypedDict):
    """A routine's ns per call over the rounds of compare."""

    min: float
    median: float


class AgainstFloor(TypedDict):
    """The routine against a hand-written floor: each one's Timings and their ratios."""

    floor: Timings
    routine: Timings
    rounds: int
    ratio_min: float
    ratio_median: float


class Figures(TypedDict):
    """What ``kingen bench`` prints and writes as JSON (benchmark's figures, against_floor
    with --floor)."""

    robot: str
    routine: str
    postures: int
    calls: int
    batch_ns_per_call: float
    cffi_ns_per_call: float
    reference_poses_per_second: float
    verify_poses_per_second: float
    verify_processes: int
    verify_passed: bool
    against_floor: NotRequired[AgainstFloor]
    single_calls: NotRequired[int]
    median_call_ns: NotRequired[float]
    worst_call_ns: NotRequired[float]


def _best_seconds(function, repeats, passes=1, tick=None):
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(passes):
            function()
            if tick is not None:
                tick()
        best = min(best, time.perf_counter() - start)
    return best


def benchmark(robot, plugin, calls=200000, seed=0, repeats=3, tick=None):
    """Figures for ``robot``'s ``plugin`` as a dict (best of ``repeats`` timings).
    ``tick()`` is called after every pass over the pose pool (progress for a watchdog)."""
    pool = min(calls, POOL_POSES)
    passes = -(-calls // pool)
    t6 = t6_from_pose(sample_poses(robot, pool, seed))
    few = t6[:PER_CALL_LIMIT]
    plugin.reset_host()
    with captured_output():
        batch = _best_seconds(plugin.batch_runner(t6), repeats, passes, tick)
        single = _best_seconds(plugin.each_runner(few), repeats, 1, tick)
        single_calls = plugin.call_times(t6, pool * passes) if hasattr(plugin, "call_times") else None
    reference = _best_seconds(lambda: solve(robot, t6), repeats, 1, tick)
    verified = min(calls, VERIFY_LIMIT)
    options = VerifyOptions(samples=verified, seed=seed, processes=None)
    report = verify(robot, plugin, options, progress=tick and (lambda _: tick()))
    timed = {} if single_calls is None else {"single_calls": len(single_calls),
                                             "median_call_ns": float(statistics.median(single_calls)),
                                             "worst_call_ns": float(max(single_calls))}
    return {
        **timed,
        "robot": robot.name,
        "routine": plugin.routine,
        "postures": robot.postures,
        "calls": pool * passes,
        "batch_ns_per_call": batch / (pool * passes) * 1e9,
        "cffi_ns_per_call": single / len(few) * 1e9,
        "reference_poses_per_second": pool / reference,
        "verify_poses_per_second": report.poses_per_second,
        "verify_processes": report.processes,
        "verify_passed": report.passed,
    }


def compare(robot, plugins, calls=200000, seed=0, repeats=ROUNDS, tick=None):
    """ns per call of each of ``plugins`` (label -> Plugin) on the same ``calls`` poses
    through the C batch driver, timed in turns (one timing of each per round, ``repeats``
    rounds) so that the machine's drift hits all alike. Returns label -> {"min", "median"}
    in ns per call."""
    pool = min(calls, POOL_POSES)
    passes = -(-calls // pool)
    t6 = t6_from_pose(sample_poses(robot, pool, seed))
    runners = {}
    for label, plugin in plugins.items():
        plugin.reset_host()
        runners[label] = plugin.batch_runner(t6)
    timings = {label: [] for label in plugins}
    with captured_output():
        for label, run in runners.items():  # warm caches and page in the code once
            run()
        for _ in range(repeats):
            for label, run in runners.items():
                timings[label].append(_best_seconds(run, 1, passes, tick) / (pool * passes) * 1e9)
    return {label: {"min": min(values), "median": statistics.median(values)} for label, values in timings.items()}


def verify_floor(robot, host, library, shown, timeout):
    """Verify the compiled floor ``library`` (built from the source ``shown``) as
    ``kingen verify --source`` would, on FLOOR_SAMPLES poses, in a child process bounded by
    ``timeout``. Returns only when every check passes; otherwise raises PluginDefect naming
    the first failing check: a floor that computes other joints (zeros, say) would make any
    ratio meaningless, so it is never timed."""
    options = VerifyOptions(samples=FLOOR_SAMPLES, timeout=timeout)
    report = verify_library(robot, library, host.routine_name(robot), options, host=host)
    if report.passed:
        return
    first = report.failures[0]
    raise PluginDefect(f"the floor {shown} fails verification on {FLOOR_SAMPLES} poses ({len(report.failures)} "
                       f"failed checks; first {first.name}: {shorten(first.detail, 160)}); it is not timed "
                       f"(kingen verify with --source {shown} gives the whole report)", check=first.name)
