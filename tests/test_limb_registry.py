"""Adding a limb model touches only its own files: a toy model, defined and registered
here with its partial in tests/limbs/, is validated, rendered, compiled, verified and
packaged by the unchanged rest of kingen."""

from pathlib import Path
from typing import Literal

import json
import re

import numpy as np
import pytest

from kingen.robot import limbs
from kingen.hosts.delmia.build import build_plugin
from kingen.errors import KingenError
from kingen.hosts.delmia.loader import Plugin
from kingen.calibrate.identification import region_poses
from kingen.calibrate.measurements import write_measurements
from kingen.cli import main
from kingen.conventions import t6_from_pose
from kingen.kinematics.reference import solve
from kingen.hosts import get_host
from kingen.robot.limbs import LimbModel, LimbSolution, Rail, c_double, c_vector
from kingen.robot.model import load_robot
from kingen.hosts.delmia.package import render_package
from kingen.robot.schema import Coordinate, Vec3
from kingen.verify import VerifyOptions, verify


class Plumb(LimbModel):
    """A toy model: a vertical actuator reaching a platform point, q = (R t + p).z - height."""

    model: Literal["plumb"]
    platform_point: Vec3
    height: Coordinate

    calibratable = {"height": "mm"}
    length_fields = ("platform_point", "height")
    c_columns = "joint, platform point t (mm, platform frame), height (mm), its dialog field"
    partial = Path(__file__).parent / "limbs" / "plumb.c.j2"

    link_length_rate = 1.0

    def solve(self, platform_point):
        q = platform_point[..., 2] - self.height
        return LimbSolution(values=np.stack([q, q], axis=-1))

    def base_side_point(self, platform_point, joint):
        """The foot of the plumb line: the force runs vertically up to the platform point."""
        return np.stack([platform_point[..., 0], platform_point[..., 1],
                         np.full(np.shape(platform_point)[:-1], self.height)], axis=-1)

    def passive_length(self, joint):
        return np.abs(joint)

    def c_row(self):
        return {"platform_point": c_vector(self.platform_point), "height": c_double(self.height)}

    def explain_offset(self, offset):
        return f"a wrong height (the routine behaves as if it were {self.height - offset:.6g} mm)"


ROBOT = """\
name: toy
description: Two plumbs and a leg.
limbs:
  - {model: plumb, platform_point: [100, 0, 0], height: -50, calibrate: {height: length1}}
  - {model: leg, base_point: [0, 300, 0], platform_point: [0, 50, 0], reference_length: 200}
  - {model: plumb, platform_point: [-100, 0, 0], height: -60, travel: [0, 100]}
verification: {home: [0, 0, 0, 0, 0, 0], range: [30, 30, 30, 10, 10, 10]}
"""


@pytest.fixture
def toy(tmp_path):
    limbs.register(Plumb)
    path = tmp_path / "toy.yaml"
    path.write_text(ROBOT)
    try:
        yield load_robot(path)
    finally:
        limbs.unregister(Plumb)


def test_a_registered_model_is_validated_with_located_errors(toy, tmp_path):
    assert [limb.model for limb in toy.limbs] == ["plumb", "leg", "plumb"]
    bad = tmp_path / "bad.yaml"
    bad.write_text(ROBOT.replace("height: -50", "height: [1]"))
    with pytest.raises(KingenError, match=r"bad.yaml:4: limbs\[0\].height: Input should be a valid number"):
        load_robot(bad)


def test_a_registered_model_renders_compiles_and_verifies(toy, tmp_path):
    result = build_plugin(toy, tmp_path / "build")
    source = result.source.read_text()
    assert "kingen_solve_plumb(&kingen_plumbs[0]" in source and "kingen_solve_leg(&kingen_legs[0]" in source
    report = verify(toy, Plugin(result.library, result.routine), VerifyOptions(samples=2000))
    assert report.passed, [check.detail for check in report.failures]
    calibrated = verify(toy, Plugin(result.library, result.routine),
                        VerifyOptions(samples=500, link_lengths=(-90.0, 0, 0, 0, 0, 0)))
    assert calibrated.passed, [check.detail for check in calibrated.failures]


def test_a_registered_model_reaches_the_setup_sheet(toy):
    sheet = render_package(toy, "windows")["SETUP.md"]
    assert "| Length 1 | joint1.height | mm | -50 |" in sheet


def test_an_unregistered_model_is_an_unknown_tag(tmp_path):
    path = tmp_path / "toy.yaml"
    path.write_text(ROBOT)
    with pytest.raises(KingenError, match=r":4: limbs\[0\].model: Input tag 'plumb' found using 'model' does not"):
        load_robot(path)


class Surveyed(Plumb):
    """The toy model, saying what calibration may identify on it: its height."""

    calibration_parameters = (("height", "length", "mm"),)


def test_calibrate_asks_the_model_what_it_identifies(tmp_path, capsys):
    """Joints read on a robot whose plumbs stand 0.7 mm lower and 0.4 mm higher than the file
    says: calibrate identifies the heights the model declares (their difference; the measuring
    frame's z takes their common part) and explains the measurements."""
    limbs.register(Surveyed)
    try:
        (tmp_path / "toy.yaml").write_text(ROBOT)
        (tmp_path / "truth.yaml").write_text(ROBOT.replace("height: -50", "height: -50.7")
                                             .replace("height: -60", "height: -59.6"))
        robot, truth = load_robot(tmp_path / "toy.yaml"), load_robot(tmp_path / "truth.yaml")
        poses = region_poses(robot, 30, 3)
        joints = solve(truth, t6_from_pose(poses)).joints[:, :, truth.working_posture]
        (tmp_path / "measured.csv").write_text(write_measurements(robot, "pose", joints, poses))
        assert main(["calibrate", str(tmp_path / "toy.yaml"), "--measurements", str(tmp_path / "measured.csv"),
                     "-o", str(tmp_path / "out")]) == 0
    finally:
        limbs.unregister(Surveyed)
    result = json.loads((tmp_path / "out" / "calibration.json").read_text())
    heights = {row["name"]: row["identified"] for row in result["parameters"] if row["name"].endswith(".height")}
    assert sorted(heights) == ["joint1.height", "joint3.height"]
    assert heights["joint1.height"] - heights["joint3.height"] == pytest.approx(-50.7 + 59.6, abs=1e-6)
    assert result["residuals_after"]["rms_mm"] < 1e-6


def test_calibrate_refuses_a_model_that_declares_no_parameters(toy, tmp_path, capsys):
    (tmp_path / "measured.csv").write_text("x\n")
    assert main(["calibrate", str(toy.path), "--measurements", str(tmp_path / "measured.csv")]) == 2
    error = capsys.readouterr().err
    assert error == (f"kingen: error: {toy.path}: limbs: calibrate does not know the parameters of the 'plumb' limb "
                     "model (it knows leg, rail, crank)\n")


@pytest.mark.parametrize("host", ["c", "linuxcnc"])
def test_the_hosts_ask_the_model_whether_the_forward_is_in_closed_form(host, monkeypatch, tmp_path, capsys):
    """Three rails on a translating platform: the closed form where the rail says it has one;
    Newton's method, verified, where it says not."""
    robot = load_robot("linear_delta")
    assert any("kingen_closed_form(" in text for text in get_host(host).render(robot).values())
    monkeypatch.setattr(Rail, "closed_form_forward", False)
    assert not any("kingen_closed_form(" in text for text in get_host(host).render(robot).values())
    assert main(["verify", "linear_delta", "--host", host, "--samples", "300", "-o", str(tmp_path)]) == 0
    assert re.search(r"ok +forward: .*(Newton steps|iterations) mean [1-9]", capsys.readouterr().out)
