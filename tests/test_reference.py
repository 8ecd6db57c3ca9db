"""The numpy reference: published values, independent constraint round-trips, postures, warnings."""

import numpy as np
import pytest

from conftest import SHIPPED, random_t6
from kingen.routine import SINGULAR_TOLERANCE, WARNINGS
from kingen.conventions import t6_from_pose
from kingen.model import load_robot
from kingen.reference import platform_points_in_base, solve

GOOD, LIMITS, UNREACHABLE, SINGULAR = (WARNINGS[k] for k in (
    "WARN_GOOD_SOLUTION", "WARN_JOINT_LIMITS_EXCEEDED", "WARN_UNREACHABLE", "WARN_SINGULAR_SOLUTION"))


def test_exechon_matches_published_matlab_and_delmia_values():
    robot = load_robot("exechon")
    solution = solve(robot, t6_from_pose([[100, 50, -1250, 0, 0, 0]]))
    np.testing.assert_allclose(solution.joints[0, :, 0], [-24.8915, 36.1332, 5.6258], atol=5e-5)


def test_exechon_home_is_all_joints_zero():
    robot = load_robot("exechon")
    solution = solve(robot, t6_from_pose([[0, 50, -1250, 0, 0, 0]]))
    np.testing.assert_allclose(solution.joints[0, :, 0], 0.0, atol=5e-4)


def limb_residual(limb, point, q):
    """|constraint| of one limb at joint value q, computed forward from the geometry (mm)."""
    return abs(float(limb.closure_residual(point[None], np.array([q]))[0]))


@pytest.mark.parametrize("name", SHIPPED)
def test_every_reachable_posture_closes_every_limb(name):
    """Forward check: put each joint where the reference says and measure the limb's length."""
    robot = load_robot(name)
    _, t6 = random_t6(robot, 40, seed=7)
    solution = solve(robot, t6)
    points = platform_points_in_base(t6, [limb.platform_point for limb in robot.limbs])
    checked = 0
    for n in range(len(t6)):
        for k in range(robot.postures):
            if solution.warnings[n, k] == UNREACHABLE:
                continue
            for j, limb in enumerate(robot.limbs):
                residual = limb_residual(limb, points[n, j], solution.joints[n, j, k])
                assert residual < 1e-8, f"{name} pose {n} posture {k} joint {j}: residual {residual} mm"
                checked += 1
    assert checked > 0


@pytest.mark.parametrize("name", ["tau", "ceart"])
def test_posture_digits_pick_branches_first_limb_most_significant(name):
    robot = load_robot(name)
    _, t6 = random_t6(robot, 5, seed=3)
    joints = solve(robot, t6).joints
    count = robot.dof
    for k in range(robot.postures):
        for j in range(count):
            branch = (k >> (count - 1 - j)) & 1
            np.testing.assert_array_equal(joints[:, j, k], joints[:, j, branch << (count - 1 - j)])
    if name == "tau":
        # branch 0 is u.w - sqrt(...): the smaller carriage value
        assert np.all(joints[:, :, 0] < joints[:, :, 7])


def tau_singular_pose():
    """A pose where tau's first link is perpendicular to its rail (radicand exactly 0)."""
    limb = load_robot("tau").limbs[0]
    centre = np.asarray(limb.rail_point) + limb.carriage_offset - np.asarray(limb.platform_point)
    return [centre[0] - limb.link_length, centre[1], -1900, 0, 0, 0]


def test_singular_limb_warns_singular_for_every_posture():
    robot = load_robot("tau")
    solution = solve(robot, t6_from_pose([tau_singular_pose()]))
    assert abs(solution.radicands[0, 0]) <= SINGULAR_TOLERANCE
    assert np.all(solution.warnings[0] == SINGULAR)
    # at the singularity both branches meet; rounding in the radicand shows as sqrt(eps) * l
    link = robot.limbs[0].link_length
    assert abs(solution.joints[0, 0, 0] - solution.joints[0, 0, 4]) < link * 1e-7


def test_unreachable_wins_and_values_stay_finite():
    robot = load_robot("ceart")
    solution = solve(robot, t6_from_pose([[0, 0, -2000, 0, 0, 0]]))
    assert np.all(solution.warnings == UNREACHABLE)
    assert np.all(np.isfinite(solution.joints))


def test_joint_limits_are_flagged_per_posture():
    robot = load_robot("exechon")
    solution = solve(robot, t6_from_pose([[0, 50, -1900, 0, 0, 0]]))
    assert solution.joints[0, 0, 0] > 595
    assert solution.warnings[0, 0] == LIMITS


def test_non_finite_t6_is_unreachable_with_zero_joints():
    robot = load_robot("tau")
    t6 = t6_from_pose([[-1200, -750, -1900, 0, 0, 0]] * 2)
    t6[1, 3, 2] = np.nan
    solution = solve(robot, t6)
    assert np.all(solution.warnings[1] == UNREACHABLE)
    assert np.all(solution.joints[1] == 0.0)
    assert np.all(solution.warnings[0] != UNREACHABLE)
