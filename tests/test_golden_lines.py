"""Golden lines: short enough for a terminal, numbers to the tolerance's precision, and a
failure names the joint that is off (the JSON report keeps the whole source)."""

from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

from kingen.robot.model import load_robot, shipped_robots
from kingen.kinematics.reference import solve
from kingen.verify.checks.golden import check_golden, decimals, golden_detail

WITH_GOLDEN = [name for name in shipped_robots() if load_robot(name).golden]


class ReferenceRoutine:
    """A stand-in routine answering the reference's joints, ``shift`` (internal units) added to one joint."""

    def __init__(self, robot, joint=None, shift=0.0):
        self.robot, self.joint, self.shift = robot, joint, shift

    def reset_host(self):
        pass

    def call(self, t6):
        solutions = solve(self.robot, t6).joints.copy()
        if self.joint is not None:
            solutions[:, self.joint, :] += self.shift
        return SimpleNamespace(solutions=solutions)


def lines(robot, routine):
    return [f"  {'ok' if result.passed else 'FAILED':6} golden[{index}]: {golden_detail(robot, result)}"
            for index, result in enumerate(check_golden(robot, routine))]


def test_decimals_follow_the_tolerance():
    assert [decimals(t) for t in (0.0003, 0.0005, 0.00005, 0.02, 5.0)] == [4, 4, 5, 2, 0]


@pytest.mark.parametrize("name", WITH_GOLDEN)
def test_a_passing_golden_line_fits_a_terminal(name):
    robot = load_robot(name)
    results = check_golden(robot, ReferenceRoutine(robot))
    assert all(result.passed for result in results)
    for line, result in zip(lines(robot, ReferenceRoutine(robot)), results):
        assert len(line) < 120, line
        assert len(result.source) > 40 or result.source in line  # the report keeps the whole text


def test_the_line_of_the_published_linuxcnc_hexapod_value_is_in_inches_to_four_decimals():
    robot = load_robot("linuxcnc_hexapod")
    line = lines(robot, ReferenceRoutine(robot))[0]
    assert "within 0.0003 inch, worst strut" in line and line.endswith(tuple(f"0.000{d}" for d in range(4)))


def test_a_wrong_routine_names_its_joint_and_error():
    robot = load_robot("exechon")
    line = lines(robot, ReferenceRoutine(robot, joint=2, shift=0.0021))[0]
    assert "FAILED" in line
    assert "routine's leg3 off by 0.0020" in line and "for 5.62580) (tolerance 0.00005)" in line
    assert "leg1" not in line and "leg2" not in line


def test_a_changed_golden_value_is_off_in_routine_and_reference():
    robot = load_robot("tau")
    entry = robot.golden[0]
    changed = replace(robot, golden=(entry.model_copy(update={"joints": [417.2158, 361.0962, 265.9219]}),))
    line = lines(changed, ReferenceRoutine(changed))[0]
    assert ": posture 0: carriage3 off by 0.11 mm (265.81 for 265.92) (tolerance 0.02)" in line
    assert line.startswith("  FAILED golden[0]: DELMIA V5 methodology thesis, Table 6\u2026")
