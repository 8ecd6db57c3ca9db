"""Direct singularities, the Jacobian and closure: the index against hand-made geometry,
the analytic Jacobian against finite differences of the reference on every shipped robot
and posture, and a 6-RUS robot tilted until the plugin and the reference agree it turns
singular."""

import math

import numpy as np
import pytest

from conftest import SHIPPED, random_t6
from kingen.kinematics.routine import WARNINGS
from kingen.conventions import t6_from_pose
from kingen.errors import KingenError
from kingen.robot.model import load_robot
from kingen.kinematics.hybrid.parasitic import on_manifold, task_rows, task_twists
from kingen.kinematics.reference import solve
from kingen.kinematics.singularity import (
    EXACT_WINDOW, PACKED, direct_index, direct_index_of_entries, direct_index_side, finite_difference_jacobian,
    jacobian, limb_wrenches, posture_gram_entries, posture_wrenches,
)

SINGULAR, UNREACHABLE = WARNINGS["WARN_SINGULAR_SOLUTION"], WARNINGS["WARN_UNREACHABLE"]


def wrench(point, direction):
    direction = np.asarray(direction, float) / np.linalg.norm(direction)
    return np.concatenate([direction, np.cross(point, direction)])


def index_of(lines):
    wrenches = np.array([wrench(point, direction) for point, direction in lines])
    return float(direct_index(wrenches.T @ wrenches))


def test_six_lines_through_one_point_leave_a_free_rotation():
    point = np.array([10.0, -20.0, 30.0])
    directions = np.random.default_rng(3).normal(size=(6, 3))
    assert index_of([(point, d) for d in directions]) == pytest.approx(0.0, abs=1e-6)


def test_parallel_lines_leave_a_free_translation():
    points = np.random.default_rng(4).normal(size=(6, 3)) * 100
    assert index_of([(p, [0, 0, 1]) for p in points]) == 0.0


def test_the_index_is_independent_of_the_base_frame():
    rng = np.random.default_rng(5)
    lines = [(p, d) for p, d in zip(rng.normal(size=(6, 3)) * 300, rng.normal(size=(6, 3)))]
    shift = np.array([1000.0, -2000.0, 500.0])
    assert index_of(lines) > 1.0
    assert index_of([(p + shift, d) for p, d in lines]) == pytest.approx(index_of(lines), rel=1e-9)


def test_an_octahedral_arrangement_has_the_index_of_its_hand_computation():
    """Three pairs of opposite forces along x, y, z at distance a from the axes: each unit
    rotation is resisted by two forces with arm a, power 2 a^2, and translations cost
    nothing extra (they are free to adjust): index = a sqrt(2)."""
    a = 100.0
    lines = [([0, a, 0], [1, 0, 0]), ([0, -a, 0], [1, 0, 0]), ([0, 0, a], [0, 1, 0]),
             ([0, 0, -a], [0, 1, 0]), ([a, 0, 0], [0, 0, 1]), ([-a, 0, 0], [0, 0, 1])]
    assert index_of(lines) == pytest.approx(a * math.sqrt(2.0), rel=1e-12)


@pytest.mark.parametrize("name", [name for name in SHIPPED if load_robot(name).wrist is None])
def test_analytic_jacobian_matches_finite_differences_of_the_reference(name):
    """As LinuxCNC's kinematics Jacobian tests do: every posture, random reachable poses. The
    limbs' Jacobian has no wrist rows: tests/test_wrist_verify.py differentiates a wrist
    machine's forward map."""
    robot = load_robot(name)
    poses, t6 = random_t6(robot, 30, seed=8)
    if robot.task:  # a constrained machine: on its manifold, the limbs' Jacobian along the task motion
        t6 = t6_from_pose(on_manifold(robot, poses))
    expected = solve(robot, t6)
    wrenches, transmissions = posture_wrenches(robot, expected.points, expected.joints)
    analytic = jacobian(wrenches, transmissions)
    if robot.task:
        analytic = np.einsum("nkpj,nji->nkpi", analytic, task_twists(robot, t6) @ task_rows(t6, robot.task))
    numeric = np.swapaxes(finite_difference_jacobian(lambda moved: solve(robot, moved).joints, t6, 1e-3, 1e-6,
                                                     robot.revolute), 1, 2)
    regular = ((expected.warnings != UNREACHABLE)[:, :, None] & (np.abs(transmissions) > 0.05)
               & np.all(expected.radicands > 1e-3, axis=1)[:, None, None])
    assert np.count_nonzero(regular) > 0
    relative = np.max(np.abs(numeric - analytic), axis=-1) / np.max(np.abs(analytic), axis=-1)
    worst = np.unravel_index(np.argmax(np.where(regular, relative, 0.0)), relative.shape)
    assert relative[worst] < 1e-6, f"{name}: pose {worst[0]} posture {worst[1]} joint {worst[2]}"


@pytest.mark.parametrize("name", ["ceart", "iwf", "hexapod"])
def test_posture_gram_entries_equal_the_sum_over_each_postures_lines(name):
    robot = load_robot(name)
    _, t6 = random_t6(robot, 20, seed=9)
    expected = solve(robot, t6)
    lines, _ = limb_wrenches(robot, expected.points, expected.branch_joints)
    per_posture, _ = posture_wrenches(robot, expected.points, expected.joints)
    direct = np.einsum("nkia,nkib->nkab", per_posture, per_posture)
    packed = np.stack([direct[..., i, j] for i, j in PACKED])
    np.testing.assert_allclose(posture_gram_entries(robot, lines), packed, rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize("name", ["iwf", "hexapod", "ceart"])
def test_the_side_of_the_threshold_agrees_with_the_index_and_is_exact_near_it(name):
    """direct_index_side (what the warnings use) against direct_index_of_entries (LAPACK
    everywhere), on sampled poses and with thresholds put right at sampled indices (inside
    the exact window) and just outside the window on either side."""
    robot = load_robot(name)
    _, t6 = random_t6(robot, 200, seed=12)
    expected = solve(robot, t6)
    lines, _ = limb_wrenches(robot, expected.points, expected.branch_joints, with_transmissions=False)
    entries = posture_gram_entries(robot, lines)
    exact = direct_index_of_entries(entries)
    assert np.all(exact >= 0.0)
    values = np.sort(exact[exact > 0.0])
    samples = values[[len(values) // 10, len(values) // 2, len(values) * 9 // 10]]
    for threshold in [robot.direct_index_min, *samples, *(samples * (1 + 3 * EXACT_WINDOW)),
                      *(samples * (1 - 3 * EXACT_WINDOW))]:
        at_a_sample = threshold in samples
        side = direct_index_side(entries, threshold)
        near = np.abs(exact - threshold) <= 0.5 * EXACT_WINDOW * threshold
        far = np.abs(exact - threshold) >= 2.0 * EXACT_WINDOW * threshold
        np.testing.assert_array_equal(side <= threshold, exact <= threshold)
        np.testing.assert_array_equal(side[near], exact[near])
        assert np.all(np.isinf(side[far & (exact > 0.0)]))
        assert np.any(near) or not at_a_sample


def test_the_crank_inverse_index_of_the_thesis_is_one_over_one_minus_d():
    """The 6-RUS thesis's Inv_I = (u^2 + v^2) / w^2 is rho^2 / K^2 here: 1 / (1 - D)."""
    robot = load_robot("ceart")
    _, t6 = random_t6(robot, 20, seed=10)
    expected = solve(robot, t6)
    crank = robot.limbs[0]
    g = expected.points[:, 0] - np.asarray(crank.pivot)
    beta = math.radians(crank.crank_direction)
    rho_squared = (g[:, 0] * math.cos(beta) + g[:, 1] * math.sin(beta)) ** 2 + g[:, 2] ** 2
    k = (np.sum(g * g, axis=1) + crank.crank_length ** 2 - crank.rod_length ** 2) / (2 * crank.crank_length)
    np.testing.assert_allclose(rho_squared / k ** 2, 1.0 / (1.0 - expected.radicands[:, 0]), rtol=1e-9)


def test_a_6rus_robot_tilted_about_y_turns_singular_where_the_reference_says(plugin):
    """IWF, working posture 63, tilted about Y in steps of 0.01 degree: the plugin's
    warnings equal the reference's at every step, and both turn singular at about 22 degrees
    (the thesis: about 18 degrees from its own, unpublished home)."""
    robot, loaded = plugin("iwf")
    home = np.array(robot.verification.home, dtype=float)
    pitches = np.arange(0.0, 30.0, 0.01)
    poses = np.tile(home, (len(pitches), 1))
    poses[:, 4] = pitches
    t6 = t6_from_pose(poses)
    loaded.reset_host()
    plugin_warnings = loaded.call(t6).warnings[:, 63]
    expected = solve(robot, t6)
    np.testing.assert_array_equal(plugin_warnings, expected.warnings[:, 63])
    first = int(np.argmax(plugin_warnings == SINGULAR))
    assert plugin_warnings[first] == SINGULAR and np.all(plugin_warnings[:first] != SINGULAR)
    assert 20.0 < pitches[first] < 24.0
    assert expected.direct_index[first, 63] <= robot.direct_index_min < expected.direct_index[first - 1, 63]


def test_a_threshold_needs_six_force_lines(tmp_path):
    text = (tmp_path / "tau.yaml")
    from kingen.robot.model import robots_dir
    text.write_text((robots_dir() / "tau.yaml").read_text() + "singularity: {direct_index_min: 10}\n")
    with pytest.raises(KingenError, match=r"singularity.direct_index_min: the direct index needs six force lines; "
                                          r"this robot has 3 limbs"):
        load_robot(text)
