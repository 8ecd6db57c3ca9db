"""kingen calibrate and calibrate plan on machines with task coordinates: the plan's poses lie on
the nominal machine's manifold (its constraint equations written out here); measurements of a
perturbed machine (its constraints' axes turned) made at its own poses are explained by the
identified machine to 1e-6 mm, its identifiable parameters recovered to 1e-6 (mm, degrees), and
the calibrated robot file, which keeps the task and the passive leg, verifies. The truth's poses
come from kingen's on_manifold on the truth's file; the test checks them against the constraint
equations and the legs' closure written out here."""

import json
import math

import numpy as np
import pytest
from ruamel.yaml import YAML

from kingen.calibrate.identification import region_poses
from kingen.calibrate.measurements import write_measurements
from kingen.cli import main
from kingen.conventions import t6_from_pose
from kingen.kinematics.hybrid.parasitic import on_manifold
from kingen.kinematics.reference import solve
from kingen.robot.model import load_robot, resolve_robot_path
from kingen.robot.reading import read_robot_file

from test_calibrate import FRAME, in_device, rotation

TILT = 0.05
"""The Exechon pair's shared platform axis is turned by this (degrees) about the base z axis."""


def constraint_residuals(data, poses):
    """(n, 3) mm: each constraint equation written out from the robot file's numbers at platform
    poses (mm, degrees): a.(C - c) for an axis a fixed in the base (c the rail or base point),
    (R e).(b - p) - e.n for an axis e fixed in the platform; for a passive leg (one column), the
    tube's offset from the platform origin across its axis, |(R t) x (p - c)|."""
    if "passive_leg" in data:
        leg = data["passive_leg"]
        return np.array([[np.linalg.norm(np.cross(rotation(*pose[3:]) @ leg["tube_axis"], pose[:3] - leg["base_point"]))]
                         for pose in poses])
    out = np.empty((len(poses), len(data["limbs"])))
    for row, pose in enumerate(poses):
        matrix = rotation(*pose[3:])
        for column, limb in enumerate(data["limbs"]):
            platform_point = np.array(limb["platform_point"], dtype=float)
            base = np.array(limb.get("base_point", limb.get("rail_point")), dtype=float)
            if "revolute_axis" in limb:
                point = matrix @ platform_point + pose[:3]
                out[row, column] = np.dot(limb["revolute_axis"], point - base)
            else:
                axis = np.array(limb["platform_revolute_axis"], dtype=float)
                out[row, column] = np.dot(matrix @ axis, base - pose[:3]) - np.dot(axis, platform_point)
    return out


def leg_joints(data, poses):
    """Leg extensions |R t + p - b| - L0 at platform poses (mm, degrees), written out."""
    return np.array([[np.linalg.norm(rotation(*pose[3:]) @ np.array(limb["platform_point"]) + pose[:3]
                                     - np.array(limb["base_point"])) - limb["reference_length"]
                      for limb in data["limbs"]] for pose in poses])


def prs_truth(limbs):
    """rail1's and rail2's points and both link lengths moved (identifiable on this head)."""
    limbs[0]["rail_point"] = [value + move for value, move in zip(limbs[0]["rail_point"], (0.4, -0.3, 0.2))]
    limbs[1]["rail_point"] = [value + move for value, move in zip(limbs[1]["rail_point"], (-0.2, 0.35, -0.25))]
    limbs[0]["platform_point"] = [value + move for value, move in zip(limbs[0]["platform_point"], (0.3, -0.2, 0.0))]
    limbs[0]["link_length"] += 0.45
    limbs[1]["link_length"] -= 0.3
    return {}


def exechon_truth(limbs):
    """The pair's shared platform axis turned by TILT about z (tilt_b), leg lengths and leg 1's
    points moved."""
    angle = math.radians(TILT)
    for limb in limbs[:2]:
        limb["platform_revolute_axis"] = [-math.sin(angle), math.cos(angle), 0.0]
    limbs[0]["base_point"] = [value + move for value, move in zip(limbs[0]["base_point"], (0.3, -0.4, 0.0))]
    limbs[0]["platform_point"] = [value + move for value, move in zip(limbs[0]["platform_point"], (-0.2, 0.3, 0.4))]
    for limb, move in zip(limbs, (0.4, -0.35, 0.25)):
        limb["reference_length"] += move
    return {"leg1+leg2.platform_revolute_axis.tilt_b": math.degrees(math.tan(angle))}


def tricept_truth(limbs):
    """Every leg length and leg 1's points moved; the passive leg as drawn."""
    limbs[0]["base_point"] = [value + move for value, move in zip(limbs[0]["base_point"], (0.3, -0.4, 0.2))]
    limbs[0]["platform_point"] = [value + move for value, move in zip(limbs[0]["platform_point"], (-0.2, 0.3, 0.4))]
    for limb, move in zip(limbs, (0.4, -0.35, 0.25)):
        limb["reference_length"] += move
    return {}


@pytest.mark.parametrize("name, change, poses", [("prs_head", prs_truth, 10), ("exechon_constrained", exechon_truth, 10),
                                                  ("tricept", tricept_truth, 10)])
def test_noise_free_measurements_recover_the_truth(tmp_path, name, change, poses):
    assert main(["calibrate", "plan", name, "--poses", str(poses), "-o", str(tmp_path / "plan.csv")]) == 0
    nominal_data = read_robot_file(resolve_robot_path(name))[0]
    planned = np.loadtxt(tmp_path / "plan.csv", delimiter=",", skiprows=1)[:, 3:]
    assert np.max(np.abs(constraint_residuals(nominal_data, planned))) < 1e-8  # on the nominal manifold (to
    # the plan file's 12 significant digits)
    data = read_robot_file(resolve_robot_path(name))[0]
    data.pop("golden")
    expected = change(data["limbs"])
    truth_path = tmp_path / f"{name}_truth.yaml"
    YAML().dump(data, truth_path)
    truth = load_robot(str(truth_path))
    nominal = load_robot(name)
    drawn = region_poses(nominal, 12, 17)  # on the nominal manifold
    held = drawn[solve(nominal, t6_from_pose(drawn)).warnings[:, nominal.working_posture] == 0][:8]
    for file_name, asked in (("train.csv", planned), ("held.csv", held)):
        machine = on_manifold(truth, asked)  # the real machine's poses for the asked task coordinates
        assert np.max(np.abs(constraint_residuals(data, machine))) < 1e-9
        joints = solve(truth, t6_from_pose(machine)).joints[:, :, truth.working_posture]
        if name != "prs_head":
            assert np.max(np.abs(joints - leg_joints(data, machine))) < 1e-9
        (tmp_path / file_name).write_text(write_measurements(nominal, "pose", joints, in_device(machine)))
    out = tmp_path / "out"
    assert main(["calibrate", name, "--measurements", str(tmp_path / "train.csv"), "--validate",
                 str(tmp_path / "held.csv"), "-o", str(out)]) == 0
    result = json.loads((out / "calibration.json").read_text())
    assert result["residuals_before"]["rms_mm"] > 0.05
    assert result["residuals_after"]["rms_mm"] < 1e-6 and result["validation"]["rms_mm"] < 1e-6
    assert np.allclose(result["measuring_frame"], FRAME, atol=1e-6)
    identified = {row["name"]: row for row in result["parameters"]}
    for limb_index, limb in enumerate(data["limbs"]):
        for field in ("rail_point", "base_point", "platform_point"):
            for axis, value in zip("xyz", limb.get(field, ())):
                row = identified[f"{limb['name']}.{field}.{axis}"]
                if row["identifiable"]:  # the files' 12 digits (1e-9 mm) through a condition number of 3e4
                    assert row["identified"] == pytest.approx(value, abs=5e-6), row
    for parameter, value in expected.items():
        assert identified[parameter]["identifiable"]
        assert identified[parameter]["identified"] == pytest.approx(value, abs=1e-6)
    calibrated = out / f"{name}_calibrated.yaml"
    written = read_robot_file(calibrated)[0]
    assert written["task"] == data["task"]
    for mine, theirs in zip(written["limbs"], data["limbs"]):
        for field in ("revolute_axis", "platform_revolute_axis"):
            if field in theirs:
                assert np.allclose(mine[field], theirs[field], atol=1e-8)
    assert main(["verify", str(calibrated), "--samples", "200", "-o", str(out / "build")]) == 0
    if "passive_leg" in data:  # its parameters come after the legs' and are kept: the file keeps the tube
        assert not any(row["identifiable"] for parameter, row in identified.items() if parameter.startswith("passive"))
        for field in ("base_point", "first_axis", "tube_axis"):
            assert np.allclose(written["passive_leg"][field], data["passive_leg"][field], atol=1e-9)


def test_too_few_poses_count_the_constraint_equations(tmp_path, capsys):
    """Each pose of a constrained machine gives its joints and its three constraint equations."""
    assert main(["calibrate", "plan", "prs_head", "--poses", "3", "-o", str(tmp_path / "p.csv")]) == 2
    err = capsys.readouterr().err.strip()
    assert err == ("kingen: error: --poses: 3 poses for 30 identifiable parameters: at least 5 are needed "
                   "(6 equations per pose)")
    assert not (tmp_path / "p.csv").exists()
