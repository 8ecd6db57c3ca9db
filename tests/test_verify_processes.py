"""verify shares the chunks among forked comparing processes: the report must be the one a
single process gives, counts, worst errors and per-posture statistics alike."""

import dataclasses

import pytest

from conftest import ChangedCalls, ChangedJoints
from kingen.runtime import cores as cores_module
from kingen.verify import processes as verify_module
from kingen.verify import VerifyOptions, chunk_size, verify


def wrong_on_some_poses(plugin, x):
    """``plugin`` with its first joint 1e-6 off wherever T6's x exceeds ``x``: errors in every
    chunk, decided by the pose alone (so either process makes them)."""
    def change(t6, solutions):
        solutions[t6[:, 3, 0] > x, 0] += 1e-6

    return ChangedJoints(plugin, change)


@pytest.mark.parametrize("name", ["hexapod", "tau", "ceart"])
def test_several_processes_report_what_one_does(name, plugin, monkeypatch):
    robot, routine = plugin(name)
    wrong = wrong_on_some_poses(routine, robot.verification.home[0])
    compared_here = []
    compare_chunk = verify_module._compare_chunk

    def counted(poses, first=False):
        compared_here.append(len(poses))
        return compare_chunk(poses, first)

    monkeypatch.setattr(verify_module, "_compare_chunk", counted)
    reports = []
    here = {1: 4, 2: 2, 3: 2, 5: 1}  # chunks 0 to 3 all here; 0 and 2; 0 and 3; 0 (4 processes: one per chunk)
    for processes, compared in here.items():
        compared_here.clear()
        report = dataclasses.asdict(verify(robot, wrong, VerifyOptions(samples=3 * chunk_size(robot) + 17,
                                                                       processes=processes)))
        report.pop("seconds")
        assert report.pop("processes") == min(processes, 4)
        reports.append(report)
        assert len(compared_here) == compared
    assert all(report == reports[0] for report in reports[1:])
    assert reports[0]["max_abs_error_mm" if name != "ceart" else "max_abs_error_rad"] == pytest.approx(1e-6, rel=1e-3)
    assert sum(row["wrong"] for row in reports[0]["posture_statistics"]) > 0


@pytest.mark.parametrize("files, cores", [
    ({"cpu.max": "150000 100000\n"}, 2),  # cgroup v2: 1.5 CPUs of quota take two processes
    ({"cpu.max": "max 100000\n"}, None),  # v2 without a quota
    ({"quota": "300000\n", "period": "100000\n"}, 3),  # cgroup v1
    ({"quota": "-1\n", "period": "100000\n"}, None),  # v1 without a quota
    ({}, None),  # no control group files at all
])
def test_a_containers_cpu_quota_bounds_the_processes(tmp_path, monkeypatch, files, cores):
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    monkeypatch.setattr(cores_module, "CPU_QUOTA_FILES", ((str(tmp_path / "cpu.max"), None),
                                                          (str(tmp_path / "quota"), str(tmp_path / "period"))))
    monkeypatch.setattr(cores_module.os, "sched_getaffinity", lambda pid: set(range(64)))
    assert cores_module.cpu_quota() == cores
    assert cores_module.usable_cores() == (cores or cores_module.MAX_PROCESSES)


class FlippedWarnings:
    """``plugin`` answering WARN_SINGULAR_SOLUTION for WARN_GOOD_SOLUTION (and back) wherever
    T6's x exceeds ``x``."""

    def __init__(self, plugin, x):
        self._plugin, self._x = plugin, x

    def __getattr__(self, name):
        return getattr(self._plugin, name)

    def call(self, t6, *arguments, **keywords):
        calls = self._plugin.call(t6, *arguments, **keywords)
        flip = (t6.reshape(-1, 4, 4)[:, 3, 0] > self._x)[:, None] & ((calls.warnings == 0) | (calls.warnings == 5))
        calls.warnings[flip] = 5 - calls.warnings[flip]
        return calls


def test_merged_counts_add_up_whatever_the_processes(plugin):
    """Warnings flipped on the poses right of home (about half of them, drawn uniformly about
    home): the mismatches are counted, positive and the same for 1 and 2 processes; the
    per-posture statistics split right and wrong joints about evenly."""
    robot, routine = plugin("tau")
    counts = []
    for processes in (1, 2):
        report = verify(robot, FlippedWarnings(wrong_on_some_poses(routine, robot.verification.home[0]),
                                               robot.verification.home[0]),
                        VerifyOptions(samples=2 * chunk_size(robot) + 5, processes=processes))
        counts.append({name: getattr(report, name) for name in verify_module.REPORT_COUNTS})
        right = sum(row["right"] for row in report.posture_statistics)
        wrong = sum(row["wrong"] for row in report.posture_statistics)
        assert 0.35 < wrong / (right + wrong) < 0.65
    assert counts[0] == counts[1] and counts[0]["warning_mismatches"] > 1000
    assert all(value >= 0 for value in counts[0].values())


class PrintsOnce:
    """``plugin`` writing ``text`` on file descriptor 1 at its first call only (a routine's
    debug print): verify captures it in the interface checks, then in every later block,
    which print nothing."""

    def __init__(self, plugin, text):
        self._plugin, self._text, self._printed = plugin, text, False

    def __getattr__(self, name):
        return getattr(self._plugin, name)

    def call(self, t6, *arguments, **keywords):
        if not self._printed:
            import os

            os.write(1, self._text)
            self._printed = True
        return self._plugin.call(t6, *arguments, **keywords)


@pytest.mark.parametrize("text, first_line", [(b"hello\n", "hello"), (b" \n\n", "")])
def test_what_a_routine_prints_once_is_counted_over_every_block(plugin, text, first_line):
    robot, routine = plugin("hexapod")
    report = verify(robot, PrintsOnce(routine, text), VerifyOptions(samples=50, processes=1))
    assert report.notices[0] == (f"the routine printed {len(text)} bytes on stdout/stderr (first line: "
                                 f"{first_line!r}); debug printing slows the host by orders of magnitude")


def stopped(plugin):
    """``plugin`` whose every call reports a fault bit other than INPUTS_MODIFIED: stopped at
    a faulting write, so none of its outputs may be compared."""
    return ChangedCalls(plugin, lambda t6, calls: calls.faults.fill(1))


def test_when_every_call_is_stopped_the_output_checks_fail_as_uncompared(plugin):
    from kingen.verify.checks.base import STOPPED_CALLS

    robot, routine = plugin("hexapod")
    report = verify(robot, stopped(routine), VerifyOptions(samples=50, processes=1))
    checks = {check.name: check for check in report.checks}
    for name in ("values", "warnings"):
        assert (checks[name].passed, checks[name].detail) == (False, STOPPED_CALLS)
    assert "jacobian" not in checks  # it judges compared poses and has no uncompared failure: left out


class OtherPostures:
    """``plugin`` claiming one posture more than it has."""

    def __init__(self, plugin):
        self._plugin = plugin
        self.postures = plugin.postures + 1

    def __getattr__(self, name):
        return getattr(self._plugin, name)


def test_a_routine_of_another_posture_count_is_not_compared(plugin):
    robot, routine = plugin("hexapod")
    report = verify(robot, OtherPostures(routine), VerifyOptions(samples=50, processes=1))
    assert [(check.name, check.passed, check.detail) for check in report.checks if check.name == "values"] == [
        ("values", False, "not compared: the routine's joint or posture count differs")]
    assert report.checks[-1].name == "values"  # nothing judged after it: no golden values, no snapshot


def test_a_library_verified_in_a_child_reports_its_progress_chunk_by_chunk(built):
    """Progress travels from the child as each chunk is merged: the poses done so far, the
    last chunk the 5 poses past three whole chunks."""
    from kingen.hosts import get_host
    from kingen.verify import verify_library

    robot, result = built("hexapod")
    size = chunk_size(robot)
    done = []
    report = verify_library(robot, result.library, result.routine, VerifyOptions(samples=3 * size + 5, processes=2),
                            progress=done.append, host=get_host("delmia"))
    assert report.passed
    assert done == [size, 2 * size, 3 * size, 3 * size + 5]


def test_a_chunk_a_cluster_lost_is_compared_here_keeping_the_first_chunks_poses(plugin):
    """kingen.verify.cluster: a chunk whose job failed on the cluster is drawn and compared in
    this process, the same poses as there; the first chunk (poses from 0) keeps its poses for
    the diagnoses as it would have on the worker, a later one does not."""
    from types import SimpleNamespace

    from kingen.verify.cluster import ClusterChunks
    from kingen.verify.processes import set_chunk_job

    robot, routine = plugin("tau")
    options = VerifyOptions(samples=40, processes=1)
    set_chunk_job(robot, robot, routine, options)
    chunks = ClusterChunks.__new__(ClusterChunks)
    chunks._local, chunks._job = (robot, robot, routine, options), SimpleNamespace(options=options)
    first, later = chunks._compare_here(0, 20), chunks._compare_here(20, 20)
    assert first.tally.first is not None and len(first.tally.first[0]) == 20
    assert later.tally.first is None and later.tally.reachable_poses > 0
