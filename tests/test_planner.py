"""The planner model (kingen.paths.planner, kingen.paths.blends) on its own, without LinuxCNC's
motion (tests/test_check_path_planner.py holds it against a real LinuxCNC): each move's path
control mode as LinuxCNC's interpreter reads it, the axis limits' caps in closed form, a blend
arc within G64's P of the corner and tangent to both moves, the look-ahead that lets a chain of
moves end at rest."""

import math

import numpy as np
import pytest

from kingen.paths.interpreter import gcode_moves
from kingen.paths.limits import Machine, limits_for
from kingen.paths.planner import merged, planned
from kingen.robot.model import load_robot
from test_check_path import needs_interpreter

INI = """[TRAJ]
LINEAR_UNITS = mm
MAX_LINEAR_VELOCITY = 100
{traj}
[AXIS_X]
MAX_VELOCITY = 50
MAX_ACCELERATION = 300
[AXIS_Y]
MAX_VELOCITY = 40
MAX_ACCELERATION = 200
[AXIS_Z]
MAX_VELOCITY = 50
MAX_ACCELERATION = 300
""" + "".join(f"[JOINT_{index}]\nMAX_VELOCITY = 1000\nMAX_ACCELERATION = 5000\n" for index in range(3))


@pytest.fixture
def interpreter():
    needs_interpreter()


def program_moves(text, folder):
    """The moves of G-code ``text`` (after G21 G90; M2 added) from the delta's home X0 Y0 Z15."""
    path = folder / "p.ngc"
    path.write_text("G21 G90\n" + text + "M2\n")
    return list(gcode_moves(path, (0.0, 0.0, 15.0, 0.0, 0.0, 0.0)))


def plans(text, tmp_path, traj=""):
    """(moves, timings) of ``text`` on the linear delta under INI."""
    ini = tmp_path / "m.ini"
    ini.write_text(INI.format(traj=traj))
    limits = limits_for(load_robot("linear_delta"), ini)
    return list(zip(*planned(program_moves(text, tmp_path), limits)))


def test_each_move_carries_the_path_mode_it_was_made_in(interpreter, tmp_path):
    moves = program_moves("G64 P0.05 Q0.02\nG1 X1 F600\nG61\nG1 X2\nG61.1 G1 X3\nG1 X3.5\nG64\nG1 X4\n"
                           "G20 G64 P0.01\nG1 X0.2\n", tmp_path)
    assert [move.path_mode for move in moves] == [
        ("G64", 0.05, 0.02), ("G61", 0.05, 0.02), ("G61.1", 0.05, 0.02), ("G61.1", 0.05, 0.02), ("G64", 0.0, 0.0),
        ("G64", pytest.approx(0.254), pytest.approx(0.254))]


def test_ini_axis_limits_and_planner_settings_are_read(tmp_path):
    ini = tmp_path / "m.ini"
    ini.write_text(INI.format(traj="ARC_BLEND_KINK_RATIO = 0.2\nARC_BLEND_ENABLE = 0"))
    machine = limits_for(load_robot("linear_delta"), ini).machine
    assert isinstance(machine, Machine)
    assert machine.axis_speed[:3].tolist() == [50, 40, 50] and machine.axis_acceleration[:3].tolist() == [300, 200, 300]
    assert np.all(np.isinf(machine.axis_speed[3:])) and machine.kink_ratio == 0.2 and not machine.arc_blends


def test_an_exact_stop_line_is_a_trapezoid_under_its_axes_caps(interpreter, tmp_path):
    """A line along (3, 4)/5: speed cap min(50/0.6, 40/0.8) = 50, acceleration min(300/0.6, 200/0.8)
    = 250 (the canon's per-axis shares); from rest to rest over 20 mm it reaches 50 mm/s."""
    moves, timings = plans("G61.1\nG1 X12 Y16 F6000\n", tmp_path)
    plan = timings[0]
    assert plan.length == pytest.approx(20.0)
    rate, change = plan.rates(np.array([0.0, 1.0, 10.0, 19.0, 20.0]))
    assert rate == pytest.approx([0.0, math.sqrt(2 * 250 * 1.0), 50.0, math.sqrt(2 * 250 * 1.0), 0.0])
    assert change[1] == pytest.approx(250.0) and change[3] == pytest.approx(-250.0) and change[2] == 0.0


def test_a_short_move_peaks_at_its_triangle(interpreter, tmp_path):
    """2 mm along X at 300 mm/s^2 from rest to rest: the peak sqrt(300 * 2) mm/s at its middle."""
    _, timings = plans("G61.1\nG1 X2 Z15 F6000\n", tmp_path)
    rate, _ = timings[0].rates(np.array([1.0]))
    assert rate[0] == pytest.approx(math.sqrt(300.0 * 2.0))


def test_a_g64_corner_gets_a_blend_arc_within_p_and_tangent_to_both_moves(interpreter, tmp_path):
    moves, timings = plans("G64 P0.1\nG1 X10 Y0 Z15 F3000\nG1 X10 Y10\nG61.1 G1 X10 Y12\n", tmp_path)
    first, second = timings[0], timings[1]
    assert first.arcs and second.arcs
    corner = np.array([10.0, 0.0, 15.0])
    # the arc leaves the first line where its straight part ends, along it (off it by second order)
    leaving = first.parts[0, 1]
    on, xyz = first.blended(np.array([leaving + 1e-9, leaving + 1e-3]))
    assert on.all() and abs(xyz[0, 1]) < 1e-9 and abs(xyz[1, 1]) < 1e-5 and xyz[1, 0] > leaving
    # and passes the corner within P (at its middle, where the second move's stretch begins)
    on2, xyz2 = second.blended(np.array([0.0]))
    assert on2[0] and 0.0 < np.linalg.norm(xyz2[0] - corner) <= 0.1 + 1e-9
    # the speed through the corner is the arc's: sqrt(a_n R) at most, above 0 (no stop)
    rate, _ = first.rates(np.array([first.length]))
    assert 0.0 < rate[0] < 50.0


def test_exact_stop_ends_every_move_at_rest_and_g64_keeps_speed_on_a_straight_run(interpreter, tmp_path):
    program = "G1 X10 Z15 F3000\nG1 X20\nG1 X30\n"
    _, stopping = plans("G61.1\n" + program, tmp_path)
    _, running = plans("G64\n" + program, tmp_path)
    assert [plan.rates(np.array([plan.length]))[0][0] for plan in stopping] == [0.0, 0.0, 0.0]
    ends = [plan.rates(np.array([plan.length]))[0][0] for plan in running]
    assert ends[0] == pytest.approx(50.0) and ends[1] > 0.0 and ends[2] == 0.0


def test_the_look_ahead_slows_a_chain_in_time_to_stop_at_its_end(interpreter, tmp_path):
    """Ten collinear 1 mm moves in G64 and a final stop: the speed at each junction is at most what
    stopping by the chain's end at the acceleration allows (the last move at half of it: a G64 move
    with nothing after it ends in a parabolic blend)."""
    program = "G64\n" + "".join(f"G1 X{index} Z15 F6000\n" for index in range(1, 11))
    _, timings = plans(program, tmp_path)
    for index, plan in enumerate(timings[:-1]):
        remaining = 10.0 - (index + 1)
        end = plan.rates(np.array([plan.length]))[0][0]
        assert end <= math.sqrt(2.0 * 300.0 * (remaining - 1.0) + 300.0 * 1.0) + 1e-9


def test_g64_q_merges_nearly_collinear_moves_into_one_line_named_by_the_last(interpreter, tmp_path):
    """Points 0.02 and 0.03 mm off the line from X0 to X8: within Q0.05 one move (line 5's, as
    LinuxCNC's canon sends it), beyond Q0.01 four; a feed change or A motion ends a run."""
    text = "G1 X2 Y0.02 Z15 F4800\nG1 X4 Y0\nG1 X6 Y0.03\nG1 X8 Y0\nG1 X8 Y4\n"
    moves = list(merged(program_moves("G64 P0.05\n" + text, tmp_path)))
    assert [move.line for move in moves] == [6, 7] and moves[0].start[:3].tolist() == [0.0, 0.0, 15.0]
    assert moves[0].end[:3] == pytest.approx([8.0, 0.0, 15.0])
    assert [move.line for move in merged(program_moves("G64 P0.01\n" + text, tmp_path))] == [3, 4, 5, 6, 7]
    feed_change = "G64 P0.05\nG1 X2 Y0.02 Z15 F4800\nG1 X4 Y0 F3000\nG1 X6 Y0\n"
    assert [move.line for move in merged(program_moves(feed_change, tmp_path))] == [3, 5]


def test_a_parabolic_blend_starts_the_next_move_while_the_first_slows(interpreter, tmp_path):
    """Moves turning A blend parabolically in G64: each at half acceleration, ending at rest on its
    own, and the next move already moving over the first's last stretch, faster the nearer the end,
    never above its own top speed; nothing overlaps in exact stop."""
    program = "G1 X5 Z15 A1 F3000\nG1 X10 Y3 A0\n"
    _, (first, second) = plans("G64\n" + program, tmp_path)
    assert first.tail is not None and first.following is not None and second.tail is None
    s = np.linspace(0.0, first.length, 501)
    rate, _ = first.rates(s)
    assert rate[-1] == 0.0 and max(rate) == pytest.approx(math.sqrt(0.5 * 300.0 * 5.0), rel=1e-3)  # X at half 300 mm/s^2
    speed = first.overlap(s)
    assert speed[0] == 0.0 and speed[-1] > 0.0 and np.all(np.diff(speed[speed > 0]) >= -1e-12)
    assert speed[-1] <= second.speed
    _, (stopping, _) = plans("G61.1\n" + program, tmp_path)
    assert stopping.tail is None
