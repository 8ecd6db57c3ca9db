"""Forward kinematics and assembly modes: the closed form against Newton, round trips on
every shipped robot, the Gantry-Tau's posture switch of the DELMIA thesis, the command line."""

import json

import numpy as np
import pytest

from conftest import SHIPPED, ChangedJoints, random_t6
from kingen.cli import main
from kingen.conventions import pose_from_t6, t6_from_pose
from kingen.kinematics.forward import assemblies, closure, free_mask, newton, t6_of
from kingen.kinematics.posture_switch import predict_switch
from kingen.robot.model import load_robot
from kingen.kinematics.reference import solve

THESIS_POSE = [-1200.0, -750.0, -1900.0, 0.0, 0.0, 0.0]


def internal(pose):
    return np.concatenate([np.asarray(pose[:3], float), np.radians(pose[3:])])


@pytest.mark.parametrize("posture, other_z", [(0, -434.361468), (7, -3365.639)])
def test_the_gantry_tau_joints_admit_two_assembly_modes(posture, other_z):
    """Three spheres: the commanded pose and its mirror image across the plane of the centres."""
    robot = load_robot("tau")
    joints = solve(robot, t6_from_pose([THESIS_POSE])).joints[0, :, posture]
    found = assemblies(robot, joints, internal(THESIS_POSE)).found
    assert len(found) == 2
    np.testing.assert_allclose(found[0].pose, internal(THESIS_POSE), atol=1e-9)
    assert found[1].pose[2] == pytest.approx(other_z, abs=1e-3)
    residual, _ = closure(robot, np.array([mode.pose for mode in found]), np.tile(joints, (2, 1)))
    assert np.max(np.abs(residual)) < 1e-9
    # Newton from the mirror's neighbourhood finds the same pose as the closed form.
    polished, _ = newton(robot, found[1].pose[None] + [5.0, -5.0, 5.0, 0, 0, 0], joints[None], free_mask(robot))
    np.testing.assert_allclose(polished[0], found[1].pose, atol=1e-8)


@pytest.mark.parametrize("name", SHIPPED)
def test_forward_kinematics_returns_the_pose_the_joints_came_from(name):
    robot = load_robot(name)
    poses, t6 = random_t6(robot, 3, seed=21)
    expected = solve(robot, t6)
    free = free_mask(robot)
    for pose, joints, warnings in zip(poses, expected.joints, expected.warnings):
        posture = int(np.argmax(warnings == 0)) if np.any(warnings == 0) else None
        if posture is None:
            continue
        near = internal(pose)
        if robot.wrist is not None:  # the tool's pose: its tip and axis (the turn about the axis is free)
            found = assemblies(robot, joints[:, posture], near).found
            reached, asked = t6_of(found[0].pose[None])[0], t6_from_pose([pose])[0]
            assert np.max(np.abs(reached[2:, :3] - asked[2:, :3])) < 1e-7, (name, pose, found[0].pose)
            continue
        found = assemblies(robot, joints[:, posture], near).found
        assert found, f"{name}: nothing found for {pose}"
        assert np.max(np.abs(found[0].pose[free] - near[free])) < 1e-7, (name, pose, found[0].pose)


def test_pose_from_t6_inverts_t6_from_pose():
    poses = np.array([[1, -2, 3, 10, -20, 30], [0, 0, 0, -170, 80, 179], [5, 5, 5, 0, 0, 0]], float)
    np.testing.assert_allclose(pose_from_t6(t6_from_pose(poses)), poses, atol=1e-9)


def test_fk_command_json_contract_and_exit_codes(capsys, tmp_path):
    report = tmp_path / "fk.json"
    code = main(["fk", "tau", "--joints", "417.207213586", "361.089021702", "265.814725691",
                 "--near", *map(str, THESIS_POSE), "--json", str(report)])
    assert code == 0
    data = json.loads(report.read_text())
    assert set(data) == {"robot", "joints", "exhaustive", "method", "solutions"} and len(data["solutions"]) == 2
    assert set(data["solutions"][0]) == {"pose", "residual_mm", "distance_from_near_mm"}
    assert data["solutions"][0]["distance_from_near_mm"] < 1e-6
    assert data["solutions"][1]["distance_from_near_mm"] == pytest.approx(1509.199, abs=1e-3)
    capsys.readouterr()
    assert main(["fk", "tau", "--joints", "0", "0", "99999"]) == 1
    assert "no pose found for these joints (best residual" in capsys.readouterr().out
    assert main(["fk", "tau", "--joints", "1", "2"]) == 2
    assert main(["fk", "ceart", "--joints", "-43.394", "32.345", "-43.394", "32.345", "-43.394", "32.345"]) == 0


def test_solve_switch_explains_the_thesis_jump_of_the_gantry_tau(capsys, tmp_path):
    """DELMIA moved the TCP to another assembly mode when the Gantry-Tau switched postures at
    (-1200, -750, -1900): posture 7's joints admit the commanded pose and one 1509 mm away."""
    code = main(["solve", "tau", "-o", str(tmp_path), "--pose", *map(str, THESIS_POSE), "--switch", "0", "7"])
    out = capsys.readouterr().out
    assert code == 0
    assert "switch 0 -> 7: the joints move by carriage1 +1822.449573 mm" in out
    assert "assembly mode 1: pose (-1105.570, -1097.373, -3365.639, 0.000, 0.000, 0.000), 1509.199 mm" in out
    assert "may jump up to 1509.199 mm (2 assembly modes)" in out


def test_the_gantry_tau_switch_is_predicted_without_the_command_line():
    """The kinematics of the thesis's switch, as a notebook gets them: B's joints' modes and the
    TCP jump; a switch to an unreachable posture predicts nothing."""
    robot = load_robot("tau")
    t6 = t6_from_pose([THESIS_POSE])
    expected = solve(robot, t6)
    predicted = predict_switch(robot, t6[0], expected.joints[0], expected.warnings[0], 0, 7)
    assert predicted.unreachable is None and predicted.change[0] == pytest.approx(1822.449573, abs=1e-6)
    assert len(predicted.modes) == 2 and predicted.jump_mm == pytest.approx(1509.199, abs=1e-3)
    far = t6_from_pose([[5000.0, -750.0, -1900.0, 0.0, 0.0, 0.0]])
    unreachable = solve(robot, far)
    predicted = predict_switch(robot, far[0], unreachable.joints[0], unreachable.warnings[0], 0, 1)
    assert predicted.unreachable == 0 and predicted.modes is None and predicted.jump_mm is None


def perturbed(plugin, ulps, shift=0.0):
    """``plugin`` with its joints moved by ``ulps`` units in the last place (signs seeded),
    plus ``shift`` mm or rad on the first joint."""
    def change(t6, solutions):
        signs = np.random.default_rng(2).choice([-1.0, 1.0], size=solutions.shape)
        solutions += ulps * signs * np.spacing(np.abs(solutions))
        solutions[:, 0] += shift

    return ChangedJoints(plugin, change)


@pytest.mark.parametrize("name", ["exechon", "tau", "hexapod"])
def test_joints_rounded_differently_go_round_and_wrong_joints_do_not(name, plugin):
    """The round trip's bound follows the joints' own closure residual through the posture's
    conditioning: a routine 256 units in the last place from kingen's (far inside the values
    bound) passes, as kingen's own does; one whose first joint is 1 um off fails."""
    from kingen.verify import VerifyOptions
    from kingen.verify.checks.round_trip import round_trip_check

    robot, routine = plugin(name)
    _, t6 = random_t6(robot, 1000, seed=0)
    for ulps in (0, 256):
        check = round_trip_check(robot, perturbed(routine, ulps), VerifyOptions(), t6)
        assert check.passed, (ulps, check.detail)
    assert not round_trip_check(robot, perturbed(routine, 0, shift=1e-3), VerifyOptions(), t6).passed
