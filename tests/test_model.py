"""Robot definitions: shipped robots, layout generators, and one-line diagnostics for bad input."""

import math

import numpy as np
import pytest

from conftest import SHIPPED
from kingen.errors import KingenError
from kingen.robot.model import load_robot

EXPECTED_SHAPE = {  # (dof, postures, limb model) from docs/explanation/conventions.md
    "hexapod": (6, 1, "leg"), "flexapod": (6, 1, "leg"), "exechon": (3, 1, "leg"), "tau": (3, 8, "rail"),
    "ceart": (6, 64, "crank"), "iwf": (6, 64, "crank"), "rus_optimized": (6, 64, "crank"),
    "stewart_gough_example": (6, 1, "leg"),
    "linuxcnc_hexapod": (6, 1, "leg"), "linear_delta": (3, 8, "rail"), "rotary_delta": (3, 8, "crank"),
    "prs_head": (3, 8, "rail"), "rps_table": (3, 1, "leg"), "exechon_constrained": (3, 1, "leg"), "exechon_wrist": (3, 2, "leg"), "tricept": (3, 1, "leg"),
    "tricept_wrist": (3, 2, "leg"), "tricept_wrist3": (3, 2, "leg"),
}


def test_exactly_the_required_robots_ship():
    assert sorted(EXPECTED_SHAPE) == SHIPPED


@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_robot_shape(name):
    robot = load_robot(name)
    assert robot.name == name
    assert (robot.dof, robot.postures, robot.models[0]) == EXPECTED_SHAPE[name]


def test_example_robot_says_it_is_an_example():
    text = (load_robot("stewart_gough_example").path).read_text()
    assert "EXAMPLE" in text and "not a published machine" in text


def test_rus6_layout_matches_the_documented_formula_for_ceart():
    robot = load_robot("ceart")
    chi = math.radians(120)
    # leg 2: m = -e_b, n = -e_p
    assert robot.limbs[0].pivot == pytest.approx([636.885, 197.555, 0])
    assert robot.limbs[0].platform_point == pytest.approx([291.73, 402.345, 0])
    assert robot.limbs[1].pivot == pytest.approx(
        [636.885 * math.cos(chi) + 197.555 * math.sin(chi), 636.885 * math.sin(chi) - 197.555 * math.cos(chi), 0])
    assert [limb.crank_direction for limb in robot.limbs] == [120, 180, 240, 300, 0, 60]


def test_stewart_gough_layout_angles():
    robot = load_robot("stewart_gough_example")
    angles = [math.degrees(math.atan2(l.platform_point[1], l.platform_point[0])) % 360 for l in robot.limbs]
    thetap = 100
    expected = [60 - thetap / 2, 60 + thetap / 2, 180 - thetap / 2, 180 + thetap / 2, 300 - thetap / 2, 300 + thetap / 2]
    np.testing.assert_allclose(angles, expected, atol=1e-9)
    assert all(l.travel == [10, 140] for l in robot.limbs)


VALID = """\
name: demo
description: test robot
limbs:
  - name: c1
    model: rail
    rail_point: [0, 0, 0]
    direction: [0, 0, -1]
    carriage_offset: [0, 0, 0]
    platform_point: [0, 0, 0]
    link_length: 100
    travel: [-1, 50]
verification:
  home: [0, 0, 0, 0, 0, 0]
  range: [1, 1, 1, 1, 1, 1]
"""

BAD = [
    # (replace this, with this, expected message fragment)
    ("name: demo", "name: 2demo", ":1: name: String should match pattern"),
    ("name: demo", "name: check_definition", ":1: name: gives the C name 'kin_check_definition', which the DELMIA"),
    ("name: demo", "name: routine", ":1: name: gives the C name 'kin_routine'"),
    ("name: demo", "name: de-mo", ":1: name:"),
    ("    link_length: 100", "    link_length: 0", ":10: limbs[0].link_length: Input should be greater than or equal to 0.001"),
    ("    link_length: 100", "    link_length: -5", ":10: limbs[0].link_length: Input should be greater than or equal to 0.001"),
    ("    link_length: 100", "    link_length: 1.0e+200", ":10: limbs[0].link_length: Input should be less than or equal to 1000000"),
    ("    link_length: 100", "    link_length: 1" + "0" * 5000, ": YAML syntax: a number with thousands of digits"),
    ("  home: [0, 0, 0, 0, 0, 0]", "  home: [0, 0, 0, 0, 0, 800]", ":13: verification.home: x, y, z must be within"),
    ("    link_length: 100", "    link_length: .nan", ":10: limbs[0].link_length: Input should be a finite number"),
    ("    link_length: 100", "    link_length: .inf", ":10: limbs[0].link_length: Input should be a finite number"),
    ("    link_length: 100", "    link_length: '100'", ":10: limbs[0].link_length: Input should be a valid number"),
    ("    direction: [0, 0, -1]", "    direction: [0, 0, 0]", ":7: limbs[0].direction: direction is the zero vector"),
    ("    direction: [0, 0, -1]", "    direction: [0, 0, -2]", ":7: limbs[0].direction: direction must be a unit vector"),
    ("    rail_point: [0, 0, 0]", "    rail_point: [0, 0]", ":6: limbs[0].rail_point: List should have at least 3 items"),
    ("    rail_point: [0, 0, 0]", "    rail_point: [0, 0, 0, 0]", ":6: limbs[0].rail_point: List should have at most 3 items"),
    ("    travel: [-1, 50]", "    travel: [50, -1]", ":11: limbs[0].travel: lower limit 50.0 must be below upper limit -1.0"),
    ("    model: rail", "    model: piston", ":5: limbs[0].model: Input tag 'piston'"),
    ("    link_length: 100", "    link_length: 100\n    colour: red", ":11: limbs[0].colour: unknown key"),
    ("    link_length: 100", "    link_length: 100\n    link_length: 200", ":11: limbs[0].link_length: duplicate key"),
    ("description: test robot\n", "", "description: required key missing"),
    ("  range: [1, 1, 1, 1, 1, 1]", "  range: [1, 1, 1, 1, 1, -1]", ":14: verification.range: ranges must not be negative"),
    ("  home: [0, 0, 0, 0, 0, 0]", "  home: [0, 0, 0]", ":13: verification.home: List should have at least 6 items"),
    ("name: demo", "name: [demo", ": YAML syntax:"),
    ("    model: rail\n", "", ":4: limbs[0].model: Unable to extract tag"),
    ("verification:", "golden:\n  - {source: s, pose: [0,0,0,0,0,0], joints: [1, 2], tolerance: 0.1}\nverification:",
     ":13: golden[0].joints: expected 1 joint values, got 2"),
    ("verification:", "golden:\n  - {source: s, pose: [0,0,0,0,0,0], posture: 2, joints: [1], tolerance: 0.1}\nverification:",
     ":13: golden[0].posture: posture 2 does not exist (the robot has 2)"),
    ("limbs:", "layout: {type: rus6, base_radius: 1, platform_radius: 1, base_half_distance: 0, platform_half_distance: 0, "
     "crank_length: 1, rod_length: 2, pair_angles: [0,0,0,0,0,0], crank_directions: [0,0,0,0,0,0]}\nlimbs:",
     ": limbs: give exactly one of 'limbs' and 'layout'"),
    ("    link_length: 100", "    link_length: true", ":10: limbs[0].link_length: Input should be a valid number"),
]


@pytest.mark.parametrize("old, new, fragment", BAD, ids=[case[2] for case in BAD])
def test_bad_input_gives_one_located_line(tmp_path, old, new, fragment):
    assert old in VALID
    path = tmp_path / "demo.yaml"
    path.write_text(VALID.replace(old, new, 1))
    with pytest.raises(KingenError) as raised:
        load_robot(str(path))
    message = str(raised.value)
    assert "\n" not in message
    assert message.startswith(str(path)), message
    assert fragment in message, message


def test_valid_demo_loads(tmp_path):
    path = tmp_path / "demo.yaml"
    path.write_text(VALID)
    robot = load_robot(str(path))
    assert (robot.dof, robot.postures, robot.joint_names) == (1, 2, ("c1",))


def test_duplicate_joint_names_are_rejected(tmp_path):
    path = tmp_path / "demo.yaml"
    second = VALID.split("limbs:\n")[1].split("verification:")[0]
    path.write_text(VALID.replace("verification:", second + "verification:"))
    with pytest.raises(KingenError, match=r":12: limbs\[1\]\.name: joint name 'c1' is used twice"):
        load_robot(str(path))


@pytest.mark.parametrize("content, fragment", [
    (b"\xff\xfe", "not UTF-8"), (b"- 1\n- 2\n", "expected a mapping"), (b"", "expected a mapping"),
])
def test_unreadable_files(tmp_path, content, fragment):
    path = tmp_path / "x.yaml"
    path.write_bytes(content)
    with pytest.raises(KingenError, match=fragment):
        load_robot(str(path))


def test_unknown_robot_names_the_shipped_ones():
    with pytest.raises(KingenError, match="no shipped robot of that name .shipped: ceart, exechon"):
        load_robot("nonexistent")


def test_a_robot_file_in_inches_is_the_same_robot_in_mm(tmp_path):
    """units: inch reads every length in inches: the Robot equals the one written in mm
    (lengths times 25.4 exactly), angles untouched."""
    inch, mm = tmp_path / "inch.yaml", tmp_path / "mm.yaml"
    geometry = ("layout: {{type: stewart_gough, base_radius: {0}, platform_radius: {1}, base_pair_angle: 20, "
                "platform_pair_angle: 100, reference_length: {2}, travel: [{3}, {4}]}}\n"
                "verification: {{home: [0, 0, {5}, 1, 2, 3], range: [{6}, {6}, {6}, 5, 5, 5]}}\n"
                "golden: [{{source: s, pose: [0, 0, {5}, 0, 0, 0], joints: [{7}, {7}, {7}, {7}, {7}, {7}], tolerance: {8}}}]\n")
    numbers = (6, 4, 8, 0.5, 5.5, 10, 1, 2.5, 0.5)
    inch.write_text("name: a\ndescription: d\nunits: inch\n" + geometry.format(*numbers))
    mm.write_text("name: a\ndescription: d\n" + geometry.format(*(value * 25.4 for value in numbers)))
    a, b = load_robot(inch), load_robot(mm)
    assert a.length_unit == "inch" and b.length_unit == "mm"
    for first, second in zip(a.limbs, b.limbs):
        assert first.base_point == pytest.approx(second.base_point, rel=1e-15)
        assert first.reference_length == pytest.approx(second.reference_length, rel=1e-15)
        assert first.travel == pytest.approx(second.travel, rel=1e-15)
    assert a.verification.home == pytest.approx(b.verification.home, rel=1e-15)
    assert a.golden[0].joints == pytest.approx(b.golden[0].joints, rel=1e-15)
    assert a.golden[0].tolerance == pytest.approx(b.golden[0].tolerance, rel=1e-15)


def test_a_leg_may_report_its_absolute_length(tmp_path):
    robot = load_robot("linuxcnc_hexapod")
    assert all(limb.reference_length == 0 for limb in robot.limbs) and robot.length_unit == "inch"


def test_delta_layouts_place_their_limbs_as_linuxcnc_does():
    """lineardeltakins: towers 0, 1, 2 at (0, R), (-sin60 R, -cos60 R), (sin60 R, -cos60 R) with
    sin60 = sqrt(3)/2 computed as it computes it; rotarydeltakins: hips at -90, 30, 150 degrees."""
    import math

    linear = load_robot("linear_delta")
    radius = 130.25
    assert [limb.rail_point for limb in linear.limbs] == [
        [0.0, radius, 0.0], [-(math.sqrt(3) / 2) * radius, -0.5 * radius, 0.0], [(math.sqrt(3) / 2) * radius, -0.5 * radius, 0.0]]
    assert {limb.link_length for limb in linear.limbs} == {269.0}
    rotary = load_robot("rotary_delta")
    assert [limb.crank_direction for limb in rotary.limbs] == [-90.0, 30.0, 150.0]
    assert rotary.limbs[1].pivot == pytest.approx([254 * math.cos(math.radians(30)), 254 * math.sin(math.radians(30)), 0])
