"""check-path judges what the robot file limits of loads: each passive joint's angle from its
neutral axis (joint_limits) and each actuator's load holding the payload (max_force), held to an
independent computation of the angles from the file's points and to kingen loads."""

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from conftest import skip_or_fail
from kingen.cli import main

HEXAPOD = Path(__file__).parents[1] / "robots" / "hexapod.yaml"
LEG = "reference_length: 399.413}"
HOME_Z = 465.0


def limited_hexapod(folder, fields):
    """robots/hexapod.yaml with ``fields`` added to every leg and a 100 kg payload."""
    text = HEXAPOD.read_text().replace(LEG, "reference_length: 399.413, " + fields + "}")
    path = Path(folder) / "limited.yaml"
    path.write_text(text.replace("verification:", "payload: {mass: 100}\nverification:", 1))
    return path


def leg_points():
    from kingen.robot.model import load_robot

    limbs = load_robot("hexapod").limbs
    return np.array([limb.base_point for limb in limbs]), np.array([limb.platform_point for limb in limbs])


def largest_base_angle(x):
    """The largest angle (deg) of any leg from its direction at home with the platform moved
    by ``x`` mm along the base x axis (no rotation): from the file's points alone."""
    base, platform = leg_points()
    home = platform + [0.0, 0.0, HOME_Z] - base
    there = platform + [x, 0.0, HOME_Z] - base
    cosine = np.sum(home * there, axis=1) / np.linalg.norm(home, axis=1) / np.linalg.norm(there, axis=1)
    return float(np.degrees(np.max(np.arccos(np.clip(cosine, -1, 1)))))


def check(folder, program, capsys):
    report = Path(folder) / "report.json"
    code = main(["check-path", str(limited_hexapod(folder, "joint_limits: {base: 4}")), str(program),
                 "--json", str(report)])
    capsys.readouterr()
    return code, json.loads(report.read_text())


def first_angle(document):
    return min((place for place in document["first"] if place["kind"] == "joint angle"),
               key=lambda place: (place["line"], place["pose"][0]))


def test_check_path_names_the_first_csv_row_where_a_base_joint_passes_its_limit(tmp_path, capsys):
    crossing = brentq(lambda x: largest_base_angle(x) - 4.0, 0.0, 50.0, xtol=1e-12)
    program = tmp_path / "path.csv"
    program.write_text("x,y,z,roll,pitch,yaw\n" + "".join(f"{x},0,{HOME_Z},0,0,0\n" for x in range(0, 60, 10)))
    code, document = check(tmp_path, program, capsys)
    assert code == 1 and document["checks"]["joint angle"] == "failed"
    place = first_angle(document)
    assert place["line"] == 2 + int(crossing // 10) + 1  # the row the path reaches the crossing on (header: line 1)
    assert place["pose"][0] == pytest.approx(crossing, abs=1e-6)
    assert place["value"] == pytest.approx(4.0, abs=1e-6) and place["between"] == "base"


def test_check_path_names_the_first_g_code_line_where_a_base_joint_passes_its_limit(tmp_path, capsys):
    if shutil.which("rs274") is None or not Path("/usr/bin/python3").exists():
        skip_or_fail("LinuxCNC's interpreter is not installed (Debian package linuxcnc-uspace; .ci/run installs it)")
    crossing = brentq(lambda x: largest_base_angle(x) - 4.0, 0.0, 50.0, xtol=1e-12)
    program = tmp_path / "path.ngc"
    program.write_text("G21 G90\nG0 X0 Y0 Z465\n" + "".join(f"G1 X{x} Y0 Z465 F600\n" for x in range(10, 60, 10))
                       + "M2\n")
    code, document = check(tmp_path, program, capsys)
    assert code == 1
    place = first_angle(document)
    assert place["line"] == 3 + int(crossing // 10)  # G1 X10 is line 3
    assert place["pose"][0] == pytest.approx(crossing, abs=1e-6)


def test_an_unlimited_file_says_loads_were_not_exercised(tmp_path, capsys):
    program = tmp_path / "path.csv"
    program.write_text("x,y,z,roll,pitch,yaw\n0,0,465,0,0,0\n10,0,465,0,0,0\n")
    report = tmp_path / "report.json"
    assert main(["check-path", "hexapod", str(program), "--json", str(report)]) == 0
    capsys.readouterr()
    checks = json.loads(report.read_text())["checks"]
    assert checks["joint angle"].startswith("not exercised: the robot file gives no limb joint_limits")
    assert checks["actuator load"].startswith("not exercised")


def test_an_actuator_load_beyond_max_force_is_found_where_kingen_loads_puts_it(tmp_path, capsys):
    from kingen.conventions import t6_from_pose
    from kingen.kinematics.loads import loads
    from kingen.robot.model import load_robot

    path = limited_hexapod(tmp_path, "max_force: 300")
    robot = load_robot(path)
    crossing = brentq(lambda x: np.max(np.abs(loads(robot, t6_from_pose(np.array([[x, 0, HOME_Z, 0, 0, 0]]))).forces))
                      - 300.0, 0.0, 50.0, xtol=1e-12)
    program = tmp_path / "path.csv"
    program.write_text("x,y,z,roll,pitch,yaw\n0,0,465,0,0,0\n50,0,465,0,0,0\n")
    report = tmp_path / "report.json"
    assert main(["check-path", str(path), str(program), "--json", str(report)]) == 1
    capsys.readouterr()
    place = min((place for place in json.loads(report.read_text())["first"] if place["kind"] == "actuator load"),
                key=lambda place: place["pose"][0])
    assert place["pose"][0] == pytest.approx(crossing, abs=1e-6)
    assert place["units"] == "N" and place["value"] == pytest.approx(300.0, rel=1e-9)
