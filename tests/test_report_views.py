"""The 3D view in check-path's, calibrate's and analyze's reports: its overlay data hold the
values the reports' own numbers and independent computations give (a finding's frame at the
finding's place with the strut lengths |R p + t - b| computed here; an arrow's vector the
residual a known error of the measuring frame makes, times the stated factor; the tilt surface's
vertices at the reported tilt limits, by Rodrigues' formula written here)."""

import html
import json
import math
import re
import subprocess

import numpy as np
import pytest

from kingen.calibrate.drawing import magnified_robot, residual_arrows
from kingen.calibrate.identification import Problem, synthetic_problem
from kingen.calibrate.parameters import Parameters
from kingen.cli import main
from kingen.design.analysis import Settings, tilt_limits
from kingen.design.tilt_view import AXIS_SHARE, tilt_overlays
from kingen.paths.check import Settings as CheckSettings
from kingen.paths.check import check_program
from kingen.paths.playback import FRAMES, playback
from kingen.robot.model import load_robot
from conftest import require_tool
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
    assert view["travel"] == [[None, pytest.approx(31.0 * INCH)]] * 6  # the .ini's MAX_LIMIT only: no lower side
    assert view["travel_from"].startswith(f"the robot file and {ini} (read by ")


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
    labelled = [arrow["label"] for arrow in arrows if arrow["label"]]
    assert labelled == [f"line {line}: 0.3 mm" for line in data.lines][:len(labelled)] and len(labelled) == 3


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
        frame = overlays["frames"][index]
        assert frame["label"].startswith(f"{row['azimuth_deg']:g}°: {row['max_tilt_deg']:g}°, ")
        assert frame["t"] == row["azimuth_deg"] and point["label"] in ("", frame["label"])
        turned = rodrigues([math.cos(azimuth), math.sin(azimuth), 0.0], row["max_tilt_deg"]) @ start
        assert np.radians(frame["pose"][3:]) == pytest.approx(
            [math.atan2(turned[2, 1], turned[2, 2]), math.asin(-turned[2, 0]), math.atan2(turned[1, 0], turned[0, 0])],
            abs=1e-9)
    least = min(rows, key=lambda row: row["max_tilt_deg"])
    assert any(point["label"].startswith(f"{least['azimuth_deg']:g}°: ") for point in overlays["points"])
    assert tilt_overlays(robot, {"tilt_limits": [], "posture": 0}, "axis") == {}



CHROMIUM = ["chromium", "--headless", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
            "--no-first-run", "--disable-background-networking", "--disable-component-update", "--disable-sync"]
PROBE = """<script>
window.addEventListener("load", function () { setTimeout(function () {
  var inner = document.querySelector("iframe.kingen-view-frame").contentDocument;
  var root = inner.querySelector(".kingen-view"), out = inner.getElementById("kingen-joints");
  document.body.setAttribute("data-ready", root ? root.getAttribute("data-ready") : "none");
  document.body.setAttribute("data-joints", out ? out.textContent : "none");
  document.body.setAttribute("data-frame", (inner.querySelector(".kingen-frame") || {}).textContent || "");
  document.body.setAttribute("data-canvas", inner.querySelectorAll("canvas").length);
  document.body.setAttribute("data-drawing", (inner.getElementById("kingen-drawing") || {}).textContent || "none");
  document.body.setAttribute("data-about", (inner.querySelector(".kingen-about") || {}).textContent || "");
  var boxes = Array.from(inner.querySelectorAll(".kingen-label"), function (div) {
    return div.style.visibility === "hidden" || !div.textContent ? null : div.getBoundingClientRect(); }).filter(Boolean);
  var overlaps = 0;
  boxes.forEach(function (a, i) { boxes.slice(i + 1).forEach(function (b) {
    if (a.left < b.right && b.left < a.right && a.top < b.bottom && b.top < a.bottom) overlaps += 1; }); });
  document.body.setAttribute("data-labels", boxes.length + " " + overlaps);
  document.body.setAttribute("data-travel", Array.from(inner.querySelectorAll(".kingen-table tbody tr"),
                                                       row => row.cells[2].textContent).join("|"));
}, 2000); });
</script></body>"""


def in_browser(report, scratch):
    """What the report's view wrote once loaded in headless Chromium: {ready, joints and drawing
    (the parsed #kingen-joints and #kingen-drawing), frame (the timeline's words), canvas (how
    many), about (the note under the table), travel (the table's travel cells, "|"-joined),
    labels ("shown overlapping": the labels shown, the pairs of them that overlap)}, and
    Chromium's console lines (none: no JS error)."""
    require_tool("chromium", "chromium")
    probe = scratch / "probe.html"
    probe.write_text(report.read_text().replace("</body>", PROBE))
    done = subprocess.run([*CHROMIUM, f"--user-data-dir={scratch / 'profile'}", "--enable-logging=stderr", "--v=0",
                           "--virtual-time-budget=15000", "--window-size=1200,900", "--dump-dom", probe.as_uri()],
                          capture_output=True, text=True, timeout=120)
    found = {name: html.unescape(value) for name, value in
             re.findall(r'data-(ready|joints|frame|canvas|drawing|about|travel|labels)="([^"]*)"', done.stdout)}
    console = [line for line in done.stderr.splitlines() if "CONSOLE" in line]
    parsed = {key: json.loads(found[key]) if found.get(key, "none") != "none" else None for key in ("joints", "drawing")}
    return {**found, **parsed}, console


def test_check_paths_report_opens_its_view_at_the_first_problem_in_a_real_browser(tmp_path):
    """The report's view starts, draws (one canvas) and writes into #kingen-joints the strut lengths
    computed here at the first problem's pose; the timeline names that problem; no JS error."""
    program = tmp_path / "p.csv"
    program.write_text("x,y,z,roll,pitch,yaw,feed\n0,0,508,0,0,0,600\n20,10,520,2,0,0,600\n0,0,560,0,0,0,600\n")
    ini = tmp_path / "machine.ini"
    ini.write_text(ini_text(maximum=31.0, velocity=0.3))
    report = tmp_path / "report.html"
    assert main(["check-path", "linuxcnc_hexapod", str(program), "--ini", str(ini), "--html", str(report),
                 "--json", str(tmp_path / "r.json")]) == 1
    first = json.loads((tmp_path / "r.json").read_text())["problems"][0]
    seen, console = in_browser(report, tmp_path)
    assert console == [] and seen["ready"] == "1" and seen["canvas"] == "1"
    assert seen["joints"]["joints"] == pytest.approx(strut_lengths([first["pose"]])[0], abs=1e-6)
    assert f"1: line {first['line']}: {first['kind']} {first['joint']}" in seen["frame"]
    assert report.stat().st_size < 3_000_000


def test_check_paths_view_judges_a_travel_limited_on_one_side_and_names_the_ini(tmp_path):
    """LinuxCNC's sample hexapod's robot file gives no strut travel; the .ini only MAX_LIMIT (31 in).
    The report's view, opened at the first problem (a strut beyond 31 in), colours exactly the
    struts longer than 787.4 mm as beyond their travel, shows each travel as "up to 787.4 mm",
    and says the travel comes from the robot file and that .ini."""
    program = tmp_path / "p.csv"
    program.write_text("x,y,z,roll,pitch,yaw,feed\n0,0,508,0,0,0,60\n0,0,560,0,0,0,60\n")
    ini = tmp_path / "machine.ini"
    ini.write_text(ini_text(maximum=31.0, velocity=100.0, acceleration=10000.0))
    report = tmp_path / "report.html"
    assert main(["check-path", "linuxcnc_hexapod", str(program), "--ini", str(ini), "--html", str(report),
                 "--json", str(tmp_path / "r.json")]) == 1
    first = json.loads((tmp_path / "r.json").read_text())["problems"][0]
    assert first["kind"] == "travel"
    seen, console = in_browser(report, tmp_path)
    assert console == [] and seen["ready"] == "1"
    lengths = strut_lengths([first["pose"]])[0]
    assert seen["joints"]["joints"] == pytest.approx(lengths, abs=1e-6)
    beyond = [length > 31.0 * INCH for length in lengths]
    assert any(beyond)
    assert [limb["status"] for limb in seen["drawing"]["limbs"]] == ["limits" if over else "good" for over in beyond]
    assert seen["travel"].split("|") == [f"up to {31.0 * INCH:g} mm"] * 6
    assert f"travel from the robot file and {ini}" in seen["about"]


def test_calibrates_report_draws_its_arrows_and_ghost_in_a_real_browser(tmp_path):
    """30 exact measurements of the hexapod with one leg's base point 0.4 mm off: the report's view
    starts, writes the nominal machine's joints at home (the reference's), states the factors, and
    shows no label over another."""
    from kingen.calibrate.identification import region_poses
    from kingen.calibrate.measurements import write_measurements
    from kingen.calibrate.prediction import synthesize
    from kingen.conventions import t6_from_pose
    from kingen.kinematics.reference import solve

    robot = load_robot("hexapod")
    parameters = Parameters(robot, "pose", frame=[100.0, -50.0, 20.0, 1.0, -2.0, 15.0])
    truth = parameters.nominal.copy()
    truth[parameters.names.index(f"{robot.joint_names[2]}.base_point.x")] += 0.4
    poses = region_poses(robot, 120, 3)
    poses = poses[solve(robot, t6_from_pose(poses)).warnings[:, robot.working_posture] == 0][:30]
    joints, measured = synthesize(parameters, truth, poses, robot.working_posture)
    (tmp_path / "measured.csv").write_text(write_measurements(robot, "pose", joints, measured))
    assert main(["calibrate", "hexapod", "--measurements", str(tmp_path / "measured.csv"), "-o",
                 str(tmp_path / "out")]) == 0
    report = tmp_path / "out" / "report.html"
    text = html.unescape(report.read_text())
    assert re.search(r"residuals after calibration \(predicted - measured\) as arrows at the measured points, "
                     r"drawn [\d,]+ times longer; the calibrated machine as a ghost, its geometry changes drawn "
                     r"[\d,]+ times larger", text)
    seen, console = in_browser(report, tmp_path)
    home = solve(robot, t6_from_pose(robot.verification.home)).joints[0, :, robot.working_posture]
    assert console == [] and seen["ready"] == "1" and seen["canvas"] == "1"
    assert seen["joints"]["joints"] == pytest.approx(home, abs=1e-9)
    shown, overlapping = map(int, seen["labels"].split())
    assert shown >= 1 and overlapping == 0  # a label that would cover another is hidden


def test_analyzes_report_draws_its_tilt_surface_in_a_real_browser(tmp_path):
    """CEART's report at a coarse step: the view starts and writes the reference's joints at home,
    its timeline says it holds the 8 azimuths' limits, and no label covers another."""
    from kingen.conventions import t6_from_pose
    from kingen.kinematics.reference import solve

    assert main(["analyze", "ceart", "--azimuth-step", "45", "--tilt-step", "2", "-o", str(tmp_path / "out")]) == 0
    report = tmp_path / "out" / "report.html"
    assert "the largest tilt towards each of 8 azimuths as a surface" in report.read_text()
    seen, console = in_browser(report, tmp_path)
    robot = load_robot("ceart")
    home = solve(robot, t6_from_pose(robot.verification.home)).joints[0, :, robot.working_posture]
    assert console == [] and seen["ready"] == "1" and seen["canvas"] == "1"
    assert seen["joints"]["joints"] == pytest.approx(home, abs=1e-9)
    assert seen["frame"] == "as it opened; move the slider to see the 8 frames"  # one per azimuth's limit
    assert int(seen["labels"].split()[1]) == 0


def test_a_five_axis_programs_frames_hold_the_tool_poses_it_commands(tmp_path):
    """G-code on the Exechon with a wrist (LinuxCNC's interpreter): along line 3, from X0 Y50 Z-1450
    A20 C30 to X50 Y20 Z-1400 A25 C60, every frame's tool tip is on the segment and its tool axis
    is Rz(C) Rx(A) w0 (w0 the home tool axis) at the same fraction of the move (Rodrigues here)."""
    from test_check_path import needs_interpreter

    needs_interpreter()
    program = tmp_path / "inside.ngc"
    program.write_text("G21 G90\nG1 F2000 X0 Y50 Z-1450 A20 C30\nG1 X50 Y20 Z-1400 A25 C60\nM2\n")
    robot = load_robot("exechon_wrist")
    frames = [frame for frame in playback(check_program(robot, program))["frames"] if frame["line"] == 3]
    start, end = np.array([0.0, 50.0, -1450.0]), np.array([50.0, 20.0, -1400.0])
    home = np.array(robot.verification.home, dtype=float)
    w0 = (rodrigues([0, 0, 1], home[5]) @ rodrigues([0, 1, 0], home[4]) @ rodrigues([1, 0, 0], home[3]))[:, 2]
    assert len(frames) > 10
    for frame in frames:
        pose = np.array(frame["pose"])
        fraction = (pose[0] - start[0]) / (end[0] - start[0])
        assert pose[:3] == pytest.approx(start + fraction * (end - start), abs=1e-6)
        a, c = 20.0 + 5.0 * fraction, 30.0 + 30.0 * fraction
        turned = rodrigues([0, 0, 1], pose[5]) @ rodrigues([0, 1, 0], pose[4]) @ rodrigues([1, 0, 0], pose[3])
        assert turned[:, 2] == pytest.approx(rodrigues([0, 0, 1], c) @ rodrigues([1, 0, 0], a) @ w0, abs=1e-9)


def test_check_paths_view_counts_its_problems_in_words(tmp_path):
    """The view's heading counts what the timeline marks in words: "no problem to mark" on a clean
    program, else the problems' number (one in the singular): the sample hexapod past 31 in."""
    from kingen.cli.report_views import path_view

    program = tmp_path / "p.csv"
    ini = tmp_path / "machine.ini"
    ini.write_text(ini_text(maximum=31.0, velocity=100.0, acceleration=10000.0, joints=6))
    for rows in ("0,0,508,0,0,0,60\n0,0,520,0,0,0,60\n", "0,0,508,0,0,0,60\n0,0,560,0,0,0,60\n"):
        program.write_text("x,y,z,roll,pitch,yaw,feed\n" + rows)
        outcome = check_program(load_robot("linuxcnc_hexapod"), program, CheckSettings(ini=ini))
        count = len(outcome.findings.sorted_problems())
        expected = (f"{count} problem{'s' if count > 1 else ''} numbered on the timeline" if count
                    else "no problem to mark on the timeline")
        assert re.search(r"[\d,]+ frames along the program, " + re.escape(expected), html.unescape(path_view(outcome)))
