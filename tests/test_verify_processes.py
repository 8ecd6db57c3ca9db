"""verify compares every other chunk in a forked second process: the report must be the one a
single process gives, counts, worst errors and per-posture statistics alike."""

import dataclasses

import pytest

from conftest import ChangedJoints
from kingen import verify as verify_module
from kingen.verify import VerifyOptions, chunk_size, verify


def wrong_on_some_poses(plugin, x):
    """``plugin`` with its first joint 1e-6 off wherever T6's x exceeds ``x``: errors in every
    chunk, decided by the pose alone (so either process makes them)."""
    def change(t6, solutions):
        solutions[t6[:, 3, 0] > x, 0] += 1e-6

    return ChangedJoints(plugin, change)


@pytest.mark.parametrize("name", ["hexapod", "tau", "ceart"])
def test_two_processes_report_what_one_does(name, plugin, monkeypatch):
    robot, routine = plugin(name)
    wrong = wrong_on_some_poses(routine, robot.verification.home[0])
    compared_here = []
    compare_chunk = verify_module._compare_chunk

    def counted(poses, first=False):
        compared_here.append(len(poses))
        return compare_chunk(poses, first)

    monkeypatch.setattr(verify_module, "_compare_chunk", counted)
    reports = []
    for processes in (1, 2):
        compared_here.clear()
        report = dataclasses.asdict(verify(robot, wrong, VerifyOptions(samples=3 * chunk_size(robot) + 17,
                                                                       processes=processes)))
        report.pop("seconds")
        reports.append(report)
        assert len(compared_here) == (4 if processes == 1 else 2)  # chunks 0 and 2 here, 1 and 3 there
    assert reports[0] == reports[1]
    assert reports[0]["max_abs_error_mm" if name != "ceart" else "max_abs_error_rad"] == pytest.approx(1e-6, rel=1e-3)
    assert sum(row["wrong"] for row in reports[0]["posture_statistics"]) > 0
