"""The numpy reference: published values, independent constraint round-trips, postures, warnings."""

import numpy as np
import pytest

from conftest import ONE_RAIL, PLUMB_LEG, SHIPPED, random_t6
from kingen.kinematics.routine import SINGULAR_TOLERANCE, WARNINGS
from kingen.conventions import t6_from_pose
from kingen.robot.model import load_robot
from kingen.kinematics.hybrid.parasitic import on_manifold
from kingen.kinematics.reference import platform_points_in_base, solve

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
    poses, t6 = random_t6(robot, 40, seed=7)
    if robot.task:  # a constrained machine reaches only the poses on its manifold
        t6 = t6_from_pose(on_manifold(robot, poses))
    solution = solve(robot, t6)
    platform = solution.platform if robot.wrist is not None else t6  # a wrist: the legs close at the platform's pose
    points = platform_points_in_base(platform, [limb.platform_point for limb in robot.limbs])
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


def test_a_rail_near_its_singular_band_keeps_its_small_root(tmp_path):
    """One rail along -z through the origin, link 100 mm, platform point at the pose: at
    (x, 0, z) its carriage positions are -z -/+ sqrt(100^2 - x^2) (u = -z). At
    x = 100 sqrt(1 - 1e-5) the root is sqrt(1e4 x 1e-5) = 0.316 mm (a radicand of 0.1 mm^2,
    D = 1e-5 normalised): both joints must keep it, however small."""
    import math

    path = tmp_path / "one_rail.yaml"
    path.write_text(ONE_RAIL)
    robot = load_robot(path)
    x = 100 * math.sqrt(1 - 1e-5)
    root = math.sqrt(100 ** 2 - x ** 2)
    assert root == pytest.approx(math.sqrt(0.1), rel=1e-6)
    joints = solve(robot, t6_from_pose([[x, 0, -50, 0, 0, 0]])).joints[0, 0]
    assert joints == pytest.approx([50 - root, 50 + root], rel=1e-9)


def test_a_leg_of_no_reference_length_blames_no_absolute_length():
    """A leg whose reference length is 0 already reports absolute lengths: an offset of any
    size, even within 1e-9 of that 0, is a wrong reference length, never 'absolute strut
    length' (which needs a positive reference length it equals)."""
    from kingen.robot.limbs.leg import Leg

    leg = Leg(model="leg", base_point=[0, 0, 0], platform_point=[0, 0, 0], reference_length=0)
    for offset in (5e-10, 22.913):
        assert leg.explain_offset(offset).startswith("a wrong reference length")
    positive = Leg(model="leg", base_point=[0, 0, 0], platform_point=[0, 0, 0], reference_length=399.413)
    assert positive.explain_offset(399.413 + 1e-7).startswith("the routine reports the leg's absolute strut length")


def test_each_model_names_the_collision_radius_of_its_passive_link():
    """docs/how-to/robot-files.md: collision: {leg_radius, rod_radius, crank_radius}; a leg is its own
    passive link (leg_radius), a crank's and a rail's link is a rod (rod_radius). CEART's
    rods of 15 mm radius: every rod clearance is 30 mm less than with no radius; so for its
    cranks' 15.5 mm, 31 mm."""
    from dataclasses import replace

    from kingen.kinematics.collision import clearances
    from kingen.robot.limbs.crank import Crank
    from kingen.robot.limbs.leg import Leg
    from kingen.robot.limbs.rail import Rail

    assert (Leg.passive_radius, Crank.passive_radius, Rail.passive_radius) == ("leg_radius", "rod_radius", "rod_radius")
    robot = load_robot("ceart")
    assert robot.collision == {"rod_radius": 15, "crank_radius": 15.5}
    _, t6 = random_t6(robot, 5, 3)
    expected = solve(robot, t6)
    joints = expected.joints[:, :, 0]
    with_radius, _ = clearances(robot, expected.points, joints)
    without, _ = clearances(replace(robot, collision={"crank_radius": 15.5}), expected.points, joints)
    assert with_radius == pytest.approx(without - 30.0, abs=1e-9)
    # and its cranks (from pivot to tip) of 15.5 mm radius: every crank clearance 31 mm less
    _, cranks = clearances(robot, expected.points, joints)
    _, bare = clearances(replace(robot, collision={"rod_radius": 15}), expected.points, joints)
    assert np.all(np.isfinite(cranks)) and cranks == pytest.approx(bare - 31.0, abs=1e-9)


def test_a_parameter_in_degrees_is_scaled_to_radians_and_lengths_are_not():
    """LimbModel.calibration_scale: what a dialog value of a parameter is multiplied by, from
    its unit word in ``calibratable`` (docs/how-to/robot-files.md: a crank's zero_offset in degrees, lengths in mm)."""
    import math

    from kingen.robot.limbs.crank import Crank
    from kingen.robot.limbs.rail import Rail

    crank = load_robot("ceart").limbs[0]
    assert isinstance(crank, Crank)
    assert crank.calibration_scale("zero_offset") == math.pi / 180.0
    assert crank.calibration_scale("crank_length") == crank.calibration_scale("rod_length") == 1.0
    rail = load_robot("tau").limbs[0]
    assert isinstance(rail, Rail) and rail.calibration_scale("origin") == rail.calibration_scale("link_length") == 1.0


def test_a_crank_whose_knees_are_equally_far_names_its_branches_by_turn():
    """Crank.branch_labels: where both knees are as far from the centre axis (here the axis
    through the crank's own pivot, the platform point level with the pivot and 650 mm out
    along the crank's plane, so the branches are mirror images: angles +/- the same half
    angle), the branches are named by which turns the crank further."""
    import math

    limb = load_robot("ceart").limbs[0]
    beta = math.radians(limb.crank_direction)
    pivot = np.asarray(limb.pivot, dtype=float)
    point = pivot + 650.0 * np.array([math.cos(beta), math.sin(beta), 0.0])
    assert limb.branch_labels(point, pivot) == ("crank turned further in the joint's positive sense",
                                                "crank turned less far")


def test_a_direct_index_exactly_at_its_threshold_is_singular():
    """A posture whose direct index is at most direct_index_min is singular, inclusive: the
    hexapod at a regular pose, its threshold set to that pose's own index (the same double:
    near the threshold the reference computes the index exactly), warns
    WARN_SINGULAR_SOLUTION; with the next float below it as the threshold, good."""
    from dataclasses import replace

    robot = load_robot("hexapod")
    t6 = t6_from_pose([[10.0, -5.0, 470.0, 2.0, -1.0, 3.0]])
    index = float(solve(replace(robot, direct_index_min=None), t6, indices=True).direct_index[0, 0])
    at = solve(replace(robot, direct_index_min=index), t6)
    assert at.direct_index[0, 0] == index and at.warnings[0, 0] == SINGULAR
    assert solve(replace(robot, direct_index_min=float(np.nextafter(index, 0.0))), t6).warnings[0, 0] == GOOD


def test_a_direct_index_not_asked_for_is_none():
    """Solution.direct_index is None unless computed: a robot without a threshold, no indices asked."""
    robot = load_robot("tau")
    t6 = t6_from_pose([robot.verification.home])
    assert robot.direct_index_min is None and solve(robot, t6).direct_index is None


def test_a_joint_exactly_at_a_travel_limit_is_within_it(tmp_path):
    """A leg from the base origin to the platform origin (reference length 0: its joint is
    |z| exactly, sqrt(z^2) = z) with travel [100, 200]: at z = 100 and 200 exactly it is
    within its travel (good); a float beyond either, outside."""
    path = tmp_path / "plumb_leg.yaml"
    path.write_text(PLUMB_LEG)
    robot = load_robot(path)
    heights = [100.0, 200.0, float(np.nextafter(100.0, 0.0)), float(np.nextafter(200.0, 300.0))]
    solution = solve(robot, t6_from_pose([[0.0, 0.0, z, 0.0, 0.0, 0.0] for z in heights]))
    assert solution.joints[:, 0, 0].tolist() == heights
    assert solution.warnings[:, 0].tolist() == [GOOD, GOOD, LIMITS, LIMITS]


def test_the_smallest_inverse_index_is_the_least_radicand_over_the_limbs():
    """Solution.min_inverse_index (solve's JSON): per pose, the smallest normalised radicand
    over the limbs; inf for a robot of legs (no limb has one)."""
    _, t6 = random_t6(load_robot("tau"), 20, 3)
    solution = solve(load_robot("tau"), t6)
    assert np.array_equal(solution.min_inverse_index, [min(row) for row in solution.radicands.tolist()])
    hexapod = load_robot("hexapod")
    assert np.all(solve(hexapod, t6_from_pose([hexapod.verification.home])).min_inverse_index == np.inf)
