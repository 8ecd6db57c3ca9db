"""check-path on a machine with a three-axis wrist (robots/tricept_wrist3.yaml): a G-code program
commands the tool pose whole, X Y Z A B C the tool tip and its roll, pitch, yaw (degrees), as for
a hexapod; a CSV gives tool poses. The samples' joints are checked against an independent
computation (the whole machine's forward: Newton on the legs' closure, then the wrist's forward,
recomposes the whole commanded tool frame)."""

import json

import numpy as np

from kingen.conventions import t6_from_pose
from kingen.robot.model import load_robot
from test_check_path import run
from test_check_path_wrist import gcode_samples, machine_forward

ROBOT = "robots/tricept_wrist3.yaml"
INSIDE = """G21 G90
G1 F2000 X0 Y50 Z-1250 A170 B10 C30
G1 X50 Y20 Z-1300 A172 B-5 C60
G1 X-40 Y80 Z-1350 A165 B8 C-20
M2
"""
"""Tool poses within the legs' travel; the first move leaves the home (the tool along Ax4: the
wrist's gimbal lock, where the machine homes)."""


def test_a_gcode_programs_samples_recompose_the_whole_commanded_tool_pose(tmp_path):
    robot = load_robot(ROBOT)
    outcome, world, joints, warnings = gcode_samples(robot, INSIDE, tmp_path)
    regular = (warnings == 0) & (np.abs(world[:, 3]) < 179.0)  # off the home's gimbal lock
    assert np.sum(regular) > 1000
    tool, residual = machine_forward(robot, joints[regular])
    assert np.max(residual) < 1e-9
    np.testing.assert_allclose(tool, t6_from_pose(world[regular]), atol=1e-9)
    assert {place.line for place in outcome.findings.problems.values()} == {2}  # leaving the home only
    assert outcome.five_axis is None


def test_a_csv_of_tool_poses_inside_the_workspace_runs(tmp_path, capsys):
    program = tmp_path / "inside.csv"
    program.write_text("60,-40,-1250,170,10,30\n-40,80,-1330,175,-8,-50\n20,40,-1300,172,5,10\n")
    code, out, _ = run(capsys, "check-path", ROBOT, program, "--json", tmp_path / "r.json")
    assert code == 0, out
    document = json.loads((tmp_path / "r.json").read_text())
    assert document["verdict"] == "runs" and "five_axis" not in document
    assert [peak["joint"] for peak in document["peaks"]] == list(load_robot(ROBOT).joint_names)
