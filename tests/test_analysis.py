"""The workspace analysis: its JSON contract, its geometry, and its report as a person sees
it in a real browser (headless Chromium: not blank, every figure loaded, no console error)."""

import json
import subprocess

import numpy as np
import pytest

from conftest import require_tool
from kingen.analysis import CAUSES
from kingen.collision import segment_distance
from kingen.cli import main

SWEEP_KEYS = {"value", "warning", "direct_index_mm", "min_inverse_index", "min_rod_distance_mm",
              "min_crank_distance_mm", "joints"}
CHROMIUM = ["chromium", "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
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
        "azimuth_deg": 90.0, "max_tilt_deg": 23.9, "cause": "unreachable"}
    assert about_y["min_direct_index_mm"] > 29.3  # above CEART's threshold all the way
    assert (ceart_analysis / "copy.json").read_text() == (ceart_analysis / "analysis.json").read_text()


def test_what_a_robot_lacks_is_said_not_failed(tmp_path, capsys):
    assert main(["analyze", "tau", "-o", str(tmp_path)]) == 0
    data = json.loads((tmp_path / "analysis.json").read_text())
    assert data["available"]["direct_index"].startswith("not available: 3 limbs")
    assert data["available"]["collision"].startswith("not available")
    assert all(entry["direct_index_mm"] is None for entry in data["sweeps"]["z"])
    assert data["tilt_limits"] == [] and data["available"]["tilt_limits"].startswith("not analysed")


def test_the_report_in_a_real_browser(ceart_analysis, tmp_path):
    require_tool("chromium", "chromium")
    page = (ceart_analysis / "report.html").read_text()
    assert "<script" not in page and 'src="data:image/png;base64,' in page
    probe = tmp_path / "probe.html"
    probe.write_text(page.replace("</body>", """<script>
window.addEventListener("load", function () {
  var images = Array.prototype.slice.call(document.images);
  var loaded = images.filter(function (image) { return image.complete && image.naturalWidth > 0; });
  document.body.setAttribute("data-images", images.length + "/" + loaded.length);
});
</script></body>"""))
    dom = subprocess.run([*CHROMIUM, f"--user-data-dir={tmp_path / 'profile'}", "--enable-logging=stderr", "--v=0",
                          "--virtual-time-budget=5000", "--dump-dom", probe.as_uri()],
                         capture_output=True, text=True, timeout=120)
    assert 'data-images="3/3"' in dom.stdout
    assert "CONSOLE" not in dom.stderr, dom.stderr
    shot = tmp_path / "shot.png"
    subprocess.run([*CHROMIUM, f"--user-data-dir={tmp_path / 'profile2'}", f"--screenshot={shot}",
                    "--window-size=1200,1600", (ceart_analysis / "report.html").as_uri()],
                   capture_output=True, timeout=120)
    import matplotlib.image

    pixels = matplotlib.image.imread(shot)
    assert pixels.shape[:2] == (1600, 1200) and float(pixels[..., :3].std()) > 0.05  # not blank


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
