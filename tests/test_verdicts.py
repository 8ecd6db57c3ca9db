"""verify's verdicts on constructed cases, each boundary from both sides and each count exact.

- The warning band has three parts (docs/explanation/verify.md): a radicand within
  WARNING_BAND of +/-1e-5 (tests/test_verify_bands.py), a joint within WARNING_BAND of a
  travel limit, a direct index within WARNING_BAND relative of direct_index_min. Each is
  pinned here by poses built to lie a third of the band inside and thirty bands outside, on
  both sides of each limit.
- The Jacobian check is given routines it must fail and is asserted on how many
  joint-postures it compared.
- Per-posture statistics are asserted entry by entry on poses whose outcome is constructed.

Every expected number follows from the construction stated beside it."""

import math
from dataclasses import replace

import numpy as np
import pytest
from conftest import ONE_RAIL, PLUMB_LEG, ChangedCalls, ReferenceRoutine

from kingen.conventions import t6_from_pose
from kingen.hosts import get_host
from kingen.robot.model import load_robot
from kingen.kinematics.reference import solve
from kingen.verify.report import Report
from kingen.kinematics.routine import INPUTS_MODIFIED, WARNING_BAND, WARNINGS, Calls
from kingen.verify.checks.jacobian import jacobian_check
from kingen.verify.options import VerifyOptions
from kingen.verify.tally import Tally, accumulate, posture_statistics, warnings_in_band

GOOD, LIMITS = WARNINGS["WARN_GOOD_SOLUTION"], WARNINGS["WARN_JOINT_LIMITS_EXCEEDED"]
SINGULAR, UNREACHABLE = WARNINGS["WARN_SINGULAR_SOLUTION"], WARNINGS["WARN_UNREACHABLE"]


def calls_of(expected, warnings=None, solutions=None):
    warnings = expected.warnings if warnings is None else warnings
    return Calls(returned=np.where(np.all(expected.warnings == UNREACHABLE, axis=1), 1, 0).astype(np.intc),
                 solutions=(expected.joints if solutions is None else solutions).copy(),
                 warnings=np.asarray(warnings, dtype=np.intc).copy(), faults=np.zeros(len(warnings), dtype=np.intc))


def compared(robot, t6, calls, expected):
    report = Report(robot=robot.name, routine=get_host("delmia").routine_name(robot), samples=len(t6), seed=0,
                    postures=robot.postures)
    tally = Tally.start(robot)
    accumulate(robot, report, tally, robot.revolute, t6, calls, expected)
    return report, tally


@pytest.fixture
def leg(tmp_path):
    path = tmp_path / "plumb_leg.yaml"
    path.write_text(PLUMB_LEG)
    return load_robot(path)


@pytest.mark.parametrize("limit", [100.0, 200.0])
@pytest.mark.parametrize("offset, excused", [(WARNING_BAND / 3, True), (-WARNING_BAND / 3, True),
                                             (30 * WARNING_BAND, False), (-30 * WARNING_BAND, False)])
def test_a_warning_may_differ_beside_a_travel_limit_only_inside_the_band(leg, limit, offset, excused):
    t6 = t6_from_pose([[0.0, 0.0, limit + offset, 0.0, 0.0, 0.0]])
    expected = solve(leg, t6)
    assert abs(expected.joints[0, 0, 0] - (limit + offset)) < WARNING_BAND / 10
    outside = offset < 0 if limit == 100.0 else offset > 0
    assert expected.warnings[0, 0] == (LIMITS if outside else GOOD)
    assert bool(warnings_in_band(leg, expected)[0, 0]) == excused
    flipped = np.where(expected.warnings == LIMITS, GOOD, LIMITS)
    report, _ = compared(leg, t6, calls_of(expected, flipped), expected)
    assert (report.warnings_in_band, report.warning_mismatches) == ((1, 0) if excused else (0, 1))


def test_far_from_its_limits_a_leg_is_never_in_the_band(leg):
    t6 = t6_from_pose([[0.0, 0.0, z, 0.0, 0.0, 0.0] for z in (50.0, 150.0, 250.0)])
    expected = solve(leg, t6)
    assert expected.warnings[:, 0].tolist() == [LIMITS, GOOD, LIMITS]
    assert not np.any(warnings_in_band(leg, expected))


HEXAPOD_POSE = [[10.0, -5.0, 470.0, 2.0, -1.0, 3.0]]
"""A regular pose of the hexapod (index near 13 mm): the threshold is set relative to the
reference's own index there, so which side the pose lies on is the construction."""


@pytest.mark.parametrize("relative, excused", [(WARNING_BAND / 3, True), (-WARNING_BAND / 3, True),
                                               (30 * WARNING_BAND, False), (-30 * WARNING_BAND, False)])
def test_a_warning_may_differ_beside_the_direct_index_threshold_only_inside_the_band(relative, excused):
    robot = load_robot("hexapod")
    t6 = t6_from_pose(HEXAPOD_POSE)
    index = float(solve(replace(robot, direct_index_min=None), t6, indices=True).direct_index[0, 0])
    assert 5.0 < index < 30.0
    threshold = index / (1.0 + relative)  # relative > 0: the index is above the threshold (good)
    moved = replace(robot, direct_index_min=threshold)
    expected = solve(moved, t6)
    assert expected.warnings[0, 0] == (GOOD if relative > 0 else SINGULAR)
    assert bool(warnings_in_band(moved, expected)[0, 0]) == excused
    flipped = np.where(expected.warnings == SINGULAR, GOOD, SINGULAR)
    report, _ = compared(moved, t6, calls_of(expected, flipped), expected)
    assert (report.warnings_in_band, report.warning_mismatches) == ((1, 0) if excused else (0, 1))


def test_verify_draws_10000_poses_unless_told():
    assert VerifyOptions().samples == 10000  # docs/explanation/verify.md: verify's --samples, default 10000


def test_an_unwritten_warning_is_never_excused_inside_a_band(leg):
    t6 = t6_from_pose([[0.0, 0.0, 200.0 + WARNING_BAND / 3, 0.0, 0.0, 0.0]])
    expected = solve(leg, t6)
    report, _ = compared(leg, t6, calls_of(expected, [[-1]]), expected)
    assert (report.warnings_in_band, report.warning_mismatches) == (0, 1)


def sg_t6():
    """Five poses of the Stewart-Gough example inside its leg travel 10..140 mm (joints 49 to
    86 mm: WARN_GOOD_SOLUTION), and one beyond it (z = 340: every leg 153.7 mm,
    WARN_JOINT_LIMITS_EXCEEDED), which the check leaves out."""
    poses = [[0, 0, 250, 0, 0, 0], [10, -5, 255, 2, -1, 3], [-12, 9, 245, -3, 2, -4],
             [5, 14, 260, 1, 3, 2], [-9, -10, 240, 4, -2, 6], [0, 0, 340, 0, 0, 0]]
    return t6_from_pose(poses)


def test_the_jacobian_check_compares_every_regular_joint_posture_and_passes_the_reference():
    robot = load_robot("stewart_gough_example")
    t6 = sg_t6()
    assert solve(robot, t6).warnings[:, 0].tolist() == [GOOD] * 5 + [LIMITS]
    check = jacobian_check(robot, ReferenceRoutine(robot), VerifyOptions(), t6)
    assert check.passed and check.judged == 5 * 6  # five good poses x six legs x one posture
    assert "on 30 regular joint-postures of 6 poses" in check.detail


@pytest.mark.parametrize("change", [
    pytest.param(lambda t6, joints: joints.__imul__(1.001), id="scaled by 1.001"),
    pytest.param(lambda t6, joints: joints.__setitem__((slice(None), 2), joints[:, 2] + 1e-3 * t6[:, 3, 0, None]),
                 id="one leg drifts with x"),
    pytest.param(lambda t6, joints: joints.__setitem__((slice(None), 0), joints[:, 0] + 1e-4 * (t6[:, 3, 2, None] - 250) ** 2),
                 id="one leg curved in z"),
])
def test_the_jacobian_check_fails_a_routine_whose_rates_are_wrong(change):
    robot = load_robot("stewart_gough_example")
    check = jacobian_check(robot, ReferenceRoutine(robot, change), VerifyOptions(), sg_t6())
    assert not check.passed and check.judged == 30


def test_the_jacobian_check_passes_a_constant_offset():
    """A constant offset changes no rate: the values check catches it, not this one."""
    robot = load_robot("stewart_gough_example")
    shifted = ReferenceRoutine(robot, lambda t6, joints: joints.__iadd__(5.0))
    check = jacobian_check(robot, shifted, VerifyOptions(), sg_t6())
    assert check.passed and check.judged == 30


def test_per_posture_statistics_count_each_outcome_exactly(tmp_path):
    path = tmp_path / "one_rail.yaml"
    path.write_text(ONE_RAIL)
    robot = load_robot(path)
    poses = [[50, 0, -50, 0, 0, 0]] * 4 + [[60, 0, -40, 0, 0, 0]] * 3 + [[150, 0, -50, 0, 0, 0]] * 2
    t6 = t6_from_pose(poses)
    expected = solve(robot, t6)
    assert expected.warnings.tolist() == [[GOOD, GOOD]] * 7 + [[UNREACHABLE, UNREACHABLE]] * 2
    joints, warnings = expected.joints.copy(), expected.warnings.copy()
    joints[0, 0, 1] += 2e-6          # pose 0: posture 1 solved wrong, by 2e-6 mm
    joints[1, 0, 0] -= 5e-7          # pose 1: posture 0 solved wrong, by 5e-7 mm
    joints[2, 0, 1] += 3e-10         # pose 2: within 1e-9 mm: right
    warnings[3, 0] = UNREACHABLE     # pose 3: posture 0 called unreachable wrongly
    warnings[4] = UNREACHABLE        # pose 4: both postures called unreachable wrongly
    warnings[7, 1] = GOOD            # pose 7: posture 1 "solved" where the reference cannot: missed
    calls = calls_of(expected, warnings, joints)
    report, tally = compared(robot, t6, calls, expected)
    statistics = posture_statistics(robot, tally)
    # posture 0: right at poses 0, 2, 5, 6 (4); wrong at 1; unreachable wrongly at 3, 4; missed none
    # posture 1: right at poses 1, 2, 3, 5, 6 (5); wrong at 0; unreachable wrongly at 4; missed at 7
    assert [(s["right"], s["wrong"], s["unreachable_wrongly"], s["missed"]) for s in statistics] == [
        (4, 1, 2, 0), (5, 1, 1, 1)]
    assert statistics[0]["worst_error_mm"] == pytest.approx(5e-7, rel=1e-6)
    assert statistics[1]["worst_error_mm"] == pytest.approx(2e-6, rel=1e-6)
    assert statistics[0]["worst_error_rad"] is None
    assert report.max_abs_error_mm == pytest.approx(2e-6, rel=1e-6)
    assert tally.reachable_poses == 7 and tally.returns_wrong == 0
    # warnings: 4 differ (pose 3 posture 0, pose 4 both, pose 7 posture 1), none in a band
    assert (report.warning_mismatches, report.warnings_in_band) == (4, 0)
    assert tally.warning_counts.tolist() == [14 if kind == "WARN_GOOD_SOLUTION" else 4 if kind == "WARN_UNREACHABLE"
                                            else 0 for kind in WARNINGS]


def test_a_rail_at_its_singular_radicand_is_counted_by_its_own_bound(tmp_path):
    """At x = 100 sqrt(1 - D) the normalised radicand is D (the rail's construction)."""
    path = tmp_path / "one_rail.yaml"
    path.write_text(ONE_RAIL)
    robot = load_robot(path)
    t6 = t6_from_pose([[100 * math.sqrt(1 - 1e-12), 0, -50, 0, 0, 0], [50, 0, -50, 0, 0, 0]])
    expected = solve(robot, t6)
    joints = expected.joints.copy()
    joints[0, 0, :] += 1e-8  # within 16 eps x 100 / sqrt(1e-12) = 3.6e-6 mm
    joints[1, 0, 0] += 1e-8  # outside the band: beyond 1e-9 mm, wrong
    report, tally = compared(robot, t6, calls_of(expected, None, joints), expected)
    statistics = posture_statistics(robot, tally)
    assert [(s["right"], s["wrong"]) for s in statistics] == [(1, 1), (2, 0)]
    assert report.singular_entries == 2 and report.singular_out_of_bound == 0


def test_closure_judges_every_reachable_branch_outside_the_singular_band_and_fails_a_wrong_joint(tmp_path):
    """The one rail at 6 regular poses (2 branches each), 1 pose in its singular band
    (x = 100 sqrt(1 - 1e-7): D = 1e-7) and 2 unreachable ones: 12 joints judged."""
    from kingen.verify.tally import closure_error

    path = tmp_path / "one_rail.yaml"
    path.write_text(ONE_RAIL)
    robot = load_robot(path)
    poses = ([[x, 0, -50, 0, 0, 0] for x in (0, 20, 40, 60, 80, 95)] + [[100 * math.sqrt(1 - 1e-7), 0, -50, 0, 0, 0]]
             + [[150, 0, -50, 0, 0, 0], [0, 150, -50, 0, 0, 0]])
    expected = solve(robot, t6_from_pose(poses))
    assert expected.warnings[:, 0].tolist() == [GOOD] * 6 + [SINGULAR] + [UNREACHABLE] * 2
    worst, judged = closure_error(robot, expected, expected.joints)
    assert judged == 12 and worst <= 1e-15
    wrong = expected.joints.copy()
    wrong[3, 0, 1] += 1e-4  # pose 3 (x = 60): the carriage moves 1e-4 mm along the rail
    worst, judged = closure_error(robot, expected, wrong)
    # |N - carriage| changes by 1e-4 times the cosine between link and rail, sqrt(1 - 0.6^2) = 0.8
    assert judged == 12 and worst == pytest.approx(0.8e-4 / 100, rel=1e-3)


def test_the_jacobian_check_with_no_regular_posture_judges_nothing_and_says_so():
    robot = load_robot("stewart_gough_example")
    check = jacobian_check(robot, ReferenceRoutine(robot), VerifyOptions(), sg_t6()[-1:])  # only the pose beyond travel
    assert (check.passed, check.exercised, check.judged) == (True, False, 0)
    assert check.detail == ("no reachable, regular joint-posture among the 1 pose to differentiate: of their 1 posture, "
                            "1 beyond travel")


def test_a_snapshot_names_exactly_the_entries_that_differ(tmp_path, capsys):
    """A recorded snapshot of tau with one joint moved by 1 mm (pose 1, carriage2, posture 3)
    and one warning changed (pose 2, posture 5): the check fails and lists those two."""
    import json

    from kingen.cli import main

    snapshot = tmp_path / "tau.golden.json"
    assert main(["golden", "record", "tau", "-o", str(snapshot), "--samples", "3"]) == 0
    data = json.loads(snapshot.read_text())
    recorded_joint = data["entries"][1]["joints"][1][3]
    data["entries"][1]["joints"][1][3] = recorded_joint + 1.0
    assert data["entries"][2]["warnings"][5] == GOOD
    data["entries"][2]["warnings"][5] = SINGULAR
    snapshot.write_text(json.dumps(data))
    capsys.readouterr()
    report = tmp_path / "report.json"
    assert main(["verify", "tau", "--golden", str(snapshot), "--samples", "50", "-o", str(tmp_path / "out"),
                 "--json", str(report)]) == 1
    check = next(check for check in json.loads(report.read_text())["checks"] if check["name"] == "snapshot")
    assert not check["passed"]
    assert "1 joints beyond" in check["detail"] and "1 warnings differ" in check["detail"]
    assert check["diagnoses"] == [
        f"pose 1 posture 3 carriage2: recorded {recorded_joint + 1.0:.9g}, now {recorded_joint:.9g} mm",
        "pose 2 posture 5: recorded warning WARN_SINGULAR_SOLUTION, now WARN_GOOD_SOLUTION"]


def test_just_outside_the_band_a_long_link_is_held_to_its_conditioning_bound(tmp_path):
    """A 20 m rail at D = 1e-3, outside the singular band: its bound 16 eps x 20 m / sqrt(1e-3)
    (about 2.2e-9 mm) exceeds the fixed 1e-9 mm, so a joint off by the mean of the two is
    within it (docs/explanation/verify.md: a 20 m rail up to |D| of about 5e-3)."""
    from kingen.verify.tally import singular_bounds

    path = tmp_path / "long_rail.yaml"
    path.write_text(ONE_RAIL.replace("link_length: 100", "link_length: 20000").replace("one_rail", "long_rail")
                    .replace("home: [50, 0, -50, 0, 0, 0]", "home: [5000, 0, -50, 0, 0, 0]"))
    robot = load_robot(path)
    t6 = t6_from_pose([[20000 * math.sqrt(1 - 1e-3), 0, -50, 0, 0, 0]])
    expected = solve(robot, t6)
    assert expected.radicands[0, 0] == pytest.approx(1e-3, rel=1e-6)
    fixed = np.array([1e-9])
    bound = singular_bounds(robot, expected, fixed)[0, 0]
    assert bound > 2e-9 and singular_bounds(robot, expected)[0, 0] == 0.0  # only the fixed bound brings it in
    shift = (bound + 1e-9) / 2
    report, _ = compared(robot, t6, calls_of(expected, None, expected.joints + shift), expected)
    assert report.singular_entries == 2 and report.singular_out_of_bound == 0 and report.max_abs_error_mm == 0.0


@pytest.mark.parametrize("name", ["iwf", "rus_optimized"])
@pytest.mark.parametrize("relative", [1e-3, -1e-3])
def test_a_routine_deciding_the_direct_index_a_little_off_its_threshold_fails(name, relative, tmp_path):
    """A routine built with direct_index_min 0.1 % above or below the robot's (a wrong
    certificate, a rounded constant) differs from the reference only where the index lies
    within 0.1 % of the threshold: the poses beside the index's own boundary
    (kingen.verify.boundaries.DIRECT_INDEX), sought apart from the cranks' singular band that
    also gives WARN_SINGULAR_SOLUTION, must catch it."""
    from kingen.hosts.delmia.build import build_plugin
    from kingen.hosts.delmia.loader import Plugin
    from kingen.verify import verify

    robot = load_robot(name)
    built = build_plugin(replace(robot, direct_index_min=robot.direct_index_min * (1.0 + relative)), tmp_path)
    report = verify(robot, Plugin(built.library, built.routine), VerifyOptions(samples=200))
    assert report.boundary_poses["boundaries_found"]["direct_index_min"] == 16  # PER_WARNING
    warnings = next(check for check in report.checks if check.name == "warnings")
    assert not warnings.passed and report.warning_mismatches > 0, warnings.detail


def test_a_snapshot_of_angles_compares_them_a_turn_apart_as_equal(tmp_path):
    """CEART's cranks (rad): a recorded snapshot of the reference, edited so that pose 0's
    crank1 in posture 0 reads a full turn (2 pi) more, the same angle, and pose 1's crank2 in
    posture 3 reads 1e-3 rad more, beyond the 1e-8 rad tolerance; the definition's digest
    edited too. The reference itself, checked against it, differs in that one joint only, named
    with its unit, and the digest is named by its first 16 hex digits."""
    import json

    from kingen.cli import main
    from kingen.verify.snapshot import load
    from kingen.verify.checks.snapshot import check

    robot = load_robot("ceart")
    path = tmp_path / "ceart.golden.json"
    assert main(["golden", "record", "ceart", "-o", str(path), "--samples", "3"]) == 0
    data = json.loads(path.read_text())
    assert data["joint_units"] == ["rad"] * 6 and data["tolerance"] == {"mm": 1e-6, "rad": 1e-8}
    assert data["entries"][0]["warnings"][0] != UNREACHABLE and data["entries"][1]["warnings"][3] != UNREACHABLE
    data["entries"][0]["joints"][0][0] += 2 * math.pi
    moved = data["entries"][1]["joints"][1][3]
    data["entries"][1]["joints"][1][3] = moved + 1e-3
    data["definition_sha256"] = "0123456789abcdef" + "0" * 48
    path.write_text(json.dumps(data))
    snapshot = load(path, robot)

    def call(t6):
        reference = solve(robot, t6)
        return reference.joints, reference.warnings

    result = check(robot, snapshot, call)
    assert not result.passed
    assert result.detail == ("3 recorded poses x 64 postures (the reference, kingen 0.1.0): 1 joints beyond 1e-06 mm / "
                             "1e-08 rad, 0 warnings differ")
    assert result.diagnoses == [
        f"pose 1 posture 3 crank2: recorded {moved + 1e-3:.9g}, now {moved:.9g} rad",
        f"recorded from another definition (sha256 0123456789abcdef; the robot file has {robot.sha256[:16]}): "
        "record it again if the change was meant"]


def test_accumulate_adds_each_chunk_to_the_running_totals(tmp_path):
    """accumulate keeps running totals over the chunks of a verification: the one rail's chunk
    of the per-posture case (4 warnings differ, 2 joints wrong, 7 reachable poses) plus a pose
    in its singular band (D = 1e-12, one joint 1e-8 mm off, within the band's bound, the other
    1e-5 mm, beyond it), given twice to the same report and tally, counts everything twice and
    keeps the same worst."""
    path = tmp_path / "one_rail.yaml"
    path.write_text(ONE_RAIL)
    robot = load_robot(path)
    poses = ([[50, 0, -50, 0, 0, 0]] * 4 + [[60, 0, -40, 0, 0, 0]] * 3 + [[150, 0, -50, 0, 0, 0]] * 2
             + [[100 * math.sqrt(1 - 1e-12), 0, -50, 0, 0, 0]])
    t6 = t6_from_pose(poses)
    expected = solve(robot, t6)
    joints, warnings = expected.joints.copy(), expected.warnings.copy()
    joints[0, 0, 1] += 2e-6
    joints[1, 0, 0] -= 5e-7
    joints[9, 0, 0] += 1e-8  # within the singular pose's bound, 16 eps x 100 / sqrt(1e-12) = 3.6e-6 mm
    joints[9, 0, 1] += 1e-5  # beyond it
    warnings[3, 0] = UNREACHABLE
    warnings[4] = UNREACHABLE
    warnings[7, 1] = GOOD
    calls = calls_of(expected, warnings, joints)
    calls.faults[5] = INPUTS_MODIFIED  # a faulty call whose outputs are still compared
    calls.faults[8] = 1  # a call stopped at a faulting write (pose 8, unreachable): left out
    report = Report(robot=robot.name, routine=get_host("delmia").routine_name(robot), samples=len(t6), seed=0,
                    postures=robot.postures)
    tally = Tally.start(robot)
    counts = []
    for _ in range(2):
        accumulate(robot, report, tally, robot.revolute, t6, calls, expected)
        counts.append((report.warning_mismatches, report.warnings_in_band, report.singular_entries,
                       report.singular_out_of_bound, tally.returns_wrong, tally.reachable_poses, tally.faulty_calls,
                       tally.aborted, tally.closure_checked, tally.fault_bits, tally.posture_counts.tolist(),
                       tally.warning_counts.tolist()))
    # 4 warnings differ (poses 3, 4 twice, 7), none in a band; the singular pose's 2 entries in its
    # band, one beyond its bound; 8 reachable poses (0-6, 9); 2 faulty calls, 1 aborted; closure
    # judges both branches of poses 0-6 (the singular pose's limb is in its band): 14
    assert counts[0][:10] == (4, 0, 2, 1, 0, 8, 2, 1, 14, INPUTS_MODIFIED | 1)
    assert counts[1][:9] == tuple(2 * value for value in counts[0][:9]) and counts[1][9] == counts[0][9]
    assert counts[1][10] == (2 * np.array(counts[0][10])).tolist()
    assert counts[1][11] == (2 * np.array(counts[0][11])).tolist()
    assert report.max_abs_error_mm == pytest.approx(2e-6, rel=1e-6)
    # the poses kept for diagnoses are the compared ones, the aborted pose 8 left out
    kept = np.arange(len(t6)) != 8
    assert np.array_equal(tally.first[0], t6[kept]) and np.array_equal(tally.first[1], joints[kept])
    assert np.array_equal(tally.first[3], expected.joints[kept])


def test_a_chunk_whose_every_call_was_stopped_counts_only_its_faults(tmp_path):
    path = tmp_path / "one_rail.yaml"
    path.write_text(ONE_RAIL)
    robot = load_robot(path)
    t6 = t6_from_pose([[50, 0, -50, 0, 0, 0], [60, 0, -40, 0, 0, 0]])
    expected = solve(robot, t6)
    calls = calls_of(expected)
    calls.faults[:] = 1
    report, tally = compared(robot, t6, calls, expected)
    assert (tally.faulty_calls, tally.aborted, tally.fault_bits, tally.reachable_poses, tally.first) == (2, 2, 1, 0, None)
    assert tally.warning_counts.sum() == 0 and tally.posture_counts.sum() == 0 and report.warning_mismatches == 0


def test_each_pytest_item_reports_its_checks():
    """docs/how-to/pytest.md: the items build, interface, values,
    warnings, closure, jacobian (golden[i] and snapshot report their own). values, warnings,
    closure and jacobian report their namesake check; build the library's definition;
    interface the loaded routine's contract (loading, the interface checks, return values,
    buffers, determinism, a crash or a timeout). The round trip is in verify's report only."""
    from kingen.hosts import get_host
    from kingen.pytest_plugin import item_checks

    assert item_checks(get_host("delmia")) == {
        "build": ("definition",),
        "interface": ("load", "get_kin_config", "kin_check_definition", "refusal", "non-finite T6", "return value",
                      "buffers", "determinism", "crash", "timeout"),
        "values": ("values",), "warnings": ("warnings",), "closure": ("closure",), "jacobian": ("jacobian",)}


def values_context(tmp_path):
    """The Values check's context after the plumb leg's twelve reachable poses (z 110 to 165 mm,
    inside its travel) compared with the reference's own joints: every error 0."""
    from kingen.verify.checks.base import Context

    path = tmp_path / "plumb_leg.yaml"
    path.write_text(PLUMB_LEG)
    robot = load_robot(path)
    t6 = t6_from_pose([[0.0, 0.0, 110.0 + 5 * k, 0.0, 0.0, 0.0] for k in range(12)])
    expected = solve(robot, t6)
    report, tally = compared(robot, t6, calls_of(expected), expected)
    return Context(robot=robot, options=VerifyOptions(), report=report, tally=tally)


@pytest.mark.parametrize("field", ["max_abs_error_mm", "max_abs_error_rad"])
def test_the_value_bounds_are_inclusive(tmp_path, field):
    """'within 1e-9 mm and rad' (docs/explanation/verify.md): an error of exactly the bound passes, the next float
    above it fails; so does one entry beyond its singular band's bound."""
    from kingen.verify.checks.values import Values

    context = values_context(tmp_path)
    bound = context.report.tolerance_mm if field.endswith("mm") else context.report.tolerance_rad
    setattr(context.report, field, bound)
    assert Values().run(context)[0].passed
    setattr(context.report, field, np.nextafter(bound, np.inf))
    assert not Values().run(context)[0].passed
    setattr(context.report, field, 0.0)
    context.report.singular_out_of_bound = 1
    assert not Values().run(context)[0].passed


class Recorder(float):
    """A bound that records the value compared with it (``value <= bound`` asks the bound first)."""

    seen = []

    def __ge__(self, other):
        Recorder.seen.append(other)
        return float(self) >= other


def test_the_jacobian_tolerance_is_inclusive(monkeypatch):
    """The reference's worst relative difference on the Stewart-Gough example, recorded, then
    made the tolerance: the check passes at it and fails at the next float below."""
    from kingen.verify.checks import jacobian as module

    robot = load_robot("stewart_gough_example")
    Recorder.seen.clear()
    monkeypatch.setattr(module, "JACOBIAN_TOLERANCE", Recorder(1e-6))
    assert jacobian_check(robot, ReferenceRoutine(robot), VerifyOptions(), sg_t6()).passed
    worst = Recorder.seen[-1]
    assert 0.0 < worst < 1e-6
    monkeypatch.setattr(module, "JACOBIAN_TOLERANCE", worst)
    assert jacobian_check(robot, ReferenceRoutine(robot), VerifyOptions(), sg_t6()).passed
    monkeypatch.setattr(module, "JACOBIAN_TOLERANCE", np.nextafter(worst, 0.0))
    assert not jacobian_check(robot, ReferenceRoutine(robot), VerifyOptions(), sg_t6()).passed


def test_closure_leaves_out_a_link_of_at_most_zero_length_inclusive(leg):
    """The plumb leg (reference length 0: its passive link is the joint itself) at z = 150 mm,
    answered with a joint of exactly ZERO_LENGTH x the robot's size: a link that short has no
    direction and is not judged; the next float above it is, and misses closing by about 150 mm."""
    from kingen.verify.tally import ZERO_LENGTH, closure_error

    expected = solve(leg, t6_from_pose([[0.0, 0.0, 150.0, 0.0, 0.0, 0.0]]))
    shortest = ZERO_LENGTH * leg.size_mm
    assert closure_error(leg, expected, np.full_like(expected.joints, shortest)) == (0.0, 0)
    worst, judged = closure_error(leg, expected, np.full_like(expected.joints, np.nextafter(shortest, np.inf)))
    assert judged == 1 and worst == pytest.approx(150.0 / shortest, rel=1e-6)


def test_a_singular_entry_exactly_at_its_bound_is_right(tmp_path):
    """The one rail at D = 1e-12 (x = 100 sqrt(1 - 1e-12)), its reference joints replaced by 0
    (a constructed reference: the comparison, not the solver, is under test), so a routine
    answering exactly the band's bound b errs by exactly b: within it, right; the next float
    above b is beyond it, wrong, and counted out of bound."""
    from kingen.verify.tally import singular_bounds

    path = tmp_path / "one_rail.yaml"
    path.write_text(ONE_RAIL)
    robot = load_robot(path)
    t6 = t6_from_pose([[100 * math.sqrt(1 - 1e-12), 0, -50, 0, 0, 0]])
    solved = solve(robot, t6)
    expected = replace(solved, branch_joints=np.zeros_like(solved.branch_joints))  # every posture's joint 0
    bound = singular_bounds(robot, expected, np.array([1e-9]))[0, 0]
    assert bound > 1e-9
    for answer, wrong in ((bound, 0), (np.nextafter(bound, np.inf), 1)):
        report, tally = compared(robot, t6, calls_of(expected, None, np.full_like(expected.joints, answer)), expected)
        statistics = posture_statistics(robot, tally)
        assert [(row["right"], row["wrong"]) for row in statistics] == [(1 - wrong, wrong)] * 2
        assert (report.singular_entries, report.singular_out_of_bound) == (2, 2 * wrong)


def _good_unless_unreachable(t6, calls):
    calls.warnings[calls.warnings != UNREACHABLE] = GOOD


class GoodOrUnreachable(ChangedCalls):
    """``plugin`` as a routine that tells only good from unreachable (a LinuxCNC module without
    a status pin): its other warnings read as WARN_GOOD_SOLUTION."""

    warning_vocabulary = ("WARN_GOOD_SOLUTION", "WARN_UNREACHABLE")

    def __init__(self, plugin):
        super().__init__(plugin, _good_unless_unreachable)


def test_a_routine_of_fewer_warnings_is_judged_on_those_and_the_detail_says_so(plugin):
    """The hexapod's reference gives WARN_JOINT_LIMITS_EXCEEDED and WARN_SINGULAR_SOLUTION
    besides good and unreachable; a routine that tells only good from unreachable is judged
    by the reference read the same way: no mismatch, and the detail, after its counts, says
    which warnings the routine tells."""
    from kingen.verify import verify

    robot, routine = plugin("hexapod")
    report = verify(robot, GoodOrUnreachable(routine), VerifyOptions(samples=200))
    warnings = next(check for check in report.checks if check.name == "warnings")
    assert warnings.passed and report.warning_mismatches == 0
    assert warnings.detail.startswith("0 mismatches, 0 inside the tolerance band, over ")
    assert ("; the routine tells only WARN_GOOD_SOLUTION, WARN_UNREACHABLE (the reference's others read as good)"
            in warnings.detail)


def test_every_check_needs_one_of_the_stages_verify_has():
    """checks.base.NEEDS lists what a check can need, in the order verify has it; every check a
    host composes needs one of them, and the library checks come first (before anything loads)."""
    from kingen.hosts import get_host
    from kingen.verify.checks.base import NEEDS

    assert NEEDS == ("library", "routine", "sampled calls", "compared poses", "golden values", "snapshot")
    for name in ("delmia", "linuxcnc"):
        needs = [check.needs for check in get_host(name).checks]
        assert set(needs) <= set(NEEDS), name
        assert needs[0] == "library"


def test_a_warning_the_robot_can_give_but_no_pose_gave_fails_and_says_what_to_do(tmp_path):
    """The plumb leg's twelve poses inside its travel (values_context: all WARN_GOOD_SOLUTION),
    no boundary poses: the travel limits' warning, which the leg can give, was never
    exercised, so warnings fails and says how to exercise it."""
    from kingen.verify.checks.warnings import Warnings

    context = values_context(tmp_path)
    [check] = Warnings().run(context)
    assert not check.passed and check.judged == 12
    assert check.detail == (
        "0 mismatches, 0 inside the tolerance band, over 12 postures of 12 sampled poses and 0 poses beside warnings' "
        "boundaries (boundaries found along 64 rays: none sought); the reference's warnings: 12 WARN_GOOD_SOLUTION; "
        "not exercised: WARN_JOINT_LIMITS_EXCEEDED (the robot can give it, no compared pose did): widen the "
        "verification region or check the robot's limits")


@pytest.mark.parametrize("tolerance, places", [(0.0003, 4), (0.02, 2), (5.0, 0), (0.0, 6)])
def test_a_golden_tolerance_is_shown_to_its_leading_digit(tolerance, places):
    """golden.decimals (its docstring): 0.0003 -> 4, 0.02 -> 2, 5 -> 0; no tolerance (exact) -> 6."""
    from kingen.verify.checks.golden import decimals

    assert decimals(tolerance) == places


def test_a_library_built_from_another_definition_is_named_with_both_digests(tmp_path):
    """The one rail built, then its file changed by one comment line: definition fails, naming
    the library's digest, the file's, and what to do, word for word."""
    import kingen
    from kingen.hosts.delmia.build import build_plugin
    from kingen.verify.checks.definition import definition_check

    path = tmp_path / "one_rail.yaml"
    path.write_text(ONE_RAIL)
    built = build_plugin(load_robot(path), tmp_path / "build")
    old = load_robot(path).sha256
    path.write_text(ONE_RAIL + "# reviewed again\n")
    robot = load_robot(path)
    check = definition_check(robot, built.library)
    assert not check.passed and old != robot.sha256
    assert check.detail == (f"the library says it was built by kingen {kingen.__version__} from another definition of "
                            f"'one_rail' (sha256 {old[:16]}), one_rail.yaml has {robot.sha256[:16]}: rebuild it from "
                            "the reviewed file")


def test_boundary_poses_of_a_tiny_region_lie_just_outside_the_band(tmp_path):
    """The plumb leg's lower travel limit (z = 100 mm) 5e-5 mm below a verification home whose
    region is 2.5e-5 mm tall: the rays (at most 1e-4 mm, REACH times the half-width) that
    cross the limit are so short that only the fourth offset, 1e-4 of a ray (at most 1e-8
    mm), clears the 1e-9 mm band; each pose then lies between 1e-9 and about 1.1e-8 mm from
    the limit (kingen.verify.boundaries: offsets tried in order, bisected to a tenth of the
    smallest), on either side."""
    from kingen.verify.boundaries import boundary_poses

    path = tmp_path / "plumb_leg.yaml"
    path.write_text(PLUMB_LEG.replace("home: [0, 0, 150, 0, 0, 0], range: [10, 10, 10, 0, 0, 0]",
                                      "home: [0, 0, 100.00005, 0, 0, 0], range: [0, 0, 0.000025, 0, 0, 0]"))
    robot = load_robot(path)
    poses, found, searched = boundary_poses(robot, 0)
    assert found == {"WARN_JOINT_LIMITS_EXCEEDED": 16} and searched == {}
    distance = np.abs(poses[:, 2] - 100.0)
    assert np.all(distance > WARNING_BAND) and np.all(distance < 1.2e-8)
    assert np.any(poses[:, 2] < 100.0) and np.any(poses[:, 2] > 100.0)
