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


POWER_PAYLOAD = 100.0  # kg at the platform origin
CRUISE, RAMP = 50.0, 2000.0  # mm/s (feed 3000 mm/min), mm/s^2 (the .ini's path acceleration)


def power_check(folder, max_power, capsys):
    """check-path on the hexapod with ``max_power`` W on every leg, a 100 kg payload at the
    platform origin and one CSV move straight up from home, timed by an .ini's path acceleration."""
    text = HEXAPOD.read_text().replace(LEG, f"reference_length: 399.413, max_power: {max_power}}}")
    robot = Path(folder) / "powered.yaml"
    robot.write_text(text.replace("verification:", f"payload: {{mass: {POWER_PAYLOAD}}}\nverification:", 1))
    ini = Path(folder) / "machine.ini"
    ini.write_text(f"[TRAJ]\nLINEAR_UNITS = mm\nMAX_LINEAR_VELOCITY = 1000\nMAX_LINEAR_ACCELERATION = {RAMP}\n"
                   + "".join(f"[JOINT_{joint}]\nMAX_VELOCITY = 1e6\nMAX_ACCELERATION = 1e9\n" for joint in range(6)))
    program = Path(folder) / "up.csv"
    program.write_text(f"x,y,z,roll,pitch,yaw,feed\n0,0,{HOME_Z},0,0,0,{CRUISE * 60}\n0,0,{HOME_Z + 20},0,0,0,"
                       f"{CRUISE * 60}\n")
    report = Path(folder) / "report.json"
    code = main(["check-path", str(robot), str(program), "--ini", str(ini), "--json", str(report)])
    capsys.readouterr()
    return code, json.loads(report.read_text())


def leg_power(speed, acceleration):
    """W per leg lifting the centred payload straight up: each leg pushes m (g + a) / (6 cos t)
    along itself and extends at v cos t (t its tilt), so its power is m (g + a) v / 6, whatever
    its tilt (speed mm/s, acceleration mm/s^2)."""
    return POWER_PAYLOAD * (9.81 + acceleration / 1000.0) * speed / 1000.0 / 6.0


@pytest.mark.parametrize("max_power", [9.0, 8.0])
def test_check_path_judges_each_actuators_power_with_the_programs_accelerations(tmp_path, capsys, max_power):
    """At 9 W the legs fit while cruising (8.2 W) and not while the platform speeds up (up to
    9.84 W); at 8 W not even cruising. The worst place is the end of the speeding up, its value
    the power there and the feed that fits gives max_power at that sample's speed and acceleration."""
    assert leg_power(CRUISE, 0.0) < 9.0 < leg_power(CRUISE, RAMP)
    code, document = power_check(tmp_path, max_power, capsys)
    assert code == 1 and document["checks"]["actuator power"] == "failed"
    places = [place for place in document["worst"] if place["kind"] == "actuator power"]
    assert len(places) == 6 and {place["line"] for place in places} == {3}
    for place in places:
        assert place["limit"] == max_power
        assert leg_power(CRUISE, RAMP) * 0.97 <= place["value"] <= leg_power(CRUISE, RAMP) * (1 + 1e-3)
        speed = 1000.0 * 6.0 * place["value"] / (POWER_PAYLOAD * (9.81 + RAMP / 1000.0))  # the sample's, mm/s
        feed = place["override"]
        assert 0.0 < feed < 1.0
        assert leg_power(feed * speed, feed ** 2 * RAMP) == pytest.approx(max_power, rel=1e-9)
    if max_power == 9.0:  # cruising fits: every place beyond is where the platform speeds up
        rising = [place for place in document["problems"] if place["kind"] == "actuator power"]
        assert all(place["pose"][2] - HOME_Z <= CRUISE ** 2 / (2 * RAMP) + 0.2 for place in rising)


def test_the_power_check_is_not_exercised_without_max_power(tmp_path, capsys):
    program = tmp_path / "up.csv"
    program.write_text(f"x,y,z,roll,pitch,yaw,feed\n0,0,{HOME_Z},0,0,0,600\n0,0,{HOME_Z + 5},0,0,0,600\n")
    report = tmp_path / "report.json"
    assert main(["check-path", str(HEXAPOD), str(program), "--json", str(report)]) == 0
    capsys.readouterr()
    verdict = json.loads(report.read_text())["checks"]["actuator power"]
    assert verdict == "not exercised: the robot file gives no limb max_power"
