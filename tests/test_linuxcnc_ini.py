"""kingen's own files work together: the ``.ini`` that ``kingen package ROBOT --host linuxcnc``
writes carries [TRAJ]'s units and path limits and each joint's MAX_VELOCITY and
MAX_ACCELERATION (the robot file's ``max_speed`` and ``max_acceleration``, or the stated
defaults), and ``kingen check-path ROBOT prog.ngc --ini`` takes it, for every shipped robot
LinuxCNC packages, judging with the limits the file holds (read back here with configparser)."""

import configparser
import json
from pathlib import Path

import pytest

from kingen.cli import main
from kingen.hosts.linuxcnc.package import (DEFAULT_ACCELERATION, DEFAULT_PATH_ACCELERATION_MM, DEFAULT_PATH_SPEED_MM,
                                           DEFAULT_SPEED)
from kingen.robot.model import load_robot

from test_check_path import needs_interpreter

ROBOTS = Path(__file__).resolve().parent.parent / "robots"
NOT_PACKAGED = {"exechon": "LinuxCNC drives six-limb robots and translating platforms"}
"""Shipped robots LinuxCNC refuses, and the words of the refusal."""
PACKAGED = sorted(path.stem for path in ROBOTS.glob("*.yaml") if path.stem not in NOT_PACKAGED)
PROGRAM = "G21 G91\nG1 A5 F600\nG1 Z-1\nG1 Z1\nM2\n"
"""From the verification home: a 5 degree tilt (off a wrist's singular home), then 1 mm down and
back, at 10 mm/s."""
INCH = 25.4


def _run(capsys, *argv):
    code = main([str(value) for value in argv])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def _packaged_ini(robot_file, folder, capsys, *options):
    code, _, err = _run(capsys, "package", robot_file, "--host", "linuxcnc", "-o", folder, *options)
    assert code == 0, err
    ini, = folder.glob("*.ini")
    parser = configparser.ConfigParser(interpolation=None)
    parser.optionxform = str
    parser.read(ini)
    return ini, parser


@pytest.mark.parametrize("name", PACKAGED)
def test_check_path_takes_the_ini_of_the_package_and_judges_with_its_limits(name, tmp_path, capsys):
    needs_interpreter()
    robot = load_robot(name)
    ini, parser = _packaged_ini(ROBOTS / f"{name}.yaml", tmp_path / "package", capsys)
    unit = {"mm": 1.0, "inch": INCH}[parser["TRAJ"]["LINEAR_UNITS"]]
    assert parser["TRAJ"]["ANGULAR_UNITS"] == "degree"
    assert float(parser["TRAJ"]["MAX_LINEAR_VELOCITY"]) * unit == pytest.approx(DEFAULT_PATH_SPEED_MM, rel=1e-9)
    program = tmp_path / "prog.ngc"
    program.write_text(PROGRAM)
    code, out, err = _run(capsys, "check-path", name, program, "--ini", ini, "--json", tmp_path / "report.json")
    assert code in (0, 1) and err == "", err
    if robot.wrist is None:  # a wrist's home is its singularity (the report's first line says so)
        assert code == 0, out
    report = json.loads((tmp_path / "report.json").read_text())
    assert report["settings"]["limits_from"][-1].startswith(str(ini))  # and says which reader read it
    assert report["settings"]["path_speed_mm_s"] == pytest.approx(DEFAULT_PATH_SPEED_MM, rel=1e-9)
    assert report["settings"]["path_acceleration_mm_s2"] == pytest.approx(DEFAULT_PATH_ACCELERATION_MM, rel=1e-9)
    assert len(report["peaks"]) == robot.joint_count == int(parser["KINS"]["JOINTS"])
    for index, peak in enumerate(report["peaks"]):
        section = parser[f"JOINT_{index}"]
        scale = 1.0 if section["TYPE"] == "ANGULAR" else unit
        written = [float(section[key]) * scale for key in ("MAX_VELOCITY", "MAX_ACCELERATION")]
        assert [peak["speed_limit"], peak["acceleration_limit"]] == pytest.approx(written, rel=1e-9)
        # No shipped robot file gives a top speed: every joint has the stated defaults.
        assert written == pytest.approx([DEFAULT_SPEED[section["TYPE"]], DEFAULT_ACCELERATION[section["TYPE"]]],
                                        rel=1e-9)


@pytest.mark.parametrize("name", sorted(NOT_PACKAGED))
def test_a_robot_linuxcnc_does_not_drive_gets_no_package(name, tmp_path, capsys):
    code, _, err = _run(capsys, "package", name, "--host", "linuxcnc", "-o", tmp_path / "package")
    assert code == 2 and NOT_PACKAGED[name] in err and not (tmp_path / "package").exists()


@pytest.mark.parametrize("units, scale", [("mm", 1.0), ("inch", 1.0 / INCH)])
def test_a_robot_files_top_speed_and_acceleration_are_the_joints(units, scale, tmp_path, capsys):
    """carriage1 of the Gantry-Tau given 254 mm/s and 2540 mm/s^2 in the robot file: its [JOINT_0]
    holds them in the machine's units (no default said), the other carriages the defaults; and
    check-path reads them back from the .ini as the same mm/s and mm/s^2."""
    needs_interpreter()
    text = (ROBOTS / "tau.yaml").read_text()
    given = "travel: [-1, 2600], max_speed: 254, max_acceleration: 2540, calibrate: {origin: offset1"
    robot_file = tmp_path / "tau.yaml"
    robot_file.write_text(text.replace("travel: [-1, 2600], calibrate: {origin: offset1", given, 1))
    ini, parser = _packaged_ini(robot_file, tmp_path / "package", capsys, "--units", units)
    assert parser["TRAJ"]["LINEAR_UNITS"] == units
    assert float(parser["JOINT_0"]["MAX_VELOCITY"]) == pytest.approx(254 * scale, rel=1e-9)
    assert float(parser["JOINT_0"]["MAX_ACCELERATION"]) == pytest.approx(2540 * scale, rel=1e-9)
    assert float(parser["JOINT_1"]["MAX_VELOCITY"]) == pytest.approx(DEFAULT_SPEED["LINEAR"] * scale, rel=1e-9)
    text = ini.read_text()
    assert "default" not in text.split("[JOINT_0]")[1].split("[JOINT_1]")[0]
    assert text.count("# kingen's defaults: the robot file gives this joint no max_speed or max_acceleration\n") == 2
    program = tmp_path / "prog.ngc"
    program.write_text(PROGRAM)
    code, out, err = _run(capsys, "check-path", ROBOTS / "tau.yaml", program, "--ini", ini, "--json",
                          tmp_path / "report.json")
    assert (code, err) == (0, ""), out
    peaks = json.loads((tmp_path / "report.json").read_text())["peaks"]
    assert [peaks[0]["speed_limit"], peaks[0]["acceleration_limit"]] == pytest.approx([254.0, 2540.0], rel=1e-9)
    assert peaks[1]["speed_limit"] == pytest.approx(DEFAULT_SPEED["LINEAR"], rel=1e-9)
