"""kingen calibrate on a machine with a serial wrist (robots/exechon_wrist.yaml): measurements on
the tool, the wrist's zero offsets, axes and the tool's reach among the parameters. Noise-free
measurements of a perturbed machine are made by the reference's inverse from tool poses (legs
and wrist joints) and the wrist's forward; the fit predicts held-out measurements of the truth
exactly (the Exechon with its A/C head, the Tricept with two and three wrist axes), recovers the
wrist's parameters that are not a gauge of the platform frame, and the
commands plan, calibrate and write a calibrated robot file that loads and verifies."""

import numpy as np
import pytest
import yaml

from kingen.calibrate.identification import identify, region_poses, validation_problem
from kingen.calibrate.measurements import Measurements, write_measurements
from kingen.calibrate.parameters import Parameters
from kingen.calibrate.prediction import synthesize
from kingen.cli import main
from kingen.robot.model import load_robot

FRAME = [150.0, -80.0, 40.0, 2.0, -3.0, 25.0]
GAUGE = ("ax4.zero_offset", "ax4.axis.tilt_a")
"""Held at nominal in the truth: Ax4 turns about the platform's z axis, so its zero is the
platform frame's turn about z (the platform points and axes take it), and a tilt of Ax4 about x
is the platform frame's turn about x with Ax5's zero (which is identified)."""


def perturbed(parameters, seed=3):
    """The truth: limb parameters moved by up to 0.5 mm / 0.05 deg, axes by 0.05 deg, the wrist's
    zeros by 0.1 deg (but GAUGE), the measuring frame at FRAME."""
    rng = np.random.default_rng(seed)
    truth = parameters.nominal.copy()
    for index, entry in enumerate(parameters.entries):
        if entry.group in ("frame", "target") or entry.name in GAUGE:
            continue
        scale = 0.05 if entry.group == "axis" else 0.1 if entry.wrist is not None and entry.group == "zero" else \
            0.5 if entry.unit == "mm" else 0.05
        truth[index] += scale * rng.uniform(-1.0, 1.0)
    truth[parameters.groups == "frame"] = FRAME
    return truth


def measured(parameters, truth, poses):
    joints, values = synthesize(parameters, truth, poses, parameters.robot.working_posture)
    assert np.all(np.isfinite(joints)) and np.all(np.isfinite(values))
    return Measurements("synthetic", parameters.measure, joints, values, tuple(range(2, len(poses) + 2)), ())


@pytest.fixture(scope="module")
def robot():
    return load_robot("exechon_wrist")


def test_pose_measurements_recover_the_wrist(robot):
    parameters = Parameters(robot, "pose")
    assert {"ax4.zero_offset", "ax5.zero_offset", "ax5.axis.tilt_b", "tool.reach"} <= set(parameters.names)
    truth = perturbed(parameters)
    fit = identify(parameters, measured(parameters, truth, region_poses(robot, 40, 5)), parameters.selected("all,-target"))
    assert fit.converged
    names = np.array(parameters.names)
    wrist = np.array([entry.wrist is not None for entry in parameters.entries])
    recovered = wrist & fit.chosen
    assert {"ax5.zero_offset", "ax5.axis.tilt_a", "ax5.axis.tilt_b", "tool.reach"} <= set(names[recovered])
    assert np.max(np.abs(fit.values[recovered] - truth[recovered])) <= 1e-6  # degrees and mm
    assert np.abs(truth[names == "ax5.zero_offset"] - parameters.nominal[names == "ax5.zero_offset"]) > 1e-3
    held = measured(parameters, truth, region_poses(robot, 30, 11))
    position, angle, _ = validation_problem(parameters, fit.values, held).errors(fit.values)
    assert np.max(position) <= 1e-6 and np.max(angle) <= 1e-5  # arccos resolves sqrt(2 eps) rad: 1.2e-6 deg
    before, _, _ = validation_problem(parameters, fit.before, held).errors(fit.before)
    assert np.sqrt(np.mean(before ** 2)) > 0.05  # the perturbation was seen


def test_position_measurements_through_the_machines_forward(robot):
    parameters = Parameters(robot, "position", target=(0.0, 0.0, 0.0))
    truth = perturbed(parameters, seed=4)
    truth[parameters.groups == "target"] = [5.0, -3.0, 2.0]
    fit = identify(parameters, measured(parameters, truth, region_poses(robot, 60, 6)), parameters.selected("all"))
    assert fit.converged
    held = measured(parameters, truth, region_poses(robot, 30, 12))
    position, angle, closed = validation_problem(parameters, fit.values, held).errors(fit.values)
    assert angle is None and np.all(closed) and np.max(position) <= 1e-6


def test_plan_and_calibrate_write_a_calibrated_file_that_verifies(robot, tmp_path, capsys):
    poses_csv = tmp_path / "poses.csv"
    assert main(["calibrate", "plan", robot.name, "--poses", "30", "-o", str(poses_csv)]) == 0
    header = poses_csv.read_text().splitlines()[0].split(",")
    assert header[:6] == ["q1", "q2", "q3", "q4", "q5", "x"]
    parameters = Parameters(robot, "pose")
    truth = perturbed(parameters, seed=8)
    data = measured(parameters, truth, region_poses(robot, 40, 9))
    measurements = tmp_path / "measured.csv"
    measurements.write_text(write_measurements(robot, "pose", data.joints, data.measured))
    out = tmp_path / "out"
    assert main(["calibrate", robot.name, "--measurements", str(measurements), "--identify", "all,-target",
                 "-o", str(out)]) == 0
    written = out / "exechon_wrist_calibrated.yaml"
    document = yaml.safe_load(written.read_text())
    names = np.array(parameters.names)
    expected = float(truth[names == "ax5.zero_offset"][0])
    assert abs(document["wrist"][1]["zero_offset"] - expected) <= 1e-6
    calibrated = load_robot(written)
    assert abs(calibrated.wrist.reach - float(truth[names == "tool.reach"][0])) <= 1e-6
    capsys.readouterr()
    assert main(["verify", str(written), "--host", "c", "--samples", "500", "-o", str(tmp_path / "verify")]) == 0


@pytest.mark.parametrize("name", ["tricept_wrist", "tricept_wrist3"])
def test_a_tube_machine_with_two_or_three_wrist_axes_fits_held_out_poses(name):
    robot = load_robot(name)
    parameters = Parameters(robot, "pose")
    truth = perturbed(parameters, seed=5)
    fit = identify(parameters, measured(parameters, truth, region_poses(robot, 40, 5)), parameters.selected("all,-target"))
    assert fit.converged and np.any(fit.chosen & (parameters.groups == "zero"))
    held = measured(parameters, truth, region_poses(robot, 30, 11))
    position, angle, _ = validation_problem(parameters, fit.values, held).errors(fit.values)
    assert np.max(position) <= 1e-6 and np.max(angle) <= 1e-5
