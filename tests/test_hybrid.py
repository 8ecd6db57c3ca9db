"""Lower-mobility machines with constraining limbs: the parasitic x, y and yaw of the shipped
3-PRS head and 3-RPS table, checked against an independent computation (Newton on the closure
and constraint equations, written here), the constraints closed at every returned pose, the
off-manifold answer, the generated routine against the reference, and bad declarations."""

import subprocess
import sys

import numpy as np
import pytest

from kingen.conventions import rotation_from_rpy, t6_from_pose
from kingen.kinematics.hybrid.parasitic import on_manifold
from kingen.kinematics.reference import solve
from kingen.kinematics.routine import WARNINGS
from kingen.robot.model import load_robot

from constrained import check_declaration_refused, check_forward_returns, newton_root

ROBOTS = ("prs_head", "rps_table")
TASKS = {"prs_head": [(-400.0, 0.0, 0.0), (-370.0, 12.0, -7.0), (-480.0, -14.0, 10.0), (-300.0, 5.0, 13.0)],
         "rps_table": [(500.0, 0.0, 0.0), (540.0, 15.0, 10.0), (430.0, -12.0, 18.0), (575.0, 19.0, -19.0)]}


def independent_pose(robot, z, roll, pitch):
    """x, y, yaw (mm, degrees) with every constraining limb's platform point in its plane:
    Newton on the three plane equations with a central-difference Jacobian, from x = y = yaw = 0."""
    planes = [limb.constraint_plane() for limb in robot.limbs]

    def residual(unknown):
        x, y, yaw = unknown
        rotation = rotation_from_rpy(np.radians(roll), np.radians(pitch), np.radians(yaw))
        return np.array([axis @ (rotation @ limb.platform_point + [x, y, z] - point)
                         for limb, (axis, point) in zip(robot.limbs, planes)])

    unknown = newton_root(residual, np.zeros(3))
    assert np.max(np.abs(residual(unknown))) < 1e-10
    return np.array([unknown[0], unknown[1], z, roll, pitch, unknown[2]])


def independent_joints(robot, pose):
    """Each limb's joint at ``pose`` from its own geometry: a leg's length less its reference
    length; a rail's carriage where its rod reaches the platform point, on the rod's +u side."""
    rotation = rotation_from_rpy(*np.radians(pose[3:]))
    joints = []
    for limb in robot.limbs:
        point = rotation @ limb.platform_point + pose[:3]
        if limb.model == "leg":
            joints.append(np.linalg.norm(point - limb.base_point) - limb.reference_length)
        else:  # |C - (s + d + t u)| = l, a quadratic in t; the carriage on the rod's +u side (branch 1)
            reach = point - np.add(limb.rail_point, limb.carriage_offset)
            roots = np.roots([1.0, -2.0 * np.dot(limb.direction, reach), reach @ reach - limb.link_length ** 2])
            joints.append(max(roots.real) - limb.origin)
    return np.array(joints)


@pytest.mark.parametrize("name", ROBOTS)
def test_parasitic_motion_and_joints_match_an_independent_newton(name):
    robot = load_robot(name)
    poses = np.array([independent_pose(robot, *task) for task in TASKS[name]])
    solution = solve(robot, t6_from_pose(poses))
    posture = robot.working_posture
    assert np.all(solution.warnings[:, posture] != WARNINGS["WARN_UNREACHABLE"])
    expected = np.array([independent_joints(robot, pose) for pose in poses])
    assert np.max(np.abs(solution.joints[:, :, posture] - expected)) < 1e-9
    # The reference solves the same pose from the task coordinates alone (x, y, yaw given as 0).
    asked = poses.copy()
    asked[:, [0, 1, 5]] = 0.0
    moved = solve(robot, t6_from_pose(asked))
    assert np.max(np.abs(moved.joints[:, :, posture] - expected)) < 1e-9
    assert np.max(np.abs(moved.points - solution.points)) < 1e-9


@pytest.mark.parametrize("name", ROBOTS)
def test_constraints_close_at_every_returned_pose(name):
    robot = load_robot(name)
    rng = np.random.default_rng(7)
    region = robot.verification
    poses = np.asarray(region.home) + rng.uniform(-1, 1, (500, 6)) * np.asarray(region.range)
    # drawn off the manifold (every one) and moved onto it: the constraints close at the pose answered
    solution = solve(robot, t6_from_pose(np.concatenate([poses, on_manifold(robot, poses)])))
    reachable = solution.warnings[:, robot.working_posture] != WARNINGS["WARN_UNREACHABLE"]
    assert np.count_nonzero(reachable) > 100
    for index, limb in enumerate(robot.limbs):
        axis, point = limb.constraint_plane()
        residual = (solution.points[:, index] - point) @ axis
        assert np.max(np.abs(residual)) < 1e-9
        closure = limb.closure_residual(solution.points[:, index], solution.joints[:, index, robot.working_posture])
        assert np.max(np.abs(closure[reachable])) < 1e-9


@pytest.mark.parametrize("name", ROBOTS)
def test_a_pose_off_the_manifold_is_never_answered_with_plain_joints(name):
    robot = load_robot(name)
    on = independent_pose(robot, *TASKS[name][1])
    for coordinate, change in ((0, 0.01), (1, -0.01), (5, 0.01)):
        off = on.copy()
        off[coordinate] += change
        solution = solve(robot, t6_from_pose(np.array([on, off])))
        assert np.all(solution.warnings[1] == WARNINGS["WARN_UNREACHABLE"])
        assert not np.any(solution.warnings[0] == WARNINGS["WARN_UNREACHABLE"])
        # the joints answered are those of the machine's pose for the same task coordinates
        assert np.max(np.abs(solution.joints[1] - solution.joints[0])) < 1e-9


@pytest.mark.parametrize("name", ROBOTS)
def test_golden_values_are_the_independent_computation(name):
    robot = load_robot(name)
    assert robot.golden, "the robot file carries golden values"
    for entry in robot.golden:
        pose = independent_pose(robot, *np.asarray(entry.pose)[[2, 3, 4]])
        assert np.max(np.abs(independent_joints(robot, pose) - entry.joints)) <= entry.tolerance


@pytest.mark.parametrize("host", ["delmia", "linuxcnc"])
@pytest.mark.parametrize("name", ROBOTS)
def test_generated_routine_equals_the_reference(name, host, tmp_path):
    result = subprocess.run([sys.executable, "-m", "kingen.cli", "verify", name, "--host", host, "--samples", "2000",
                             "--out-dir", str(tmp_path)], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "PASSED" in result.stdout
    checks = ("values", "warnings", "closure", "jacobian", "round trip", "golden") + (("forward",) if host == "linuxcnc" else ())
    for check in checks:
        assert any(line.strip().startswith("ok") and f" {check}" in line for line in result.stdout.splitlines()), check


BAD = [
    ("task: [z, roll, pitch]\n", "task: [z, roll, yaw]\n", "task: kingen solves the parasitic x, y, yaw"),
    ("task: [z, roll, pitch]\n", "", "revolute_axis: a revolute axis constrains the platform"),
    ("revolute_axis: [-1, 0, 0]", "revolute_axis: [0, 0, 1]", "revolute_axis must be perpendicular"),
]


@pytest.mark.parametrize("old, new, words", BAD)
def test_bad_declarations_are_refused_on_one_line(old, new, words, tmp_path):
    check_declaration_refused("prs_head", old, new, words, tmp_path)



@pytest.mark.parametrize("name", ROBOTS)
def test_forward_kinematics_solves_the_parasitic_coordinates(name):
    robot = load_robot(name)
    poses = np.array([independent_pose(robot, *task) for task in TASKS[name]])
    joints = np.array([independent_joints(robot, pose) for pose in poses])
    check_forward_returns(robot, poses, joints,
                          np.array([3.0, -3.0, 5.0, np.radians(2.0), np.radians(-2.0), np.radians(1.0)]), 1e-11)
