"""verify's JSON report is a contract: the same counts, verdicts and statistics whoever
compares the poses and however fast. Recorded reports of small samples (tests/data/verify_reports,
written by this version's comparison before it was sped up, CEART's and the Gantry-Tau's again since verify
searches for the boundaries its rays miss and tau has a third golden entry) must come out again, and a run on
a Dask cluster (--scheduler) must give the report a local run gives."""

import json
from pathlib import Path

import pytest

from kingen.cli import main

REPORTS = Path(__file__).parent / "data" / "verify_reports"
TIMING = ("seconds", "poses_per_second")
"""The only fields of a report that may differ between two runs of the same verification,
with ``isolation``: what the machine's kernel grants (and a cluster's client keeps its network)."""
RUNS = {"hexapod": ["--samples", "20000", "--seed", "3"], "ceart": ["--samples", "12000", "--seed", "1"],
        "tau": ["--samples", "20000", "--seed", "2"]}
"""Each recorded report's robot and options: several chunks each (CEART's and the hexapod's
direct index, the Gantry-Tau's travel limits). CEART's was recorded again with 12,000 poses
(three chunks of 5,208) by the version before its chunks grew, from 2,057 poses."""


def _report(tmp_path, robot, *extra):
    path = tmp_path / f"{robot}.json"
    code = main(["verify", robot, *RUNS[robot], "-o", str(tmp_path / "build" / robot), "--json", str(path), *extra])
    report = json.loads(path.read_text())
    for name in TIMING:
        report.pop(name)
    assert report.pop("isolation")
    return code, report


FLOAT_AGREEMENT = 1e-9
"""Relative: a recorded float may differ in its last digits where it comes from LAPACK (the direct
index's eigenvalues near a boundary), whose rounding depends on the machine's BLAS kernel; every
count, verdict and text is compared exactly."""


def _same(found, recorded, where="report"):
    """Assert ``found`` equals ``recorded``: exactly but for floats, within FLOAT_AGREEMENT."""
    if isinstance(recorded, float) and isinstance(found, float):
        assert found == pytest.approx(recorded, rel=FLOAT_AGREEMENT, abs=1e-300), where
    elif isinstance(recorded, dict):
        assert isinstance(found, dict) and found.keys() == recorded.keys(), where
        for key in recorded:
            _same(found[key], recorded[key], f"{where}.{key}")
    elif isinstance(recorded, list):
        assert isinstance(found, list) and len(found) == len(recorded), where
        for index, (one, other) in enumerate(zip(found, recorded)):
            _same(one, other, f"{where}[{index}]")
    else:
        assert found == recorded, where


@pytest.mark.parametrize("robot", sorted(RUNS))
def test_reports_are_those_recorded(robot, tmp_path):
    code, report = _report(tmp_path, robot, "--processes", "2")
    expected = json.loads((REPORTS / f"{robot}.json").read_text())
    assert code == (0 if expected["passed"] else 1)
    _same(report, expected)


def test_a_dask_cluster_gives_the_report_local_processes_give(tmp_path):
    distributed = pytest.importorskip("distributed")
    local = _report(tmp_path, "hexapod", "--processes", "2")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        remote = _report(tmp_path, "hexapod", "--scheduler", cluster.scheduler_address)
    assert remote == local


def test_processes_and_scheduler_are_exclusive():
    assert main(["verify", "hexapod", "--processes", "2", "--scheduler", "tcp://127.0.0.1:1"]) == 2


def test_no_scheduler_is_bad_input(tmp_path, monkeypatch, capsys):
    """Nothing listens on port 9: after the scheduler timeout (20 s; 1 s here) a one-line error, exit 2."""
    monkeypatch.setattr("kingen.runtime.executors.SCHEDULER_TIMEOUT", 1.0)
    assert main(["verify", "hexapod", "--samples", "10", "-o", str(tmp_path), "--scheduler", "tcp://127.0.0.1:9"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("kingen: error: --scheduler: no Dask scheduler at tcp://127.0.0.1:9 (Timed out") and err.count("\n") == 1, err


def test_a_routine_that_crashes_a_worker_still_fails(tmp_path):
    """Its chunk's job fails on the cluster, is compared again in verify's own child, and
    the crash is named there with its poses."""
    distributed = pytest.importorskip("distributed")
    from test_hostile import plugin_source, verify_source

    crashing = plugin_source(ROUTINE="if (T6[3][0] > 19.0) *(volatile int *)8 = 1;")  # 2.5 % of the region's poses
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        result = verify_source(tmp_path, crashing, "--scheduler", cluster.scheduler_address)
    assert result.returncode == 1, result.stdout + result.stderr
    assert "FAILED crash: the plugin ended the host process (signal SIGSEGV) during poses 0 to 199" in result.stdout
