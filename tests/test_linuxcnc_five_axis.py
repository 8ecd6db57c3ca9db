"""LinuxCNC's five-axis module for a machine with a wrist (exechon_wrist): world X Y Z (tool
tip) A C (tool axis w = Rz(C) Rx(A) w0), its inverse against the reference at the working
posture over verify's sample, its forward (then the inverse of what it returns) from seeds a
servo cycle and far away, the wrist's singularity answered, the package's five joints, and the
world conversion's two (A, C) pairs cross-checked against rotation matrices built independently."""

import re

import numpy as np
import pytest

from conftest import require_linuxcnc_headers
from kingen.cli import main
from kingen.conventions import t6_from_pose
from kingen.hosts import get_host
from kingen.hosts.linuxcnc.five_axis import axis_of_world, home_axis, world_of_axis, world_of_t6
from kingen.hosts.linuxcnc.loader import Module
from kingen.hosts.linuxcnc.package import render_package
from kingen.kinematics.reference import solve
from kingen.robot.model import load_robot
from kingen.runtime.resources import robots_dir
from kingen.verify import VerifyOptions, verify_library


def rotation(axis, degrees):
    """An elementary rotation matrix about base x or z, written out (not kingen's)."""
    c, s = np.cos(np.radians(degrees)), np.sin(np.radians(degrees))
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]]) if axis == "x" else np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def test_the_tool_axis_of_a_and_c_is_rz_rx_of_the_home_axis():
    robot = load_robot("exechon_wrist")
    w0 = home_axis(robot)
    assert np.allclose(w0, [0, 0, -1], atol=1e-15)  # the tool points down at the home, the wrist at 0
    generator = np.random.default_rng(3)
    a, c = generator.uniform(-170, 170, 50), generator.uniform(-170, 170, 50)
    expected = np.array([rotation("z", cc) @ rotation("x", aa) @ w0 for aa, cc in zip(a, c)])
    assert np.max(np.abs(axis_of_world(w0, a, c) - expected)) <= 1e-15


def test_a_and_c_come_back_on_the_pair_nearest_the_seed():
    w0 = np.array([0.0, 0.0, -1.0])
    generator = np.random.default_rng(4)
    a, c = generator.uniform(5, 100, 200), generator.uniform(-300, 300, 200)
    w = axis_of_world(w0, a, c)
    found_a, found_c = world_of_axis(w0, w, a + 0.5, c - 0.5)
    assert np.max(np.abs(found_a - a)) <= 1e-9 and np.max(np.abs(found_c - c)) <= 1e-9
    flipped_a, flipped_c = world_of_axis(w0, w, -a, c + 180.0)  # the other pair: (-A, C + 180) for w0 = -z
    assert np.max(np.abs(flipped_a + a)) <= 1e-9 and np.max(np.abs(flipped_c - c - 180.0)) <= 1e-9
    pole_a, pole_c = world_of_axis(w0, np.array([[0.0, 0.0, -1.0]]), 0.0, 37.0)  # C free: kept
    assert pole_a[0] == 0.0 and pole_c[0] == 37.0


def built_module(name, folder):
    """(robot, robot as LinuxCNC sees it, BuildResult) of shipped robot ``name``."""
    require_linuxcnc_headers()
    robot, host = load_robot(name), get_host("linuxcnc")
    return robot, host.as_seen(robot), host.build(robot, folder)


@pytest.fixture(scope="module")
def module(tmp_path_factory):
    return built_module("exechon_wrist", tmp_path_factory.mktemp("five_axis"))


@pytest.mark.parametrize("name", ["exechon_wrist", "tricept_wrist"])
def test_the_five_axis_module_passes_verify(name, tmp_path):
    _, seen, built = built_module(name, tmp_path)
    report = verify_library(seen, built.library, built.routine, VerifyOptions(samples=3000), host=get_host("linuxcnc"))
    assert report.passed, [(check.name, check.detail) for check in report.failures]
    assert report.max_abs_error_mm <= 1e-9 and report.max_abs_error_rad <= 1e-9
    forward = {check.name: check.detail for check in report.checks}["forward"]
    servo = re.search(r"a servo cycle away: (\d+) of (\d+) returned the tool tip and axis, 0 failed", forward)
    assert servo and servo.group(1) == servo.group(2) and int(servo.group(2)) > 100
    back = re.search(r"gave the joints back for (\d+)", forward)
    assert back.group(1) == servo.group(2)


def test_the_module_answers_the_wrists_singularity_at_home_and_says_so(module):
    robot, seen, built = module
    loaded = Module(built.library, built.routine, seen)
    home = world_of_t6(robot, t6_from_pose(np.array([robot.verification.home])))
    assert solve(seen, t6_from_pose(np.array([robot.verification.home]))).warnings[0, 0] == 5
    joints, returns, status = loaded.inverse(home)
    assert returns[0] == 0 and status[0] == 5  # the tool axis along Ax4: singular, answered
    assert np.allclose(joints[0, 3:5], 0.0, atol=1e-9)
    home[0, 0] = np.nan
    assert loaded.inverse(home)[1][0] != 0


def test_the_package_carries_the_five_joints_and_coordinates():
    robot = load_robot("exechon_wrist")
    files = render_package(robot, compiled=False)
    ini, hal = files["exechon_wristkins.ini"], files["exechon_wristkins.hal"]
    assert "JOINTS = 5" in ini and "COORDINATES = X Y Z A C" in ini
    assert re.search(r"\[TRAJ\]\nHOME = 0\.0 50\.0 -1450\.0 0\.0 0\.0 0\.0\n", ini)
    for index, (name, low, high) in enumerate([("ax4", -270, 270), ("ax5", -110, 110)], start=3):
        section = ini.split(f"[JOINT_{index}]\n")[1].split("\n\n")[0]
        assert f"# {name} (wrist, degrees)" in section and "TYPE = ANGULAR" in section
        assert f"MIN_LIMIT = {low}\n" in section and f"MAX_LIMIT = {high}\n" in section
    assert "loadrt exechon_wristkins" in hal


def test_a_wrist_robot_without_a_working_posture_is_refused(tmp_path, capsys):
    path = tmp_path / "robot.yaml"
    text = (robots_dir() / "exechon_wrist.yaml").read_text()
    path.write_text(re.sub(r"working_posture: 0[^\n]*\n", "", text))
    assert main(["build", str(path), "--host", "linuxcnc", "-o", str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err
    assert "working_posture: LinuxCNC's inverse kinematics has one answer" in err and err.count("\n") == 1
    assert not (tmp_path / "b").exists()


def test_the_one_posture_view_of_a_wrist_robot_is_that_posture_of_the_whole_machine():
    from kingen.robot.one_posture import at_posture

    robot = load_robot("exechon_wrist")
    generator = np.random.default_rng(5)
    poses = np.array(robot.verification.home) + generator.uniform(-1, 1, (200, 6)) * np.array(robot.verification.range)
    t6 = t6_from_pose(poses)
    whole = solve(robot, t6)
    for posture in range(robot.postures):
        seen = solve(at_posture(robot, posture), t6)
        assert at_posture(robot, posture).postures == 1 and seen.joints.shape == (200, 5, 1)
        assert np.array_equal(seen.joints[:, :, 0], whole.joints[:, :, posture])
        assert np.array_equal(seen.warnings[:, 0], whole.warnings[:, posture])
