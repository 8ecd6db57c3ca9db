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

import numpy as np
import pytest
import yaml

from conftest import require_linuxcnc_headers
from kingen.conventions import t6_from_pose
from kingen.hosts.linuxcnc.render import robot_problem
from kingen.kinematics.reference import solve as reference_solve
from kingen.robot.model import load_robot
from kingen.runtime.resources import robots_dir
from kingen.verify.checks.machine import machine_check

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


def metres_hexapod(folder, units):
    """The shipped thesis hexapod with every length divided by 1000 (its file in metres), with a
    ``units:`` line when ``units`` is given: (path, its joints in the file's units at the pose
    (12.5, -7.25, 470) mm, (3.5, -2.25, 6) degrees, from the mm robot's reference)."""
    document = yaml.safe_load((robots_dir() / "hexapod.yaml").read_text())
    document.pop("golden")
    for limb in document["limbs"]:
        limb["base_point"] = [value / 1000 for value in limb["base_point"]]
        limb["platform_point"] = [value / 1000 for value in limb["platform_point"]]
        limb["reference_length"] /= 1000
    document["singularity"]["direct_index_min"] /= 1000
    region = document["verification"]
    for key in ("home", "range"):
        region[key] = [value / 1000 for value in region[key][:3]] + region[key][3:]
    if units:
        document["units"] = units
    path = folder / f"hexapod_{units or 'unitless'}.yaml"
    path.write_text(yaml.safe_dump(document, sort_keys=False))
    pose = np.array([[12.5, -7.25, 470.0, 3.5, -2.25, 6.0]])
    return path, reference_solve(load_robot("hexapod"), t6_from_pose(pose)).joints[0, :, 0] / 1000


def test_a_hexapod_in_metres_fails_without_units_m_and_passes_with_it(tmp_path):
    require_linuxcnc_headers()
    unitless, _ = metres_hexapod(tmp_path, None)
    stated, joints = metres_hexapod(tmp_path, "m")
    for host in HOSTS:
        code, out, err = run_verify(unitless, host, tmp_path)
        assert code == 1 and re.findall(r"^  FAILED (.+?):", out, re.MULTILINE) == ["machine"], out + err
        assert "less than 10 mm: the file states no units" in out and "add the line 'units: m'" in out
        code, out, err = run_verify(stated, host, tmp_path)
        assert code == 0, out + err
    refused = subprocess.run([sys.executable, "-m", "kingen.cli", "package", str(unitless), "--host", "linuxcnc",
                              "-o", str(tmp_path / "refused")], capture_output=True, text=True)
    assert refused.returncode == 2 and len(refused.stderr.splitlines()) == 1 and not (tmp_path / "refused").exists()
    robot = load_robot(str(stated))
    assert robot.length_unit == "m" and robot.size_mm == pytest.approx(load_robot("hexapod").size_mm)
    pose = np.array([[12.5, -7.25, 470.0, 3.5, -2.25, 6.0]])
    assert np.allclose(reference_solve(robot, t6_from_pose(pose)).joints[0, :, 0] / 1000, joints, rtol=0, atol=1e-12)


def test_a_home_off_the_manifold_by_more_than_the_tolerance_is_named_with_its_deviation(tmp_path):
    """vertical_prs with its rail points rounded to one decimal: its home (0, 0, -500) is off the
    manifold in y by what Newton on the constraint planes gives (test_hybrid.independent_pose),
    about ten times the tolerance (1e-5 of the machine's size); the machine check says so."""
    from test_hybrid import independent_pose

    text = (REGRESSIONS[0].parent / "vertical_prs.yaml").read_text().replace("458.9934640057092", "458.9")
    path = tmp_path / "coarse_prs.yaml"
    path.write_text(text)
    robot = load_robot(str(path))
    pose = independent_pose(robot, -500.0, 0.0, 0.0)
    x, y, yaw = pose[0], pose[1], pose[5]
    tolerance = 1e-5 * robot.size_mm
    assert abs(y) > 5 * tolerance and abs(x) < tolerance and abs(yaw) < 1e-7
    detail = machine_check(robot).detail
    assert detail.startswith(f"the verification home is off the machine's manifold by {abs(y):.3g} mm in y "
                             f"(tolerance {tolerance:.3g} mm, 1e-05 of its {robot.size_mm:g} mm size): the machine's "
                             f"pose for its z, roll, pitch there is x y z roll pitch yaw = "), detail
    shown = [float(value) for value in detail.split("yaw = ")[1].split(" (mm")[0].split()]
    assert np.allclose(shown, pose, rtol=0, atol=1e-8)
