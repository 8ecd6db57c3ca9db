"""The compiled tilt judge against the numpy reference (analyze's tilt limits): the same
limit and cause towards every azimuth, on the thesis's optimum and on designs around it and
at random, in both tilt conventions and both collision models."""

import numpy as np
import pytest

from kingen.design.analysis import Settings, home_values, tilt_limits
from kingen.kinematics.collision import clearances
from kingen.design.problem import Problem, evaluate
from kingen.robot.model import load_robot, resolve_robot_path
from kingen.robot.reading import read_robot_file
from kingen.design.tilt_judge import home, judges, tilt_table


@pytest.fixture(scope="module")
def problem():
    path = resolve_robot_path("rus_optimized")
    return Problem(read_robot_file(path)[0], path)


def test_the_thesis_optimum_scores_as_published(problem):
    """optimisation.md: 47 degrees with 1-degree steps, ended by the rods; about Y 57."""
    objective, table, judged = evaluate(problem, problem.start())
    assert objective == 47.0 and len(table) == 360
    assert table[90] == (57.0, "collision")
    assert min(table)[1] == "collision"
    assert 15000 < judged < 43560  # each azimuth stops at its first failing step


@pytest.mark.parametrize("convention,collision", [("euler", "thesis"), ("axis", "segments"), ("euler", "segments")])
def test_the_judge_agrees_with_the_reference_on_every_azimuth(problem, convention, collision):
    rng = np.random.default_rng({"thesis": 1, "segments": 2}[collision] + len(convention))
    start = problem.start()
    designs = [start] + [np.clip(start + rng.normal(0.0, 0.05, start.size) * (problem.upper - problem.lower),
                                 problem.lower, problem.upper) for _ in range(4)] + \
        [problem.lower + rng.uniform(size=start.size) * (problem.upper - problem.lower) for _ in range(3)]
    settings = Settings(convention, 1.0, 4.0, 120.0, collision)
    stopped = set()
    for design in designs:
        robot = problem.robot(design)
        assert judges(robot)
        fast, _ = tilt_table(robot, 21, settings)
        reference = [(row["max_tilt_deg"], row["cause"]) for row in tilt_limits(robot, 21, settings)]
        assert fast == reference
        stopped |= {cause for _, cause in fast}
    assert {"collision", "unreachable"} <= stopped  # the designs exercise more than one cause


@pytest.mark.parametrize("name,posture", [("rus_optimized", 21), ("ceart", 63), ("iwf", 63)])
def test_the_judge_sees_home_as_the_reference_does(name, posture):
    """The direct index and det W's sign at home (the crossing rules' references) and the
    thesis's static crank check, in C and in numpy (both find the smallest eigenvalue in
    closed form, to about eps times the largest: 1e-9 of the index here)."""
    robot = load_robot(name)
    index, sign, cranks = home(robot, posture)
    expected = home_values(robot, posture)
    assert index == pytest.approx(expected.index_mm, rel=1e-8) and sign == expected.det_sign
    _, crank_clearance = clearances(robot, np.zeros((1, 6, 3)), np.zeros((1, 6)), "thesis")
    assert cranks == bool(crank_clearance[0] < 0.0)


def test_ceart_and_the_crossing_rule_agree_too():
    robot = load_robot("ceart")
    settings = Settings("axis", 0.5, 15.0, 90.0, "segments")
    fast, _ = tilt_table(robot, 63, settings)
    assert fast == [(row["max_tilt_deg"], row["cause"]) for row in tilt_limits(robot, 63, settings)]
    assert not judges(load_robot("hexapod"))  # legs: the reference judges them


def test_a_design_singular_at_home_scores_0(tmp_path):
    """The thesis's design with every crank pointing inwards from its pivot and the platform's
    joints straight below the crank tips at angle 0 (posture 63), no direct_index_min: at home
    the six rods hang vertical, a direct singularity. It scores 0 (judge and reference
    alike), not the tilts the crossing rules, relative to that singular home, would allow."""
    text = resolve_robot_path("rus_optimized").read_text()
    for old, new in (("platform_radius: 197.2", "platform_radius: 442.885"),
                     ("platform_half_distance: 50.1", "platform_half_distance: 76.6"),
                     ("crank_directions: [60, 159, 181, 285, 302, 44]",
                      "crank_directions: [180, 300, 300, 60, 60, 180]"),
                     ("home: [0, 0, -404.2, 0, 0, 0]", "home: [0, 0, -650, 0, 0, 0]"),
                     ("singularity: {direct_index_min: 29.3}\n", ""), ("working_posture: 21", "working_posture: 63"),
                     ("objective: {posture: 21, tilt_convention: euler, tilt_step: 1, azimuth_step: 1",
                      "objective: {posture: 63, tilt_convention: euler, tilt_step: 1, azimuth_step: 15"),
                     ("collision: thesis}", "collision: segments}")):
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / "singular.yaml"
    path.write_text(text[:text.index("golden:")])
    singular = Problem(read_robot_file(path)[0], path)
    robot = singular.robot(singular.start())
    objective, table, _ = evaluate(singular, singular.start())
    assert objective == 0.0 and table == [(0.0, "direct_singularity")] * 24
    assert judges(robot) and home(robot, 63)[:2] == (0.0, 0.0)
    reference = tilt_limits(robot, 63, Settings("euler", 1.0, 15.0, 120.0))
    assert [(row["max_tilt_deg"], row["cause"]) for row in reference] == table
