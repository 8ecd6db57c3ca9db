"""check-path on a machine with a serial wrist (robots/exechon_wrist.yaml): a G-code program
commands the five-axis module's world X Y Z A C; a CSV gives tool poses. The samples' joints
are checked against an independent computation (the whole machine's forward: Newton on the
legs' closure, then the wrist's forward, recomposes the commanded tool tip and axis); a path
that drives A through 0 (the wrist's axes aligned: Ax4 swings by half a turn) is caught at its
line; the routines agree with the reference."""

import csv
import json

import numpy as np
import pytest

from kingen.conventions import pose_from_t6
from kingen.hosts.linuxcnc.five_axis import axis_of_world, home_axis
from kingen.kinematics.hybrid.wrist_forward import tool_forward
from kingen.paths.check import Settings, check_program
from kingen.robot.model import load_robot
from conftest import require_linuxcnc_headers, require_tool
from test_check_path import needs_interpreter, run

ROBOT = "robots/exechon_wrist.yaml"
INSIDE = """G21 G90
G1 F2000 X0 Y50 Z-1450 A20 C30
G1 X50 Y20 Z-1400 A25 C60
G1 X-40 Y80 Z-1480 A15 C-20
M2
"""
"""Tool tip and axis within the legs' travel; the first move leaves the home (A = 0: the wrist's
singularity, where the machine homes)."""
FLIP = """G21 G90
G1 F2000 X0 Y50 Z-1450 A20 C30
G1 A10
G1 A-10
G1 X30 Y20 Z-1420 A-20
G1 A10
M2
"""
"""Line 4 drives A through 0 at the home's tip (the tool axis through the first wrist axis);
line 6 through 0 beside it, where the tilted platform's axis is missed and Ax4 swings fast."""


def ini_text(joints=5):
    lines = ["[TRAJ]", "LINEAR_UNITS = mm", "MAX_LINEAR_VELOCITY = 100", "MAX_LINEAR_ACCELERATION = 1000", ""]
    for index in range(joints):
        lines += [f"[JOINT_{index}]", f"MAX_VELOCITY = {100 if index < 3 else 90}",
                  f"MAX_ACCELERATION = {1000 if index < 3 else 900}", ""]
    return "\n".join(lines)


def gcode_samples(robot, text, folder):
    """(outcome, world (n, 6), joints (n, joint_count), warnings (n,)) of check-path on ``robot``
    for the G-code ``text`` (written to ``folder``/inside.ngc): every sample it judged."""
    needs_interpreter()
    program = folder / "inside.ngc"
    program.write_text(text)
    rows = []

    def sink(lines, batch, rates):
        rows.append((batch.poses.copy(), batch.joints.copy(), batch.warnings.copy()))
    outcome = check_program(robot, program, Settings(), sink=sink)
    return (outcome, *(np.concatenate(part) for part in zip(*rows)))


def machine_forward(robot, joints):
    """(tool T6 (n, 4, 4), residual (n,)) of the machine's forward from ``joints``, the platform
    started at its home's position."""
    near = np.tile(np.concatenate([robot.parallel.verification.home[:3], [0.0, 0.0, 0.0]]), (len(joints), 1))
    tool, _, residual = tool_forward(robot, joints, near)
    return tool, residual


def test_a_gcode_programs_samples_recompose_the_commanded_tool_tip_and_axis(tmp_path):
    robot = load_robot(ROBOT)
    outcome, world, joints, warnings = gcode_samples(robot, INSIDE, tmp_path)
    regular = (warnings == 0) & (world[:, 3] > 1.0)  # off the home's singularity, where Ax4 is free
    assert np.sum(regular) > 1000
    tool, residual = machine_forward(robot, joints[regular])
    assert np.max(residual) < 1e-9
    np.testing.assert_allclose(tool[:, 3, :3], world[regular, :3], atol=1e-9)
    axis = axis_of_world(home_axis(robot), world[regular, 3], world[regular, 5])
    np.testing.assert_allclose(tool[:, 2, :3], axis, atol=1e-9)
    assert {place.line for place in outcome.findings.problems.values()} == {2}  # leaving the home only


def test_a_csv_of_tool_poses_inside_the_workspace_runs(tmp_path, capsys):
    robot = load_robot(ROBOT)
    program = tmp_path / "inside.csv"
    program.write_text("50,-20,-1380,165,8,40\n-60,100,-1330,170,-10,-40\n20,40,-1450,172,5,10\n")
    code, out, _ = run(capsys, "check-path", ROBOT, program, "--json", tmp_path / "r.json", "--csv", tmp_path / "s.csv")
    assert code == 0, out
    document = json.loads((tmp_path / "r.json").read_text())
    assert document["verdict"] == "runs" and document["checks"]["limb singular"] == "passed"
    assert document["five_axis"]["program"] == "CSV: tool poses"
    assert [peak["joint"] for peak in document["peaks"]] == list(robot.joint_names)
    with open(tmp_path / "s.csv") as stream:
        samples = list(csv.DictReader(stream))
    first = samples[0]
    near = np.array([robot.parallel.verification.home[:3] + [0.0, 0.0, 0.0]])
    joints = np.array([[float(first[name]) * (np.pi / 180.0 if index >= 3 else 1.0)
                        for index, name in enumerate(robot.joint_names)]])
    tool, _, _ = tool_forward(robot, joints, near)
    np.testing.assert_allclose(pose_from_t6(tool)[0, :3], [50, -20, -1380], atol=1e-9)
    assert "five-axis:" in out and "ax4" in out


def test_driving_a_through_0_is_caught_at_its_line(tmp_path, capsys):
    needs_interpreter()
    program, ini = tmp_path / "flip.ngc", tmp_path / "machine.ini"
    program.write_text(FLIP)
    ini.write_text(ini_text())
    code, out, _ = run(capsys, "check-path", ROBOT, program, "--ini", ini, "--json", tmp_path / "r.json")
    assert code == 1
    problems = json.loads((tmp_path / "r.json").read_text())["problems"]
    found = {(place["line"], place["kind"], place["joint"]) for place in problems}
    assert {(4, "limb singular", "ax4"), (4, "joint speed", "ax4"), (6, "joint speed", "ax4")} <= found
    assert not any(line in (3, 5) for line, _, _ in found)


def test_an_ini_without_the_wrists_joints_is_bad_input(tmp_path, capsys):
    program, ini = tmp_path / "p.csv", tmp_path / "machine.ini"
    program.write_text("50,-20,-1380,165,8,40\n20,40,-1450,170,5,10\n")
    ini.write_text(ini_text(joints=3))
    code, _, err = run(capsys, "check-path", ROBOT, program, "--ini", ini)
    assert code == 2
    assert err.strip().splitlines() == [f"kingen: error: {ini}:16: [JOINT_3]: missing (the file ends here): the robot "
                                        f"has 5 joints (JOINT_0 .. JOINT_4)"]


@pytest.mark.parametrize("host", ["delmia", "linuxcnc"])
def test_the_routine_cross_check_agrees_with_the_reference(host, tmp_path, capsys):
    needs_interpreter()
    require_tool("cc", "gcc")
    if host == "linuxcnc":
        require_linuxcnc_headers()
    program = tmp_path / "flip.ngc"
    program.write_text(FLIP)
    code, _, _ = run(capsys, "check-path", ROBOT, program, "--host", host, "--routine", "--out-dir", tmp_path / "build",
                     "--json", tmp_path / "r.json")
    assert code == 1
    solver = json.loads((tmp_path / "r.json").read_text())["settings"]["solver"]
    difference = float(solver.split("largest difference from the reference ")[1].split()[0])
    assert difference < 1e-9 and "0 warnings differing" in solver


def test_the_tricepts_head_through_a_0_is_caught_by_its_wrist_joints_speed(tmp_path, capsys):
    needs_interpreter()
    program, ini = tmp_path / "flip.ngc", tmp_path / "machine.ini"
    program.write_text(FLIP.replace("Z-1450", "Z-1300").replace("Z-1420", "Z-1280"))
    ini.write_text(ini_text())
    code, _, _ = run(capsys, "check-path", "robots/tricept_wrist.yaml", program, "--ini", ini, "--json", tmp_path / "r.json")
    assert code == 1
    found = {(place["line"], place["kind"], place["joint"]) for place in json.loads((tmp_path / "r.json").read_text())["problems"]}
    assert {(4, "joint speed", "ax4"), (6, "joint speed", "ax4")} <= found
    assert not any(line in (3, 5) for line, _, _ in found)


def test_a_move_along_the_wrists_singular_pole_ends_in_bounded_samples(tmp_path, capsys):
    """From home the tool axis lies on the wrist's pole, where its singular measure grazes 0 along
    a pure Z move: refinement stops at its bound (kingen.paths.refinement.MAX_REFINED) instead of
    doubling the samples forty times (gigabytes), and the singularity is reported at its line."""
    needs_interpreter()
    program = tmp_path / "along_the_pole.ngc"
    program.write_text("G21 G91\nG1 Z-1 F600\nG1 Z1\nM2\n")
    report = tmp_path / "report.json"
    code, out, err = run(capsys, "check-path", "exechon_wrist", program, "--json", report)
    assert code == 1, err
    document = json.loads(report.read_text())
    assert document["samples"] < 1000
    assert {place["line"] for place in document["problems"]} == {2, 3}
