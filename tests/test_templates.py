"""Branches of the generated C that no shipped robot renders, rendered and run: the rail
model's force lines (a rail robot with a direct-index threshold: six vertical rails, a
Hexaglide-like example) and kingen_wrap's floored modulo (crank zero offsets more than one
turn from 0). Every expectation is kingen's independent numpy reference, on every joint
and warning, or a property of the construction stated beside it."""

import math

import numpy as np
import pytest

from conftest import random_t6
from kingen.cli import main
from kingen.conventions import joint_errors
from kingen.hosts.delmia.build import build_plugin
from kingen.hosts.delmia.loader import Plugin
from kingen.robot.model import load_robot
from kingen.kinematics.reference import solve
from kingen.kinematics.routine import SINGULAR_TOLERANCE, WARNINGS

SINGULAR = WARNINGS["WARN_SINGULAR_SOLUTION"]


def hexaglide(direct_index_min, rail_z=0, offset=(0, 0, 0)):
    """Six rails at radius 300 mm, every 60 degrees, each leaning 10 degrees outwards and 5
    degrees sideways from vertical (so that every component of each direction counts);
    platform points at radius 100, 12 degrees to alternate sides of each rail; links of
    250 mm; 64 postures. ``rail_z`` raises every rail point, ``offset`` is every carriage's offset."""
    rows = []
    for i in range(6):
        rail, point = math.radians(60 * i), math.radians(60 * i + (12 if i % 2 else -12))
        lean, side = math.radians(10), math.radians(5)
        direction = np.array([math.sin(lean) * math.cos(rail) - math.sin(side) * math.sin(rail),
                              math.sin(lean) * math.sin(rail) + math.sin(side) * math.cos(rail), 1.0])
        direction = ", ".join(f"{value:.12f}" for value in direction / np.linalg.norm(direction))
        rows.append(f"  - {{name: rail{i + 1}, model: rail, rail_point: [{300 * math.cos(rail):.3f}, "
                    f"{300 * math.sin(rail):.3f}, {rail_z}], direction: [{direction}], "
                    f"carriage_offset: [{offset[0]}, {offset[1]}, {offset[2]}], "
                    f"platform_point: [{100 * math.cos(point):.3f}, {100 * math.sin(point):.3f}, 0], link_length: 250}}")
    return ("name: hexaglide\ndescription: six vertical rails, a Hexaglide-like example\nlimbs:\n" + "\n".join(rows)
            + f"\nsingularity: {{direct_index_min: {direct_index_min}}}\n"
            "verification: {home: [0, 0, -150, 0, 0, 0], range: [30, 30, 30, 8, 8, 8]}\n")


def one_crank(zero_offset):
    return ("name: crank\ndescription: one crank with a zero offset beyond a turn\nlimbs:\n"
            "  - {model: crank, pivot: [200, 0, 0], crank_direction: 0, crank_length: 100, rod_length: 300,\n"
            f"     platform_point: [60, 0, 0], zero_offset: {zero_offset}}}\n"
            "verification: {home: [0, 0, -250, 0, 0, 0], range: [80, 80, 80, 20, 20, 20]}\n")


def loaded(tmp_path, text, name):
    path = tmp_path / f"{name}.yaml"
    path.write_text(text)
    robot = load_robot(path)
    built = build_plugin(robot, tmp_path / "build")
    return robot, Plugin(built.library, built.routine)


def test_a_rail_robot_warns_at_its_direct_index_threshold_as_the_reference(tmp_path):
    robot, plugin = loaded(tmp_path, hexaglide(15), "hexaglide")
    _, t6 = random_t6(robot, 5000, seed=3)
    calls, expected = plugin.call(t6), solve(robot, t6)
    assert joint_errors(calls.solutions, expected.joints, robot.revolute).max() <= 1e-9
    np.testing.assert_array_equal(calls.warnings, expected.warnings)
    # Postures singular only by their direct index (every limb far from its own band), and
    # regular ones beside them: the C's force lines decided both.
    regular_limbs = np.all(np.abs(expected.radicands) > 10 * SINGULAR_TOLERANCE, axis=1)[:, None]
    by_index = (expected.warnings == SINGULAR) & regular_limbs
    assert by_index.sum() > 1000 and ((expected.warnings == 0) & regular_limbs).sum() > 1000
    # and near the threshold itself (where the reference computes the index exactly, else
    # only its side): postures on both sides of 15 mm.
    near = np.isfinite(expected.direct_index) & regular_limbs
    assert near.sum() >= 5 and np.any(near & by_index) and np.any(near & (expected.warnings == 0))


def test_a_rail_robot_with_a_direct_index_threshold_passes_verify(tmp_path, capsys):
    (tmp_path / "hexaglide.yaml").write_text(hexaglide(15))
    code = main(["verify", str(tmp_path / "hexaglide.yaml"), "-o", str(tmp_path / "out"), "--samples", "1000",
                 "--processes", "1"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "WARN_SINGULAR_SOLUTION 16" in out  # boundaries of the singular warning found and compared
    assert "; the reference's warnings: " in out and " WARN_GOOD_SOLUTION, " in out.split("the reference's warnings: ")[1]


@pytest.mark.parametrize("zero_offset", [700, -700, 540, -400, 359.5])
def test_crank_zero_offsets_beyond_a_turn_wrap_as_the_reference(tmp_path, zero_offset):
    robot, plugin = loaded(tmp_path, one_crank(zero_offset), "crank")
    _, t6 = random_t6(robot, 2000, seed=5)
    calls, expected = plugin.call(t6), solve(robot, t6)
    reachable = expected.warnings != WARNINGS["WARN_UNREACHABLE"]
    assert reachable.sum() > 1000
    assert joint_errors(calls.solutions, expected.joints, robot.revolute).max() <= 1e-9
    np.testing.assert_array_equal(calls.warnings, expected.warnings)
    joints = calls.solutions[:, 0, :][reachable]
    assert np.all((joints > -math.pi) & (joints <= math.pi))
    # The geometric angle is in (-pi, 2 pi]: minus 700 degrees (12.2 rad) it lies beyond one
    # 2 pi step from (-pi, pi] (below -3 pi) for most poses, which only the floored modulo maps.
    geometric = joints + math.radians(zero_offset)
    if abs(zero_offset) == 700:
        raw = np.angle(np.exp(1j * geometric))  # the geometric angle, in (-pi, pi]
        assert np.mean(np.abs(raw - math.radians(zero_offset)) > 3 * math.pi) > 0.3


@pytest.mark.parametrize("entry", [(0, 0), (1, 2), (2, 1), (3, 0), (3, 2)])
def test_a_non_finite_t6_entry_no_limb_reads_still_makes_every_posture_unreachable(tmp_path, entry):
    """A leg to the platform origin, whose point takes T6's rotation rows times 0 (NaN still:
    NaN x 0 is NaN): a non-finite entry anywhere makes the routine return 1, every posture
    WARN_UNREACHABLE and every joint 0 (docs/explanation/warnings.md)."""
    robot, plugin = loaded(tmp_path, "name: plumb\ndescription: one leg to the platform origin\nlimbs:\n"
                           "  - {model: leg, base_point: [0, 0, 0], platform_point: [0, 0, 0], reference_length: 0}\n"
                           "verification: {home: [0, 0, 150, 0, 0, 0], range: [10, 10, 10, 5, 5, 5]}\n", "plumb")
    t6 = np.eye(4)
    t6[3, :3] = [10.0, 20.0, 150.0]
    t6[entry] = math.nan
    calls = plugin.call(t6[None])
    assert calls.returned.tolist() == [1] and calls.warnings.tolist() == [[WARNINGS["WARN_UNREACHABLE"]]]
    assert calls.solutions.tolist() == [[[0.0]]]


def test_raised_rail_points_and_carriage_offsets_count_in_every_component(tmp_path):
    """The Hexaglide-like rails with their rail points 40 mm up and every carriage offset by
    (5, -3, 7) mm (each component of both in use): the C's joints and warnings are the
    reference's."""
    robot, plugin = loaded(tmp_path, hexaglide(15, rail_z=40, offset=(5, -3, 7)), "hexaglide")
    _, t6 = random_t6(robot, 2000, seed=4)
    calls, expected = plugin.call(t6), solve(robot, t6)
    assert np.sum(expected.warnings != WARNINGS["WARN_UNREACHABLE"]) > 10000
    assert joint_errors(calls.solutions, expected.joints, robot.revolute).max() <= 1e-9
    np.testing.assert_array_equal(calls.warnings, expected.warnings)
