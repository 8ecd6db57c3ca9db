"""check-path's timing against LinuxCNC's own trajectory planner: a real, headless LinuxCNC
(Debian's linuxcnc-uspace) runs kingen's module for the linear delta on five short programs (a
polyline blended in G64, the same with G64 P0.05 and in exact path G61, nearly collinear moves
that G64's Q merges, tangent lines and arcs in G64) with HAL's
sampler recording every servo period's program line and joint velocities; each joint's largest
speed on each line, as check-path's planner model times the program (its CSV of samples), lies
within 5 % of LinuxCNC's. LinuxCNC shows a blend arc as part of the line after the corner, so a
sample check-path places on the arc's first half (off its own line's programmed path, past its
middle) counts for the next line here (benchmarks/planner.py compares more programs, a parabolic
blend's among them, the same way). The machine is set up as in test_linuxcnc_machine.py (root, a private
mount namespace); in CI (KINGEN_REQUIRE_TOOLCHAINS=1) a missing LinuxCNC fails."""

import numpy as np
import pytest

from conftest import skip_or_fail
from kingen.cli import main
from kingen.paths.interpreter import gcode_moves
from kingen.paths.limits import limits_for
from kingen.paths.planner import planned
from kingen.robot.model import load_robot
from test_check_path_machine import ROBOTS, run_programs
from test_linuxcnc_machine import missing

PROGRAMS = {
    # a polyline of 5 mm moves turning by 40 to 110 degrees: blend arcs at every corner
    "blends": "G21 G90 G64\nG1 X4 Y3 Z15 F4800\nG1 X8 Y0\nG1 X12 Y3\nG1 X16 Y0 Z18\nG1 X8 Y-4 Z18\nG1 X0 Y0 Z15\nM2\n",
    # the same with G64 P0.05: arcs within 0.05 mm of each corner, slower through them
    "tolerance": "G21 G90 G64 P0.05\nG1 X4 Y3 Z15 F4800\nG1 X8 Y0\nG1 X12 Y3\nG1 X16 Y0 Z18\nG1 X8 Y-4 Z18\n"
                 "G1 X0 Y0 Z15\nM2\n",
    # the same in exact path (G61): every move from rest to rest, its acceleration cut by the kink ratio
    "exact": "G21 G90 G61\nG1 X4 Y3 Z15 F4800\nG1 X8 Y0\nG1 X12 Y3\nG1 X16 Y0 Z18\nG1 X8 Y-4 Z18\nG1 X0 Y0 Z15\nM2\n",
    # G64 P0.05 (and so Q0.05): lines 2 to 5 within 0.05 mm of one line, which LinuxCNC moves as line 5
    "merged": "G21 G90 G64 P0.05\nG1 X2 Y0.02 Z15 F4800\nG1 X4 Y0\nG1 X6 Y0.03\nG1 X8 Y0\nG1 X8 Y4\nG1 X0 Y0\nM2\n",
    # lines and half circles of 4 mm radius meeting tangentially: the arcs' normal acceleration caps them
    "arcs": "G21 G90 G64\nG1 X4 Y0 Z15 F3000\nG3 X4 Y8 I0 J4\nG1 X-4 Y8\nG3 X-4 Y0 I0 J-4\nG1 X0 Y0\nM2\n",
}
"""Each starts and ends at the delta's home (X0 Y0 Z15), in the order LinuxCNC runs them."""
TOLERANCE = 0.05
"""A joint's peak speed on a line within this fraction of LinuxCNC's (of the line's fastest joint's
peak for a joint that moves at under a fifth of it)."""


@pytest.fixture(autouse=True)
def linuxcnc_machine():
    reason = missing()
    if reason is not None:
        skip_or_fail(reason)


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """(the .ini, {program: (its file, LinuxCNC's run)}) of one LinuxCNC running the programs."""
    folder = tmp_path_factory.mktemp("planner")
    paths = {name: folder / f"{name}.ngc" for name in PROGRAMS}
    for name, path in paths.items():
        path.write_text(PROGRAMS[name])
    ini, outcome = run_programs(ROBOTS / "linear_delta.yaml", list(paths.values()), 1000.0, folder, sampled=True)
    return ini, {name: (paths[name], run) for name, run in zip(paths, outcome)}


def peaks(lines, speeds):
    """{line: each joint's largest |speed| (dof,)} over samples on ``lines`` (n,) with ``speeds`` (n, dof)."""
    return {int(line): np.max(np.abs(speeds[lines == line]), axis=0) for line in np.unique(lines) if line > 0}


def model_peaks(program, ini, folder, robot="linear_delta", home=(0.0, 0.0, 15.0)):
    """check-path's per-line joint peaks (the .ini's units per s) on ``program`` under ``ini`` for
    shipped ``robot`` at ``home`` (mm), from its CSV of samples, each sample counted for the line
    LinuxCNC shows there: the next line's on a blend arc's first half (off its own line's
    programmed path, past its middle) and where, in a parabolic blend, the next move already
    moves faster than this one (the planner model's speeds, planner.Plan.overlap)."""
    code = main(["check-path", str(ROBOTS / f"{robot}.yaml"), str(program), "--ini", str(ini),
                 "--csv", str(folder / "samples.csv")])
    assert code in (0, 1)
    samples = np.genfromtxt(folder / "samples.csv", delimiter=",", names=True)
    model = load_robot(robot)
    scale = 25.4 if model.length_unit == "inch" else 1.0
    speeds = np.column_stack([samples[name] for name in samples.dtype.names if name.endswith("_speed")]) / scale
    regular = np.all(np.isfinite(speeds), axis=1)
    lines = samples["line"].astype(int)
    timed = dict((move.line, (move, plan)) for move, plan in planned(
        gcode_moves(program, (*home, 0.0, 0.0, 0.0)), limits_for(model, ini)))  # the lines LinuxCNC's canon makes
    following = dict(zip(sorted(timed), sorted(timed)[1:]))
    for row in np.flatnonzero(regular & (samples["u"] > 0.5)):
        move, plan = timed.get(lines[row], (None, None))
        if move is None or lines[row] not in following:
            continue
        s = samples["u"][row] * plan.length
        on_line = move.start[:3] + samples["u"][row] * (move.end[:3] - move.start[:3])
        arc = move.arc is None and np.linalg.norm(on_line - [samples[axis][row] for axis in "xyz"]) > 1e-6
        if arc or plan.overlap([s])[0] > plan.rates([s])[0][0]:
            lines[row] = following[lines[row]]
    return peaks(lines[regular], speeds[regular])


def linuxcnc_peaks(run):
    """LinuxCNC's per-line joint peaks (the .ini's units per s) from its servo-period samples (line,
    velocities...)."""
    servo = np.array(run["servo"])
    assert len(servo) > 1000, "the sampler recorded too little"
    return peaks(servo[:, 0].astype(int), servo[:, 1:])


@pytest.mark.xdist_group("linuxcnc")
@pytest.mark.parametrize("name", sorted(PROGRAMS))
def test_planner_model_peaks_match_linuxcncs_per_servo_period_speeds(name, runs, tmp_path, capsys):
    ini, programs = runs
    program, run = programs[name]
    assert run["finished"], run["errors"]
    model, real = model_peaks(program, ini, tmp_path), linuxcnc_peaks(run)
    capsys.readouterr()
    assert sorted(model) == sorted(real)
    for line, measured in real.items():
        floor = np.where(measured >= 0.2 * np.max(measured), measured, np.max(measured))
        error = np.abs(model[line] - measured) / floor
        assert np.all(error <= TOLERANCE), (name, line, model[line], measured)
