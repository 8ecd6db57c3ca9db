"""The 3D view in check-path's, calibrate's and analyze's reports: its overlay data hold the
values the reports' own numbers and independent computations give (a finding's frame at the
finding's place with the strut lengths |R p + t - b| computed here; an arrow's vector the
residual a known error of the measuring frame makes, times the stated factor; the tilt surface's
vertices at the reported tilt limits, by Rodrigues' formula written here)."""

import json
import math

import numpy as np
import pytest

from kingen.calibrate.drawing import magnified_robot, residual_arrows
from kingen.calibrate.identification import Problem, synthetic_problem
from kingen.calibrate.parameters import Parameters
from kingen.design.analysis import Settings, tilt_limits
from kingen.design.tilt_view import AXIS_SHARE, tilt_overlays
from kingen.paths.check import Settings as CheckSettings
from kingen.paths.check import check_program
from kingen.paths.playback import FRAMES, playback
from kingen.robot.model import load_robot
from test_check_path import INCH, ini_text, strut_lengths


def test_a_findings_frame_is_at_its_place_with_the_strut_lengths_there(tmp_path):
    """Every problem of LinuxCNC's sample hexapod (struts beyond 31 in, too fast) has a marker
    whose frame holds the problem's own pose and, as joints, the strut lengths computed here at
    that pose; the frames follow the program in order, start at its first row, and stay bounded."""
    program = tmp_path / "p.csv"
    program.write_text("x,y,z,roll,pitch,yaw,feed\n0,0,508,0,0,0,600\n20,10,520,2,0,0,600\n0,0,560,0,0,0,600\n")
    ini = tmp_path / "machine.ini"
    ini.write_text(ini_text(maximum=31.0, velocity=0.3))
    outcome = check_program(load_robot("linuxcnc_hexapod"), program, CheckSettings(ini=ini))
    view = playback(outcome)
    frames, markers = view["frames"], view["markers"]
    problems = outcome.findings.sorted_problems()
    assert len(markers) == len(problems) > 0
    assert {problem.kind for problem in problems} >= {"travel", "joint speed"}
    for problem, marker in zip(problems, markers):
        frame = frames[marker["frame"]]
        assert frame["pose"] == pytest.approx(problem.pose, abs=1e-9)
        assert frame["joints"] == pytest.approx(strut_lengths([problem.pose])[0], abs=1e-6)
        assert marker["label"].startswith(f"line {problem.line}: {problem.kind} {problem.joint}")
        if problem.kind == "travel":
            assert max(frame["joints"]) > 31.0 * INCH
    times = [frame["t"] for frame in frames]
    assert times == sorted(times) and frames[0]["pose"] == [0.0, 0.0, 508.0, 0.0, 0.0, 0.0]
    assert len(frames) <= FRAMES + len(problems)
    assert json.loads(json.dumps(view, allow_nan=False)) == view


def test_a_long_path_is_thinned_to_the_frame_bound_keeping_every_finding(tmp_path):
    """A 400 mm climb at a 0.05 mm chord (8,000 samples): at most FRAMES frames of the path
    (first and last rows kept) plus one per problem."""
    program = tmp_path / "long.csv"
    program.write_text("0,0,460,0,0,0\n0,0,860,0,0,0\n")
    ini = tmp_path / "machine.ini"
    ini.write_text(ini_text(maximum=31.0))
    outcome = check_program(load_robot("linuxcnc_hexapod"), program, CheckSettings(ini=ini, chord=0.05))
    assert outcome.findings.samples > 2 * FRAMES
    view = playback(outcome)
    problems = outcome.findings.sorted_problems()
    assert FRAMES // 2 <= len(view["frames"]) - len(problems) <= FRAMES
    assert view["frames"][0]["pose"][2] == 460.0 and view["frames"][-1]["pose"][2] == pytest.approx(860.0)
    first = view["frames"][view["markers"][0]["frame"]]
    assert first["pose"] == pytest.approx(problems[0].pose) and max(first["joints"]) > 31.0 * INCH


def test_an_arrow_is_the_residual_a_shifted_measuring_frame_makes_times_the_stated_factor():
    """Measurements of the nominal hexapod through a device frame at FRAME, explained with the
    frame believed 0.3 mm off along (1, -2, 2)/3: in the base frame each measured point is the
    true target point plus that shift d, and predicted minus measured is -d at every pose."""
    robot = load_robot("hexapod")
    true_frame = np.array([12.0, -7.0, 3.0, 0.8, -0.5, 20.0])
    shift = 0.3 * np.array([1.0, -2.0, 2.0]) / 3.0
    truth = Parameters(robot, "pose", frame=true_frame)
    poses = np.array(robot.verification.home) + np.array([[0, 0, 0, 0, 0, 0], [10, -5, 8, 3, -2, 4],
                                                          [-12, 6, -4, -3, 4, -5]], dtype=float)
    _, data = synthetic_problem(truth, truth.nominal, poses, robot.working_posture)
    believed = Parameters(robot, "pose", frame=np.concatenate([true_frame[:3] + shift, true_frame[3:]]))
    arrows, factor = residual_arrows(Problem(believed, data, None), believed.nominal)
    assert factor * 0.3 <= 0.1 * robot.size_mm < 2.5 * factor * 0.3
    assert factor / 10.0 ** math.floor(math.log10(factor)) in (1.0, 2.0, 5.0)
    for arrow, pose, line in zip(arrows, poses, data.lines):
        assert arrow["origin"] == pytest.approx(pose[:3] + shift, abs=1e-7)
        assert arrow["vector"] == pytest.approx(-shift * factor, abs=1e-6 * factor)
        assert arrow["label"] == f"line {line}: 0.3 mm"


def test_the_ghost_magnifies_the_identified_changes_by_its_factor():
    """A limb's base point moved 0.02 mm: the ghost's is nominal + factor * 0.02 mm, the factor
    1, 2 or 5 times a power of ten, the largest that keeps the change within 10 % of the robot's
    size; the measuring frame's identified change is not the machine's and stays out."""
    robot = load_robot("hexapod")
    parameters = Parameters(robot, "pose")
    values = parameters.nominal.copy()
    moved = parameters.names.index(f"{robot.joint_names[1]}.base_point.y")
    values[moved] += 0.02
    values[parameters.names.index("measuring_frame.x")] += 40.0
    ghost, factor = magnified_robot(parameters, values)
    room = 0.1 * robot.size_mm
    assert factor * 0.02 <= room < 2.5 * factor * 0.02 and factor / 10.0 ** math.floor(math.log10(factor)) in (1, 2, 5)
    assert ghost.limbs[1].base_point[1] == pytest.approx(robot.limbs[1].base_point[1] + factor * 0.02)
    assert ghost.limbs[0].base_point == pytest.approx(robot.limbs[0].base_point)
    assert magnified_robot(parameters, parameters.nominal) == (None, None)


def rodrigues(axis, angle):
    """The rotation by ``angle`` (degrees) about the unit ``axis``, written out here."""
    x, y, z = axis
    k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    turn = math.radians(angle)
    return np.eye(3) + math.sin(turn) * k + (1.0 - math.cos(turn)) * k @ k


@pytest.mark.parametrize("robot_name, away", [("hexapod", 1.0), ("ceart", -1.0)])
def test_the_tilt_surface_vertices_lie_at_the_reported_tilt_limits(robot_name, away):
    """The fan's apex is home's tool point; each rim vertex is the home tool axis turned by the
    reported largest tilt about (cos a, sin a, 0) (Rodrigues here), AXIS_SHARE of the size long
    and drawn away from the base (up on the hexapod, down from CEART's platform, which hangs
    below its base); each azimuth's frame holds the machine there and its point names the cause."""
    robot = load_robot(robot_name)
    settings = Settings(azimuth_step_deg=45.0, tilt_step_deg=1.0)
    rows = tilt_limits(robot, robot.working_posture, settings)
    overlays = tilt_overlays(robot, {"tilt_limits": rows, "posture": robot.working_posture}, "axis")
    home = np.array(robot.verification.home, dtype=float)
    start = rodrigues([0, 0, 1], home[5]) @ rodrigues([0, 1, 0], home[4]) @ rodrigues([1, 0, 0], home[3])
    vertices = np.array(overlays["surface"]["vertices"])
    assert vertices[0] == pytest.approx(home[:3]) and len(vertices) == len(rows) + 1
    for index, row in enumerate(rows):
        azimuth = math.radians(row["azimuth_deg"])
        axis = rodrigues([math.cos(azimuth), math.sin(azimuth), 0.0], row["max_tilt_deg"]) @ start[:, 2]
        assert vertices[index + 1] == pytest.approx(home[:3] + away * AXIS_SHARE * robot.size_mm * axis, abs=1e-9)
        assert overlays["surface"]["triangles"][index][:2] == [0, index + 1]
        point = overlays["points"][index]
        assert point["position"] == pytest.approx(vertices[index + 1])
        assert point["label"].startswith(f"{row['azimuth_deg']:g}°: {row['max_tilt_deg']:g}°, ")
        frame = overlays["frames"][index]
        assert frame["label"] == point["label"] and frame["t"] == row["azimuth_deg"]
        turned = rodrigues([math.cos(azimuth), math.sin(azimuth), 0.0], row["max_tilt_deg"]) @ start
        assert np.radians(frame["pose"][3:]) == pytest.approx(
            [math.atan2(turned[2, 1], turned[2, 2]), math.asin(-turned[2, 0]), math.atan2(turned[1, 0], turned[0, 0])],
            abs=1e-9)
    assert tilt_overlays(robot, {"tilt_limits": [], "posture": 0}, "axis") == {}

