"""LinuxCNC modules of wrist machines on an inch machine (LINEAR_UNITS = inch): the world's X Y Z
and the legs are in inches, the wrist's angles in degrees, and the wrist's lengths (its reach,
its tool frame's offset, a three-axis wrist's tip, the platform's home) in inches too. Through
``kingen verify --host linuxcnc --units inch`` as a user runs it, against the reference; a module
whose wrist lengths were left in mm (as on a mm machine) fails it."""

import json

import numpy as np
import pytest

from conftest import require_linuxcnc_headers
from kingen.cli import main
from kingen.conventions import t6_from_pose
from kingen.hosts import get_host
from kingen.hosts.linuxcnc import render as linuxcnc_render
from kingen.hosts.linuxcnc.five_axis import wrist_view
from kingen.robot.model import load_robot

INCH = 25.4
"""mm per inch."""


@pytest.mark.parametrize("name", ["tricept_wrist", "tricept_wrist3", "exechon_wrist"])
def test_an_inch_wrist_machines_module_passes_verify(name, tmp_path):
    require_linuxcnc_headers()
    report_file = tmp_path / "report.json"
    assert main(["verify", name, "--host", "linuxcnc", "--units", "inch", "--samples", "1500", "--processes", "1",
                 "-o", str(tmp_path / "build"), "--json", str(report_file)]) == 0
    report = json.loads(report_file.read_text())
    checks = {check["name"]: check["passed"] for check in report["checks"]}
    assert all(checks.values()) and {"values", "warnings", "forward", "hal loads"} <= set(checks), checks
    assert report["max_abs_error_mm"] <= 1e-9 and report["max_abs_error_rad"] <= 1e-9


def test_the_inch_module_answers_the_mm_modules_joints_in_inches(tmp_path):
    """The same tool poses given to the inch module in inches and to the mm module in mm: the legs'
    joints differ by 25.4 exactly but for rounding, the wrist's degrees not at all."""
    require_linuxcnc_headers()
    robot = load_robot("tricept_wrist3")
    home, spread = np.array(robot.verification.home), np.array(robot.verification.range)
    poses = home + np.random.default_rng(5).uniform(-0.5, 0.5, (200, 6)) * spread
    t6 = t6_from_pose(poses)
    joints = {}
    for units in ("mm", "inch"):
        host = get_host("linuxcnc").configured(units=units)
        built = host.build(robot, tmp_path / units)
        module = host.load(built.library, built.routine, host.as_seen(robot))
        world = module.emc_poses(t6)
        assert np.allclose(world[:, :3] * (INCH if units == "inch" else 1.0), poses[:, :3], rtol=0, atol=1e-9)
        found, returns, _ = module.inverse(world)
        assert np.all(returns == 0)
        joints[units] = found[:, :robot.joint_count]
    legs = robot.parallel.joint_count
    assert np.max(np.abs(joints["inch"][:, :legs] * INCH - joints["mm"][:, :legs])) <= 1e-9
    assert np.max(np.abs(joints["inch"][:, legs:] - joints["mm"][:, legs:])) <= 1e-9
    assert np.max(np.abs(joints["mm"][:, legs:])) > 1.0  # the wrist turned


def test_a_wrist_left_in_mm_on_an_inch_machine_fails_verify(tmp_path, monkeypatch, capsys):
    """A planted inch error: the legs in inches, the wrist's lengths in mm."""
    require_linuxcnc_headers()
    robot = load_robot("exechon_wrist")
    monkeypatch.setattr(linuxcnc_render, "wrist_view", lambda robot, units="mm": wrist_view(robot, "mm"))
    (name, text), = linuxcnc_render.render(robot, "inch").items()
    monkeypatch.undo()
    source = tmp_path / name
    source.write_text(text)
    assert main(["verify", "exechon_wrist", "--host", "linuxcnc", "--units", "inch", "--source", str(source),
                 "--samples", "300", "--processes", "1", "-o", str(tmp_path / "build")]) == 1
    out = capsys.readouterr().out
    assert "FAILED values" in out and "FAILED forward" in out
