"""verify's two excuses, each pinned by poses built to lie inside them: a warning that
differs where the reference's radicand is within WARNING_BAND of the singular threshold,
and a joint that differs by more than 1e-9 mm inside a limb's singular band but within
its conditioning bound. Outside the bands the same differences fail."""

import math

import numpy as np
import pytest

from conftest import ONE_RAIL
from kingen.kinematics.routine import SINGULAR_TOLERANCE, WARNING_BAND, WARNINGS
from kingen.conventions import t6_from_pose
from kingen.kinematics.routine import Calls
from kingen.hosts import get_host
from kingen.robot.model import load_robot
from kingen.kinematics.reference import solve
from kingen.verify.report import Report
from kingen.verify.tally import Tally as _Tally
from kingen.verify.tally import accumulate as _accumulate
from kingen.verify.tally import singular_bounds, warnings_in_band


@pytest.fixture
def rail(tmp_path):
    path = tmp_path / "one_rail.yaml"
    path.write_text(ONE_RAIL)
    return load_robot(path)


def pose_with_radicand(radicand):
    """The platform x (mm) at which the rail's normalised radicand is ``radicand``: D = 1 - x^2 / l^2."""
    return t6_from_pose([[100.0 * math.sqrt(1.0 - radicand), 0.0, -50.0, 0.0, 0.0, 0.0]])


def flipped(expected, joint_shift=0.0):
    """Calls equal to the reference, with the warning changed and the joints shifted."""
    warnings = expected.warnings.copy()
    warnings[warnings == WARNINGS["WARN_SINGULAR_SOLUTION"]] = -2
    warnings[warnings == WARNINGS["WARN_GOOD_SOLUTION"]] = WARNINGS["WARN_SINGULAR_SOLUTION"]
    warnings[warnings == -2] = WARNINGS["WARN_GOOD_SOLUTION"]
    return Calls(returned=np.zeros(len(warnings), dtype=np.intc), solutions=expected.joints + joint_shift,
                 warnings=warnings.astype(np.intc), faults=np.zeros(len(warnings), dtype=np.intc))


def accumulate(robot, t6, calls, expected):
    report = Report(robot=robot.name, routine=get_host("delmia").routine_name(robot), samples=len(t6), seed=0,
                    postures=robot.postures)
    _accumulate(robot, report, _Tally.start(robot), robot.revolute, t6, calls, expected)
    return report


@pytest.mark.parametrize("offset, excused", [(WARNING_BAND / 3, True), (-WARNING_BAND / 3, True),
                                             (30 * WARNING_BAND, False), (-30 * WARNING_BAND, False)])
def test_a_warning_may_differ_only_inside_the_band(rail, offset, excused):
    t6 = pose_with_radicand(SINGULAR_TOLERANCE + offset)
    expected = solve(rail, t6)
    assert abs(expected.radicands[0, 0] - (SINGULAR_TOLERANCE + offset)) < WARNING_BAND / 10
    assert bool(warnings_in_band(rail, expected)[0, 0]) == excused
    report = accumulate(rail, t6, flipped(expected), expected)
    assert (report.warnings_in_band, report.warning_mismatches) == ((2, 0) if excused else (0, 2))


@pytest.mark.parametrize("radicand, shift, within", [(1e-12, 1e-8, True), (1e-12, 1e-6, False),
                                                     (0.25, 1e-8, None)])
def test_a_joint_may_differ_only_within_its_singular_bound(rail, radicand, shift, within):
    t6 = pose_with_radicand(radicand)
    expected = solve(rail, t6)
    bound = singular_bounds(rail, expected)[0, 0]
    report = accumulate(rail, t6, flipped(expected, shift), expected)
    if within is None:  # outside the singular band: the fixed 1e-9 mm holds
        assert bound == 0.0 and report.singular_entries == 0 and report.max_abs_error_mm == pytest.approx(shift)
        return
    assert bound == pytest.approx(16 * np.finfo(float).eps * 100 / math.sqrt(radicand), rel=1e-3)
    assert report.singular_entries == 2 and report.max_abs_error_mm == 0.0
    assert report.singular_out_of_bound == (0 if within else 2)


def test_a_carriage_far_along_its_rail_is_held_to_its_own_rounding(tmp_path, capsys):
    """Found by the fuzz test: a 150 m link whose carriage runs 590 m along its rail. In the
    singular band the joint's rounding grows with (590 m / 150 m)^2, beyond a bound scaled by
    the link alone; the bound now scales by the joint's reach too, and kingen's own routine passes."""
    from kingen.cli import main

    robot = tmp_path / "far.yaml"
    robot.write_text(
        "name: far\ndescription: a carriage far along its rail\nlimbs:\n"
        "  - {model: rail, rail_point: [58593.75, 50000.0, 0.0], direction: [0.9922778767136677, "
        "0.12403473458920847, 0.0], carriage_offset: [0, 0, 0], platform_point: [0, 0, 0], link_length: 150000.0}\n"
        "verification: {home: [12500.0, 25000.0, -37500.0, 0, 0, 0], range: [20000.0, 20000.0, 20000.0, 0, 0, 0]}\n")
    assert main(["verify", str(robot), "-o", str(tmp_path / "out")]) == 0, capsys.readouterr().out
