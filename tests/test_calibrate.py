"""kingen calibrate and calibrate plan: measurements made from a perturbed robot file in two
independent ways (kingen's reference inverse or forward kinematics, and the legs' closure
|R t + p - b| - L0 written out here) are explained by the identified robot; an unidentifiable
combination is named; the calibrated robot file verifies; every bad input is one line."""

import json
import math
import re

import numpy as np
import pytest
from ruamel.yaml import YAML

from kingen.calibrate import identification
from kingen.calibrate.identification import region_poses
from kingen.calibrate.measurements import write_measurements
from kingen.cli import main
from kingen.conventions import t6_from_pose
from kingen.kinematics.forward import newton
from kingen.kinematics.reference import solve
from kingen.robot.model import load_robot, resolve_robot_path
from kingen.robot.reading import read_robot_file

FRAME = np.array([12.0, -7.0, 3.0, 0.8, -0.5, 20.0])
"""The measuring device's true pose in the base frame (mm, degrees)."""


def rotation(roll, pitch, yaw):
    """Rz(yaw) Ry(pitch) Rx(roll), degrees, written out here."""
    a, b, c = np.radians([roll, pitch, yaw])
    rx = np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])
    ry = np.array([[math.cos(b), 0, math.sin(b)], [0, 1, 0], [-math.sin(b), 0, math.cos(b)]])
    rz = np.array([[math.cos(c), -math.sin(c), 0], [math.sin(c), math.cos(c), 0], [0, 0, 1]])
    return rz @ ry @ rx


def homogeneous(pose):
    matrix = np.eye(4)
    matrix[:3, :3], matrix[:3, 3] = rotation(*pose[3:]), pose[:3]
    return matrix


def in_device(platform_poses):
    """What the device measures (mm, degrees) with the platform at ``platform_poses``: F^-1 T."""
    inverse = np.linalg.inv(homogeneous(FRAME))
    out = []
    for pose in platform_poses:
        matrix = inverse @ homogeneous(pose)
        r = matrix[:3, :3]
        out.append([*matrix[:3, 3], math.degrees(math.atan2(r[2, 1], r[2, 2])), math.degrees(math.asin(-r[2, 0])),
                    math.degrees(math.atan2(r[1, 0], r[0, 0]))])
    return np.array(out)


def perturbed_file(tmp_path, name, change):
    """The shipped robot ``name`` with its limbs written out and changed by ``change(index, limb)``."""
    data = read_robot_file(resolve_robot_path(name))[0]
    robot = load_robot(name)
    data.pop("layout", None)
    data.pop("golden", None)
    data.pop("optimize", None)
    data["limbs"] = [change(index, limb.model_dump(mode="json", exclude_defaults=True) | {"model": limb.model})
                     for index, limb in enumerate(robot.limbs)]
    path = tmp_path / f"{name}_truth.yaml"
    YAML().dump(data, path)
    return path


def hexapod_truth(index, limb):
    """Every reference length and legs 1-3's points moved by up to a millimetre (legs 4-6's points,
    which the measuring frame and target stand in for, stay nominal: the truth is then the
    identified robot's own gauge)."""
    rng = np.random.default_rng(index)
    limb["reference_length"] += rng.uniform(-1, 1)
    if index < 3:
        for field in ("base_point", "platform_point"):
            limb[field] = [value + rng.uniform(-1, 1) for value in limb[field]]
    return limb


def closure_joints(truth, poses):
    """Leg extensions |R t + p - b| - L0 at platform poses (mm, degrees), from the robot file's numbers."""
    limbs = read_robot_file(truth)[0]["limbs"]
    joints = np.empty((len(poses), len(limbs)))
    for row, pose in enumerate(poses):
        for column, limb in enumerate(limbs):
            point = rotation(*pose[3:]) @ np.array(limb["platform_point"]) + pose[:3]
            joints[row, column] = np.linalg.norm(point - np.array(limb["base_point"])) - limb["reference_length"]
    return joints


def reference_joints(truth, poses):
    robot = load_robot(str(truth))
    return solve(robot, t6_from_pose(poses)).joints[:, :, robot.working_posture]


@pytest.fixture(scope="module")
def hexapod_case(tmp_path_factory):
    folder = tmp_path_factory.mktemp("calibrate")
    truth = perturbed_file(folder, "hexapod", hexapod_truth)
    assert main(["calibrate", "plan", "hexapod", "--poses", "30", "-o", str(folder / "poses.csv")]) == 0
    poses = np.loadtxt(folder / "poses.csv", delimiter=",", skiprows=1)[:, 6:]
    (folder / "perturbed.csv").write_text(write_measurements(load_robot("hexapod"), "pose",
                                                             reference_joints(truth, poses), in_device(poses)))
    return folder, truth


def test_two_ways_of_measuring_agree(hexapod_case):
    """kingen's reference inverse and the closure written here give the same joints."""
    _, truth = hexapod_case
    poses = region_poses(load_robot("hexapod"), 50, 3)
    assert np.max(np.abs(reference_joints(truth, poses) - closure_joints(truth, poses))) < 1e-9


@pytest.mark.parametrize("joints_of", [reference_joints, closure_joints])
def test_hexapod_pose_measurements_recover_the_truth(hexapod_case, joints_of, capsys):
    folder, truth = hexapod_case
    robot = load_robot("hexapod")
    planned = np.loadtxt(folder / "poses.csv", delimiter=",", skiprows=1)[:, 6:]
    held = region_poses(robot, 40, 11)
    for name, poses in (("train.csv", planned), ("held.csv", held)):
        (folder / name).write_text(write_measurements(robot, "pose", joints_of(truth, poses), in_device(poses)))
    out = folder / joints_of.__name__
    assert main(["calibrate", "hexapod", "--measurements", str(folder / "train.csv"), "--validate",
                 str(folder / "held.csv"), "-o", str(out)]) == 0
    result = json.loads((out / "calibration.json").read_text())
    assert result["residuals_before"]["rms_mm"] > 0.1
    assert result["residuals_after"]["rms_mm"] < 1e-6 and result["validation"]["rms_mm"] < 1e-6
    assert np.allclose(result["measuring_frame"], FRAME, atol=1e-6)
    truth_limbs = read_robot_file(truth)[0]["limbs"]
    for row in result["parameters"]:
        limb, field, *axis = row["name"].split(".")
        if row["identifiable"] and limb.startswith("leg"):
            value = truth_limbs[int(limb[3:]) - 1][field]
            assert row["identified"] == pytest.approx(value["xyz".index(axis[0])] if axis else value, abs=1e-6)
    assert any(words.startswith("leg6.base_point.x moves together with measuring_frame.x")
               for words in result["unidentifiable"])
    said = capsys.readouterr().out
    assert "not identifiable: leg6.base_point.x" in said
    # The residuals are written for people: a number without exponent in the unit that suits it.
    for key, words in (("residuals_before", "residuals before"), ("residuals_after", "; after"),
                       ("validation", "held-out validation:")):
        number, unit = re.search(words + r" (-?\d+(?:\.\d+)?) (mm|um|nm|pm) RMS", said).groups()
        written = float(number) * {"mm": 1.0, "um": 1e-3, "nm": 1e-6, "pm": 1e-9}[unit]
        assert written == pytest.approx(result[key]["rms_mm"], rel=5e-3, abs=1e-12), (key, number, unit)
        assert 0.1 <= float(number) < 1000 or unit in ("mm", "pm") or float(number) == 0
    calibrated = out / "hexapod_calibrated.yaml"
    assert "source: 'kingen calibrate hexapod from train.csv" in calibrated.read_text()
    assert main(["verify", str(calibrated), "--samples", "300", "-o", str(out / "build")]) == 0
    assert (out / "report.html").read_text().count("data:image/png;base64,") == 2


def crank_truth(index, limb):
    rng = np.random.default_rng(10 + index)
    limb["zero_offset"] = limb.get("zero_offset", 0.0) + rng.uniform(-0.05, 0.05)
    limb["rod_length"] += rng.uniform(-1, 1)
    return limb


def rail_truth(index, limb):
    rng = np.random.default_rng(20 + index)
    limb["link_length"] += rng.uniform(-1, 1)
    limb["origin"] = limb.get("origin", 0.0) + rng.uniform(-1, 1)
    return limb


@pytest.mark.parametrize("name, change", [("rus_optimized", crank_truth), ("tau", rail_truth)])
def test_positions_only_through_forward_kinematics(tmp_path, name, change):
    """A reflector 30 mm off the platform's origin, measured where kingen's forward kinematics
    of the perturbed robot puts it for the nominal robot's joints."""
    truth = load_robot(str(perturbed_file(tmp_path, name, change)))
    nominal = load_robot(name)
    poses = region_poses(nominal, 120, 5)
    good = solve(nominal, t6_from_pose(poses)).warnings[:, nominal.working_posture] == 0
    poses = poses[good][:70]
    joints = reference_joints(resolve_robot_path(name), poses)
    start = np.concatenate([poses[:, :3], np.radians(poses[:, 3:])], axis=1)
    reached, residual = newton(truth, start, joints, np.array([True] * 3 + [nominal.dof == 6] * 3))
    assert np.max(residual) < 1e-9
    reflector = np.array([10.0, -20.0, 20.0])
    points = np.array([homogeneous(np.concatenate([pose[:3], np.degrees(pose[3:])]))[:3, :3] @ reflector + pose[:3]
                       for pose in reached])
    inverse = np.linalg.inv(homogeneous(FRAME))
    measured = points @ inverse[:3, :3].T + inverse[:3, 3]
    for file_name, rows in (("train.csv", slice(0, 50)), ("held.csv", slice(50, 70))):
        (tmp_path / file_name).write_text(write_measurements(nominal, "position", joints[rows], measured[rows]))
    assert main(["calibrate", name, "--measure", "position", "--measurements", str(tmp_path / "train.csv"),
                 "--validate", str(tmp_path / "held.csv"), "-o", str(tmp_path / "out")]) == 0
    result = json.loads((tmp_path / "out" / "calibration.json").read_text())
    assert result["validation"]["rms_mm"] < 1e-5 and result["validation"]["rms_deg"] is None
    assert len(result["target"]) == 3


def test_plan_beats_random_poses(hexapod_case, capsys):
    from kingen.calibrate import plan
    from kingen.calibrate.parameters import Parameters

    parameters = Parameters(load_robot("hexapod"), "pose")
    found = plan.candidates(parameters, parameters.selected("all"), 0.01, 0.001, count=600)
    chosen = plan.greedy(found.weighted, 30)
    random = np.random.default_rng(2).choice(len(found.poses), 30, replace=False)

    def logdet(rows):
        block = found.weighted[rows].reshape(-1, found.weighted.shape[2])
        return np.linalg.slogdet(block.T @ block)[1]

    assert logdet(chosen) > logdet(random)
    assert np.median(plan.predicted(found, random, parameters)[0][found.chosen]
                     / plan.predicted(found, chosen, parameters)[0][found.chosen]) > 1.0


def bad(capsys, argv):
    status = main(argv)
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    return status, err


@pytest.fixture
def good_csv(hexapod_case):
    folder, truth = hexapod_case
    return (folder / "poses.csv").read_text().splitlines()


@pytest.mark.parametrize("edit, words", [
    (lambda lines: [lines[0].replace(",yaw", "")] + [line.rsplit(",", 1)[0] for line in lines[1:]],
     ":1: yaw: missing column"),
    (lambda lines: [lines[0] + ",w"] + [line + ",1" for line in lines[1:]], ":1: w: unexpected column"),
    (lambda lines: lines[:2] + [lines[2].replace(lines[2].split(",")[2], "abc", 1)] + lines[3:],
     ":3: q3: 'abc' is not a number"),
    (lambda lines: lines[:4] + ["nan," + lines[4].split(",", 1)[1]] + lines[5:], ":5: q1: nan is not a finite number"),
    (lambda lines: lines[:3] + ["300," + lines[3].split(",", 1)[1]] + lines[4:],
     ":4: q1: the nominal robot reaches no pose with these joints in its working posture"),
    (lambda lines: lines[:4], ":4: poses: 3 measurements for 42 identifiable parameters: at least 7 poses are needed"),
    (lambda lines: [lines[0]] + [scaled(line, 1e-3) for line in lines[1:]], ":2: x: the measured positions spread"),
    (lambda lines: [lines[0]] + [scaled(line, 1 / 25.4) for line in lines[1:]], "they look like inches"),
])
def test_bad_measurements_are_one_line(tmp_path, good_csv, capsys, edit, words):
    path = tmp_path / "bad.csv"
    path.write_text("\n".join(edit(good_csv)) + "\n")
    status, err = bad(capsys, ["calibrate", "hexapod", "--measurements", str(path), "-o", str(tmp_path / "out")])
    assert status == 2 and err.startswith(f"kingen: error: {path}") and words in err, err
    assert not (tmp_path / "out").exists()


def scaled(line, factor):
    """A measurement row with its x, y, z in another unit."""
    values = line.split(",")
    return ",".join(values[:6] + [repr(float(value) * factor) for value in values[6:9]] + values[9:])


def test_a_pose_the_nominal_robot_cannot_reach(tmp_path, capsys):
    robot = load_robot("rus_optimized")
    poses = region_poses(robot, 40, 4)
    poses = poses[solve(robot, t6_from_pose(poses)).warnings[:, robot.working_posture] == 0][:20]
    measured = poses.copy()
    measured[7, 2] -= 500.0
    path = tmp_path / "far.csv"
    path.write_text(write_measurements(robot, "pose", reference_joints(resolve_robot_path("rus_optimized"), poses),
                                       measured))
    status, err = bad(capsys, ["calibrate", "rus_optimized", "--measurements", str(path)])
    assert status == 2 and f"{path}:9: x: the nominal robot cannot reach this measured pose" in err, err


def test_a_fit_that_does_not_converge_writes_no_robot(hexapod_case, tmp_path, capsys, monkeypatch):
    folder, _ = hexapod_case
    monkeypatch.setattr(identification, "MAX_EVALUATIONS", 1)
    status = main(["calibrate", "hexapod", "--measurements", str(folder / "perturbed.csv"), "-o",
                   str(tmp_path / "out")])
    assert status == 1 and "the fit did not converge" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_bad_options_are_one_line(tmp_path, hexapod_case, capsys):
    folder, _ = hexapod_case
    status, err = bad(capsys, ["calibrate", "hexapod", "--measurements", str(folder / "poses.csv"),
                               "--identify", "all,-wheels"])
    assert status == 2 and "--identify: unknown group 'wheels'" in err
    status, err = bad(capsys, ["calibrate", "plan", "hexapod", "--poses", "3", "-o", str(tmp_path / "p.csv")])
    assert status == 2 and "--poses: 3 poses for 42 identifiable parameters: at least 7 are needed" in err
    for spec in ("zero", "-all"):  # no crank on a hexapod; nothing left
        for argv in (["calibrate", "hexapod", "--measurements", str(folder / "poses.csv")],
                     ["calibrate", "plan", "hexapod", "--poses", "30", "-o", str(tmp_path / "p.csv")]):
            status, err = bad(capsys, [*argv, "--identify", spec])
            assert status == 2 and err.endswith(f"--identify: '{spec}' selects none of hexapod's parameters (its "
                                                "groups: base, platform, length, frame, target)"), err


def test_a_plan_of_angles_alone_states_their_deviations_in_degrees(tmp_path, capsys):
    """--identify zero on a 6-RUS identifies the cranks' zero angles only: the plan states
    their deviations in degrees (there is no length to state)."""
    assert main(["calibrate", "plan", "rus_optimized", "--poses", "30", "--identify", "zero",
                 "-o", str(tmp_path / "p.csv")]) == 0
    out = capsys.readouterr().out
    assert "6 identifiable parameters" in out and "parameter deviations (one std): median " in out
    assert " mm" not in out.split("parameter deviations")[1].split("\n")[0] and "deg (crank" in out


def test_a_robot_file_in_inches_is_measured_and_written_in_inches(tmp_path):
    """linuxcnc_hexapod is written in inches: the plan's CSV, the measurements read and the
    calibrated file are in inches; measurements of the nominal robot give back its geometry."""
    plan_csv = tmp_path / "poses.csv"
    assert main(["calibrate", "plan", "linuxcnc_hexapod", "--poses", "12", "-o", str(plan_csv)]) == 0
    home = load_robot("linuxcnc_hexapod").verification.home
    rows = np.loadtxt(plan_csv, delimiter=",", skiprows=1)
    assert abs(np.mean(rows[:, 8]) * 25.4 - home[2]) < 0.5 * abs(home[2])  # z in inches, near home's
    assert main(["calibrate", "linuxcnc_hexapod", "--measurements", str(plan_csv), "-o", str(tmp_path / "out")]) == 0
    result = json.loads((tmp_path / "out" / "calibration.json").read_text())
    assert result["residuals_after"]["rms_mm"] < 1e-6
    written = tmp_path / "out" / "linuxcnc_hexapod_calibrated.yaml"
    assert read_robot_file(written)[0]["units"] == "inch"
    for mine, theirs in zip(load_robot(str(written)).limbs, load_robot("linuxcnc_hexapod").limbs):
        assert np.allclose(mine.base_point, theirs.base_point, atol=1e-6)
        assert np.allclose(mine.platform_point, theirs.platform_point, atol=1e-6)
