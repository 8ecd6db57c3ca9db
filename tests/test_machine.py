"""verify's ``machine`` check and the LinuxCNC package's refusal: a robot that cannot work at
its verification home (legs too short, an architecturally singular layout) fails verify with
the cause named and gets no package; a robot drawn in metres in a file that states no units
fails, naming its size and the `units:` line to add, and gets no package from any host; every
shipped robot passes the check."""

import json
from pathlib import Path

import pytest

from kingen.cli import main
from kingen.kinematics.home import extent_mm, scale_notice
from kingen.robot.model import load_robot, shipped_robots
from kingen.verify.checks.machine import machine_check

DATA = Path(__file__).parent / "data" / "machine"
LEGS = ", ".join(f"leg{i} 451.949 mm (travel 300 to 400)" for i in range(1, 7))


def verify_json(tmp_path, name):
    report = tmp_path / f"{name}.json"
    code = main(["verify", str(DATA / f"{name}.yaml"), "--samples", "200", "-o", str(tmp_path / "build" / name),
                 "--json", str(report)])
    data = json.loads(report.read_text())
    return code, {check["name"]: check for check in data["checks"]}, data["notices"]


def test_legs_too_short_for_home_fail_verify_naming_each_leg_and_its_travel(tmp_path):
    code, checks, _ = verify_json(tmp_path, "short_legs")
    assert code == 1
    assert checks["machine"]["passed"] is False
    assert checks["machine"]["detail"] == (f"the verification home lies beyond travel in posture 0: {LEGS}: "
                                           "the machine cannot work there")
    # the jacobian's "not exercised" gives the true reason: every posture is beyond travel
    assert checks["jacobian"]["detail"].endswith("of their 200 postures, 200 beyond travel")


def test_an_architecturally_singular_layout_fails_verify_naming_its_direct_index(tmp_path):
    code, checks, _ = verify_json(tmp_path, "singular_layout")
    assert code == 1
    detail = checks["machine"]["detail"]
    assert detail.startswith("the direct index at the verification home is ")
    assert "mm in posture 0, at most 0.00027 mm: the design is singular there" in detail


SIZE_PROBLEM = ("the machine is 0.524 mm across its base and platform points at home, less than 10 mm: the file "
                "states no units, so its lengths were read in mm; add the line 'units: m' if they are metres "
                "('units: inch' for inches, 'units: mm' if the machine is this small)")


def test_a_robot_typed_in_metres_without_units_fails_machine_naming_its_size_and_the_line_to_add(tmp_path):
    code, checks, notices = verify_json(tmp_path, "metre_legs")
    assert code == 1
    assert checks["machine"]["detail"] == SIZE_PROBLEM
    assert not any("across" in notice for notice in notices)  # the failure says it once


def test_the_same_file_with_units_m_is_the_mm_machine(tmp_path):
    """metre_legs with 'units: m' is short_legs (the same numbers in mm): the same verdict, its
    joints named in metres (451.949 mm = 0.451949 m)."""
    path = tmp_path / "metre_legs_m.yaml"
    path.write_text((DATA / "metre_legs.yaml").read_text() + "units: m\n")
    robot, in_mm = load_robot(str(path)), load_robot(str(DATA / "short_legs.yaml"))
    assert robot.size_mm == pytest.approx(in_mm.size_mm, rel=1e-12)
    detail = machine_check(robot).detail
    assert detail.startswith("the verification home lies beyond travel in posture 0: "
                             "leg1 0.451949 m (travel 0.3 to 0.4)"), detail
    assert machine_check(in_mm).detail.startswith(f"the verification home lies beyond travel in posture 0: {LEGS}")


@pytest.mark.parametrize("host", ["delmia", "c", "linuxcnc"])
def test_no_host_packages_a_robot_typed_in_metres_without_units(tmp_path, capsys, host):
    out = tmp_path / "package"
    assert main(["package", str(DATA / "metre_legs.yaml"), "--host", host, "-o", str(out)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert lines == [f"kingen: error: {DATA / 'metre_legs'}.yaml:2: units: {SIZE_PROBLEM}: a package is not written for it"]
    assert not out.exists()


@pytest.mark.parametrize("name", shipped_robots())
def test_every_shipped_robot_can_work_at_its_home_and_gets_no_notice(name):
    robot = load_robot(name)
    check = machine_check(robot)
    assert check.passed, check.detail
    assert scale_notice(robot) is None and 10 <= extent_mm(robot) <= 1e5


def test_a_robot_larger_than_100_m_gets_the_notice(tmp_path):
    text = (DATA / "short_legs.yaml").read_text()
    for before, after in (("base_radius: 200", "base_radius: 200000"), ("platform_radius: 100", "platform_radius: 100000"),
                          ("430, ", "430000, "), ("[300, 400]", "[300000, 500000]")):
        text = text.replace(before, after)
    path = tmp_path / "huge.yaml"
    path.write_text(text)
    robot = load_robot(str(path))
    assert machine_check(robot).passed
    assert scale_notice(robot).startswith("the robot is 5.24e+05 mm across its base and platform points at home, "
                                          "more than 100 m")
