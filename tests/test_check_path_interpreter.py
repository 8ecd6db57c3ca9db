"""check-path reads G-code through LinuxCNC's own interpreter and follows every motion it emits:
the sample programs LinuxCNC ships, compared motion for motion with ``rs274 -g``'s canonical
output (parsed here on its own, tests/linuxcnc/rs274_motions.py); probes, rigid taps and full
circles out of reach; tool changes, work offsets, subroutines, messages, bounds, and the
interpreter's private environment. Reach is judged on the linear delta (towers 130.25 mm from
its axis, rods 269 mm, carriages 0 .. 375 mm): a point farther than 269 + 130.25 mm from the axis
is out of every rod's reach, and one 900 mm below the base puts every carriage below 0."""

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from kingen.paths.ini import linuxcnc_python, linuxcnc_values, read_ini
from kingen.paths.interpreter import Setup, canonical_motions
from test_check_path import needs_interpreter, run

sys.path.insert(0, str(Path(__file__).resolve().parent / "linuxcnc"))
from rs274_motions import rs274_motions  # noqa: E402

NCFILES = Path("/usr/share/linuxcnc/ncfiles")
TABLE = """T1 P1 Z0.511 D0.0625
T2 P2 Z0.1 D0.0625
T3 P3 Z1.273 D0.25
T4 P4 Z0.4 D0.125
T5 P5 Z0.5 D0.03
T6 P6 Z0.6 D0.03
T7 P7 Z0.7 X0.1 D0.03
T8 P8 Z0.8 D0.03
T9 P9 Z0.9 D0.03
T10 P10 Z1 X0.2 D0.03
"""
"""The walk's tool table, in inches (rs274 reads a tool table in inches): lengths and diameters
as the programs' comments ask."""


def in_mm(table):
    """The tool table ``table`` (inches) in mm, for kingen on a machine in mm (whose programs
    without G20 or G21 are read in mm, as rs274 reads them)."""
    return "".join(" ".join(f"{word[0]}{float(word[1:]) * 25.4!r}" if word[0] in "XYZD" else word
                            for word in line.split()) + "\n" for line in table.splitlines())

JUDGED_IN_CI = ("3dtest", "comp-g1", "gridprobe", "lathe_g7x_face_boring", "lathe_g7x_quadrants", "plasmatest",
                "skeleton", "useful-subroutines", "threading", "systems")
"""The programs judged (check-path's exit) in CI; KINGEN_FULL_SWEEPS=1 judges every one."""
PROBES_AHEAD = "after a probe, where the program goes depends on where the probe tripped"


def ncfiles():
    return sorted(path.stem for path in NCFILES.glob("*.ngc")) if NCFILES.is_dir() else []


def theirs(program, tmp_path):
    """rs274's motions for ``program`` with the walk's table, or None when rs274 refuses it."""
    table, variables, home = tmp_path / "rs274.tbl", tmp_path / "rs274.var", tmp_path / "home"
    table.write_text(TABLE)
    variables.write_text("")
    home.mkdir(exist_ok=True)
    try:
        return rs274_motions(program, table, variables, home, NCFILES)
    except AssertionError:
        return None


@pytest.mark.parametrize("name", ncfiles())
def test_every_sample_program_rs274_reads_is_followed_motion_for_motion(tmp_path, name):
    """Every canonical motion rs274 prints is one of kingen's (a spline, one NURBS_FEED, is the
    straight pieces LinuxCNC's gcode module cuts it into, on its line), in order, ending at the
    same point (to rs274's four printed decimals), up to the first probe: PROBES_AHEAD."""
    needs_interpreter()
    expected = theirs(NCFILES / f"{name}.ngc", tmp_path)
    if expected is None:
        pytest.skip(f"rs274 -g refuses {name}.ngc")
    table = tmp_path / "kingen.tbl"
    table.write_text(in_mm(TABLE))
    ours = list(canonical_motions(NCFILES / f"{name}.ngc", setup=Setup(tool_table=table)))
    at, probed = 0, False
    for number, (call, end) in enumerate(expected):
        assert at < len(ours), f"{name}: rs274's motion {number} ({call}) is not among kingen's {len(ours)}"
        if call == "NURBS_FEED":
            while at + 1 < len(ours) and ours[at + 1][1:3] == ours[at][1:3]:
                at += 1
        kind, _, line, _, _, position, _, _ = ours[at]
        assert kind == {"STRAIGHT_TRAVERSE": "T", "STRAIGHT_FEED": "F", "NURBS_FEED": "F", "STRAIGHT_PROBE": "P",
                        "ARC_FEED": "A", "RIGID_TAP": "R"}[call], f"{name}: motion {number}: {call} at line {line}"
        if end is not None and not probed:
            assert np.allclose(position, end, atol=0.003), f"{name}: motion {number} ({call}) at line {line}"
        probed = probed or call == "STRAIGHT_PROBE"
        at += 1
    assert at == len(ours), f"{name}: kingen has {len(ours) - at} motions more than rs274"


@pytest.mark.parametrize("name", [name for name in ncfiles()
                                  if name in JUDGED_IN_CI or os.environ.get("KINGEN_FULL_SWEEPS") == "1"])
def test_every_sample_program_rs274_reads_is_judged(tmp_path, capsys, name):
    """check-path judges it on the linear delta with the walk's tool table (exit 0 or 1, never bad
    input), and its report counts rs274's motions as rs274 prints them."""
    needs_interpreter()
    expected = theirs(NCFILES / f"{name}.ngc", tmp_path)
    if expected is None:
        pytest.skip(f"rs274 -g refuses {name}.ngc")
    (tmp_path / "kingen.tbl").write_text(in_mm(TABLE))
    ini = tmp_path / "machine.ini"
    ini.write_text("[TRAJ]\nLINEAR_UNITS = mm\n[EMCIO]\nTOOL_TABLE = kingen.tbl\n" + "".join(
        f"[JOINT_{index}]\nMAX_VELOCITY = 500\nMAX_ACCELERATION = 12000\n" for index in range(3)))
    report = tmp_path / "report.json"
    code, out, err = run(capsys, "check-path", "linear_delta", NCFILES / f"{name}.ngc", "--json", report, "--ini", ini)
    assert code in (0, 1), err
    document = json.loads(report.read_text())
    assert document["gcode"]["rs274_motions"] == len(expected)
    assert document["moves"] + document["gcode"]["zero_length"] >= len(expected) - sum(
        call == "RIGID_TAP" for call, _ in expected)


def check(capsys, tmp_path, text, *options, name="part.ngc"):
    program = tmp_path / name
    program.write_text(text)
    report = tmp_path / "report.json"
    code, out, err = run(capsys, "check-path", "linear_delta", program, "--json", report, *options)
    return code, out, err, json.loads(report.read_text()) if report.exists() else None


def failing_lines(document, kinds):
    return sorted({place["line"] for place in document["problems"] if place["kind"] in kinds})


@pytest.mark.parametrize("motion, kinds", [
    ("G2 X0 Y0 I500 J0", {"unreachable"}),  # a full circle: its far side 1000 mm from the axis
    ("G38.2 Z-900", {"travel"}),  # a probe to its programmed end
    ("M3 S500\nG33.1 Z-900 K1", {"travel"}),  # a rigid tap down and back
])
def test_a_full_circle_a_probe_and_a_rigid_tap_out_of_reach_fail(tmp_path, capsys, motion, kinds):
    needs_interpreter()
    code, out, err, document = check(capsys, tmp_path, f"G21 G90\nG0 X0 Y0 Z15\nG1 F600\n{motion}\nM2\n")
    assert code == 1, out + err
    line = 3 + motion.count("\n") + 1
    assert failing_lines(document, kinds) == [line]


def test_print_and_debug_comments_change_no_verdict(tmp_path, capsys):
    needs_interpreter()
    moves = "G21 G90\nG0 X0 Y0 Z15\nG1 X50 F600\nG1 Z-900\nG1 X0 Z15\nM2\n"
    chatty = moves.replace("G1 X50", "(PRINT,D)\n(PRINT,starting pass 1)\n(DEBUG,at #<_x>)\n(MSG,hello)\nG1 X50")
    _, _, _, quiet = check(capsys, tmp_path, moves)
    code, out, err, loud = check(capsys, tmp_path, chatty, name="chatty.ngc")
    assert code == 1 and err == ""
    assert loud["moves"] == quiet["moves"] == 3 and loud["samples"] == quiet["samples"]
    assert [place["line"] - 4 for place in loud["problems"]] == [place["line"] for place in quiet["problems"]]


def three_joint_ini(folder, head):
    """``folder``/machine.ini: ``head`` (the sections a test is about), then three joints at 500
    mm/s and 5000 mm/s^2."""
    ini = folder / "machine.ini"
    ini.write_text(head + "".join(f"[JOINT_{index}]\nMAX_VELOCITY = 500\nMAX_ACCELERATION = 5000\n"
                                  for index in range(3)))
    return ini


@pytest.mark.parametrize("change", ["T1 M6", "M61 Q1"])
def test_a_tool_change_applies_the_tools_length_offset_from_the_ini_tool_table(tmp_path, capsys, change):
    """With T1 50 mm long (G43), the machine's controlled point is 50 mm above the programmed one,
    whether the tool was changed (M6) or declared in the spindle (M61)."""
    needs_interpreter()
    (tmp_path / "tools.tbl").write_text("T1 P1 Z50 D6 ;a 6 mm end mill\n")
    ini = three_joint_ini(tmp_path, "[EMCIO]\nTOOL_TABLE = tools.tbl\n")
    samples = tmp_path / "samples.csv"
    code, out, err, document = check(capsys, tmp_path, f"G21 G90\n{change}\nG43\nG1 X10 Y0 Z20 F600\nM2\n",
                                     "--ini", ini, "--csv", samples)
    assert code in (0, 1), err
    rows = np.genfromtxt(samples, delimiter=",", names=True)
    last = rows[rows["line"] == 4][-1]
    assert (last["x"], last["y"], last["z"]) == pytest.approx((10.0, 0.0, 70.0))


def test_the_work_offset_comes_from_the_parameter_file_or_offset(tmp_path, capsys):
    needs_interpreter()
    (tmp_path / "machine.var").write_text("5220 1\n5221 5\n5222 -7\n5223 20\n")
    ini = three_joint_ini(tmp_path, "[RS274NGC]\nPARAMETER_FILE = machine.var\n")
    samples = tmp_path / "samples.csv"
    program = "G21 G90\nG1 X10 Y0 Z0 F600\nM2\n"
    code, out, err, document = check(capsys, tmp_path, program, "--ini", ini, "--csv", samples)
    assert code in (0, 1), err
    assert document["gcode"]["work_offset"]["g5x"] == [5.0, -7.0, 20.0, 0.0, 0.0, 0.0]
    assert "work offset G54 5 -7 20 0 0 0" in out
    end = np.genfromtxt(samples, delimiter=",", names=True)[-1]
    assert (end["x"], end["y"], end["z"]) == pytest.approx((15.0, -7.0, 20.0))
    code, out, err, document = check(capsys, tmp_path, program, "--ini", ini, "--csv", samples,
                                     "--offset", "1", "2", "3")
    end = np.genfromtxt(samples, delimiter=",", names=True)[-1]
    assert (end["x"], end["y"], end["z"]) == pytest.approx((11.0, 2.0, 3.0))
    assert document["gcode"]["offset_from"] == "--offset"


def test_an_endless_loop_ends_as_bad_input_within_the_stated_bound(tmp_path, capsys):
    needs_interpreter()
    started = time.perf_counter()
    code, out, err, _ = check(capsys, tmp_path, "G21\n#1=0\no100 while [1]\n#1=[#1+1]\no100 endwhile\nM2\n",
                              "--interpreter-seconds", "1")
    assert time.perf_counter() - started < 15.0
    assert code == 2 and out == ""
    assert err.startswith(f"kingen: error: {tmp_path / 'part.ngc'}:") and "1 s of CPU time" in err


def test_a_move_asking_for_too_many_samples_is_bad_input_at_its_line(tmp_path, capsys):
    needs_interpreter()
    code, out, err, _ = check(capsys, tmp_path, "G21 G90\nG0 X0 Y0 Z15\nG1 X1000000000000 F600\nM2\n")
    assert code == 2 and out == ""
    assert err == (f"kingen: error: {tmp_path / 'part.ngc'}:3: samples: the program asks for more than 100000000 "
                   f"samples at chord 0.1 mm/deg by this line (--max-samples)\n")


def test_a_feed_move_without_a_feed_is_bad_input_as_rs274_reads_it(tmp_path, capsys):
    needs_interpreter()
    code, out, err, _ = check(capsys, tmp_path, "G21 G90\nG1 X10 Y0 Z610\nM2\n")
    assert (code, out) == (2, "")
    assert err == f"kingen: error: {tmp_path / 'part.ngc'}:2: G-code: Cannot do g1 with zero feed rate\n"


def test_a_subroutines_bad_move_names_its_file_and_line(tmp_path, capsys):
    needs_interpreter()
    (tmp_path / "drop.ngc").write_text("o<drop> sub\nG1 X#1 F600\nG1 Z-900\no<drop> endsub\nM2\n")
    code, out, err, document = check(capsys, tmp_path, "G21 G90\nG0 X0 Y0 Z15\no<drop> call [5]\nM2\n")
    assert code == 1, err
    places = [place for place in document["problems"] if place["kind"] == "travel"]
    assert places and {(place["file"], place["line"], place["source"]) for place in places} == {
        (str(tmp_path / "drop.ngc"), 3, "G1 Z-900")}
    assert f"{tmp_path / 'drop.ngc'}:3" in out


def test_a_csv_whose_only_pose_is_out_of_reach_does_not_pass(tmp_path, capsys):
    program = tmp_path / "far.csv"
    program.write_text("1000,0,15,0,0,0\n")
    code, out, err = run(capsys, "check-path", "linear_delta", program)
    assert code == 1 and "judged nothing" in out


def test_the_interpreter_has_a_private_home_and_a_clean_environment(tmp_path, capsys, monkeypatch):
    """No $HOME/.tool.mmap is made (LinuxCNC's live tool table), and an INI_FILE_NAME's Python
    (what LinuxCNC exports to every process it starts) does not run."""
    needs_interpreter()
    home, marker = tmp_path / "home", tmp_path / "ran"
    home.mkdir()
    (tmp_path / "top.py").write_text(f"open({str(marker)!r}, 'w').close()\n")
    (tmp_path / "live.ini").write_text(f"[PYTHON]\nTOPLEVEL = {tmp_path / 'top.py'}\nPATH_APPEND = {tmp_path}\n")
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.setenv("INI_FILE_NAME", str(tmp_path / "live.ini"))
    code, out, err, _ = check(capsys, tmp_path, "G21 G90\nT1 M6\nG0 X0 Y0 Z15\nG1 X5 F600\nM2\n")
    assert code in (0, 1), err
    assert not (home / ".tool.mmap").exists() and not marker.exists()


INI_CASES = {
    "duplicate": "[JOINT_0]\nMAX_VELOCITY = 1\nMAX_VELOCITY = 1000\n",
    "case": "[JOINT_0]\nmax_velocity = 3\nMAX_VELOCITY = 4\n[joint_1]\nMAX_VELOCITY = 5\n",
    "comments": "# top\n[TRAJ]\n; note\nLINEAR_UNITS = inch # trailing\n  MAX_VELOCITY =  7  \n",
    "sections": "[JOINT_0]\nMIN_LIMIT = -1\n[TRAJ]\nLINEAR_UNITS = mm\n[JOINT_0]\nMIN_LIMIT = -2\nMAX_LIMIT = 9\n",
    "odd lines": "[EMCIO]\nNO EQUALS SIGN\nEMPTY =\nTOOL_TABLE = a b.tbl\n [RS274NGC]\nPARAMETER_FILE=x.var\n",
}
INI_KEYS = [(section, key) for section in ("JOINT_0", "joint_1", "JOINT_1", "TRAJ", "EMCIO", "RS274NGC")
            for key in ("MAX_VELOCITY", "max_velocity", "MIN_LIMIT", "MAX_LIMIT", "LINEAR_UNITS", "EMPTY",
                        "TOOL_TABLE", "PARAMETER_FILE", "NO EQUALS SIGN")]


@pytest.mark.parametrize("case", sorted(INI_CASES))
def test_kingens_ini_reader_reads_as_linuxcncs(tmp_path, case):
    if linuxcnc_python() is None or linuxcnc_values(__file__, []) is None:
        pytest.skip("LinuxCNC's linuxcnc module is not installed")
    path = tmp_path / "machine.ini"
    path.write_text(INI_CASES[case])
    ours, _ = read_ini(INI_CASES[case])
    assert {pair: value for pair, value in ours.items() if pair in INI_KEYS} == linuxcnc_values(path, INI_KEYS)


def test_a_duplicated_ini_key_is_read_as_linuxcnc_reads_it(tmp_path, capsys):
    """The first MAX_VELOCITY (1 mm/s) holds: a 600 mm/min move along X outruns the carriages."""
    needs_interpreter()
    ini = tmp_path / "machine.ini"
    ini.write_text("".join(f"[JOINT_{index}]\nMAX_VELOCITY = 1\nMAX_VELOCITY = 1000\nMAX_ACCELERATION = 5000\n"
                           for index in range(3)))
    code, out, err, document = check(capsys, tmp_path, "G21 G90\nG0 X0 Y0 Z15\nG1 X20 F600\nM2\n", "--ini", ini)
    assert code == 1, err
    assert {place["limit"] for place in document["problems"] if place["kind"] == "joint speed"} == {1.0}


@pytest.mark.parametrize("reader", ["linuxcnc", "kingen"])
def test_either_ini_reader_gives_the_same_limits(tmp_path, capsys, monkeypatch, reader):
    """The first of a duplicated key, keys in their case, a repeated section read where it first
    stands: 1 mm/s and 0 .. 300 mm, through LinuxCNC's reader or (no LinuxCNC Python) kingen's."""
    if reader == "kingen":
        monkeypatch.setenv("KINGEN_LINUXCNC_PYTHON", str(tmp_path / "no-python"))
    elif linuxcnc_python() is None:
        pytest.skip("LinuxCNC's linuxcnc module is not installed")
    ini = tmp_path / "machine.ini"
    ini.write_text("".join(f"[JOINT_{index}]\nMAX_VELOCITY = 1\nMAX_VELOCITY = 1000\nmax_acceleration = 1\n"
                           f"MAX_ACCELERATION = 5000\nMIN_LIMIT = 0\nMAX_LIMIT = 300\n[JOINT_{index}]\nMAX_LIMIT = 9\n"
                           for index in range(3)))
    program = tmp_path / "path.csv"
    program.write_text("x,y,z,roll,pitch,yaw,feed\n0,0,15,0,0,0,600\n20,0,15,0,0,0,600\n")
    report = tmp_path / "report.json"
    code, out, err = run(capsys, "check-path", "linear_delta", program, "--ini", ini, "--json", report)
    assert code == 1, err
    document = json.loads(report.read_text())
    assert document["settings"]["limits_from"][-1] == f"{ini} (read by " + (
        "LinuxCNC's linuxcnc.ini reader)" if reader == "linuxcnc" else "kingen's reader)")
    peaks = document["peaks"]
    assert [(peak["speed_limit"], peak["acceleration_limit"], peak["travel_limits"]) for peak in peaks] == [
        (1.0, 5000.0, [0.0, 300.0])] * 3


def test_a_subroutine_is_found_on_the_ini_subroutine_path(tmp_path, capsys):
    needs_interpreter()
    (tmp_path / "library").mkdir()
    (tmp_path / "library" / "drop.ngc").write_text("o<drop> sub\nG1 X#1 F600\nG1 Z-900\no<drop> endsub\nM2\n")
    ini = tmp_path / "machine.ini"
    ini.write_text("[RS274NGC]\nSUBROUTINE_PATH = nowhere:library\n" + "".join(
        f"[JOINT_{index}]\nMAX_VELOCITY = 500\nMAX_ACCELERATION = 5000\n" for index in range(3)))
    (tmp_path / "cam").mkdir()
    code, out, err, document = check(capsys, tmp_path / "cam", "G21 G90\nG0 X0 Y0 Z15\no<drop> call [5]\nM2\n",
                                     "--ini", ini)
    assert code == 1, err
    assert {place["file"] for place in document["problems"]} == {str(tmp_path / "library" / "drop.ngc")}


def test_a_program_without_units_is_read_in_the_machines_units(tmp_path, capsys):
    """On an inch machine (LINEAR_UNITS = inch) X1 is an inch, as LinuxCNC reads it; without an
    .ini, a millimetre (from the linear delta's home, Z 15 mm)."""
    needs_interpreter()
    ini = tmp_path / "machine.ini"
    ini.write_text("[TRAJ]\nLINEAR_UNITS = inch\n" + "".join(
        f"[JOINT_{index}]\nMAX_VELOCITY = 20\nMAX_ACCELERATION = 200\n" for index in range(3)))
    samples = tmp_path / "samples.csv"
    for options, x in ((["--ini", ini], 25.4), ([], 1.0)):
        code, out, err, _ = check(capsys, tmp_path, "G90\nG1 X1 F10\nM2\n", "--csv", samples, *options)
        assert code in (0, 1), err
        end = np.genfromtxt(samples, delimiter=",", names=True)[-1]
        assert (end["x"], end["z"]) == pytest.approx((x, 15.0))


@pytest.mark.parametrize("unit, table", [(1.0, "T1 P1 D10 ;10 mm\n"), (25.4, f"T1 P1 D{10 / 25.4!r}\n")])
def test_cutter_compensation_offsets_by_the_tools_radius_on_a_machine_in_mm_or_inches(tmp_path, unit, table):
    """A 10 mm tool left of a square's corner (G41): entry on the 45-degree line 5 mm to its left,
    the arc around the corner, then 5 mm inside each side, whatever the machine's unit."""
    needs_interpreter()
    (tmp_path / "tools.tbl").write_text(table)
    program = tmp_path / "square.ngc"
    program.write_text("G21 G90\nT1 M6\nG0 X-20 Y-20 Z0\nG41 D1\nG1 X0 Y0 F100\nG1 X50\nG1 Y50\nG40\nG0 X80\nM2\n")
    ends = [motion[5][:2] for motion in canonical_motions(program, setup=Setup(tool_table=tmp_path / "tools.tbl",
                                                                                machine_unit=unit))]
    half = 5.0 / np.sqrt(2.0)
    assert np.allclose(ends, [(-20, -20), (-half, half), (0, 5), (45, 5), (45, 50), (80, 50)], atol=1e-9)
