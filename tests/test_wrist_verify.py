"""verify's numpy side and the commands on a machine with a serial wrist (robots/exechon_wrist.yaml,
robots/tricept_wrist.yaml): the checks are fed the reference's answers as a routine (as
tests/test_verdicts.py does) and routines changed by a known amount, which they must fail; fk
from legs and wrist joints returns the golden tool pose; the Tricept's golden values are an independent computation (Newton
on the whole chain, tests/test_wrist.py's, with tests/test_tricept.py's platform pose)."""

import json

import numpy as np
import pytest

from kingen.cli import main
from kingen.conventions import t6_from_pose
from kingen.kinematics.poses import sample_poses
from kingen.kinematics.reference import solve
from kingen.kinematics.routine import WARNINGS, warnings_to_exercise
from kingen.kinematics.forward import poses_of
from kingen.kinematics.hybrid.wrist_forward import tool_rates
from kingen.robot.model import load_robot
from kingen.verify.boundaries import boundary_poses
from kingen.verify.checks import Closure, Context
from kingen.verify.checks.jacobian import jacobian_check
from kingen.verify.checks.machine import machine_check
from kingen.verify.checks.round_trip import round_trip_check
from kingen.verify.options import VerifyOptions
from kingen.verify.report import Report
from kingen.verify.tally import Tally, accumulate, posture_statistics

import test_tricept
from conftest import ReferenceRoutine
from test_wrist import independent_branches

UNREACHABLE = WARNINGS["WARN_UNREACHABLE"]


@pytest.fixture(scope="module", params=["exechon_wrist", "tricept_wrist"])
def robot(request):
    return load_robot(request.param)


@pytest.fixture(scope="module")
def t6(robot):
    return t6_from_pose(sample_poses(robot, 200, 0))


def test_the_tricepts_golden_values_are_the_independent_computation():
    robot = load_robot("tricept_wrist")
    assert len(robot.golden) == 2
    scale = np.array([1, 1, 1, np.radians(1.0), np.radians(1.0)])
    for entry in robot.golden:
        assert "Independent computation (tests/test_wrist_verify.py)" in entry.source
        expected = independent_branches(robot.parallel, entry.pose, lambda _, x, y, z: test_tricept.independent_pose(x, y, z),
                                        test_tricept.independent_joints)[entry.posture]
        assert np.max(np.abs(expected - np.array(entry.joints) * scale)) < entry.tolerance * scale[-1]
        solution = solve(robot, t6_from_pose(np.array([entry.pose], dtype=float)))
        assert np.max(np.abs(solution.joints[0, :, entry.posture] - expected)) < 1e-9


def shifted(joint, amount):
    return lambda t6, joints: joints.__setitem__((slice(None), joint), joints[:, joint] + amount)


def closure_lines(robot, t6, routine):
    report = Report(robot=robot.name, routine="kin", samples=len(t6), seed=0, postures=robot.postures)
    tally = Tally.start(robot)
    accumulate(robot, report, tally, robot.revolute, t6, routine.call(t6), solve(robot, t6))
    results = Closure().run(Context(robot=robot, options=VerifyOptions(), routine=routine, report=report, tally=tally))
    return {check.name: check for check in results}, tally


def test_closure_the_constraints_and_the_wrist_pass_the_reference_and_judge_every_reached_posture(robot, t6):
    lines, tally = closure_lines(robot, t6, ReferenceRoutine(robot))
    assert set(lines) == {"closure", "constraints", "wrist"}
    assert all(check.passed and check.exercised for check in lines.values())
    reached = int(np.count_nonzero(solve(robot, t6).warnings != UNREACHABLE))
    assert lines["wrist"].judged == reached == 2 * len(t6)  # this A/C head reaches every tool axis
    assert lines["constraints"].judged == len(t6)
    assert lines["closure"].judged == 3 * len(t6)  # three legs, one branch each
    statistics = posture_statistics(robot, tally)
    assert [entry["right"] for entry in statistics] == [len(t6)] * 2


def test_a_wrong_wrist_joint_fails_the_wrist_line_by_its_lever_and_counts_as_wrong(robot, t6):
    """Ax5 off by 1e-6 rad: the tool axis turns 1e-6 and the tip, 200 mm out, moves 2e-4 mm."""
    lines, tally = closure_lines(robot, t6, ReferenceRoutine(robot, shifted(4, 1e-6)))
    assert lines["closure"].passed and lines["constraints"].passed and not lines["wrist"].passed
    assert f"{tally.wrist_worst:.3g}" == "0.0002"
    assert [entry["wrong"] for entry in posture_statistics(robot, tally)] == [len(t6)] * 2


def test_a_wrong_leg_fails_the_closure_at_the_platform(robot, t6):
    lines, _ = closure_lines(robot, t6, ReferenceRoutine(robot, shifted(0, 1e-6)))
    assert not lines["closure"].passed and lines["wrist"].passed


def test_the_jacobian_passes_the_reference_against_the_forward_maps_differences(robot, t6):
    check = jacobian_check(robot, ReferenceRoutine(robot), VerifyOptions(), t6[:60])
    assert check.passed and check.exercised and check.judged > 0
    assert "turning the tool 0.5 rad about its axis changes no joint: at most 0 " in check.detail


@pytest.mark.parametrize("change", [
    pytest.param(lambda t6, joints: joints.__setitem__((slice(None), 3), joints[:, 3] + 1e-3 * t6[:, 3, 0, None]),
                 id="ax4 drifts with x"),
    pytest.param(lambda t6, joints: joints.__setitem__((slice(None), 1), joints[:, 1] * 1.001), id="leg2 scaled"),
    pytest.param(lambda t6, joints: joints.__setitem__((slice(None), 4), joints[:, 4] + 1e-3 * t6[:, 0, 0, None]),
                 id="ax5 follows the tool's turn"),
])
def test_the_jacobian_fails_a_routine_whose_rates_are_wrong(robot, t6, change):
    check = jacobian_check(robot, ReferenceRoutine(robot, change), VerifyOptions(), t6[:60])
    assert not check.passed


def test_the_twist_about_the_tool_axis_gives_zero_joint_rates(robot, t6):
    """tool_rates from the forward map alone: a turn about the tool axis through the tip
    (omega = w, v = -w x tip at the base origin) asks no motion of tip or axis."""
    expected = solve(robot, t6[:20])
    rates = tool_rates(robot, expected.joints[:, :, 0], poses_of(expected.platform), 1e-5 * robot.size_mm, 1e-5)
    axis, tip = t6[:20, 2, :3], t6[:20, 3, :3]
    about_axis = np.concatenate([-np.cross(axis, tip), axis], axis=1)
    assert np.max(np.abs(np.einsum("nkj,nj->nk", rates, about_axis))) < 1e-9
    assert np.min(np.max(np.abs(rates), axis=(1, 2))) > 1e-3  # the other twists move joints


def test_forward_then_inverse_gives_every_regular_posture_back(robot, t6):
    check = round_trip_check(robot, ReferenceRoutine(robot), VerifyOptions(), t6[:100])
    assert check.passed and check.judged > 100  # of 200 (pose, posture) pairs, those away from singularities
    wrong = round_trip_check(robot, ReferenceRoutine(robot, shifted(2, 1e-6)), VerifyOptions(), t6[:100])
    assert not wrong.passed


def test_the_machine_check_judges_the_parallel_part_at_the_platforms_home(robot):
    check = machine_check(robot)
    assert check.passed
    assert check.detail.startswith("the parallel part at the platform's home: posture 0 reaches the verification home")


def test_verify_exercises_the_wrists_singularity_and_finds_its_boundary(robot):
    assert warnings_to_exercise(robot) == ["WARN_JOINT_LIMITS_EXCEEDED", "WARN_SINGULAR_SOLUTION"]
    poses, found, _ = boundary_poses(robot, 0)
    assert found["WARN_SINGULAR_SOLUTION"] >= 1
    warnings = solve(robot, t6_from_pose(poses)).warnings
    assert np.any(warnings == WARNINGS["WARN_SINGULAR_SOLUTION"]) and np.any(warnings == WARNINGS["WARN_GOOD_SOLUTION"])


def test_fk_from_legs_and_wrist_joints_gives_the_golden_tool_tip_and_axis(robot, capsys, tmp_path):
    entry = robot.golden[0]
    output = tmp_path / "fk.json"
    code = main(["fk", robot.name, "--joints", " ".join(f"{v:.9f}" for v in entry.joints), "--json", str(output)])
    out = capsys.readouterr().out
    assert code == 0 and out.startswith("the parallel part, then the wrist's forward: not exhaustive")
    found = json.loads(output.read_text())["solutions"]
    asked, reached = t6_from_pose(np.array([entry.pose])), t6_from_pose(np.array([found[0]["pose"]]))
    assert np.max(np.abs(reached[0, 3, :3] - asked[0, 3, :3])) < 1e-5  # the golden joints' 9 decimals
    assert np.max(np.abs(reached[0, 2, :3] - asked[0, 2, :3])) < 1e-8


def test_the_public_assembly_modes_and_a_posture_switch_are_the_tools(robot, capsys):
    """kingen.assembly_modes of the legs' and the wrist's joints gives tool poses (one of them the
    golden pose's tool tip), and a switch of the wrist's branch alone moves no tool: `kingen solve
    --switch` finds the commanded TCP, 0 mm away."""
    import kingen

    entry = robot.golden[0]
    joints = np.array(entry.joints) * robot.joint_scale()
    modes = kingen.assembly_modes(robot, joints).found
    assert min(np.linalg.norm(mode.pose[:3] - np.array(entry.pose[:3])) for mode in modes) < 1e-5  # 9 decimals
    assert main(["solve", robot.name, "--pose", *map(str, entry.pose), "--switch", "0", "1"]) == 0
    assert "may jump up to 0.000 mm" in capsys.readouterr().out


def test_fk_asks_for_every_joint_of_legs_and_wrist(robot, capsys):
    assert main(["fk", robot.name, "--joints", "1 2 3"]) == 2
    assert capsys.readouterr().err.strip().endswith(f"{robot.name} has 5 joints; give 5 finite numbers")


def test_solve_says_the_turn_about_the_tool_axis_per_posture(robot):
    from kingen.cli.solve_commands import _turn_note

    asked = t6_from_pose(np.array([robot.golden[0].pose]))
    note = _turn_note(robot, asked, solve(robot, asked))
    turns = [float(part.split()[-1]) for part in note.split(": ")[-1].split(", ")]
    assert len(turns) == 2 and abs(abs(turns[0] - turns[1]) - 180.0) < 1e-6  # the A/C head's flip

