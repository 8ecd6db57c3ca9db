"""Benchmarks: nanoseconds per routine call through the C batch driver and through one
cffi call per pose, and the reference's and verify's poses per second. Figures are
printed, never asserted: speed targets live here, not in unit tests."""

import time

from .conventions import t6_from_pose
from .host import captured_output
from .reference import solve
from .verify import sample_poses, verify

PER_CALL_LIMIT = 20000
"""The per-call cffi path is slow; it is timed on at most this many poses."""


def _best_seconds(function, repeats):
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        best = min(best, time.perf_counter() - start)
    return best


def benchmark(robot, plugin, calls=200000, seed=0, repeats=3):
    """Figures for ``robot``'s ``plugin`` as a dict (best of ``repeats`` timings)."""
    t6 = t6_from_pose(sample_poses(robot, calls, seed))
    few = t6[:PER_CALL_LIMIT]
    plugin.reset_host()
    with captured_output():
        batch = _best_seconds(plugin.batch_runner(t6), repeats)
        single = _best_seconds(lambda: plugin.call(few), repeats)
    reference = _best_seconds(lambda: solve(robot, t6), repeats)
    report = verify(robot, plugin, samples=calls, seed=seed)
    return {
        "robot": robot.name,
        "routine": plugin.routine,
        "postures": robot.postures,
        "calls": calls,
        "batch_ns_per_call": batch / calls * 1e9,
        "cffi_ns_per_call": single / len(few) * 1e9,
        "reference_poses_per_second": calls / reference,
        "verify_poses_per_second": report.poses_per_second,
        "verify_passed": report.passed,
    }
