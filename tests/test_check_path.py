"""kingen check-path: programs checked along their path on LinuxCNC's sample hexapod, against
strut lengths computed here from the robot file's points (|R p + t - b|), the golden values
LinuxCNC's genhexkins gives, and the same program checked at a ten times finer chord."""

import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml

from kingen.cli import main
from kingen.conventions import matrix_from_pose
from conftest import require_tool, skip_or_fail

ROBOTS = Path(__file__).resolve().parent.parent / "robots"
INCH = 25.4
DOCUMENT = yaml.safe_load((ROBOTS / "linuxcnc_hexapod.yaml").read_text())
BASE = np.array([limb["base_point"] for limb in DOCUMENT["limbs"]]) * INCH
PLATFORM = np.array([limb["platform_point"] for limb in DOCUMENT["limbs"]]) * INCH
HOME = [0.0, 0.0, 20.0 * INCH, 0.0, 0.0, 0.0]


def strut_lengths(poses):
    """(n, 6) each strut's length (mm) at poses (n, 6) in mm and degrees."""
    matrices = matrix_from_pose(np.asarray(poses, dtype=float))
    points = np.einsum("nij,kj->nki", matrices[:, :3, :3], PLATFORM) + matrices[:, None, :3, 3]
    return np.linalg.norm(points - BASE, axis=2)


def run(capsys, *argv):
    code = main([str(value) for value in argv])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def needs_interpreter():
    if shutil.which("rs274") is None or not Path("/usr/bin/python3").exists():
        skip_or_fail("LinuxCNC's interpreter is not installed (Debian package linuxcnc-uspace; .ci/run installs it)")


def ini_text(minimum=None, maximum=None, velocity=10.0, acceleration=100.0, joints=6):
    """A LinuxCNC .ini in inches for the hexapod's struts (``minimum``, ``maximum``: every joint's,
    or {joint: limit})."""
    lines = ["[TRAJ]", "LINEAR_UNITS = inch", "MAX_LINEAR_VELOCITY = 20", "MAX_LINEAR_ACCELERATION = 1000", ""]
    for index in range(joints):
        lines += [f"[JOINT_{index}]", f"MAX_VELOCITY = {velocity!r}", f"MAX_ACCELERATION = {acceleration!r}"]
        for key, value in (("MIN_LIMIT", minimum), ("MAX_LIMIT", maximum)):
            value = value.get(index) if isinstance(value, dict) else value
            lines += [f"{key} = {float(value)!r}"] if value is not None else []
        lines.append("")
    return "\n".join(lines)


def test_a_csv_that_runs_clean_passes_and_its_samples_hold_linuxcnc_genhexkins_joints(tmp_path, capsys):
    golden = DOCUMENT["golden"][1]
    pose = [value * INCH for value in golden["pose"][:3]] + golden["pose"][3:]
    program = tmp_path / "clean.csv"
    program.write_text("x,y,z,roll,pitch,yaw,feed\n" + "\n".join(
        ",".join(repr(v) for v in row) for row in (HOME + [600.0], pose + [600.0], HOME + [900.0])) + "\n")
    samples = tmp_path / "samples.csv"
    code, out, err = run(capsys, "check-path", "linuxcnc_hexapod", program, "--csv", samples, "--json",
                         tmp_path / "r.json")
    assert (code, err) == (0, "")
    assert "runs within every limit judged" in out
    rows = np.genfromtxt(samples, delimiter=",", names=True)
    at_golden = rows[(rows["line"] == 3) & (rows["u"] == 1.0)]
    joints = np.array([at_golden[f"strut{index}"][0] for index in range(6)])
    assert np.max(np.abs(joints / INCH - golden["joints"])) < 1e-6
    poses = np.column_stack([rows[name] for name in ("x", "y", "z", "roll", "pitch", "yaw")])
    struts = np.column_stack([rows[f"strut{index}"] for index in range(6)])
    assert np.max(np.abs(struts - strut_lengths(poses))) < 1e-9
    steps = np.linalg.norm(np.diff(poses[:, :3], axis=0), axis=1)
    assert np.max(steps) <= 0.1 + 1e-12
    document = json.loads((tmp_path / "r.json").read_text())
    assert document["verdict"] == "runs" and document["moves"] == 2 and document["samples"] == len(rows)
    assert [peak["joint"] for peak in document["peaks"]] == [f"strut{index}" for index in range(6)]
    assert document["checks"]["travel"].startswith("not exercised")


def test_a_gcode_program_with_an_arc_runs_clean_and_its_arc_samples_lie_on_the_circle(tmp_path, capsys):
    needs_interpreter()
    program = tmp_path / "clean.ngc"
    program.write_text("G21 G90\nG1 X10 Y0 Z508 F600\nG3 X-10 Y0 I-10 J0\nG1 X0 Y0 A2 B-1\nM2\n")
    samples = tmp_path / "samples.csv"
    code, out, err = run(capsys, "check-path", "linuxcnc_hexapod", program, "--csv", samples)
    assert (code, err) == (0, "")
    rows = np.genfromtxt(samples, delimiter=",", names=True)
    arc = rows[rows["line"] == 3]
    assert len(arc) >= math.ceil(10 * math.pi / 0.1)
    assert np.max(np.abs(np.hypot(arc["x"], arc["y"]) - 10.0)) < 1e-9
    assert np.all(arc["y"] >= -1e-9)  # counter-clockwise from +x to -x through +y


def test_leaving_a_joints_travel_is_named_at_its_line(tmp_path, capsys):
    needs_interpreter()
    top = strut_lengths([[0, 0, 520.0, 0, 0, 0]]).max() / INCH
    ini = tmp_path / "machine.ini"
    ini.write_text(ini_text(maximum=top))
    program = tmp_path / "travel.ngc"
    program.write_text("G21 G90\nG1 Z510 F300\nG1 X5\nG1 Z530\nG1 Z508\nM2\n")
    code, out, err = run(capsys, "check-path", "linuxcnc_hexapod", program, "--ini", ini, "--json", tmp_path / "r.json")
    assert code == 1 and err == ""
    document = json.loads((tmp_path / "r.json").read_text())
    travel = [problem for problem in document["problems"] if problem["kind"] == "travel"]
    assert sorted({problem["line"] for problem in travel}) == [4, 5]  # leaves at line 4, comes back in line 5
    assert {problem["source"] for problem in travel} == {"G1 Z530", "G1 Z508"}
    first = min((place for place in document["first"] if place["kind"] == "travel"), key=lambda p: p["pose"][2])
    crossing = first["pose"]
    assert strut_lengths([crossing]).max() == pytest.approx(top * INCH, abs=1e-6)
    assert "does not run" in out.splitlines()[0]


def test_a_feed_too_fast_for_the_ini_is_named_with_the_override_that_fits(tmp_path, capsys):
    needs_interpreter()
    feed = 600.0  # mm/min along z
    z_end = 540.0
    # a pure z move: each strut lengthens at v * (z - b_z) / L with b_z = 0, largest at the top
    lengths = strut_lengths([[0, 0, z_end, 0, 0, 0]])[0]
    needed = feed / 60.0 * np.max(z_end / lengths)
    limit = 5.0  # mm/s
    ini = tmp_path / "machine.ini"
    ini.write_text(ini_text(velocity=limit / INCH))
    program = tmp_path / "fast.ngc"
    program.write_text(f"G21 G90\nG1 Z{z_end:g} F{feed:g}\nM2\n")
    code, out, err = run(capsys, "check-path", "linuxcnc_hexapod", program, "--ini", ini, "--json", tmp_path / "r.json")
    assert code == 1 and err == ""
    speeds = [p for p in json.loads((tmp_path / "r.json").read_text())["problems"] if p["kind"] == "joint speed"]
    assert {p["line"] for p in speeds} == {2}
    worst = max(speeds, key=lambda p: p["value"])
    assert worst["value"] == pytest.approx(needed, rel=1e-4)
    assert worst["override"] == pytest.approx(limit / needed, rel=1e-4)


def grazing_program(tmp_path, offset):
    """A 60 mm straight move whose strut 0 is shortest midway between two samples at the default
    chord (30.05 mm from its start), with the travel's lower limit ``offset`` mm above that
    shortest length: (the program, the limit in inches, the pose where strut 0 is shortest)."""
    middle = np.array([0.0, 0.0, 508.0])
    reach = BASE[0] - PLATFORM[0] - middle  # strut 0 is shortest where the move is square to this
    direction = np.cross(reach, [0.0, 0.0, 1.0])
    direction /= np.linalg.norm(direction)
    start, end = middle - 30.05 * direction, middle + 29.95 * direction
    program = tmp_path / "graze.csv"
    program.write_text("x,y,z,roll,pitch,yaw\n" + "\n".join(",".join(repr(float(v)) for v in list(p) + [0, 0, 0])
                                                         for p in (start, end)) + "\n")
    return program, (float(np.linalg.norm(reach)) + offset) / INCH, middle, start, end


@pytest.mark.parametrize("offset", [1e-7, 1e-6])
def test_a_crossing_grazed_between_two_samples_is_found_as_at_a_ten_times_finer_chord(tmp_path, capsys, offset):
    program, minimum, middle, start, end = grazing_program(tmp_path, offset)
    ini = tmp_path / "machine.ini"
    ini.write_text(ini_text(minimum={0: minimum}))
    grid = np.column_stack([start + np.linspace(0.0, 1.0, 601)[:, None] * (end - start), np.zeros((601, 3))])
    assert np.min(strut_lengths(grid)[:, 0]) > minimum * INCH  # the regular samples never see it
    found = []
    for chord in (0.1, 0.01):
        code, _, err = run(capsys, "check-path", "linuxcnc_hexapod", program, "--ini", ini, "--chord", chord,
                           "--json", tmp_path / "r.json")
        document = json.loads((tmp_path / "r.json").read_text())
        assert code == 1 and err == ""
        found.append(sorted((p["kind"], p["line"], p["joint"]) for p in document["problems"]))
        worst = next(p for p in document["worst"] if p["kind"] == "travel")
        shortest = minimum * INCH - offset
        assert shortest - 1e-9 <= worst["value"] < minimum * INCH
        assert np.linalg.norm(np.array(worst["pose"][:3]) - middle) <= math.sqrt(2.0 * shortest * offset)
    assert found[0] == found[1] == [("travel", 3, "strut0")]


@pytest.mark.parametrize("text, problem", [
    ("x,y,z,roll,pitch,yaw\n0,0,508,0,0,0\n1,2,508,0\n", ":3: row: 4 values, 6 expected"),
    ("x,y,z,roll,pitch,yaw\n0,0,508,0,0,0\n1,two,508,0,0,0\n", ":3: y: 'two' is not a number"),
    ("x,y,z,roll,pitch,yaw,feed\n0,0,508,0,0,0,100\n1,0,508,0,0,0,0\n", ":3: feed: 0 mm/min: a feed must be above 0"),
    ("x,y,z,roll,pitch,yaw,feed\n0,0,508,0,0,0,100\n1,0,508,0,0,0,-5\n", ":3: feed: -5 mm/min: a feed must be above 0"),
    ("x,y,z,roll,pitch,yaw\n0,0,508,0,0,0\n1e308,0,508,0,0,0\n", ":3: x: 1e+308 mm is not within -1e+06 to 1e+06"),
    ("x,y,z,roll,pitch,yaw\n0,0,508,0,0,0\n0,0,508,0,-721,0\n", ":3: pitch: -721 degrees is not within -720 to 720"),
    ("x,y,z,roll,pitch,yaw,t\n0,0,508,0,0,0,-1e308\n1,0,508,0,0,0,1\n", ":2: t: -1e+308 s is not within -1e+09 to 1e+09"),
    ("x,y,z,roll,pitch,yaw,feed\n0,0,508,0,0,0,100\n1,0,508,0,0,0,1e-300\n",
     ":3: feed: 1e-300 mm/min is not within 1e-06 to 1e+09"),
    ("x,y,z,roll,pitch,yaw\n0,0,508,0,0,0\n" + "1" * 200000 + ",0,508,0,0,0\n",
     ":3: not CSV: field larger than field limit (131072)"),
])
def test_a_bad_csv_is_one_line_naming_file_and_line(tmp_path, capsys, text, problem):
    program = tmp_path / "bad.csv"
    program.write_text(text)
    output = tmp_path / "samples.csv"
    code, out, err = run(capsys, "check-path", "linuxcnc_hexapod", program, "--csv", output)
    assert code == 2 and out == ""
    assert err == f"kingen: error: {program}{problem}\n"
    assert not output.exists()


@pytest.mark.parametrize("text, line, message", [
    ("G21\nG1 X1 F100\nG1 X2 Y1 G2\nM2\n", 3, "Two g codes used from same modal group"),
    ("G21\nG1 X1 F0\nM2\n", 2, None),
])
def test_a_program_linuxcncs_interpreter_refuses_is_its_message_at_its_line(tmp_path, capsys, text, line, message):
    needs_interpreter()
    program = tmp_path / "bad.ngc"
    program.write_text(text)
    code, out, err = run(capsys, "check-path", "linuxcnc_hexapod", program)
    assert code == 2 and out == ""
    assert err.startswith(f"kingen: error: {program}:{line}: G-code: ") and err.count("\n") == 1
    if message:
        assert err.endswith(f": {message}\n")


def test_an_ini_without_the_robots_joints_is_bad_input(tmp_path, capsys):
    ini = tmp_path / "machine.ini"
    ini.write_text(ini_text(joints=5))
    program = tmp_path / "p.csv"
    program.write_text("0,0,508,0,0,0\n1,0,508,0,0,0\n")
    code, out, err = run(capsys, "check-path", "linuxcnc_hexapod", program, "--ini", ini)
    assert code == 2 and out == ""
    lines = len(ini.read_text().splitlines())
    assert err == (f"kingen: error: {ini}:{lines}: [JOINT_5]: missing (the file ends here): the robot has 6 joints "
                   f"(JOINT_0 .. JOINT_5)\n")


@pytest.mark.parametrize("velocity, acceleration, key, text", [(0.0, 100.0, "MAX_VELOCITY", "'0.0'"),
                                                               (10.0, -5.0, "MAX_ACCELERATION", "'-5.0'")])
def test_an_ini_speed_or_acceleration_not_above_zero_is_bad_input(tmp_path, capsys, velocity, acceleration, key,
                                                                  text):
    ini = tmp_path / "machine.ini"
    ini.write_text(ini_text(velocity=velocity, acceleration=acceleration))
    program = tmp_path / "p.csv"
    program.write_text("0,0,508,0,0,0\n1,0,508,0,0,0\n")
    code, out, err = run(capsys, "check-path", "linuxcnc_hexapod", program, "--ini", ini)
    lines = ini.read_text().splitlines()
    line = lines.index(f"{key} = {velocity if key == 'MAX_VELOCITY' else acceleration!r}", lines.index("[JOINT_0]")) + 1
    assert (code, out) == (2, "") and err == f"kingen: error: {ini}:{line}: [JOINT_0] {key}: {text}: must be above 0\n"


def test_speed_limits_in_an_inch_robot_file_judge_as_the_same_limits_in_an_ini(tmp_path, capsys):
    document = yaml.safe_load((ROBOTS / "linuxcnc_hexapod.yaml").read_text())
    limit = 5.0  # mm/s
    for limb in document["limbs"]:
        limb["max_speed"] = limit / INCH
    robot = tmp_path / "limited.yaml"
    robot.write_text(yaml.safe_dump(document))
    ini = tmp_path / "machine.ini"
    ini.write_text(ini_text(velocity=limit / INCH, acceleration=1e9))
    program = tmp_path / "fast.csv"
    program.write_text("x,y,z,roll,pitch,yaw,feed\n0,0,508,0,0,0,600\n0,0,540,0,0,0,600\n")
    problems = []
    for extra in (["--ini", ini], []):
        code, _, err = run(capsys, "check-path", robot if not extra else "linuxcnc_hexapod", program,
                           "--json", tmp_path / "r.json", *extra)
        assert code == 1 and err == ""
        problems.append([(p["kind"], p["joint"], p["value"], p["limit"])
                         for p in json.loads((tmp_path / "r.json").read_text())["problems"]])
    assert [row[:2] for row in problems[0]] == [row[:2] for row in problems[1]]
    assert {kind for kind, *_ in problems[0]} == {"joint speed"}
    for (_, _, with_ini, ini_limit), (_, _, with_file, file_limit) in zip(*problems):
        # the .ini's path acceleration (1000 in/s^2) slows only the last 0.002 mm of the move
        assert with_ini == pytest.approx(with_file, rel=1e-3) and ini_limit == pytest.approx(file_limit) == limit


def test_delmia_turns_the_orientation_about_one_axis_at_a_uniform_rate(tmp_path, capsys):
    from scipy.spatial.transform import Rotation

    program = tmp_path / "turn.csv"
    program.write_text("0,0,508,0,0,0\n0,0,508,20,0,20\n")
    angles = {}
    for host in ("delmia", "linuxcnc"):
        samples = tmp_path / f"{host}.csv"
        code, _, err = run(capsys, "check-path", "linuxcnc_hexapod", program, "--host", host, "--csv", samples)
        assert (code, err) == (0, "")
        rows = np.genfromtxt(samples, delimiter=",", names=True)
        rotations = Rotation.from_euler("xyz", np.column_stack([rows["roll"], rows["pitch"], rows["yaw"]]), degrees=True)
        turned = (rotations[0].inv() * rotations).magnitude()
        angles[host] = (rows["u"], turned, rows)
    u, turned, rows = angles["delmia"]
    assert np.max(np.abs(turned - u * turned[-1])) < 1e-9  # uniform about one axis
    u, turned, rows = angles["linuxcnc"]
    assert np.max(np.abs(rows["roll"] - 20 * u)) < 1e-9 and np.max(np.abs(rows["yaw"] - 20 * u)) < 1e-9
    assert np.max(np.abs(turned - u * turned[-1])) > 1e-4  # A, B, C linear: not uniform about one axis


def test_a_program_without_a_move_exercises_nothing_and_does_not_pass(tmp_path, capsys):
    program = tmp_path / "still.csv"
    program.write_text("0,0,508,0,0,0\n0,0,508,0,0,0\n")
    code, out, err = run(capsys, "check-path", "linuxcnc_hexapod", program, "--json", tmp_path / "r.json")
    document = json.loads((tmp_path / "r.json").read_text())
    assert code == 1 and err == "" and "judged nothing" in out and "runs" not in out
    assert document["verdict"] == "judged nothing"
    assert set(document["checks"].values()) == {"not exercised: the program has no move"}


def test_the_html_report_in_a_real_browser(tmp_path, capsys):
    """The page's figure loads in Chromium, and a screenshot of it is not blank."""
    import subprocess

    import matplotlib.image


    require_tool("chromium", "chromium")
    program = tmp_path / "p.csv"
    program.write_text("x,y,z,roll,pitch,yaw,feed\n0,0,508,0,0,0,600\n20,10,520,2,0,0,600\n0,0,560,0,0,0,600\n")
    ini = tmp_path / "machine.ini"
    ini.write_text(ini_text(maximum=31.0, velocity=0.3))
    page = tmp_path / "report.html"
    code, _, err = run(capsys, "check-path", "linuxcnc_hexapod", program, "--ini", ini, "--html", page)
    assert code == 1 and err == ""
    chromium = ["chromium", "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                "--disable-background-networking", "--disable-component-update", "--disable-sync"]
    probe = tmp_path / "probe.html"
    probe.write_text(page.read_text().replace("</body>", """<script>
window.addEventListener("load", function () {
  var loaded = Array.prototype.filter.call(document.images, function (i) { return i.complete && i.naturalWidth > 0; });
  document.body.setAttribute("data-images", document.images.length + "/" + loaded.length);
});
</script></body>"""))
    dom = subprocess.run([*chromium, f"--user-data-dir={tmp_path / 'profile'}", "--virtual-time-budget=5000",
                          "--dump-dom", probe.as_uri()], capture_output=True, text=True, timeout=120)
    assert 'data-images="1/1"' in dom.stdout
    assert "joint speed" in dom.stdout and "travel" in dom.stdout
    shot = tmp_path / "report.png"
    subprocess.run([*chromium, f"--user-data-dir={tmp_path / 'profile2'}", f"--screenshot={shot}", "--hide-scrollbars",
                    "--window-size=1200,1600", page.as_uri()], capture_output=True, timeout=120)
    pixels = matplotlib.image.imread(shot)
    assert pixels.shape[:2] == (1600, 1200) and float(pixels[..., :3].std()) > 0.05


def test_csv_times_give_the_speed_that_reaches_each_row_on_time(tmp_path, capsys):
    """Rows 2 s apart, 32 mm up along z: 16 mm/s of the path, each strut at 16 z / L mm/s
    (largest at the top, z = 540 mm)."""
    program = tmp_path / "timed.csv"
    program.write_text("x,y,z,roll,pitch,yaw,t\n0,0,508,0,0,0,0\n0,0,540,0,0,0,2\n")
    ini = tmp_path / "machine.ini"
    ini.write_text(ini_text(velocity=5.0 / INCH, acceleration=1e9))
    code, _, err = run(capsys, "check-path", "linuxcnc_hexapod", program, "--ini", ini, "--json", tmp_path / "r.json")
    assert code == 1 and err == ""
    problems = json.loads((tmp_path / "r.json").read_text())["problems"]
    needed = 16.0 * 540.0 / strut_lengths([[0, 0, 540.0, 0, 0, 0]])[0]
    assert sorted(p["value"] for p in problems) == pytest.approx(sorted(needed), rel=1e-6)


@pytest.mark.parametrize("column, rows, verdict", [
    ("t", ("0", "2"), "passed"),
    ("feed", ("600", "600"), "not exercised: no move's accelerations are known (a path acceleration, .ini [TRAJ], or "
                             "CSV times)"),
])
def test_the_acceleration_verdict_is_of_the_moves_it_judged(tmp_path, capsys, column, rows, verdict):
    """Without a path acceleration in the .ini, CSV times still give each move's accelerations
    (judged: passed under a generous limit); feeds alone give none (not exercised)."""
    program = tmp_path / "moves.csv"
    program.write_text(f"x,y,z,roll,pitch,yaw,{column}\n0,0,508,0,0,0,{rows[0]}\n0,0,540,0,0,0,{rows[1]}\n")
    ini = tmp_path / "machine.ini"
    ini.write_text(ini_text(velocity=1e6, acceleration=1e9).replace("MAX_LINEAR_ACCELERATION = 1000\n", ""))
    code, _, _ = run(capsys, "check-path", "linuxcnc_hexapod", program, "--ini", ini, "--json", tmp_path / "r.json")
    report = json.loads((tmp_path / "r.json").read_text())
    assert code == 0 and report["checks"]["joint acceleration"] == verdict
    assert report["accelerated_moves"] == (1 if column == "t" else 0)


def test_passing_the_base_plane_is_an_assembly_change_where_the_struts_lie_flat(tmp_path, capsys):
    """At z = 0 every strut lies in the base plane: the six force lines cannot resist a vertical
    force, their determinant is 0, and it changes sign as the platform passes through."""
    program = tmp_path / "through.csv"
    program.write_text("0,0,100,0,0,0\n0,0,-100.05,0,0,0\n")
    code, _, err = run(capsys, "check-path", "linuxcnc_hexapod", program, "--json", tmp_path / "r.json")
    assert code == 1 and err == ""
    document = json.loads((tmp_path / "r.json").read_text())
    assert [(p["kind"], p["line"]) for p in document["problems"]] == [("assembly change", 2)]
    first = next(p for p in document["first"] if p["kind"] == "assembly change")
    assert abs(first["pose"][2]) < 1e-9
