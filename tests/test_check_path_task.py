"""kingen check-path on machines with task coordinates: every sample is the machine's pose at
its task coordinates. Checked against the constraints stated forward here from the limbs'
joints (the residuals at each sample's own pose, not re-solved), the robot files' golden
poses (an independent Newton computation, see their ``source``), the commanded task
coordinates along each straight move, and the routine compiled for LinuxCNC."""

import csv
import json

import numpy as np
import pytest

from kingen.cli import main
from kingen.conventions import matrix_from_pose, t6_from_pose
from kingen.kinematics.hybrid.parasitic import constraint_residuals
from kingen.kinematics.hybrid.parasitic_tube import tube_residuals
from kingen.robot.model import load_robot
from conftest import require_linuxcnc_headers, require_tool
from test_check_path import needs_interpreter, run

NAMES = ("x", "y", "z", "roll", "pitch", "yaw")
PROGRAMS = {
    # z, roll, pitch read (Z A B); the X, Y, C words are not read. Ends at the file's first golden pose.
    "prs_head": ("G21 G90\nG1 Z-380 A5 B-3 F2000\nG1 X40 Y-20 Z-370 A12 B-7 C3\nM2\n", 0, (2, 3, 4)),
    # x, y, z read (X Y Z); the A, B, C words are not read. Ends at the file's third golden pose.
    "exechon_constrained": ("G21 G90\nG1 X80 Y-60 Z-1150 A4 F2000\nG1 X-120 Y150 Z-1400 B-3 C9\nM2\n", 2, (0, 1, 2)),
    "tricept": ("G21 G90\nG1 X200 Y-100 Z-1000 A4 F2000\nG1 X-250 Y180 Z-1250 B-3 C9\nM2\n", 2, (0, 1, 2)),
}


def stated_residuals(robot, poses):
    """(n, 3) mm: the constraints at ``poses`` (n, 6) themselves, from each limb's joint: a base
    revolute axis a keeps the platform point in its plane, a.(R p + t - c) = 0; a platform
    revolute axis e keeps (R e).(b - t) = e.n; the Tricept's tube its own equations."""
    if robot.passive_leg is not None:
        return tube_residuals(robot, t6_from_pose(poses))
    matrices = matrix_from_pose(np.asarray(poses, dtype=float))
    rotation, position = matrices[:, :3, :3], matrices[:, :3, 3]
    columns = []
    for limb in robot.limbs:
        if limb.constraint_plane() is not None:
            axis, point = limb.constraint_plane()
            columns.append((rotation @ np.asarray(limb.platform_point, dtype=float) + position - point) @ axis)
        else:
            axis, base, point = limb.platform_constraint()
            columns.append(np.sum((rotation @ axis) * (base - position), -1) - axis @ point)
    return np.stack(columns, axis=1)


def samples(path):
    """(lines, u, poses (n, 6), joints (n, dof)) of check-path's --csv file."""
    with open(path, newline="") as stream:
        rows = list(csv.reader(stream))
    header, body = rows[0], rows[1:]
    data = np.array([[float(value) if value else np.nan for value in row] for row in body])
    dof = (len(header) - 10) // 3
    return data[:, 0].astype(int), data[:, 1], data[:, 2:8], data[:, 8:8 + dof]


@pytest.mark.parametrize("name", sorted(PROGRAMS))
def test_a_program_inside_the_workspace_runs_on_the_machines_manifold(name, tmp_path, capsys):
    needs_interpreter()
    robot = load_robot(name)
    text, golden_index, task = PROGRAMS[name]
    program = tmp_path / "inside.ngc"
    program.write_text(text)
    code, out, err = run(capsys, "check-path", name, program, "--chord", 1, "--json", tmp_path / "r.json",
                         "--csv", tmp_path / "s.csv")
    assert code == 0 and err == "", out + err
    document = json.loads((tmp_path / "r.json").read_text())
    parasitic = [index for index in range(6) if index not in task]
    not_read = ", ".join("XYZABC"[index] for index in parasitic)
    assert f"{not_read} not read: parasitic" in out
    assert document["checks"]["off manifold"] == (f"not exercised: G-code commands the task coordinates only "
                                                  f"({not_read} not read: parasitic)")
    assert document["checks"]["unreachable"] == "passed" and document["checks"]["travel"] == "passed"
    lines, u, poses, joints = samples(tmp_path / "s.csv")
    # Every sample closes the constraints at its own pose (stated forward here, and kingen's own).
    assert np.max(np.abs(stated_residuals(robot, poses))) <= 1e-9
    assert np.max(np.abs(constraint_residuals(robot, t6_from_pose(poses))[0])) <= 1e-9
    # Its task coordinates are the commanded ones, linear along each move.
    home = np.array(robot.verification.home)
    ends = {2: home.copy(), 3: home.copy()}
    words = [dict((word[0], float(word[1:])) for word in line.split()[1:] if word[0] in "XYZABC")
             for line in text.splitlines()[1:3]]
    for index in task:
        ends[2][index] = words[0].get("XYZABC"[index], home[index])
        ends[3][index] = words[1].get("XYZABC"[index], ends[2][index])
    starts = {2: home, 3: ends[2]}
    commanded = np.array([starts[line] + step * (ends[line] - starts[line]) for line, step in zip(lines, u)])
    assert np.max(np.abs(poses[:, task] - commanded[:, task])) <= 1e-9
    # The parasitic coordinates' range is the samples', and the last sample is the golden pose.
    for index in parasitic:
        assert document["parasitic"][NAMES[index]] == pytest.approx(
            [poses[:, index].min(), poses[:, index].max()], abs=1e-12)
    golden = robot.golden[golden_index]
    last = np.flatnonzero((lines == 3) & (u == 1.0))
    assert len(last) == 1
    assert np.max(np.abs(poses[last[0]] - np.array(golden.pose))) <= 1e-6
    assert np.max(np.abs(joints[last[0]] - np.array(golden.joints))) <= 1e-6


@pytest.mark.parametrize("name, text, limit", [
    ("prs_head", "G21 G90\nG1 Z-380 A5 B-3 F2000\nG1 X40 Y-20 Z-420 A-8 B6 C3\nG1 Z-900\nM2\n", -350.0),
    ("exechon_constrained", "G21 G90\nG1 X80 Y-60 Z-1150 F2000\nG1 X-120 Y150 Z-1400 A3\nG1 Z-2600\nM2\n", None),
])
def test_a_program_leaving_the_workspace_fails_at_its_line_on_the_manifold(name, text, limit, tmp_path, capsys):
    needs_interpreter()
    robot = load_robot(name)
    program = tmp_path / "out.ngc"
    program.write_text(text)
    code, out, err = run(capsys, "check-path", name, program, "--chord", 1, "--json", tmp_path / "r.json")
    assert code == 1 and err == ""
    document = json.loads((tmp_path / "r.json").read_text())
    assert {problem["line"] for problem in document["problems"]} == {4}
    travel = [place for place in document["first"] if place["kind"] == "travel"]
    assert travel
    for place in travel:
        index = robot.joint_names.index(place["joint"])
        bound = robot.limbs[index].travel[0 if place["value"] < place["limit"] else 1]
        assert place["limit"] == pytest.approx(bound if limit is None else limit)
        assert abs(place["value"] - place["limit"]) <= 1e-6  # bisected to the boundary
        assert np.max(np.abs(stated_residuals(robot, np.array([place["pose"]])))) <= 1e-9


@pytest.mark.parametrize("name, golden_index, coordinate, shift", [
    ("prs_head", 0, 0, 0.5), ("exechon_constrained", 1, 5, 0.5)])
def test_a_csv_row_off_the_manifold_fails_unless_task_only(name, golden_index, coordinate, shift, tmp_path, capsys):
    robot = load_robot(name)
    golden = np.array(robot.golden[golden_index].pose)
    off = golden.copy()
    off[coordinate] += shift
    program = tmp_path / "rows.csv"
    program.write_text("x,y,z,roll,pitch,yaw\n" + "\n".join(",".join(repr(float(v)) for v in row)
                                                            for row in (robot.verification.home, golden, off)) + "\n")
    code, out, err = run(capsys, "check-path", name, program, "--chord", 1, "--json", tmp_path / "r.json")
    assert code == 1 and err == ""
    document = json.loads((tmp_path / "r.json").read_text())
    assert [(problem["kind"], problem["line"], problem["between"]) for problem in document["problems"]] == \
        [("off manifold", 4, NAMES[coordinate])]
    assert document["problems"][0]["value"] == pytest.approx(shift, abs=1e-6)
    manifold = document["manifold"]
    assert manifold["rows"] == 3 and manifold["rows_off"] == 1 and manifold["first_off"]["line"] == 4
    assert manifold["max_deviation"][NAMES[coordinate]] == pytest.approx(shift, abs=1e-6)
    assert document["checks"]["off manifold"] == "failed"
    assert "first row off the manifold: line 4" in out

    code, out, err = run(capsys, "check-path", name, program, "--chord", 1, "--task-only", "--json", tmp_path / "t.json")
    assert code == 0 and err == ""
    document = json.loads((tmp_path / "t.json").read_text())
    assert document["manifold"]["rows_off"] == 1 and document["manifold"]["first_off"]["line"] == 4
    assert document["checks"]["off manifold"] == "not exercised: --task-only reads the rows' task coordinates only"
    assert "first row off the manifold: line 4" in out and "(--task-only)" in out


def test_task_only_on_a_robot_without_task_coordinates_is_bad_input(tmp_path, capsys):
    program = tmp_path / "rows.csv"
    program.write_text("0,0,-450,0,0,0\n0,0,-440,0,0,0\n")
    code, out, err = run(capsys, "check-path", "ceart", program, "--task-only", "--json", tmp_path / "r.json")
    assert code == 2 and out == "" and err.count("\n") == 1 and not (tmp_path / "r.json").exists()
    assert err == "kingen: error: Invalid value for '--task-only': ceart has no task coordinates (robot file task)\n"


@pytest.mark.parametrize("host", ["linuxcnc", "delmia"])
def test_the_routine_agrees_with_the_reference_on_the_manifold(host, tmp_path):
    needs_interpreter()
    require_tool("cc", "gcc")
    if host == "linuxcnc":
        require_linuxcnc_headers()
    from kingen.paths.check import Settings, check_program

    program = tmp_path / "inside.ngc"
    program.write_text(PROGRAMS["prs_head"][0])
    outcome = check_program(load_robot("prs_head"), program,
                            Settings(host=host, chord=1.0, routine=True, out_dir=tmp_path / "b"))
    agreement = outcome.agreement
    assert agreement.samples > 0 and agreement.warning_mismatches == 0 and agreement.joint_difference <= 1e-9
    assert not outcome.findings.worst


def test_the_constraints_singular_band_is_judged_where_the_tube_lies_in_the_base_plane(tmp_path, capsys):
    """The Tricept's tube from its universal joint at the base origin to (300, 0, z): its
    constraint's radicand is z^2 / (300^2 + z^2) (the squared sine of the tube's slope), so its
    singular band |D| <= tol begins at z = -300 sqrt(tol / (1 - tol))."""
    needs_interpreter()
    from kingen.kinematics.routine import SINGULAR_TOLERANCE

    program = tmp_path / "flat.ngc"
    program.write_text("G21 G90\nG1 X300 Z-300 F2000\nG1 Z100\nM2\n")
    code, _, err = run(capsys, "check-path", "tricept", program, "--chord", 1, "--json", tmp_path / "r.json")
    assert code == 1 and err == ""
    document = json.loads((tmp_path / "r.json").read_text())
    first = {(place["kind"], place.get("between")): place for place in document["first"]}
    band = first[("limb singular", "constraint")]
    assert band["line"] == 3 and band["pose"][0] == pytest.approx(300.0, abs=1e-9)
    assert band["pose"][2] == pytest.approx(-300.0 * np.sqrt(SINGULAR_TOLERANCE / (1.0 - SINGULAR_TOLERANCE)), abs=1e-6)
    assert first[("unreachable", "constraint")]["line"] == 3


def test_csv_rows_solved_in_chunks_match_rows_solved_one_at_a_time(tmp_path, monkeypatch):
    """Manifold.moves solves ROWS_AT_ONCE moves per call: across chunk boundaries (chunks of 3
    over 10 rows) the moves, the off-manifold findings and the rows' bookkeeping are those of
    machine_poses called on each row alone."""
    from kingen.paths import manifold as module
    from kingen.paths.program import csv_moves

    robot = load_robot("prs_head")
    golden = np.array(robot.golden[0].pose)
    rows = np.tile(golden, (10, 1))
    rows[:, 2] += np.linspace(-5.0, 5.0, 10)
    rows[[1, 4, 8], 0] += 0.5  # off the manifold in x
    program = tmp_path / "rows.csv"
    program.write_text("x,y,z,roll,pitch,yaw\n" + "\n".join(",".join(repr(float(v)) for v in row) for row in rows) + "\n")

    class Findings:
        def __init__(self):
            self.added = []

        def place(self, kind, joint, line, pose, joints, value, limit, margin, between=None):
            return kind, line, value, between

        def add(self, index, place):
            self.added.append((index, place))

    monkeypatch.setattr(module, "ROWS_AT_ONCE", 3)
    manifold, findings = module.Manifold(robot, False, True), Findings()
    moves = list(manifold.moves(csv_moves(program), findings))
    machine = np.concatenate([module.machine_poses(robot, row[None])[0] for row in rows])
    assert len(moves) == 9
    assert all(np.allclose(move.start, machine[index], rtol=0, atol=1e-12)
               and np.allclose(move.end, machine[index + 1], rtol=0, atol=1e-12) for index, move in enumerate(moves))
    assert [(index, place[0], place[1], place[3]) for index, place in findings.added] == \
        [(0, "off manifold", 3, "x"), (3, "off manifold", 6, "x"), (7, "off manifold", 10, "x")]
    assert [place[2] for _, place in findings.added] == pytest.approx([0.5] * 3, abs=1e-6)
    assert manifold.rows == 10 and manifold.rows_off == 3 and manifold.first_off[0] == 3
