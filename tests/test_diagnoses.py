"""Every diagnosis of kingen/verify/diagnose.py asserted word for word on data built to have it, where
its count and its complement differ. The routines here are the reference's own joints with
one constructed defect; each expected number follows from that construction (an offset of
22.913 mm on leg6 makes L0 look like 399.413 - 22.913 = 376.5 mm, the Flexapod's)."""

import math

import numpy as np
import pytest

from conftest import ONE_RAIL, random_t6
from kingen.verify.diagnose import MATCH, NAMED_SCALES, _ranges, diagnose, diagnose_warnings
from kingen.robot.model import load_robot
from kingen.kinematics.reference import solve
from kingen.kinematics.routine import WARNINGS

NAMES = {code: name for name, code in WARNINGS.items()}
GOOD, LIMITS = WARNINGS["WARN_GOOD_SOLUTION"], WARNINGS["WARN_JOINT_LIMITS_EXCEEDED"]
UNREACHABLE, SINGULAR = WARNINGS["WARN_UNREACHABLE"], WARNINGS["WARN_SINGULAR_SOLUTION"]


def case(name, count=40, seed=2):
    robot = load_robot(name)
    _, t6 = random_t6(robot, count, seed)
    expected = solve(robot, t6)
    return robot, t6, expected


def findings(robot, t6, joints, expected):
    return diagnose(robot, t6, joints, expected.joints, expected.warnings)


def test_the_reference_itself_needs_no_diagnosis():
    robot, t6, expected = case("tau")
    assert findings(robot, t6, expected.joints.copy(), expected) == []


def test_a_leg_off_by_a_constant_names_the_reference_length_it_behaves_as():
    robot, t6, expected = case("hexapod")
    joints = expected.joints.copy()
    joints[:, 5] += 22.913
    assert findings(robot, t6, joints, expected) == [
        "joint 5 (leg6) is off by a constant +22.913 mm on every pose and posture: a wrong reference length "
        "(the routine behaves as if L0 = 376.5 mm; the robot says 399.413 mm)"]


def test_a_leg_off_by_its_reference_length_reports_absolute_lengths():
    robot, t6, expected = case("hexapod")
    joints = expected.joints.copy()
    joints[:, 0] += 399.413
    assert findings(robot, t6, joints, expected)[0].endswith(
        "absolute strut length, not its extension from the reference length 399.413 mm (as LinuxCNC's genhexkins "
        "does): to verify it, set reference_length: 0")


def test_a_rail_off_by_a_constant_names_its_origin():
    """tau: some poses leave postures unreachable, where the routine's joints are free (here
    garbage): the offset is still found on the poses every posture reaches."""
    robot, t6, expected = case("tau", count=60)
    joints = expected.joints.copy()
    joints[:, 1] -= 5.0
    unreachable = np.any(expected.warnings == UNREACHABLE, axis=1)
    assert 0 < unreachable.sum() < len(t6)
    joints[unreachable] = 1e6 * np.random.default_rng(0).random(joints[unreachable].shape)
    assert findings(robot, t6, joints, expected) == [
        "joint 1 (carriage2) is off by a constant -5 mm on every pose and posture: "
        "a wrong rail origin or carriage offset along the rail"]


def test_a_crank_off_by_a_constant_names_its_zero_in_degrees():
    robot, t6, expected = case("ceart", count=20)
    joints = expected.joints.copy()
    joints[:, 3] = np.angle(np.exp(1j * (joints[:, 3] + math.radians(2.5))))  # wrapped as a routine answers
    reachable = np.all(expected.warnings != UNREACHABLE, axis=1)
    assert reachable.sum() >= 5
    assert findings(robot, t6, joints, expected) == [
        "joint 3 (crank4) is off by a constant +0.0436332 rad on every pose and posture: a wrong crank zero (+2.5 deg)"]


def test_a_sign_flip_a_scale_and_a_swap_are_each_named():
    robot, t6, expected = case("hexapod")
    joints = expected.joints.copy()
    joints[:, 1] = -expected.joints[:, 1]
    joints[:, 2] = 1e-3 * expected.joints[:, 2]
    joints[:, 3] = 2.5 * expected.joints[:, 3]
    joints[:, 4], joints[:, 5] = expected.joints[:, 5], expected.joints[:, 4]
    assert findings(robot, t6, joints, expected) == [
        "joint 1 (leg2) has its sign flipped: the routine returns minus the reference value",
        "joint 2 (leg3) is scaled by 0.001 (metres instead of mm)",
        "joint 3 (leg4) is scaled by 2.5 (a unit or gear-ratio error)",
        "joint 4 (leg5) holds the values of reference joint 5 (leg6): joints swapped in the solutions array",
        "joint 5 (leg6) holds the values of reference joint 4 (leg5): joints swapped in the solutions array"]


def test_degrees_for_radians_is_named():
    robot, t6, expected = case("ceart", count=20)
    joints = expected.joints.copy()
    joints[:, 0] = np.degrees(expected.joints[:, 0])
    assert findings(robot, t6, joints, expected) == [
        "joint 0 (crank1) is scaled by 57.2957795 (degrees instead of radians)"]


def test_postures_in_another_order_are_named_with_the_permutation():
    robot, t6, expected = case("tau", count=60)
    joints = expected.joints[:, :, ::-1].copy()
    assert findings(robot, t6, joints, expected) == [
        "postures are in another order: plugin posture -> reference posture 0->7, 1->6, 2->5, 3->4, 4->3, 5->2, "
        "6->1, 7->0 (permutation [7, 6, 5, 4, 3, 2, 1, 0]; kingen numbers postures with the first two-branch limb "
        "most significant, branch 0 first)"]


def test_two_postures_swapped_are_named_alone():
    robot, t6, expected = case("tau", count=60)
    joints = expected.joints[:, :, [0, 1, 3, 2, 4, 5, 6, 7]].copy()
    assert findings(robot, t6, joints, expected) == [
        "postures are in another order: plugin posture -> reference posture 2->3, 3->2 (permutation "
        "[0, 1, 3, 2, 4, 5, 6, 7]; kingen numbers postures with the first two-branch limb most significant, "
        "branch 0 first)"]


def test_t6_read_untransposed_is_named_with_its_pose_count():
    robot, t6, expected = case("hexapod", count=25)
    joints = solve(robot, np.swapaxes(t6, 1, 2)).joints
    text = findings(robot, t6, joints, expected)
    assert len(text) == 1 and text[0].startswith("the routine reads T6 untransposed")
    assert text[0].endswith("(its values match the reference fed the transpose on all 25 poses)")


def test_postures_never_written_are_named_by_range():
    robot, t6, expected = case("tau")
    joints = expected.joints.copy()
    joints[:, :, [2, 3, 5]] = np.nan
    assert findings(robot, t6, joints, expected) == [
        "the joints of postures 2-3, 5 are never written (or are NaN) on any pose"]


def test_an_unexplained_difference_names_its_worst_pose():
    robot, t6, expected = case("hexapod", count=10)
    joints = expected.joints.copy()
    joints[3, 0] += 0.5
    joints[7, 0] -= 0.2
    assert findings(robot, t6, joints, expected) == [
        "joint 0 (leg1) disagrees by up to 0.5 mm (worst on pose 3); no constant offset, sign flip, scale, "
        "joint swap or posture order explains it"]


def test_ranges():
    assert [_ranges(i) for i in ([0, 1, 2, 5], [4], [1, 3], [0, 1, 2, 3], [2, 3, 7, 8, 9])] == [
        "0-2, 5", "4", "1, 3", "0-3", "2-3, 7-9"]


def warnings_of(pairs, postures=4):
    """(plugin, reference) warning arrays holding ``pairs`` [(mine, theirs, count)] in that
    order, padded with agreeing WARN_GOOD_SOLUTION entries."""
    mine, theirs = [], []
    for a, b, count in pairs:
        mine += [a] * count
        theirs += [b] * count
    pad = -len(mine) % postures + postures
    mine, theirs = mine + [GOOD] * pad, theirs + [GOOD] * pad
    return np.array(mine).reshape(-1, postures), np.array(theirs).reshape(-1, postures)


def test_differing_warnings_are_counted_pair_by_pair_most_frequent_first_four_at_most():
    mine, theirs = warnings_of([(GOOD, SINGULAR, 2), (SINGULAR, GOOD, 5), (LIMITS, GOOD, 1), (UNREACHABLE, GOOD, 4),
                                (GOOD, LIMITS, 3)])
    assert diagnose_warnings(mine, theirs, NAMES) == [
        "5 postures answer WARN_SINGULAR_SOLUTION where the reference says WARN_GOOD_SOLUTION",
        "4 postures answer WARN_UNREACHABLE where the reference says WARN_GOOD_SOLUTION",
        "3 postures answer WARN_GOOD_SOLUTION where the reference says WARN_JOINT_LIMITS_EXCEEDED",
        "2 postures answer WARN_GOOD_SOLUTION where the reference says WARN_SINGULAR_SOLUTION"]


def test_an_unknown_code_is_named_by_its_number():
    mine, theirs = warnings_of([(7, GOOD, 3)])
    assert diagnose_warnings(mine, theirs, NAMES) == ["3 postures answer 7 where the reference says WARN_GOOD_SOLUTION"]


def test_one_differing_posture_is_counted_in_the_singular():
    mine, theirs = warnings_of([(7, GOOD, 1)])
    assert diagnose_warnings(mine, theirs, NAMES) == ["1 posture answers 7 where the reference says WARN_GOOD_SOLUTION"]


def test_unwritten_warnings_are_named_and_not_counted_as_differing():
    mine, theirs = warnings_of([(-1, GOOD, 1), (SINGULAR, GOOD, 2)])
    mine[1, 3] = -1  # postures 0 and 3 unwritten somewhere
    assert diagnose_warnings(mine, theirs, NAMES) == [
        "the warnings of postures 0, 3 are never written on some poses",
        "2 postures answer WARN_SINGULAR_SOLUTION where the reference says WARN_GOOD_SOLUTION"]


def test_a_routine_that_always_answers_good_is_told_what_the_reference_finds():
    """3 of 12 entries unreachable and 1 singular: neither half nor all."""
    mine = np.zeros((3, 4), dtype=int)
    theirs = np.array([[GOOD, UNREACHABLE, GOOD, GOOD], [SINGULAR, GOOD, UNREACHABLE, GOOD],
                       [GOOD, GOOD, GOOD, UNREACHABLE]])
    assert diagnose_warnings(mine, theirs, NAMES) == [
        "the routine always answers WARN_GOOD_SOLUTION; the reference finds "
        "{'WARN_UNREACHABLE': 3, 'WARN_SINGULAR_SOLUTION': 1}"]


@pytest.mark.parametrize("mine, theirs", [(np.zeros((2, 2), int), np.zeros((2, 2), int)),
                                          (np.full((2, 2), SINGULAR), np.full((2, 2), SINGULAR))])
def test_agreeing_warnings_need_no_diagnosis(mine, theirs):
    assert diagnose_warnings(mine, theirs, NAMES) == []


@pytest.mark.parametrize("scale, label", [
    (1e-3, "metres instead of mm"), (1e3, "micrometres instead of mm"), (1 / 25.4, "inches instead of mm"),
    (180 / math.pi, "degrees instead of radians"), (math.pi / 180, "radians read as degrees")])
def test_every_named_scale_is_named(scale, label):
    """The unit factors themselves (1 m = 1000 mm, 1 in = 25.4 mm, 1 rad = 180 / pi degrees),
    written here, not read from kingen."""
    assert len(NAMED_SCALES) == 5
    robot, t6, expected = case("hexapod", count=12)
    joints = expected.joints.copy()
    joints[:, 4] = scale * expected.joints[:, 4]
    assert findings(robot, t6, joints, expected) == [f"joint 4 (leg5) is scaled by {scale:.9g} ({label})"]


@pytest.mark.parametrize("jitter, explained", [(0.6 * MATCH, True), (1.5 * MATCH, False)])
def test_an_offset_explains_the_data_only_within_match(jitter, explained):
    """A constant +3 mm with alternating +/-jitter: the median is 3 mm, the residual the jitter."""
    robot, t6, expected = case("hexapod", count=12)
    joints = expected.joints.copy()
    joints[:, 2] += 3.0 + jitter * np.where(np.arange(12) % 2 == 0, 1.0, -1.0)[:, None]
    text = findings(robot, t6, joints, expected)
    assert len(text) == 1
    assert text[0].startswith("joint 2 (leg3) is off by a constant +3 mm") == explained
    assert text[0].startswith("joint 2 (leg3) disagrees by up to 3 mm") == (not explained)


def test_a_crank_offset_is_measured_across_the_half_turn():
    """+170 degrees on a crank near +32 degrees wraps to about -158: the offset is the wrapped
    difference, +170 degrees, not -190."""
    robot, t6, expected = case("ceart", count=20)
    joints = expected.joints.copy()
    joints[:, 1] = np.angle(np.exp(1j * (joints[:, 1] + math.radians(170.0))))
    assert findings(robot, t6, joints, expected) == [
        "joint 1 (crank2) is off by a constant +2.96706 rad on every pose and posture: a wrong crank zero (+170 deg)"]


def one_rail_robot(tmp_path):
    path = tmp_path / "one_rail.yaml"
    path.write_text(ONE_RAIL)
    return load_robot(path)


def test_two_postures_in_the_other_order_are_named(tmp_path):
    robot = one_rail_robot(tmp_path)
    _, t6 = random_t6(robot, 10, 1)
    expected = solve(robot, t6)
    assert findings(robot, t6, expected.joints[:, :, ::-1].copy(), expected) == [
        "postures are in another order: plugin posture -> reference posture 0->1, 1->0 (permutation [1, 0]; kingen "
        "numbers postures with the first two-branch limb most significant, branch 0 first)"]


def given_reference(joint_values, mine_values, count=10):
    """diagnose on the hexapod with joint 0 of the reference set to ``joint_values`` (n,) and
    the routine's to ``mine_values`` (n,), every other joint agreeing."""
    robot, t6, expected = case("hexapod", count=count)
    reference = expected.joints.copy()
    reference[:, 0, 0] = joint_values
    mine = reference.copy()
    mine[:, 0, 0] = mine_values
    return diagnose(robot, t6, mine, reference, expected.warnings)


def test_a_reference_joint_of_zero_everywhere_has_no_scale():
    noise = np.linspace(-1.0, 1.0, 10) ** 3
    assert given_reference(np.zeros(10), noise) == [
        "joint 0 (leg1) disagrees by up to 1 mm (worst on pose 0); no constant offset, sign flip, scale, joint swap "
        "or posture order explains it"]


def test_a_scale_of_small_values_is_named():
    theirs = np.linspace(1e-3, 2e-3, 10)  # their sum of squares is far below 1
    assert given_reference(theirs, 3.0 * theirs) == ["joint 0 (leg1) is scaled by 3 (a unit or gear-ratio error)"]


@pytest.mark.parametrize("scale, jitter, explained", [(1000.0, 0.5e-3, True), (1.5, 1.8e-6, False), (1.5, 1.2e-6, True)])
def test_a_scale_explains_within_match_times_the_scale(scale, jitter, explained):
    theirs = np.linspace(50.0, 80.0, 10)
    text = given_reference(theirs, scale * theirs + jitter * (-1.0) ** np.arange(10))
    assert len(text) == 1 and (" is scaled by " in text[0]) == explained


@pytest.mark.parametrize("error, label", [(0.5e-6, "inches instead of mm"), (1.5e-6, "a unit or gear-ratio error")])
def test_a_scale_is_named_within_1e_6_relative(error, label):
    theirs = np.linspace(50.0, 80.0, 10)
    text = given_reference(theirs, theirs / 25.4 * (1.0 + error))
    assert text[0].endswith(f"({label})")


def exactly_match(count):
    """``count`` values of exactly MATCH and their doubles: 2 x 1e-6 is 1e-6 doubled in binary,
    so 2e-6 - 1e-6 == 1e-6 == MATCH holds exactly (no rounding)."""
    assert 2 * MATCH - MATCH == MATCH
    return np.full(count, MATCH)


def test_a_joint_off_by_exactly_match_agrees():
    """'Largest residual at which a hypothesis counts' (MATCH) is inclusive: a joint off by
    exactly 1e-6 mm on every pose needs no diagnosis."""
    assert given_reference(np.zeros(10), exactly_match(10)) == []


def test_an_offset_with_a_residual_of_exactly_match_explains_the_data():
    """Six values of 1e-6 and five of 2e-6 (11 poses): the median is 1e-6, the largest residual
    about it 2e-6 - 1e-6 = MATCH exactly, the largest difference 2e-6 (above MATCH)."""
    mine = np.concatenate([exactly_match(6), 2 * exactly_match(5)])
    assert given_reference(np.zeros(11), mine, count=11)[0].startswith(
        "joint 0 (leg1) is off by a constant +1e-06 mm on every pose and posture: ")


def test_a_joint_within_exactly_match_of_another_joint_is_named_swapped():
    """The reference's joint 0 at 5 mm and joint 1 at 0; the routine's joint 0 at exactly
    MATCH (joint 1 right): it holds joint 1's values within MATCH, inclusive."""
    robot, t6, expected = case("hexapod", count=10)
    reference = expected.joints.copy()
    reference[:, 0, 0], reference[:, 1, 0] = 5.0, 0.0
    mine = reference.copy()
    mine[:, 0, 0] = MATCH
    assert diagnose(robot, t6, mine, reference, expected.warnings) == [
        "joint 0 (leg1) holds the values of reference joint 1 (leg2): joints swapped in the solutions array"]


def test_a_sign_flip_within_exactly_match_is_named():
    """The reference's joint 0 at 2e-6, 4e-6, ... (exact doublings of MATCH), the routine's
    their negatives but on pose 0, where it answers -1e-6: mine + theirs = MATCH exactly there."""
    theirs = 2.0 ** np.arange(1, 11) * MATCH
    mine = -theirs
    mine[0] = -MATCH
    assert mine[0] + theirs[0] == MATCH
    assert given_reference(theirs, mine) == [
        "joint 0 (leg1) has its sign flipped: the routine returns minus the reference value"]


def test_postures_within_exactly_match_of_each_other_are_matched(tmp_path):
    """A one-rail robot's reference at 0 (posture 0) and 5 mm (posture 1) on every pose; the
    routine answers 5 mm in posture 0 and exactly MATCH in posture 1: each matches the other
    posture (the second within MATCH, inclusive) and no other, so the order is named."""
    robot = one_rail_robot(tmp_path)
    _, t6 = random_t6(robot, 10, 1)
    expected = solve(robot, t6)
    reference = np.zeros((10, 1, 2))
    reference[:, :, 1] = 5.0
    mine = np.full((10, 1, 2), 5.0)
    mine[:, :, 1] = MATCH
    assert diagnose(robot, t6, mine, reference, expected.warnings)[0].startswith(
        "postures are in another order: plugin posture -> reference posture 0->1, 1->0 (permutation [1, 0]; ")
