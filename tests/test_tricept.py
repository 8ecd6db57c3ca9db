"""The Tricept-type machine (robots/tricept.yaml): three U-P-S legs and the passive central tube
(a universal joint at the base, a prismatic joint, fixed to the platform), task coordinates
x, y, z, the parasitic roll, pitch and yaw in closed form; checked against an independent
computation (the universal joint's two angles by Newton on the tube's direction, the rotation
through the joint's chain, written here), the constraints closed at every answered pose, the
off-manifold answer, the generated routine against the reference on both hosts, forward
kinematics and bad declarations."""


import numpy as np
import pytest

from kingen.conventions import rotation_from_rpy
from kingen.robot.model import load_robot

from constrained import (check_declaration_refused, check_forward_returns, check_task_poses_match,
                         newton_root)

NAME = "tricept"
TASKS = [(0.0, 0.0, -1100.0), (200.0, -100.0, -1000.0), (-250.0, 180.0, -1250.0), (280.0, 260.0, -950.0)]
CENTRE, FIRST, TUBE, HOME = np.zeros(3), np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, -1.0]), (0.0, 0.0, -1100.0)
"""The robot file's passive_leg and verification home, restated (home rotation 0)."""


def turn(axis, angle):
    """Rodrigues' rotation about the unit ``axis`` by ``angle`` (rad)."""
    cross = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * cross + (1 - np.cos(angle)) * cross @ cross


def independent_pose(x, y, z):
    """roll, pitch, yaw (degrees) of R = Rot(a, u1) Rot(b0, u2) (the universal joint's chain
    from the home, whose rotation is 0; b0 its second axis there), with u1, u2 by Newton so
    that the tube R t_p points from the joint's centre to (x, y, z)."""
    direction = (np.array([x, y, z]) - CENTRE) / np.linalg.norm(np.array([x, y, z]) - CENTRE)
    home = (np.array(HOME) - CENTRE) / np.linalg.norm(np.array(HOME) - CENTRE)
    second = np.cross(FIRST, home) / np.linalg.norm(np.cross(FIRST, home))
    across = np.linalg.svd(direction[None, :])[2][1:]  # two unit vectors normal to the direction

    def rotation(angles):
        return turn(FIRST, angles[0]) @ turn(second, angles[1])

    def residual(angles):
        return across @ (rotation(angles) @ TUBE)

    angles = newton_root(residual, np.zeros(2), tolerance=1e-14)
    found = rotation(angles)
    assert np.max(np.abs(residual(angles))) < 1e-12 and found @ TUBE @ direction > 0
    rpy = np.array([np.arctan2(found[2, 1], found[2, 2]), -np.arcsin(found[2, 0]), np.arctan2(found[1, 0], found[0, 0])])
    assert np.max(np.abs(rotation_from_rpy(*rpy) - found)) < 1e-12
    return np.array([x, y, z, *np.degrees(rpy)])


def independent_joints(robot, pose):
    """Each leg's length at ``pose`` less its reference length (mm)."""
    rotation = rotation_from_rpy(*np.radians(pose[3:]))
    return np.array([np.linalg.norm(rotation @ limb.platform_point + pose[:3] - limb.base_point)
                     - limb.reference_length for limb in robot.limbs])


def test_restated_declaration_is_the_robot_file_s():
    leg, robot = load_robot(NAME).passive_leg, load_robot(NAME)
    assert np.allclose(leg.base_point, CENTRE) and np.allclose(leg.first_axis, FIRST)
    assert np.allclose(leg.tube_axis, TUBE) and list(robot.verification.home) == [*HOME, 0, 0, 0]


def test_parasitic_rotation_and_joints_match_an_independent_newton():
    robot = load_robot(NAME)
    poses = np.array([independent_pose(*task) for task in TASKS])
    check_task_poses_match(robot, poses, independent_joints)


def test_golden_values_are_the_independent_computation():
    robot = load_robot(NAME)
    assert len(robot.golden) == 3
    for entry in robot.golden:
        assert "Independent computation (tests/test_tricept.py)" in entry.source
        pose = independent_pose(*entry.pose[:3])
        assert np.max(np.abs(pose[3:] - entry.pose[3:])) < 1e-8
        assert np.max(np.abs(independent_joints(robot, pose) - entry.joints)) <= entry.tolerance


def test_forward_kinematics_solves_the_parasitic_rotation():
    robot = load_robot(NAME)
    poses = np.array([independent_pose(*task) for task in TASKS])
    joints = np.array([independent_joints(robot, pose) for pose in poses])
    check_forward_returns(robot, poses, joints, np.array([20.0, -20.0, 30.0, 0.0, 0.0, 0.0]))


BAD = [
    ("task: [x, y, z]", "task: [z, roll, pitch]", "task: a machine with a passive_leg has the task coordinates of "
                                                  "its platform origin"),
    ("tube_axis: [0, 0, -1]", "tube_axis: [0, 0, 1]", "passive_leg.tube_axis: at the verification home the tube"),
    ("first_axis: [1, 0, 0]", "first_axis: [0, 0, 1]", "passive_leg.first_axis: at the verification home the tube "
                                                       "lies along"),
    ("reference_length: 1000, travel", "reference_length: 1000, revolute_axis: [1, 0, 0], travel",
     "revolute_axis: the passive_leg alone constrains the platform"),
    ("first_axis: [1, 0, 0]", "first_axis: [2, 0, 0]", "passive_leg.first_axis: direction must be a unit vector"),
    ("task: [x, y, z]\n", "", "passive_leg: a passive leg constrains the platform: declare the task coordinates"),
]


@pytest.mark.parametrize("old, new, words", BAD)
def test_bad_declarations_are_refused_on_one_line(old, new, words, tmp_path):
    check_declaration_refused(NAME, old, new, words, tmp_path)
