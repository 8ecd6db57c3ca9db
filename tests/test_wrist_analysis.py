"""analyze on a machine with a serial wrist: the tool's tilt limits checked against a bisection
written here (the tool frame turned by scipy about a horizontal axis through the tool tip, each
pose judged by the reference's warnings alone), the wrist's pole met away from home, and what
the analysis says it did not judge."""

import json

import numpy as np
import pytest
import yaml
from scipy.spatial.transform import Rotation

from kingen.cli import main
from kingen.cli.common import load_model
from kingen.design.analysis import Settings, analyze, tilt_limits
from kingen.kinematics.reference import solve
from kingen.kinematics.routine import WARNINGS
from kingen.robot.model import robots_dir

SETTINGS = Settings(tilt_step_deg=0.1, azimuth_step_deg=90.0, tilt_max_deg=180.0)


def tool_tilted(robot, azimuth_deg, tilt_deg):
    """(n, 4, 4) kingen T6 (transposed): the home tool frame turned by each tilt about the base's
    horizontal axis (cos a, sin a, 0) through the tool tip."""
    home = robot.verification.home
    start = Rotation.from_euler("ZYX", [home[5], home[4], home[3]], degrees=True).as_matrix()
    axis = np.array([np.cos(np.radians(azimuth_deg)), np.sin(np.radians(azimuth_deg)), 0.0])
    tilts = np.atleast_1d(tilt_deg)
    turned = Rotation.from_rotvec(np.outer(np.radians(tilts), axis)).as_matrix() @ start
    t6 = np.zeros((len(tilts), 4, 4))
    t6[:, :3, :3] = np.swapaxes(turned, 1, 2)
    t6[:, 3, :3] = home[:3]
    t6[:, 3, 3] = 1.0
    return t6


def good(robot, posture, azimuth_deg, tilt_deg):
    return solve(robot, tool_tilted(robot, azimuth_deg, tilt_deg)).warnings[0, posture] == WARNINGS[
        "WARN_GOOD_SOLUTION"]


def bisected_limit(robot, posture, azimuth_deg, low=1.0, high=180.0):
    """The tilt (deg, within 1e-7) where the reference's answer stops being WARN_GOOD_SOLUTION,
    from a bracket [low good, high not good]."""
    assert good(robot, posture, azimuth_deg, low) and not good(robot, posture, azimuth_deg, high)
    while high - low > 1e-7:
        middle = (low + high) / 2
        low, high = (middle, high) if good(robot, posture, azimuth_deg, middle) else (low, middle)
    return low


@pytest.mark.parametrize("name", ["exechon_wrist", "tricept_wrist"])
def test_the_tool_tilt_limit_is_the_bisected_one(name):
    robot = load_model(name)
    posture = robot.working_posture
    limits = tilt_limits(robot, posture, SETTINGS)
    assert [row["azimuth_deg"] for row in limits] == [0.0, 90.0, 180.0, 270.0]
    for row in limits:
        bisected = bisected_limit(robot, posture, row["azimuth_deg"])
        # the analysis's limit is the last 0.1-degree step at or below the bisected one
        assert row["max_tilt_deg"] <= bisected + 1e-9 < row["max_tilt_deg"] + SETTINGS.tilt_step_deg
        assert row["cause"] == "joint_limits"
        # what stops it: Ax5 reaches its travel (110 degrees) there, the tool axis beyond 100 degrees
        # from vertical because the platform itself turns (the parasitic motion)
        past = solve(robot, tool_tilted(robot, row["azimuth_deg"], bisected + 1e-6)).joints[0, :, posture]
        assert abs(np.degrees(past[4])) == pytest.approx(110.0, abs=1e-4)
        assert 100.0 < bisected < 110.0


@pytest.fixture
def tilted_tool(tmp_path):
    """exechon_wrist with its tool axis 30 degrees from Ax4 at zero (roll 150 instead of 180,
    the tip 200 mm along it): home is off the wrist's pole, which a tilt about x then meets."""
    document = yaml.safe_load((robots_dir() / "exechon_wrist.yaml").read_text())
    roll = np.radians(150.0)
    # the tool's z axis is Rx(150) e_z = (0, -sin 150, cos 150); the tip 200 mm along it
    document["tool"] = [0.0, float(-200 * np.sin(roll)), float(200 * np.cos(roll)), 150.0, 0.0, 0.0]
    document.pop("golden")
    path = tmp_path / "tilted_tool.yaml"
    path.write_text(yaml.safe_dump(document))
    return load_model(str(path))


def test_the_wrist_pole_away_from_home_stops_a_tilt(tilted_tool):
    robot = tilted_tool
    settings = Settings(tilt_step_deg=0.1, azimuth_step_deg=180.0, tilt_max_deg=60.0)
    limits = tilt_limits(robot, 0, settings)
    stopped = [row for row in limits if row["cause"] == "unreachable"]
    assert len(stopped) == 1
    # independently: the first 0.1-degree step where the tool axis, in the platform frame the
    # reference solves, is within the reference's band (1 - (a1.w)^2 <= 1e-5) of Ax4
    tilts = settings.tilts
    solution = solve(robot, tool_tilted(robot, stopped[0]["azimuth_deg"], tilts))
    tool_axis = np.einsum("nij,nj->ni", solution.platform[:, :3, :3], solve_axis(robot, tilts, stopped[0]))
    aligned = 1.0 - tool_axis[:, 2] ** 2
    first = int(np.argmax(aligned <= 1e-5))
    assert first > 0 and stopped[0]["max_tilt_deg"] == pytest.approx(tilts[first - 1])
    assert 25.0 < stopped[0]["max_tilt_deg"] < 35.0  # the tool axis starts 30 degrees from Ax4


def solve_axis(robot, tilts, row):
    """The tool axis (n, 3), base frame, of each tilted tool pose."""
    return tool_tilted(robot, row["azimuth_deg"], tilts)[:, 2, :3]


def test_analyze_says_what_it_judged_on_a_wrist(tmp_path, capsys):
    assert main(["analyze", "exechon_wrist", "-o", str(tmp_path), "--tilt-max", "30", "--azimuth-step", "90"]) == 0
    data = json.loads((tmp_path / "analysis.json").read_text())
    assert set(data["sweeps"]) == {"roll", "pitch", "x", "y", "z"}
    assert data["available"]["sweeps"].startswith("yaw not swept")
    assert "not exercised" in data["available"]["collision"]
    assert "pole" in data["available"]["wrist_singularity"]
    assert all(len(entry["joints"]) == 5 for entries in data["sweeps"].values() for entry in entries)
    # the home tool pose has the reference's pole warning, and analysis judges it through
    home = data["sweeps"]["x"][len(data["sweeps"]["x"]) // 2]
    assert home["warning"] == WARNINGS["WARN_SINGULAR_SOLUTION"] and home["cause"] == "none"
    assert {row["cause"] for row in data["tilt_limits"]} == {"none"}
    assert "least tilt 30 deg" in capsys.readouterr().out


def test_analysis_data_of_a_wrist_names_the_tool_poses():
    data = analyze(load_model("tricept_wrist"), 0, Settings(tilt_max_deg=5.0, azimuth_step_deg=180.0))
    assert data["available"]["poses"].startswith("tool poses")
    assert data["singular_at_home"] is None
