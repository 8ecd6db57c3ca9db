"""The setup sheet: what a user types into DELMIA's Inverse Kinematics dialog."""

import math
import re

import numpy as np
import pytest

from kingen.robot.limbs.base import axis_words
from kingen.conventions import t6_from_pose
from kingen.hosts.c.package import render_package as render_c
from kingen.hosts.delmia.package import render_package
from kingen.hosts.linuxcnc.package import render_package as render_linuxcnc
from kingen.hosts.linuxcnc.render import robot_problem
from kingen.hosts.wrist import sheet_words
from kingen.kinematics.poses import sample_poses
from kingen.robot.model import load_robot, robots_dir, shipped_robots
from kingen.robot.placement import branch_words
from kingen.kinematics.reference import solve
from kingen.kinematics.routine import WARNINGS, warnings_to_exercise
from kingen.runtime.text import markdown


def sheet(name, target="windows"):
    return render_package(load_robot(name), target)["SETUP.md"]


def test_tau_sheet_names_library_routine_postures_and_actuators():
    text = sheet("tau")
    assert "| Library | `libtau` |" in text and "| Routine | `kin_tau` |" in text
    assert "User Inverse" in text
    assert "8 postures" in text
    assert "| 5 (101) | branch 1 | branch 0 | branch 1 |" in text
    rows = re.findall(r"^\| (\d) \| dof\(\d\) \| Translational \| Trans Z \| (carriage\d) \|$", text, flags=re.MULTILINE)
    assert rows == [("1", "carriage1"), ("2", "carriage2"), ("3", "carriage3")]
    assert "| carriage3 | -1 | 2600 | mm |" in text


def test_ceart_sheet_lists_64_postures_and_rotational_actuators():
    text = sheet("ceart")
    assert "64 postures" in text
    assert len(re.findall(r"^\| \d+ \([01]{6}\) \|", text, flags=re.MULTILINE)) == 64
    assert "| 63 (111111) | branch 1 | branch 1 | branch 1 | branch 1 | branch 1 | branch 1 |" in text
    assert text.count("| Rotational | Rot Z |") == 6


def test_sheet_lists_calibration_fields_with_units_and_built_in_values():
    text = sheet("exechon")
    assert "| Length 3 | leg3.reference_length | mm | 886.021 |" in text
    assert "| Length 3 | read, see below |" in text and "| Length 4 | leave empty |" in text
    ceart = sheet("ceart")
    assert "| Offset 6 | crank6.zero_offset | degrees | 0 |" in ceart


def test_sheet_says_when_nothing_is_read_and_no_limits_exist():
    text = sheet("hexapod", "linux")
    assert "The routine reads no Length or Offset field" in text
    assert "No travel limits are declared" in text
    assert "libhexapod.so" in text


def test_frames_are_placed_by_the_joints_of_the_robot_file(tmp_path):
    text = sheet("hexapod")
    assert "**Base frame:** Origin on the Z axis through the centre of the base joints, 40.205 mm on its -Z side." in text
    assert "+Z is normal to their plane and points toward the platform" in text
    assert "| leg1 | (31, 118.156, 40.205) | - | (31, 48.799, -31.45) |" in text
    moved = tmp_path / "hexapod.yaml"
    moved.write_text((robots_dir() / "hexapod.yaml").read_text().replace("40.205]", "50]"))
    assert "centre of the base joints, 50 mm on its -Z side" in render_package(load_robot(moved), "linux")["SETUP.md"]
    tau = sheet("tau")
    assert "Every actuated joint moves along -Z." in tau and "| carriage1 | (-96.569, -185, -400) | -Z |" in tau


def _knee_reach(limb, joint, centre):
    """The crank tip's distance from the Z axis through ``centre``, from the crank's own formula."""
    theta = joint + math.radians(limb.zero_offset)
    beta = math.radians(limb.crank_direction)
    tip = np.asarray(limb.pivot) + limb.crank_length * np.array(
        [math.cos(theta) * math.cos(beta), math.cos(theta) * math.sin(beta), -math.sin(theta)])
    return math.hypot(*(tip - centre)[:2])


@pytest.mark.parametrize("name", [name for name in shipped_robots() if any(limb.branches == 2 for limb in load_robot(name).limbs)])
def test_branch_words_hold_for_the_reference_at_the_verification_home(name):
    robot = load_robot(name)
    solution = solve(robot, t6_from_pose(np.asarray(robot.verification.home, dtype=float)[None]))
    centre = np.mean([limb.base_joint() for limb in robot.limbs], axis=0)
    words = branch_words(robot)
    for index, limb in enumerate(robot.limbs):
        joints, point = solution.branch_joints[0, index], solution.points[0, index]
        if limb.model == "crank":
            farther = int(_knee_reach(limb, joints[1], centre) > _knee_reach(limb, joints[0], centre))
            assert words[index][farther].startswith("knee out") and words[index][1 - farther].startswith("knee in")
        elif limb.model == "rail":
            carriage = np.asarray(limb.rail_point) + limb.carriage_offset + (joints + limb.origin)[:, None] * limb.direction
            direction = np.asarray(limb.direction)
            above = int((carriage[1] - point) @ direction > 0)  # the branch whose carriage lies on the +u side
            assert f"on the {axis_words(direction)} side" in words[index][above]
            assert f"on the {axis_words(-direction)} side" in words[index][1 - above]
    text = sheet(name)
    for index, limb in enumerate(robot.limbs):
        if words[index]:
            assert f"| {robot.joint_names[index]} | {markdown(words[index][0])} | {markdown(words[index][1])} |" in text


def test_rotary_delta_is_built_knees_out_and_the_tau_carriages_above_their_links():
    assert all(words[1].startswith("knee out") for words in branch_words(load_robot("rotary_delta")))
    assert all(words[0] == "carriage on the +Z side of its link's platform joint" for words in branch_words(load_robot("tau")))


@pytest.mark.parametrize("name", shipped_robots())
def test_sheets_list_only_the_warnings_the_routine_can_give(name):
    robot = load_robot(name)
    can_give = ["WARN_GOOD_SOLUTION", *warnings_to_exercise(robot)]
    listed = re.findall(r"^\| \d \| (WARN_\w+) \|", sheet(name), flags=re.MULTILINE)
    assert sorted(listed) == sorted(can_give)
    if robot_problem(robot) is None:
        status = render_linuxcnc(robot)["SETUP.md"]
        line = status[status.index("for this robot one of:"):].splitlines()[1]
        assert sorted(re.findall(r"\b(\d) ", line)) == sorted(str(WARNINGS[kind]) for kind in can_give)


def test_hexapod_sheet_says_its_only_warning_is_the_direct_index():
    text = sheet("hexapod")
    assert "| 5 | WARN_SINGULAR_SOLUTION | the posture's direct index at most 6.5 mm (section 8) |" in text
    assert "WARN_JOINT_LIMITS_EXCEEDED" not in text and "WARN_UNREACHABLE" not in text
    assert "No limb has a singular band" in sheet("exechon")


def test_linuxcnc_package_without_headers_writes_the_source_and_says_how_to_build_it(tmp_path):
    import os
    import subprocess
    import sys

    out = tmp_path / "package"
    env = {**os.environ, "KINGEN_LINUXCNC_INCLUDE": str(tmp_path / "no-headers")}
    done = subprocess.run([sys.executable, "-m", "kingen.cli", "package", "linear_delta", "--host", "linuxcnc",
                           "--out-dir", str(out)], capture_output=True, text=True, env=env, timeout=300)
    assert done.returncode == 0, done.stderr
    assert sorted(path.name for path in out.iterdir() if not path.name.startswith(".")) == [
        "SETUP.md", "linear_deltakins.c", "linear_deltakins.hal", "linear_deltakins.ini"]
    assert done.stdout.split() == [str(out / name) for name in
                                   ("linear_deltakins.c", "linear_deltakins.hal", "linear_deltakins.ini", "SETUP.md")]
    assert done.stderr == (f"notice: linear_deltakins.so not built: LinuxCNC's headers are not in {tmp_path / 'no-headers'} "
                           "(install Debian's linuxcnc-uspace-dev or set KINGEN_LINUXCNC_INCLUDE); on the machine, "
                           "build it with 'halcompile --install linear_deltakins.c' (SETUP.md)\n")
    text = (out / "SETUP.md").read_text()
    assert "build it with `halcompile --install linear_deltakins.c` (as root, with LinuxCNC's headers" in text
    assert "this package holds no `linear_deltakins.so`" in text
    assert (out / "linear_deltakins.c").read_text() == \
        render_linuxcnc(load_robot("linear_delta"))["linear_deltakins.c"]


def test_linuxcnc_sheet_of_a_closed_form_delta_speaks_of_carriages_not_newton_or_reference_lengths():
    text = render_linuxcnc(load_robot("linear_delta"))["SETUP.md"]
    assert "Newton's steps" not in text and "reference length" not in text
    assert "`linear_deltakins.iterations` (s32 out): always 0: the forward is in closed form" in text
    assert ("- A rail joint (mm) is the carriage's position along its rail, 0 at the origin's distance from the rail "
            "point (positive moves it along the rail's direction); the link keeps its length.") in text
    rotary = render_linuxcnc(load_robot("rotary_delta"))["SETUP.md"]
    assert "`rotary_deltakins.iterations` (s32 out): Newton's steps in the last forward." in rotary
    assert "`.max-step-angle` is unused: the platform does not turn." in rotary
    assert "- A crank joint (degrees) is the crank's angle from the horizontal less its zero offset" in rotary
    assert "reference length" not in rotary


def test_linuxcnc_sheet_of_a_hexapod_speaks_of_newton_and_leg_extensions():
    robot = load_robot("hexapod")
    text = render_linuxcnc(robot)["SETUP.md"]
    assert "`hexapodkins.iterations` (s32 out): Newton's steps in the last forward." in text
    # the tolerance: 1e-12 of the robot's size where that exceeds 1e-10 (kingen.hosts.render.newton_stops)
    assert robot.size_mm == 515.0  # z 465 + 50 of the verification region
    assert "`.max-step`, `.max-step-angle`: the forward's\n  settings (20, 5.15e-10, 25.0 mm, 10.0 degrees)." in text
    assert "halves the one before it and is at most 5.15e-07 (rounding's floor, compiled in)." in text  # 1e-9 of 515 mm
    assert "- A leg joint (mm) is the leg's extension from its reference length (positive extends it" in text
    assert "closed form" not in text and "carriage" not in text


@pytest.mark.parametrize("host", ["delmia", "linuxcnc"])
def test_sheets_read_as_plain_text_and_neutralise_markdown_and_html(tmp_path, host):
    import markdown as python_markdown

    description = "Hexapod (centroid) +Z up, 1+1 & a_b; # not a heading <script>x</script> | [x](y) *e* _u_"
    source = (robots_dir() / "hexapod.yaml").read_text()
    path = tmp_path / "hexapod.yaml"
    path.write_text(re.sub(r"(?m)^description:.*$", f"description: '{description}'", source))
    robot = load_robot(path)
    text = (render_package(robot, "windows") if host == "delmia" else render_linuxcnc(robot))["SETUP.md"]
    line = next(line for line in text.splitlines() if line.startswith("Hexapod"))
    assert line == ("Hexapod (centroid) +Z up, 1+1 & a_b; # not a heading \\<script\\>x\\</script\\> \\| "
                    "\\[x\\](y) \\*e\\* \\_u\\_")
    assert "\\(" not in text and "\\+" not in text and "\\)" not in text
    for html in (python_markdown.markdown(line), python_markdown.markdown(line, extensions=["tables"])):
        assert "(centroid) +Z up, 1+1 &amp; a_b; # not a heading" in html
        assert "<script" not in html and "<a " not in html and "<em>" not in html and "<h1>" not in html


@pytest.mark.parametrize("name", ["exechon_wrist", "tricept_wrist"])
def test_a_wrist_sheet_lists_legs_and_wrist_joints_its_flip_and_the_tool_as_the_other_hosts(name):
    """DELMIA's sheet of a machine with a wrist: five commanded joints (the legs', then the
    wrist's, rotational in degrees), two postures whose wrist branch is the last digit, the
    branches in words the reference bears out on sampled tool poses, and the tool; the C
    package's and LinuxCNC's sheets say the same branches and tool."""
    robot = load_robot(name)
    text, words = sheet(name), sheet_words(robot)
    assert "5 commanded joints" in text and "2 postures" in text
    rows = re.findall(r"^\| (\d) \| dof\(\d\) \| (\w+) \| (.+?) \| (\w+) \|$", text, flags=re.MULTILINE)
    assert rows == [("1", "Translational", "Trans Z", "leg1"), ("2", "Translational", "Trans Z", "leg2"),
                    ("3", "Translational", "Trans Z", "leg3"), ("4", "Rotational", "Rot Z", "ax4"),
                    ("5", "Rotational", "Rot Z", "ax5")]
    assert "| ax4 | -270 | 270 | deg |" in text and "| ax5 | -110 | 110 | deg |" in text
    assert "| 0 (0) | branch 0 |" in text and "| 1 (1) | branch 1 |" in text
    assert words["branches"] == ("ax5 >= 0", "ax5 < 0 (the head's flip)")
    assert f"| wrist (ax4, ax5) | {markdown(words['branches'][0])} | {markdown(words['branches'][1])} |" in text
    assert "tool tip at (0, 0, -200) mm, tool axis -Z" in text and "one configuration" not in text
    # The words hold for the reference: posture 2 k + 0 has ax5 >= 0, 2 k + 1 ax5 < 0, where reached.
    solved = solve(robot, t6_from_pose(sample_poses(robot, 300, 0)))
    reached = solved.warnings != WARNINGS["WARN_UNREACHABLE"]
    ax5 = solved.joints[:, robot.dof + 1]
    assert np.all(ax5[:, 0::2][reached[:, 0::2]] >= 0.0) and np.all(ax5[:, 1::2][reached[:, 1::2]] < 0.0)
    assert reached.sum() >= 500
    c_sheet = render_c(robot)["SETUP.md"]
    assert f"branch 0 {words['branches'][0]}, branch 1\n{words['branches'][1]}" in c_sheet and words["tool"] in c_sheet
    assert f"the wrist's branch 0, {words['branches'][0]}" in render_linuxcnc(robot)["SETUP.md"]
