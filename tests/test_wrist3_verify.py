"""verify's numpy side, fk and solve on a machine with a three-axis wrist (robots/tricept_wrist3.yaml):
the checks are fed the reference's answers as a routine (tests/test_wrist_verify.py's) and
routines changed by a known amount, which they must fail, including changes a five-axis reading
(tool tip and tool axis only) would not see; fk from legs and wrist joints returns the whole
golden tool pose."""

import json

import numpy as np
import pytest

from kingen.cli import main
from kingen.conventions import t6_from_pose
from kingen.kinematics.poses import sample_poses
from kingen.kinematics.reference import solve
from kingen.robot.model import load_robot
from kingen.kinematics.hybrid.wrist_forward import tool_forward
from kingen.verify.checks.jacobian import jacobian_check
from kingen.verify.checks.round_trip import round_trip_check
from kingen.verify.options import VerifyOptions

from conftest import ReferenceRoutine
from test_wrist_verify import UNREACHABLE, closure_lines, shifted


@pytest.fixture(scope="module")
def robot():
    return load_robot("tricept_wrist3")


@pytest.fixture(scope="module")
def t6(robot):
    return t6_from_pose(sample_poses(robot, 200, 0))


def test_closure_the_constraints_and_the_wrist_pass_the_reference(robot, t6):
    lines, _ = closure_lines(robot, t6, ReferenceRoutine(robot))
    assert set(lines) == {"closure", "constraints", "wrist"}
    assert all(check.passed and check.exercised for check in lines.values())
    assert "tool frame (its three axes)" in lines["wrist"].detail and "the whole pose is read" in lines["wrist"].detail
    reached = int(np.count_nonzero(solve(robot, t6).warnings != UNREACHABLE))
    assert 0 < lines["wrist"].judged <= reached and lines["constraints"].judged == len(t6)


def test_a_wrong_last_wrist_joint_fails_the_wrist_line_though_tip_and_axis_are_right(robot, t6):
    """Ax6 off by 1e-6 rad turns the tool about its own axis (the tool lies along Ax6): tip and tool
    axis stay put, so only the whole pose's reading sees the tool's x and y axes turn 1e-6."""
    lines, tally = closure_lines(robot, t6, ReferenceRoutine(robot, shifted(5, 1e-6)))
    assert lines["closure"].passed and lines["constraints"].passed and not lines["wrist"].passed
    assert f"{tally.wrist_worst:.2g}" == "1e-06"


def test_the_jacobian_passes_the_reference_over_all_six_twists(robot, t6):
    check = jacobian_check(robot, ReferenceRoutine(robot), VerifyOptions(), t6[:60])
    assert check.passed and check.exercised and check.judged > 0
    assert "turning the tool" not in check.detail


def test_the_jacobian_fails_a_routine_that_ignores_the_turn_about_the_tool_axis(robot, t6):
    change = (lambda poses, joints: joints.__setitem__((slice(None), 5), joints[:, 5] + 1e-3 * poses[:, 0, 0, None]))
    assert not jacobian_check(robot, ReferenceRoutine(robot, change), VerifyOptions(), t6[:60]).passed


def test_forward_then_inverse_gives_every_regular_posture_and_the_whole_pose_back(robot, t6):
    check = round_trip_check(robot, ReferenceRoutine(robot), VerifyOptions(), t6[:100])
    assert check.passed and check.judged > 100 and "tool frame within" in check.detail
    assert not round_trip_check(robot, ReferenceRoutine(robot, shifted(5, 1e-6)), VerifyOptions(), t6[:100]).passed


def test_fk_from_legs_and_wrist_joints_gives_the_whole_golden_tool_pose(robot, tmp_path, capsys):
    entry = robot.golden[0]
    output = tmp_path / "fk.json"
    assert main(["fk", robot.name, "--joints", " ".join(f"{v:.9f}" for v in entry.joints), "--json", str(output)]) == 0
    found = json.loads(output.read_text())["solutions"]
    asked, reached = t6_from_pose(np.array([entry.pose])), t6_from_pose(np.array([found[0]["pose"]]))
    assert np.max(np.abs(reached[0, 3, :3] - asked[0, 3, :3])) < 1e-5  # the golden joints' 9 decimals
    assert np.max(np.abs(reached[0, :3, :3] - asked[0, :3, :3])) < 1e-8
    capsys.readouterr()



def test_analyze_sweeps_every_coordinate_and_its_joints_give_the_swept_tool_pose_back(robot, tmp_path):
    output = tmp_path / "analysis.json"
    assert main(["analyze", robot.name, "-o", str(tmp_path / "out"), "--json", str(output), "--tilt-max", "20"]) == 0
    document = json.loads(output.read_text())
    assert document["available"]["poses"].startswith("tool poses (the whole pose")
    assert document["available"]["sweeps"] == "available" and "yaw" in document["sweeps"]  # no free turn
    home = np.array(robot.verification.home, dtype=float)
    for index, name in enumerate(("x", "y", "z", "roll", "pitch", "yaw")):
        # z and yaw keep the tool along Ax4 (home's gimbal lock, singular): its joints give the pose all the same
        entries = [entry for entry in document["sweeps"][name] if entry["warning"] != UNREACHABLE]
        assert len(entries) > 40
        poses = np.tile(home, (len(entries), 1))
        poses[:, index] = [entry["value"] for entry in entries]
        joints = np.array([entry["joints"] for entry in entries]) * robot.joint_scale()
        tool, _, _ = tool_forward(robot, joints, np.tile([*robot.parallel.verification.home[:3], 0, 0, 0],
                                                         (len(entries), 1)))
        assert np.max(np.abs(tool - t6_from_pose(poses))) < 1e-6  # the joints as analysis.json rounds them
