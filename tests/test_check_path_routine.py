"""check-path --routine: the regular samples' joints and warnings from the robot's compiled
routine (through the host's batch driver, in a child process) equal the numpy reference's,
and the check judges the same problems at the same places as the reference alone."""

import json

import numpy as np
import pytest

from kingen.cli import main
from kingen.conventions import t6_from_pose
from kingen.kinematics.reference import solve
from kingen.kinematics.routine import WARNINGS
from kingen.paths.routine import RoutineSolver
from kingen.robot.model import load_robot
from kingen.robot.one_posture import at_posture
from conftest import require_linuxcnc_headers, require_tool

PROGRAM = "0,0,-450,0,0,0\n40,-30,-420,5,-3,8\n0,0,-250,0,0,0\n0,0,-150,0,0,0\n0,0,-450,0,0,0\n"
"""CEART through its region, past a crank's singular band and out of reach (z = -150) and back."""


def poses_along(text, count=400):
    """(count * moves + 1, 6) poses on the straight moves between the rows of ``text``."""
    rows = np.array([[float(v) for v in line.split(",")] for line in text.splitlines()])
    u = np.linspace(0.0, 1.0, count, endpoint=False)[:, None]
    return np.vstack([start + u * (end - start) for start, end in zip(rows[:-1], rows[1:])] + [rows[-1:]])


@pytest.mark.parametrize("host", ["delmia", "linuxcnc"])
def test_the_routines_joints_and_warnings_equal_the_references(host, tmp_path):
    require_tool("cc", "gcc")
    if host == "linuxcnc":
        require_linuxcnc_headers()
    robot = load_robot("ceart")
    posture = robot.working_posture
    solver = RoutineSolver(robot, host, posture, tmp_path / "build")
    poses = poses_along(PROGRAM)
    t6 = t6_from_pose(poses)
    joints, warnings = solver(t6)
    expected = solve(at_posture(robot, posture), t6)
    reachable = expected.warnings[:, 0] != WARNINGS["WARN_UNREACHABLE"]
    assert 0 < np.sum(~reachable) < len(poses)  # the program leaves the workspace: both kinds are compared
    assert np.array_equal(warnings, expected.warnings[:, 0])
    assert np.max(np.abs(joints[reachable] - expected.branch_joints[reachable, :, 0])) < 1e-9
    assert len(set(warnings.tolist())) >= 2


def test_check_path_with_the_routine_finds_what_the_reference_finds(tmp_path, capsys):
    require_tool("cc", "gcc")
    program = tmp_path / "up.csv"
    program.write_text(PROGRAM)
    documents = []
    for extra in ([], ["--routine", "--host", "delmia", "-o", str(tmp_path / "build")]):
        code = main(["check-path", "ceart", str(program), "--json", str(tmp_path / "r.json"), *extra])
        assert code == 1 and capsys.readouterr().err == ""
        documents.append(json.loads((tmp_path / "r.json").read_text()))
    reference, routine = documents
    assert "0 warnings differing" in routine["settings"]["solver"]
    assert routine["samples"] == reference["samples"]
    assert [(p["kind"], p["line"], p["joint"]) for p in routine["problems"]] == \
        [(p["kind"], p["line"], p["joint"]) for p in reference["problems"]]
    assert np.allclose([p["pose"] for p in routine["first"]], [p["pose"] for p in reference["first"]], atol=1e-9)
