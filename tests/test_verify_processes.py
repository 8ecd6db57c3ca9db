"""verify shares the chunks among forked comparing processes: the report must be the one a
single process gives, counts, worst errors and per-posture statistics alike."""

import dataclasses

import pytest

from conftest import ChangedJoints
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
    monkeypatch.setattr(verify_module, "CPU_QUOTA_FILES", ((str(tmp_path / "cpu.max"), None),
                                                           (str(tmp_path / "quota"), str(tmp_path / "period"))))
    monkeypatch.setattr(verify_module.os, "sched_getaffinity", lambda pid: set(range(64)))
    assert verify_module.cpu_quota() == cores
    assert verify_module.comparing_processes() == (cores or verify_module.MAX_PROCESSES)


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
