"""The workspace analysis: its JSON contract, its geometry, and its report as a person sees
it in a real browser (headless Chromium: not blank, every figure loaded, no console error)."""

import copy
import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from markupsafe import escape

from conftest import require_tool
from kingen.design.analysis import CAUSES
from kingen.kinematics.collision import segment_distance
from kingen.cli import main
from kingen.cli.common import load_model
from kingen.robot.model import robots_dir
from kingen.design.figures import LABELS, OUTSIDE_LABEL, QUANTITIES, figure_objects, figures, report_html

SWEEP_KEYS = {"value", "warning", "direct_index_mm", "min_inverse_index", "min_rod_distance_mm",
              "min_crank_distance_mm", "joints"}
CURVES = {name for _, curves in QUANTITIES for _, name, *_ in curves}
SCREENSHOTS = Path(__file__).resolve().parent.parent / "build" / "screenshots"
# One worker under -n N: the module's analyses (CEART's takes seconds) are then made once.
pytestmark = pytest.mark.xdist_group("analysis")
CHROMIUM = ["chromium", "--headless", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
            "--disable-quic", "--no-first-run",
            "--disable-background-networking", "--disable-component-update", "--disable-sync"]


def test_segment_distances_written_out_by_hand():
    p1, q1 = np.array([[0.0, 0, 0]] * 3), np.array([[10.0, 0, 0]] * 3)
    p2 = np.array([[5.0, 3, -1], [12.0, 4, 0], [0.0, 0, 2]])
    q2 = np.array([[5.0, 3, 1], [20.0, 4, 0], [10.0, 0, 2]])
    np.testing.assert_allclose(segment_distance(p1, q1, p2, q2), [3.0, np.hypot(2.0, 4.0), 2.0])


@pytest.fixture(scope="module")
def ceart_analysis(tmp_path_factory):
    folder = tmp_path_factory.mktemp("analysis")
    assert main(["analyze", "ceart", "-o", str(folder), "--json", str(folder / "copy.json")]) == 0
    return folder


def test_analysis_json_contract(ceart_analysis):
    data = json.loads((ceart_analysis / "analysis.json").read_text())
    assert {"robot", "posture", "tilt_limits", "sweeps"} <= set(data)
    assert data["robot"] == "ceart" and data["posture"] == 63
    assert [row["azimuth_deg"] for row in data["tilt_limits"]] == list(range(0, 360, 15))
    assert {row["cause"] for row in data["tilt_limits"]} <= set(CAUSES)
    assert set(data["sweeps"]) == {"roll", "pitch", "yaw", "x", "y", "z"}
    assert all(SWEEP_KEYS <= set(entry) for entries in data["sweeps"].values() for entry in entries)
    about_y = data["tilt_limits"][6]
    assert {key: about_y[key] for key in ("azimuth_deg", "max_tilt_deg", "cause")} == {
        "azimuth_deg": 90.0, "max_tilt_deg": 23.9, "cause": "unreachable"}  # derived independently:
    # tests/test_golden_values.py, the cranks reach at +23.9 degrees about Y and not at 24.0
    assert about_y["min_direct_index_mm"] > 29.3  # above CEART's threshold all the way
    assert (ceart_analysis / "copy.json").read_text() == (ceart_analysis / "analysis.json").read_text()


def test_what_a_robot_lacks_is_said_not_failed(tmp_path, capsys):
    assert main(["analyze", "tau", "-o", str(tmp_path)]) == 0
    data = json.loads((tmp_path / "analysis.json").read_text())
    assert data["available"]["direct_index"].startswith("not available: 3 limbs")
    assert data["available"]["collision"].startswith("not available")
    assert all(entry["direct_index_mm"] is None for entry in data["sweeps"]["z"])
    assert data["tilt_limits"] == [] and data["available"]["tilt_limits"].startswith("not analysed")


@pytest.fixture(scope="module")
def analysed(ceart_analysis, tmp_path_factory):
    """The analysis folder of a robot, made once per module (CEART's is the shared one)."""
    folders = {"ceart": ceart_analysis}

    def folder(robot):
        if robot not in folders:
            folders[robot] = tmp_path_factory.mktemp(robot)
            assert main(["analyze", robot, "-o", str(folders[robot])]) == 0
        return folders[robot]

    return folder


@pytest.mark.parametrize("robot", ["ceart", "hexapod", "linear_delta"])
def test_the_report_in_a_real_browser(robot, analysed, tmp_path):
    """Every figure loads, no console error, and a full-page screenshot that is not blank,
    kept as build/screenshots/report-<robot>.png for a person to look at."""
    require_tool("chromium", "chromium")
    folder = analysed(robot)
    page = (folder / "report.html").read_text()
    assert "<script" not in page and 'src="data:image/png;base64,' in page
    probe = tmp_path / "probe.html"
    probe.write_text(page.replace("</body>", """<script>
window.addEventListener("load", function () {
  var images = Array.prototype.slice.call(document.images);
  var loaded = images.filter(function (image) { return image.complete && image.naturalWidth > 0; });
  document.body.setAttribute("data-images", images.length + "/" + loaded.length);
  document.body.setAttribute("data-height", document.documentElement.scrollHeight);
});
</script></body>"""))
    dom = subprocess.run([*CHROMIUM, f"--user-data-dir={tmp_path / 'profile'}", "--enable-logging=stderr", "--v=0",
                          "--virtual-time-budget=5000", "--window-size=1200,900", "--dump-dom", probe.as_uri()],
                         capture_output=True, text=True, timeout=120)
    figures = len(list(folder.glob("*.png")))
    assert f'data-images="{figures}/{figures}"' in dom.stdout
    assert "CONSOLE" not in dom.stderr, dom.stderr
    height = int(re.search(r'data-height="(\d+)"', dom.stdout).group(1))
    shot = tmp_path / f"report-{robot}.png"
    subprocess.run([*CHROMIUM, f"--user-data-dir={tmp_path / 'profile2'}", f"--screenshot={shot}",
                    "--hide-scrollbars", f"--window-size=1200,{height}", (folder / "report.html").as_uri()],
                   capture_output=True, timeout=120)
    import matplotlib.image

    pixels = matplotlib.image.imread(shot)
    assert pixels.shape[:2] == (height, 1200) and float(pixels[..., :3].std()) > 0.05  # not blank
    kept = SCREENSHOTS / shot.name
    kept.parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(shot, kept)
    print(f"screenshot of the {robot} report: {kept}")


def test_a_crossing_of_a_direct_singularity_stops_a_tilt_without_a_threshold(tmp_path):
    """LinuxCNC's sample hexapod sets no direct_index_min; its index falls from 336.7 mm at home
    towards 0 rolling to about -56.5 degrees (tilt about -X): analyze stops there instead of
    reporting no limit, and states the settings and the least index of every tilt."""
    assert main(["analyze", "linuxcnc_hexapod", "-o", str(tmp_path)]) == 0
    data = json.loads((tmp_path / "analysis.json").read_text())
    assert data["settings"]["direct_index_at_home_mm"] == pytest.approx(336.724, abs=1e-3)
    assert data["settings"]["crossing_fraction"] == 0.05
    about_minus_x = next(row for row in data["tilt_limits"] if row["azimuth_deg"] == 180.0)
    assert about_minus_x["cause"] == "direct_singularity" and 50.0 < about_minus_x["max_tilt_deg"] < 56.5
    assert about_minus_x["min_direct_index_mm"] >= 0.05 * 336.724
    assert all(row["min_direct_index_mm"] is not None for row in data["tilt_limits"])
    rolled = {entry["value"]: entry for entry in data["sweeps"]["roll"]}
    assert rolled[-57.0]["cause"] == "direct_singularity" and rolled[0.0]["cause"] == "none"


def congruent_hexapod(folder):
    """The example Stewart-Gough layout with the platform's joints congruent to the base's and
    no travel limits: at home (straight above the base) every leg is vertical, so the six
    force lines cannot resist a horizontal force: a direct singularity (index 0)."""
    text = (robots_dir() / "stewart_gough_example.yaml").read_text()
    for old, new in (("platform_radius: 100", "platform_radius: 150"), ("platform_pair_angle: 100",
                                                                        "platform_pair_angle: 20"),
                     ("  travel: [10, 140]\n", ""), ("name: stewart_gough_example", "name: congruent")):
        assert old in text
        text = text.replace(old, new)
    path = folder / "congruent.yaml"
    path.write_text(text[:text.index("golden:")])
    return path


def test_a_robot_singular_at_home_is_stopped_at_home(tmp_path, capsys):
    """Crossing rules relative to a singular home see nothing: home itself is judged singular,
    every azimuth's tilt limit is 0, and the text, JSON and report say why."""
    assert main(["analyze", str(congruent_hexapod(tmp_path)), "-o", str(tmp_path / "out"),
                 "--tilt-step", "1", "--azimuth-step", "45"]) == 0
    reason = "home is a direct singularity: its direct index is 0 mm, at most 0.00027 mm (1e-06 of the robot's size)"
    assert capsys.readouterr().out.splitlines()[0] == (
        f"analyze congruent, posture 0: {reason}; every azimuth's tilt limit is 0 deg")
    data = json.loads((tmp_path / "out" / "analysis.json").read_text())
    assert data["singular_at_home"] == reason and data["settings"]["det_j_sign_at_home"] == 0.0
    assert [(row["max_tilt_deg"], row["cause"]) for row in data["tilt_limits"]] == [(0.0, "direct_singularity")] * 8
    assert {entry["value"]: entry["cause"] for entry in data["sweeps"]["roll"]}[0.0] == "direct_singularity"
    assert f"<th>singular at home</th><td>{escape(reason)}" in (tmp_path / "out" / "report.html").read_text()


def test_a_robot_regular_at_home_says_so(ceart_analysis):
    assert json.loads((ceart_analysis / "analysis.json").read_text())["singular_at_home"] is None


def delta_like(data):
    """An analysis shaped as the coming ones of a platform that cannot tilt: x, y, z sweeps
    only, no tilt limits, more settings, slices with more keys."""
    shaped = copy.deepcopy(data)
    shaped["sweeps"] = {name: shaped["sweeps"][name] for name in ("x", "y", "z")}
    shaped["tilt_limits"] = []
    shaped["available"]["tilt_limits"] = "not analysed: the platform cannot tilt (free: x, y, z)"
    shaped["settings"].update(azimuth_step_deg=15.0, new_setting="a value nobody planned for")
    for entry in shaped["slices"].values():
        entry["reaches_boundary"] = True
    return shaped


def colliding(data):
    """CEART's analysis with rods 4 mm into each other at the last roll pose."""
    shaped = copy.deepcopy(data)
    shaped["sweeps"]["roll"][-1].update(cause="collision", min_rod_distance_mm=-4.0, min_inverse_index=0.5)
    return shaped


def drawn_labels(figure):
    return {label for axes in figure.axes for label in axes.get_legend_handles_labels()[1]}


def check_figures(analysis):
    """What every figure promises its reader; the figures, for more checks."""
    made = figure_objects(analysis)
    for name, figure in made.items():
        (legend,) = figure.legends  # one legend, the figure's, outside the data
        for axes in figure.axes:
            assert axes.get_legend() is None, name
            assert axes.lines or axes.images, f"{name}: an axis with nothing on it"
        entries = {text.get_text() for text in legend.get_texts()}
        if name == "slices.png":
            present = {LABELS[CAUSES[i]] for data in analysis["slices"].values() for row in data["causes"] for i in row}
            assert entries == present | {OUTSIDE_LABEL}
            assert all(axes.get_aspect() == 1.0 and OUTSIDE_LABEL in drawn_labels(axes.figure) for axes in figure.axes)
        else:
            assert entries == drawn_labels(figure), name
    sweeps = made.get("sweeps.png")
    for axes in sweeps.axes if sweeps else ():
        curves = np.concatenate([line.get_xydata() for line in axes.lines if line.get_label() in CURVES])
        for dots in axes.collections:  # limited poses sit on a curve, never at 0
            for point in dots.get_offsets():
                assert np.any(np.all(np.isclose(curves, point), axis=1)), point
        if not any(line.get_label().startswith("collision") for line in axes.lines):
            assert axes.get_ylim()[0] == 0.0
    return made


def test_the_figures_say_only_what_was_drawn(ceart_analysis):
    data = json.loads((ceart_analysis / "analysis.json").read_text())
    made = check_figures(data)
    assert set(made) == {"tilt_limits.png", "sweeps.png", "slices.png"}
    assert len(made["sweeps.png"].axes) == 18  # three quantities under two rows of three sweeps
    assert "no limit" not in LABELS.values() and LABELS["none"] == "within limits"
    polar = made["tilt_limits.png"].axes[0]
    assert polar.get_ylim() == (0.0, data["settings"]["tilt_max_deg"])

    shaped = delta_like(data)
    made = check_figures(shaped)
    assert set(made) == {"sweeps.png", "slices.png"} and len(made["sweeps.png"].axes) == 9
    page = report_html(load_model("ceart"), shaped, figures(shaped), 1.0)
    assert "Not analysed: the platform cannot tilt (free: x, y, z)." in page and "tilt_limits.png" not in page
    assert all(f"<th>{key}</th>" in page for key in shaped["settings"]) and "a value nobody planned for" in page
    assert "no limit" not in page

    crossed = colliding(data)
    sweeps = check_figures(crossed)["sweeps.png"]
    clearance = [axes for axes in sweeps.axes if axes.get_ylabel() == "clearance (mm)"]
    assert clearance and all(axes.get_ylim()[0] < -4.0 for axes in clearance)


def test_a_robot_without_clearances_draws_only_its_direct_index(analysed):
    data = json.loads((analysed("hexapod") / "analysis.json").read_text())
    sweeps = check_figures(data)["sweeps.png"]
    assert {axes.get_ylabel() for axes in sweeps.axes} == {"direct index (mm)", ""}
    assert len(sweeps.axes) == 6
