"""Numerical building blocks pinned from both sides of each bound, against independent
computations: the closed-form smallest eigenvalue (the direct index analyze uses) against
LAPACK (numpy.linalg.eigvalsh); trilateration against points whose distances are known;
forward kinematics' acceptance bounds (SAME_POSE_MM, SAME_POSE_RAD, 1e-9 of the size);
the robot-file reader's depth and value limits at their exact values."""

import math

import numpy as np
import pytest

from kingen.kinematics import forward
from kingen.errors import KingenError
from kingen.kinematics.forward import SAME_POSE_MM, SAME_POSE_RAD, _polished, _same, _three_spheres
from kingen.robot.model import load_robot
from kingen.robot.reading import MAX_DEPTH, MAX_NODES, read_robot_file
from kingen.kinematics.singularity import PACKED, _exact_smallest_eigenvalue, _smallest_eigenvalue, direct_index, \
    direct_index_of_entries


def as_entries(matrices):
    return {(i, j): matrices[:, i, j] for i in range(3) for j in range(i, 3)}


@pytest.mark.parametrize("scale, spread", [(1.0, 1.0), (1e6, 1.0), (1e4, 1e-3), (1.0, 1e-6)])
def test_the_closed_form_smallest_eigenvalue_agrees_with_lapack(scale, spread):
    """Symmetric positive semi-definite 3x3 matrices Q diag(l) Q^T, eigenvalues l drawn as
    scale x (1 + spread x u): clustered (spread 1e-6) and well spread."""
    rng = np.random.default_rng(11)
    q, _ = np.linalg.qr(rng.normal(size=(500, 3, 3)))
    eigenvalues = scale * (1.0 + spread * rng.uniform(-0.9, 5.0, (500, 3)))
    matrices = q @ (eigenvalues[:, :, None] * np.swapaxes(q, 1, 2))
    lapack = np.linalg.eigvalsh(matrices)
    closed = _smallest_eigenvalue(as_entries(matrices))
    assert np.max(np.abs(closed - lapack[:, 0]) / lapack[:, 2]) < 1e-9
    assert np.allclose(_exact_smallest_eigenvalue(as_entries(matrices), np.ones(500, bool)), lapack[:, 0],
                       rtol=0, atol=1e-12 * scale)


def test_the_closed_form_smallest_eigenvalue_of_repeated_eigenvalues():
    """A multiple of the identity gives its value (the 0 / 0 the code guards); a repeated
    eigenvalue puts acos at +/-1, where the closed form loses half the digits: its error is
    about sqrt(eps) x the largest eigenvalue there (hence LAPACK within EXACT_WINDOW = 1e-4
    of a threshold), measured 5e-9 x 9 for diag(2, 2, 9)."""
    matrices = np.array([np.eye(3) * 7.5, np.diag([2.0, 2.0, 9.0]), np.diag([4.0, 1.0, 4.0])])
    assert _smallest_eigenvalue(as_entries(matrices)).tolist() == pytest.approx([7.5, 2.0, 1.0], rel=1e-7)
    assert _smallest_eigenvalue(as_entries(matrices[:1]))[0] == 7.5


def test_the_direct_index_in_closed_form_agrees_with_lapack_on_a_robot():
    """direct_index_of_entries uses the closed form away from exact_near (here 1e9 mm, far
    from every value) and LAPACK near it (exact_near None: everywhere)."""
    rng = np.random.default_rng(5)
    wrenches = rng.normal(size=(300, 6, 6)) * np.array([1, 1, 1, 300, 300, 300])
    gram = np.swapaxes(wrenches, 1, 2) @ wrenches
    entries = np.stack([gram[:, i, j] for i, j in PACKED])
    closed = direct_index_of_entries(entries, exact_near=1e9)
    exact = direct_index(gram)
    # Independently: sqrt of the smallest eigenvalue of M_ww - M_wv M_vv^-1 M_vw, by numpy.
    schur = gram[:, 3:, 3:] - gram[:, 3:, :3] @ np.linalg.solve(gram[:, :3, :3], gram[:, :3, 3:])
    numpy_index = np.sqrt(np.maximum(np.linalg.eigvalsh(schur)[:, 0], 0.0))
    assert np.allclose(exact, numpy_index, rtol=1e-9)
    assert np.max(np.abs(closed - numpy_index) / np.sqrt(np.linalg.eigvalsh(schur)[:, 2])) < 1e-7


CENTRES = np.array([[0.0, 0.0, 0.0], [100.0, 0.0, 0.0], [0.0, 100.0, 0.0]])


def radii_to(point, centres=CENTRES):
    return np.linalg.norm(centres - np.asarray(point), axis=1)


def test_three_spheres_meet_at_both_mirror_points():
    found = _three_spheres(CENTRES, radii_to([30.0, 40.0, 50.0]))
    assert len(found) == 2
    np.testing.assert_allclose(sorted(found, key=lambda p: -p[2]), [[30, 40, 50], [30, 40, -50]], atol=1e-12)


def test_three_spheres_tangent_in_their_plane_meet_once():
    found = _three_spheres(CENTRES, radii_to([30.0, 40.0, 0.0]))
    assert len(found) == 1
    np.testing.assert_allclose(found[0], [30, 40, 0], atol=1e-6)


def test_three_spheres_that_miss_each_other_meet_nowhere():
    assert _three_spheres(CENTRES, radii_to([30.0, 40.0, 0.0]) * np.array([0.5, 0.5, 0.5])) == []


@pytest.mark.parametrize("centres", [
    np.array([[5.0, 5.0, 5.0], [5.0, 5.0, 5.0], [0.0, 100.0, 0.0]]),     # first two coincide
    np.array([[0.0, 0.0, 0.0], [100.0, 0.0, 0.0], [100.0, 0.0, 0.0]]),  # last two coincide
    np.array([[0.0, 0.0, 0.0], [100.0, 0.0, 0.0], [250.0, 0.0, 0.0]]),  # collinear
])
def test_three_spheres_with_coincident_or_collinear_centres_give_no_isolated_point(centres):
    """Their intersection, where there is one, is a circle: no isolated pose to report, and no crash."""
    assert _three_spheres(centres, np.array([120.0, 120.0, 120.0])) == []


@pytest.mark.parametrize("offset_mm, offset_rad, same", [
    (0.5 * SAME_POSE_MM, 0.0, True), (2.0 * SAME_POSE_MM, 0.0, False),
    (0.0, 0.5 * SAME_POSE_RAD, True), (0.0, 2.0 * SAME_POSE_RAD, False)])
def test_two_poses_are_the_same_assembly_only_within_the_bounds(offset_mm, offset_rad, same):
    pose = np.array([10.0, -20.0, 400.0, 0.1, -0.2, 0.3])
    other = pose + np.array([0.0, offset_mm, 0.0, 0.0, 0.0, offset_rad])
    assert _same(pose, other) == same


@pytest.mark.parametrize("relative, kept", [(0.5e-9, True), (2e-9, False)])
def test_an_assembly_is_kept_only_with_a_residual_within_1e_9_of_the_size(monkeypatch, relative, kept):
    robot = load_robot("hexapod")
    residual = relative * robot.size_mm
    monkeypatch.setattr(forward, "newton", lambda robot, poses, joints, free: (np.array(poses), np.full(len(poses), residual)))
    found = _polished(robot, [[0, 0, 465, 0, 0, 0]], np.zeros(6), np.array([0, 0, 465, 0, 0, 0.0]), np.ones(6, bool))
    assert len(found) == (1 if kept else 0)


def test_assemblies_are_ordered_by_distance_and_duplicates_dropped(monkeypatch):
    robot = load_robot("hexapod")
    monkeypatch.setattr(forward, "newton", lambda robot, poses, joints, free: (np.array(poses), np.zeros(len(poses))))
    candidates = [[0, 0, 500, 0, 0, 0], [0, 0, 470, 0, 0, 0], [0, 0, 500 + 0.5 * SAME_POSE_MM, 0, 0, 0],
                  [0, 0, 440, 0, 0, 0]]
    found = _polished(robot, candidates, np.zeros(6), np.array([0, 0, 465, 0, 0, 0.0]), np.ones(6, bool))
    assert [assembly.pose[2] for assembly in found] == [470, 440, 500]  # 5, 25 and 35 mm from 465


def read(tmp_path, text):
    path = tmp_path / "r.yaml"
    path.write_text(text)
    return read_robot_file(path)[0]


def test_flow_nesting_is_refused_beyond_max_depth_before_parsing(tmp_path):
    assert MAX_DEPTH == 32
    depth = MAX_DEPTH - 1  # the top-level mapping is one level: 31 brackets make 32
    assert read(tmp_path, "a: " + "[" * depth + "]" * depth + "\n")["a"] is not None
    with pytest.raises(KingenError, match=r":1: nested deeper than 32 levels"):
        read(tmp_path, "a: " + "[" * (MAX_DEPTH + 1) + "]" * (MAX_DEPTH + 1) + "\n")
    # Unclosed: only the check on the raw text, before the parser, names the depth.
    with pytest.raises(KingenError, match=r":2: nested deeper than 32 levels"):
        read(tmp_path, "b: 1\na: " + "[" * (MAX_DEPTH + 1) + "\n")
    # Brackets in quotes and comments are text, not nesting.
    assert read(tmp_path, "a: '" + "[" * 40 + "'  # " + "{" * 40 + "\nb: \"" + "{" * 40 + "\"\n")["b"] == "{" * 40


def values(aliases, padding):
    """A document of 1 (top mapping) + 1 (key a) + 1001 (a list of 1000) + 2 (key b, its list)
    + 1001 per alias of a + 2 (key c, its list) + ``padding`` values."""
    return ("a: &a [" + "1, " * 999 + "1]\nb: [" + ", ".join(["*a"] * aliases) + "]\nc: ["
            + ", ".join(["2"] * padding) + "]\n")


def test_a_document_may_expand_to_exactly_max_nodes_values(tmp_path):
    assert MAX_NODES == 100_000
    assert 1 + 1 + 1001 + 2 + 98 * 1001 + 2 + 895 == MAX_NODES
    assert len(read(tmp_path, values(98, 895))["c"]) == 895
    with pytest.raises(KingenError, match=r":3: expands to more than 100000 values"):
        read(tmp_path, values(98, 896))
    with pytest.raises(KingenError, match=r"expands to more than 100000 values"):
        read(tmp_path, values(120, 1))


def test_crank_angles_far_from_a_turn_are_not_rounded_by_the_reference():
    """math.remainder wraps exactly: the reference's wrapped joint plus the offset is the
    geometric angle modulo 2 pi (checked on a crank offset by 700 degrees)."""
    robot = load_robot("ceart")
    limb = robot.limbs[0].model_copy(update={"zero_offset": 700.0})
    points = np.array([[robot.limbs[0].platform_point[0], robot.limbs[0].platform_point[1], -700.0]])
    plain = robot.limbs[0].solve(points)
    shifted = limb.solve(points)
    difference = np.angle(np.exp(1j * (plain.values - shifted.values - math.radians(700.0))))
    assert np.max(np.abs(difference)) < 1e-12


@pytest.mark.parametrize("scale", [1e-3, 0.3, 1.0, 1e4])
def test_positive_definiteness_after_a_shift_agrees_with_lapack(scale):
    """Sylvester's criterion on A - shift I (what the warnings decide the direct index's side
    with) against the sign of LAPACK's smallest eigenvalue, on matrices of every size."""
    from kingen.kinematics.singularity import _positive_definite

    rng = np.random.default_rng(3)
    q, _ = np.linalg.qr(rng.normal(size=(400, 3, 3)))
    eigenvalues = scale * rng.uniform(0.05, 1.0, (400, 3))
    matrices = q @ (eigenvalues[:, :, None] * np.swapaxes(q, 1, 2))
    for shift in (0.0, 0.3 * scale, 0.6 * scale):
        smallest = np.linalg.eigvalsh(matrices)[:, 0] - shift
        clear = np.abs(smallest) > 1e-9 * scale
        decided = _positive_definite(as_entries(matrices), shift)
        assert np.array_equal(decided[clear], (smallest > 0)[clear])
        assert decided.any() and not decided.all() or shift == 0.0


BLOCK_LIMIT = 1e-12 * (2.0 / 3.0) ** 3
"""diag(1, 1, p)'s limit: 1e-12 x (trace / 3)^3, the trace 2 + p within 1e-12 of 2."""


@pytest.mark.parametrize("smallest_pivot, singular", [(1e-13, True), (1e-11, False), (0.9 * BLOCK_LIMIT, True),
                                                      (1.1 * BLOCK_LIMIT, False)])
def test_a_force_block_is_translation_singular_below_1e_12_of_its_trace_cubed(smallest_pivot, singular):
    """M_vv = diag(1, 1, p) (trace about 2, (trace / 3)^3 = 0.296): singular, index 0, when the
    product of its pivots p is below 1e-12 x 0.296 (BLOCK_LIMIT; 10 % either side of it too);
    else the Schur complement's index, here M_ww = 4 I with no coupling: sqrt(4) = 2 mm."""
    gram = np.zeros((6, 6))
    gram[:3, :3] = np.diag([1.0, 1.0, smallest_pivot])
    gram[3:, 3:] = 4.0 * np.eye(3)
    assert direct_index(gram) == (0.0 if singular else pytest.approx(2.0))


@pytest.mark.parametrize("entry", [(0, 0), (1, 1), (2, 2), (3, 3), (4, 4), (5, 5)])
def test_a_gram_with_an_infinite_diagonal_entry_has_index_0(entry):
    """docs/explanation/warnings.md, Singularities: the index is 0 where M is not finite (an overflowed pose)."""
    gram = np.eye(6)
    gram[entry] = np.inf
    assert direct_index(gram) == 0.0


def test_a_crank_whose_platform_point_lies_on_its_axis_is_unreachable_with_finite_joints():
    """Pivot (200, 0, 0), crank turning in the x-z plane (direction 0 degrees): a platform
    point on the line through the pivot along y has a = b = 0 (rho = 0): no crank angle
    reaches it; the joints stay finite (docs/explanation/warnings.md)."""
    robot = load_robot("ceart")
    limb = robot.limbs[0].model_copy(update={"pivot": (200.0, 0.0, 0.0), "crank_direction": 0.0})
    solution = limb.solve(np.array([[200.0, 50.0, 0.0]]))
    assert solution.radicand.tolist() == [-1.0]
    assert np.all(np.isfinite(solution.values))


def test_newton_steps_are_at_most_a_fifth_of_the_size_and_of_a_turn():
    """forward._limited: a step of the robot's whole size shrinks to a fifth of it, one of a
    whole turn to a fifth of a turn (0.4 pi), every coordinate by the same factor (the
    direction kept); a step within both limits is kept as it is."""
    from kingen.kinematics.forward import _limited

    size = 500.0
    steps = np.array([[size, 0.0, 50.0, 0.0, 0.0, 0.0],
                      [0.0, 0.0, 0.0, 0.0, 2 * math.pi, 0.1],
                      [10.0, -20.0, 30.0, 0.1, -0.2, 0.3]])
    limited = _limited(steps, size, np.ones(6, dtype=bool))
    assert np.allclose(limited[0], [size / 5, 0.0, 10.0, 0.0, 0.0, 0.0], rtol=1e-15, atol=0)
    assert np.allclose(limited[1], [0.0, 0.0, 0.0, 0.0, 0.4 * math.pi, 0.02], rtol=1e-15, atol=0)
    assert np.array_equal(limited[2], steps[2])


def test_forward_results_are_values_that_cannot_change():
    """AssemblyModes and Assembly are frozen: a result handed out cannot be altered afterwards."""
    import dataclasses

    modes = forward.AssemblyModes(found=[], exhaustive=True, method="closed form")
    assembly = forward.Assembly(pose=np.zeros(6), residual_mm=0.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        modes.exhaustive = False
    with pytest.raises(dataclasses.FrozenInstanceError):
        assembly.residual_mm = 1.0


def test_a_singular_leading_minor_is_not_positive_definite_whatever_the_last_rounds_to():
    """A = [[1, 1, 1], [1, 1, 2], [1, 2, 1e17]]: its leading 2 x 2 minor is 1 - 1 = 0 exactly, so
    A is not positive definite (exactly, its determinant is -1: a negative eigenvalue; LAPACK's
    eigenvalues of the rounded matrix may say either), although the expanded 3 x 3 determinant
    rounds to +1 (1e17 - 4 and 1e17 - 2 both round to 1e17)."""
    from fractions import Fraction

    from kingen.kinematics.singularity import _positive_definite, _shifted

    matrix = np.array([[1.0, 1.0, 1.0], [1.0, 1.0, 2.0], [1.0, 2.0, 1e17]])
    a = [[Fraction(value) for value in row] for row in matrix]
    exact = (a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
             + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]))
    assert exact == -1
    entries = as_entries(matrix[None])
    assert _shifted(entries, 0.0)[1] > 0  # the rounded determinant alone would say positive
    assert not _positive_definite(entries, 0.0)[0]


@pytest.mark.parametrize("index, name", list(enumerate(["x", "y", "z", "roll", "pitch", "yaw"])))
def test_each_named_coordinate_frees_its_own_pose_coordinate(index, name):
    """docs/how-to/robot-files.md: forward: {free: [...]} names pose coordinates x, y, z, roll, pitch,
    yaw (the pose's order): freeing one name frees that coordinate alone; naming none frees all."""
    from dataclasses import replace

    robot = load_robot("exechon")
    assert forward.free_mask(replace(robot, forward_free=(name,))).tolist() == [k == index for k in range(6)]
    assert forward.free_mask(replace(robot, forward_free=None)).tolist() == [True] * 6


def test_three_spheres_missing_by_exactly_the_allowance_still_meet():
    """Trilateration accepts a negative z^2 down to -1e-9 r0^2 inclusive (rounding of spheres
    that touch). Centres 0, (2^17, 0, 0), (0, 4, 0) and radii 1e5, r1, 1e5: y = 16 / 8 = 2
    exactly, and r1 (found by a search over consecutive floats) makes x = 100000.00003 with
    r0^2 - x^2 - y^2 = -10 = -1e-9 r0^2 exactly in floating point: one point, at z = 0."""
    centres = np.array([[0.0, 0.0, 0.0], [2.0 ** 17, 0.0, 0.0], [0.0, 4.0, 0.0]])
    radii = np.array([1e5, 31071.999873450026, 1e5])
    x = (radii[0] ** 2 - radii[1] ** 2 + centres[1, 0] ** 2) / (2 * centres[1, 0])
    assert (x, radii[0] ** 2 - x ** 2 - 2.0 ** 2) == (100000.00003, -1e-9 * radii[0] ** 2)
    found = _three_spheres(centres, radii)
    assert len(found) == 1 and np.array_equal(found[0], [100000.00003, 2.0, 0.0])


def test_the_multi_start_search_spans_search_times_the_region_and_at_most_half_a_turn():
    """forward.search_region: centred on the verification home (mm, radians), half widths
    ``search`` times the region's (angles in radians), angles capped at pi (a half turn)."""
    robot = load_robot("exechon")
    region = robot.verification
    home, half = forward.search_region(robot, 2.0)
    assert np.array_equal(home, np.concatenate([region.home[:3], np.radians(region.home[3:])]))
    assert np.array_equal(half[:3], 2.0 * np.asarray(region.range[:3], dtype=float))
    assert np.array_equal(half[3:], np.minimum(2.0 * np.radians(region.range[3:]), np.pi))
    _, wide = forward.search_region(robot, 1e6)
    assert wide[3:].tolist() == [np.pi] * 3 and np.all(wide[:3] == 1e6 * np.asarray(region.range[:3], dtype=float))


def test_newton_stops_at_its_first_step_within_1e_13_of_the_size(monkeypatch):
    """forward.CONVERGED: Newton stops when no step exceeds 1e-13 of the robot's size (mm) or of a
    radian, and not before. Newton's steps from starts near the Stewart-Gough example's home
    are recorded (|step| / scale, translations then rotations); among seeded starts one takes a
    step whose rotations reach between 1e-13 and 2e-13 rad, its translations within 1e-13 of the
    size: Newton goes on after it and stops at the next, the first wholly within 1e-13, which is
    not 0 (so a stricter stop would go on)."""
    from kingen.conventions import t6_from_pose
    from kingen.kinematics.reference import solve

    robot = load_robot("stewart_gough_example")
    home = np.asarray(robot.verification.home, dtype=float)
    target = np.concatenate([home[:3], np.radians(home[3:])])
    joints = solve(robot, t6_from_pose([home])).joints[0, :, 0]
    free = forward.free_mask(robot)
    scale = np.array([robot.size_mm] * 3 + [1.0] * 3)
    limited, steps = forward._limited, []

    def recorded(step, size_mm, free):
        step = limited(step, size_mm, free)
        steps.append(np.abs(step[0]) / scale[free])
        return step

    monkeypatch.setattr(forward, "_limited", recorded)
    rng = np.random.default_rng(1)
    for _ in range(100):
        steps.clear()
        start = target + rng.normal(size=6) * np.where(scale > 1, 1e-3 * robot.size_mm, 1e-3) * rng.uniform(0.1, 10)
        forward.newton(robot, start[None], joints[None], free)
        if any(1e-13 < size[3:].max() <= 2e-13 and size[:3].max() <= 1e-13 for size in steps):
            break
    else:
        pytest.fail("no start took a step of 1e-13 to 2e-13 rad with translations within 1e-13")
    largest = [size.max() for size in steps]
    assert 0.0 < largest[-1] <= 1e-13 and all(size > 1e-13 for size in largest[:-1]), largest


def test_a_multi_start_search_is_never_called_exhaustive_and_says_where_it_looked():
    """The Exechon (free: z, roll, pitch; fewer than six limbs, no closed form) at its home:
    Newton from the pose itself, the home and STARTS seeded starts over SEARCH = 2 times its
    verification region (home (0, 50, -1250) mm, 0 deg; range 200 mm in z, 10 deg): not
    exhaustive, and the region it searched is named coordinate by coordinate."""
    from kingen.conventions import t6_from_pose
    from kingen.kinematics.reference import solve

    robot = load_robot("exechon")
    home = np.asarray(robot.verification.home, dtype=float)
    joints = solve(robot, t6_from_pose([home])).joints[0, :, 0]
    modes = forward.assemblies(robot, joints, np.concatenate([home[:3], np.radians(home[3:])]))
    assert not modes.exhaustive and len(modes.found) >= 1
    assert modes.method == (f"not exhaustive: Newton from {forward.STARTS + 2} starts over 2 x the verification region "
                            "(z -1250 +- 400, roll 0 +- 20, pitch 0 +- 20; mm, deg); --search widens it")


def test_the_seeded_starts_spread_over_the_whole_search_region():
    """forward.starts: ``near`` first, then the home, then STARTS seeded poses drawn uniformly
    over home +/- the search region's half widths: inside it, and on both sides of home in
    every coordinate (256 uniform draws all on one side would have odds of 2^-256)."""
    robot = load_robot("exechon")
    home, half = forward.search_region(robot)
    near = home + 0.1 * half
    begin = forward.starts(robot, near)
    assert len(begin) == forward.STARTS + 2
    assert np.array_equal(begin[0], near) and np.array_equal(begin[1], home)
    drawn = begin[2:]
    assert np.all(np.abs(drawn - home) <= half)
    assert np.all(drawn.min(axis=0) < home) and np.all(drawn.max(axis=0) > home)


def test_a_repeated_largest_eigenvalue_rounding_past_minus_one_still_gives_the_smallest():
    """Q diag(7, 7, 2) Q^T for seeded rotations Q: det(B) / 2 is -1 exactly (two equal largest
    eigenvalues), and rounds below -1 for about half of them; clamped to -1, the closed form
    still gives 2 (to the sqrt(eps) x 7 it keeps at +/-1), never NaN."""
    rng = np.random.default_rng(0)
    rotations = [np.linalg.qr(rng.normal(size=(3, 3)))[0] for _ in range(40)]
    matrices = np.array([q @ np.diag([7.0, 7.0, 2.0]) @ q.T for q in rotations])
    matrices = (matrices + np.swapaxes(matrices, 1, 2)) / 2
    assert _smallest_eigenvalue(as_entries(matrices)) == pytest.approx(np.full(40, 2.0), rel=1e-6)
