"""The Exechon with its joints' constraints (robots/exechon_constrained.yaml): revolute axes
fixed in the platform, task coordinates x, y, z, the parasitic roll, pitch and yaw in closed
form; checked against an independent computation (Newton on the three constraint equations,
written here), the thesis's home and its observed tilt, the constraints closed at every answered
pose, the off-manifold answer, the generated routine against the reference on both hosts, forward
kinematics and bad declarations."""

from pathlib import Path

import numpy as np
import pytest

from kingen.conventions import rotation_from_rpy, t6_from_pose
from kingen.kinematics.hybrid.parasitic import on_manifold
from kingen.kinematics.reference import solve
from kingen.kinematics.hybrid.wrist import tool_t6
from kingen.robot.model import load_robot

from constrained import (UNREACHABLE, check_declaration_refused, check_forward_returns, check_task_poses_match,
                         newton_root)

NAME = "exechon_constrained"
TASKS = [(0.0, 50.0, -1250.0), (100.0, 50.0, -1250.0), (80.0, -60.0, -1150.0), (-120.0, 150.0, -1400.0),
         (140.0, 190.0, -1070.0)]


def independent_pose(robot, x, y, z):
    """roll, pitch, yaw (degrees) with every leg normal to its platform revolute axis,
    (R e).(b - p) = e.n: Newton on the three equations with a central-difference Jacobian, from 0."""
    constraints = [limb.platform_constraint() for limb in robot.limbs]

    def residual(angles):
        rotation = rotation_from_rpy(*np.radians(angles))
        return np.array([(rotation @ axis) @ (base - [x, y, z]) - axis @ point for axis, base, point in constraints])

    angles = newton_root(residual, np.zeros(3))
    assert np.max(np.abs(residual(angles))) < 1e-10
    return np.array([x, y, z, *angles])


def independent_joints(robot, pose):
    """Each leg's length at ``pose`` less its reference length (mm)."""
    rotation = rotation_from_rpy(*np.radians(pose[3:]))
    return np.array([np.linalg.norm(rotation @ limb.platform_point + pose[:3] - limb.base_point)
                     - limb.reference_length for limb in robot.limbs])


def test_parasitic_rotation_and_joints_match_an_independent_newton():
    robot = load_robot(NAME)
    poses = np.array([independent_pose(robot, *task) for task in TASKS])
    check_task_poses_match(robot, poses, independent_joints)


def test_golden_values_are_the_published_home_and_the_independent_computation():
    robot = load_robot(NAME)
    assert robot.golden[0].joints == [0, 0, 0] and "Table 3" in robot.golden[0].source
    for entry in robot.golden:
        pose = independent_pose(robot, *entry.pose[:3])
        assert np.max(np.abs(pose[3:] - entry.pose[3:])) < 1e-8
        assert np.max(np.abs(independent_joints(robot, pose) - entry.joints)) <= entry.tolerance


def test_the_thesis_pure_x_move_is_off_the_manifold_and_tilts_the_platform():
    """The thesis asked its DELMIA Exechon for (100, 50, -1250, 0, 0, 0) and saw it taken to
    'the nearest point' with a 4-degree tilt: the machine's pose there pitches by 4.57 degrees."""
    robot = load_robot(NAME)
    asked = np.array([[100.0, 50.0, -1250.0, 0.0, 0.0, 0.0]])
    assert np.all(solve(robot, t6_from_pose(asked)).warnings == UNREACHABLE)
    machine = on_manifold(robot, asked)[0]
    assert 4.0 < -machine[4] < 5.0 and abs(machine[3]) < 1e-12 and abs(machine[5]) < 1e-12


def test_forward_kinematics_solves_the_parasitic_rotation():
    robot = load_robot(NAME)
    poses = np.array([independent_pose(robot, *task) for task in TASKS])
    joints = np.array([independent_joints(robot, pose) for pose in poses])
    check_forward_returns(robot, poses, joints, np.array([20.0, -20.0, 30.0, 0.0, 0.0, 0.0]))


BAD = [
    ("task: [x, y, z]\n", "", "platform_revolute_axis: a platform revolute axis constrains the platform"),
    ("platform_revolute_axis: [1, 0, 0]", "platform_revolute_axis: [1, 0, 0], revolute_axis: [1, 0, 0]",
     "revolute_axis: task: [x, y, z] takes revolute axes fixed in the platform"),
    ("platform_revolute_axis: [1, 0, 0]", "platform_revolute_axis: [0, 1, 0]",
     "platform_revolute_axis: kingen solves two limbs sharing one platform revolute axis"),
]


@pytest.mark.parametrize("old, new, words", BAD)
def test_bad_declarations_are_refused_on_one_line(old, new, words, tmp_path):
    check_declaration_refused(NAME, old, new, words, tmp_path)


def test_analyze_sweeps_the_task_coordinates_with_the_parasitic_rotation_following():
    from kingen.design.analysis import analyze

    result = analyze(load_robot(NAME))
    assert result["available"]["tilt_limits"] == "not analysed: the platform's tilt is parasitic (task: x, y, z)"
    # the sweeps along x and y leave the home orientation: drawn as given they would be off the manifold
    for axis in ("x", "y"):
        assert [entry["cause"] for entry in result["sweeps"][axis]] == ["none"] * len(result["sweeps"][axis])
    assert "xy" in result["slices"] and "xz" in result["slices"]


def test_inside_the_constraint_singular_band_the_platform_turns_by_a_rotation_the_wrist_completes():
    """Just inside the constraint's singular band (D = -9e-6: the pair's two planes' line misses
    the unit sphere) the machine's platform rotation is a rotation, its pair axis the unit vector
    nearest that line (x0 / |x0|, x0 the line's point nearest the origin, by least squares here),
    and the three-axis wrist's joints of every posture rebuild the asked tool pose (the routine
    matched the reference there only once this held: tests/data/random_machines)."""
    robot = load_robot(str(Path(__file__).parent / "data" / "random_machines" / "exechon_spherical_wrist.yaml"))
    t6 = t6_from_pose(np.array([[-250.60345390497815, -9.122110697473602, -70.59626883590306, 180.0, 0.0, 0.0]]))
    answer = solve(robot, t6)
    assert -1e-5 <= answer.constraint[0] < 0.0
    platform = answer.platform[0]
    rotation, centre = platform[:3, :3].T, platform[3, :3]
    assert np.max(np.abs(rotation @ rotation.T - np.eye(3))) < 1e-14 and abs(np.linalg.det(rotation) - 1.0) < 1e-14
    (axis, base_1, point_1), (_, base_2, point_2) = (limb.platform_constraint() for limb in robot.limbs[:2])
    nearest = np.linalg.lstsq(np.array([base_1 - base_2, base_1 - centre]),
                              np.array([axis @ (point_1 - point_2), axis @ point_1]), rcond=None)[0]
    assert np.linalg.norm(nearest) > 1.0
    assert np.max(np.abs(rotation @ axis - nearest / np.linalg.norm(nearest))) < 1e-12
    for posture in range(robot.postures):
        rebuilt = tool_t6(robot, answer.platform, answer.joints[:, robot.dof:, posture])
        assert np.max(np.abs(rebuilt - t6)) < 1e-12, posture
