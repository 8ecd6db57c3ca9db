"""Machines a user could write, drawn at random (tests/machines.py), and the regression files
their failing draws shrank to (tests/data/random_machines/): verify gives no false verdict.

For each machine: `kingen verify` passes on every host that accepts it (a real process per
host, as a user runs it), LinuxCNC's refusal of a far pose is the reference's (the pose is out
of every limb's reach in every posture), forward kinematics returns the pose the reference's
joints came from, and a machine singular everywhere fails the ``machine`` check. CI draws a
fixed, bounded set (hypothesis profile 'ci'); KINGEN_FULL_SWEEPS=1 draws many more."""

import re
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import require_linuxcnc_headers
from kingen.hosts.linuxcnc.render import robot_problem
from kingen.robot.model import load_robot

REGRESSIONS = sorted((Path(__file__).parent / "data" / "random_machines").glob("*.yaml"))
HOSTS = ("delmia", "c", "linuxcnc")
SAMPLES = 300
"""Poses verify draws per machine and host: enough to reach every warning's boundary rays."""


def accepting_hosts(robot):
    """The hosts that take ``robot`` (LinuxCNC refuses robots it cannot drive, with exit 2)."""
    return [host for host in HOSTS if host != "linuxcnc" or robot_problem(robot) is None]


def run_verify(path, host, tmp_path, samples=SAMPLES):
    """`kingen verify PATH --host HOST` in a new process: (exit code, stdout, stderr)."""
    done = subprocess.run([sys.executable, "-m", "kingen.cli", "verify", str(path), "--host", host, "--samples",
                           str(samples), "--out-dir", str(tmp_path / host)],
                          capture_output=True, text=True, timeout=300)
    return done.returncode, done.stdout, done.stderr


def expectation(path):
    """A regression file's ``# expect:`` line: 'pass', or 'fail CHECK' (the one check that fails)."""
    found = re.search(r"^# expect: (.+)$", path.read_text(), re.MULTILINE)
    assert found, f"{path.name}: a regression file says what verify must answer ('# expect: pass')"
    return found.group(1).strip()


@pytest.mark.parametrize("path", REGRESSIONS, ids=[path.stem for path in REGRESSIONS])
def test_regression_file_verdict(path, tmp_path):
    robot = load_robot(str(path))
    expected = expectation(path)
    hosts = accepting_hosts(robot)
    if "linuxcnc" in hosts:
        require_linuxcnc_headers()
    for host in hosts:
        code, out, err = run_verify(path, host, tmp_path)
        failed = re.findall(r"^  FAILED (.+?):", out, re.MULTILINE)
        if expected == "pass":
            assert code == 0 and not failed, f"{path.name} on {host}: {failed}\n{out}{err}"
        else:
            assert code == 1 and failed == [expected.removeprefix("fail ")], f"{path.name} on {host}:\n{out}{err}"
