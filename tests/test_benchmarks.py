"""The hand-written floors of benchmarks/ honour the contract the generated routines do
(so comparing them is fair), and `kingen bench --floor` reports the comparison; run.py renders
every section of the performance page from saved figures. Speeds are printed by
benchmarks/run.py, never asserted here."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from kingen.cli import main

FLOORS = Path(__file__).resolve().parent.parent / "benchmarks" / "floors"
ROBOTS = sorted(path.stem for path in FLOORS.glob("*.c"))


def test_every_limb_family_and_every_direct_index_robot_has_a_floor():
    """One floor per limb family (crank, leg, rail, legs with travel limits), and one for every
    shipped robot with a direct-index threshold, where the generated code's speed matters most."""
    assert ROBOTS == ["ceart", "exechon", "flexapod", "hexapod", "iwf", "rus_optimized", "tau"]


@pytest.mark.parametrize("robot", ROBOTS)
def test_the_floor_passes_verify(robot, capsys, tmp_path):
    code = main(["verify", robot, "--source", str(FLOORS / f"{robot}.c"), "-o", str(tmp_path), "--samples", "3000"])
    assert code == 0, capsys.readouterr().out


def test_the_floor_passes_verify_with_calibration(capsys, tmp_path):
    code = main(["verify", "tau", "--source", str(FLOORS / "tau.c"), "-o", str(tmp_path), "--samples", "3000",
                 "--link-lengths", "1500.5", "1499", "0", "0", "0", "0", "--link-offsets", "3", "-2", "1", "0", "0", "0"])
    assert code == 0, capsys.readouterr().out


def test_bench_against_a_floor_prints_and_writes_the_ratio(capsys, tmp_path):
    figures = tmp_path / "bench.json"
    code = main(["bench", "exechon", "--floor", str(FLOORS / "exechon.c"), "-o", str(tmp_path / "build"),
                 "--calls", "2000", "--json", str(figures)])
    out = capsys.readouterr().out
    assert code == 0
    assert "against the floor" in out and "ratio:" in out
    against = json.loads(figures.read_text())["against_floor"]
    for label in ("floor", "routine"):
        assert 0 < against[label]["min"] <= against[label]["median"]
    assert against["ratio_min"] == pytest.approx(against["routine"]["min"] / against["floor"]["min"])


@pytest.mark.parametrize("text, code, message", [
    (None, 2, "Invalid value for '--floor'"),
    ("int broken(\n", 2, "does not compile"),
    ('#include "shlibdefs.h"\nint nothing;\n', 1, "does not export get_kin_config"),
])
def test_a_bad_floor_is_one_line_and_no_figures(text, code, message, capsys, tmp_path):
    floor = tmp_path / "floor.c"
    if text is not None:
        floor.write_text(text)
    figures = tmp_path / "bench.json"
    assert main(["bench", "exechon", "--floor", str(floor), "-o", str(tmp_path / "build"), "--calls", "1000",
                 "--json", str(figures)]) == code
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert not figures.exists()


SECTION_FIGURES = {
    "calibrate": {
        "hexapod": {"poses": 30, "held_out": 200, "before_um": 1226.0, "before_urad": 3100.0, "after_um": 6.98,
                    "after_urad": 23.7, "converged": True, "identified": 42, "condition_number": 812.5, "seconds": 0.4},
        "planning": {"poses": 30, "parameters": 36, "planned_median_um": 3.1,
                     "draws": [{"random_median_um": 6.2, "ratio_of_medians": 2.0, "median_of_ratios": 1.94}]},
        "positions": [{"robot": "tau", "perturbed": "link lengths 1 mm", "poses": 30, "held_out": 200,
                       "before_um": 940.0, "after_um": 6.9}],
        "constrained": [{"robot": "prs_head", "parameters": 45, "identified": 30, "poses": 30, "held_out": 200,
                         "before_um": 165.9, "before_urad": 776.3, "after_um": 6.7, "after_urad": 21.3,
                         "within_3_sigma": 29, "judged": 30, "converged": True, "seconds": 0.5,
                         "runs": 2, "least": 0.5, "median": 1.0}],
        "speed": {"poses": 50, "repeats": 3, "identify_s": 0.3, "planning_s": 2.6}},
    "calibrate_montecarlo": {
        "robot": "hexapod", "seeds": 3, "poses": 30, "parameters": 42, "draws": 126, "rms_z": 0.987,
        "least_coverage": 2 / 3, "least_covered": "leg1.base_point.x", "beyond": 1, "beyond_expected": 0.34,
        "beyond_likely": 3, "beyond_likely_independent": 2, "worst_z": 3.2, "parameter_rms_z": [0.5, 1.6],
        "variance_factor": [0.9, 1.0, 1.1], "evaluations": [9, 12], "outliers": 0, "seconds": 20.0},
    "c_host": {
        "calls": 2000, "single_calls": 3000, "forward_poses": 100,
        "inverse": [{"robot": "tau", "postures": 8, "delmia": {"min": 40.0, "median": 50.0},
                     "c": {"min": 44.0, "median": 52.5}, "single_median": 70.0, "single_worst": 1402.0}],
        "forward": [{"robot": "tau", "poses": 84, "linuxcnc": 400.0, "c": 300.0, "linuxcnc_failed": 0, "c_failed": 1}],
        "package": {"robot": "tau", "steps": [["kingen package", 2.0], ["cmake configure", 0.5]],
                    "failed": "cmake configure failed:\nno compiler\n"},
        "instructions": [{"robot": "tau", "delmia": 800.0, "c": 760.0}]},
    "hybrid": {"calls": 2000, "rounds": 3, "baseline": "hexapod", "reference": "linuxcnc_hexapod",
               "load_average": [1.5, 1.25, 1.0],
               "rows": [{"host": "delmia", "robot": "hexapod", "ns": 231.1, "ratio": 1.0, "reference_ratio": 2.5},
                        {"host": "linuxcnc", "robot": "exechon_wrist", "ns": 333.6, "ratio": 1.44, "reference_ratio": 3.61}]},
    "check_path": {
        "samples": 2000, "moves": 2,
        "speed": [{"robot": "hexapod", "long": {"samples": 2573, "moves": 3, "seconds": 0.02, "problems": 0, "peak_mb": 91.6},
                   "short": {"samples": 1002, "moves": 1, "seconds": 0.01, "problems": 0, "peak_mb": 91.5},
                   "short_moves": {"samples": 401, "moves": 200, "seconds": 0.3, "problems": 0, "peak_mb": 91.7},
                   "long_routine": {"samples": 2573, "moves": 3, "seconds": 0.05, "problems": 0, "peak_mb": 95.0}}],
        "grazing": {"set up": 2, "found": 2, "more at finer chord": 0, "regular samples alone": 0}},
    "loads": {"loads": [{"robot": "hexapod", "poses": 1000, "postures": 1, "reference_s": 0.01, "loads_s": 0.02,
                         "ratio": 2.0}],
              "check_path": {"rows": 100, "plain_s": 1.0, "loads_s": 1.1, "ratio": 1.1}},
    "ncfiles": {"robot": "linear_delta", "programs": [
        {"program": "arcspiral.ngc", "rs274": True, "exit": 0, "seconds": 1.25, "motions": 1005, "moves": 1004,
         "samples": 61234},
        {"program": "cone.ngc", "rs274": False, "exit": 2, "seconds": 0.5, "motions": None, "moves": None,
         "samples": None}]},
    "planner": {"blends": [{"line": 2, "linuxcnc": 20.59, "planner": 20.56, "rest_to_rest": 21.82,
                            "planner_error": 0.002, "rest_to_rest_error": 0.06}]},
    "view": {"changes": 300, "load_average": 1.5, "pages": [
        {"robot": "tau", "bytes": 772522, "load_ms": 100.4, "changes": 300, "median_ms": 1.0, "p95_ms": 3.2,
         "max_ms": 7.3, "over_50_ms": 0, "routine_median_ms": 0.0, "routine_max_ms": 1.9}]},
    "wasm_host": {"rounds": 2, "calls": 1000, "verify": [{"robot": "tau", "c": [1.8, 2.2], "wasm": [1.4, 2.1]}],
                  "inverse": [{"robot": "tau", "postures": 8, "c": {"min": 36.6, "median": 62.8},
                               "wasm": {"min": 109.4, "median": 150.7}}]},
}
"""Small figures of every section of benchmarks/sections.py, in the shapes their scripts write."""


def test_render_only_renders_every_section_from_saved_figures(tmp_path):
    """run.py --render-only writes the page from a figures file alone: every section's heading,
    the command, date and machine behind it, and its figures as its script renders them."""
    root = Path(__file__).resolve().parent.parent
    sys.path.insert(0, str(root / "benchmarks"))
    try:
        from sections import SECTIONS
    finally:
        sys.path.remove(str(root / "benchmarks"))
    assert set(SECTION_FIGURES) == set(SECTIONS)
    saved = json.loads((root / "benchmarks" / "results" / "performance.json").read_text())
    core = {key: saved[key] for key in ("date", "machine", "calls", "floors", "verify", "startup", "pytest", "seconds")}
    runs = {name: {"command": f"python benchmarks/{name}.py --small", "date": "2000-01-02", "machine": f"machine of {name}",
                   "seconds": 12.0, "figures": figures} for name, figures in SECTION_FIGURES.items()}
    figures, page = tmp_path / "figures.json", tmp_path / "performance.md"
    figures.write_text(json.dumps({**core, "sections": runs}))
    done = subprocess.run([sys.executable, str(root / "benchmarks" / "run.py"), "--render-only", "--figures", str(figures),
                           "--page", str(page)], capture_output=True, text=True, env={**os.environ, "PYTHONPATH": str(root)})
    assert done.returncode == 0, done.stderr
    text = page.read_text()
    for name, (_, _, title) in SECTIONS.items():
        assert f"\n## {title}\n" in text
        assert f"`python benchmarks/{name}.py --small`, run on 2000-01-02 in 12 s; machine: machine of {name}." in text
    assert "| after | 6.98 | 23.70 |" in text and f"{100 * (1 - 6.98 / 1226):.2f} %" in text
    assert "| 0.987 | 0.50, 1.60 | 66.7 % (leg1.base_point.x) | 1 (0.3, 3, 2) | 3.20 |" in text
    assert "| linuxcnc | exechon_wrist | 333.6 | 1.44 | 3.61 |" in text and "at the end: 1.50, 1.25, 1.00." in text
    assert f"| tau | 8 | 50.0 | 52.5 | {52.5 / 50:.3f} | {44 / 40:.3f} | 70 ns | 1,402 ns |" in text
    assert f"| tau | 84 | 400 | 300 | {300 / 400:.3f} | 0 | 1 |" in text
    assert "| total | 2.50 |" in text and "no compiler" in text and f"| {760 / 800:.3f} |" in text
    assert f"{saved['floors'][0]['ratio_min']:.2f}" in text
    assert "| `arcspiral.ngc` | reads | 0 | 1.25 | 1005 | 1004 | 61234 |" in text
    assert "| `cone.ngc` | refuses | 2 | 0.50 | - | - | - |" in text
    assert "| blends | 2 | 20.6 | 20.6 | 21.8 | 0.2 % | 6.0 % |" in text and "the planner model's 0.2 %" in text
    assert f"| hexapod | 2573 | 0.0 | {2573 / 0.02:,.0f} | 92 MB | 1002, 92 MB | 200 in 0.3 s | 0.1 |" in text
    assert "grazes set up: 2; seen by the regular samples alone: 0; found by check-path at the default chord: 2" in text


def test_only_refuses_an_unknown_section_and_measures_nothing(tmp_path):
    root = Path(__file__).resolve().parent.parent
    figures, page = tmp_path / "figures.json", tmp_path / "performance.md"
    done = subprocess.run([sys.executable, str(root / "benchmarks" / "run.py"), "--only", "hybrid,nosuch",
                           "--figures", str(figures), "--page", str(page)], capture_output=True, text=True,
                          env={**os.environ, "PYTHONPATH": str(root)})
    assert done.returncode == 2
    assert "--only: no section nosuch (sections: core, " in done.stderr.splitlines()[-1]
    assert not figures.exists() and not page.exists()


def test_render_only_without_saved_figures_says_so_and_writes_nothing(tmp_path):
    root = Path(__file__).resolve().parent.parent
    figures, page = tmp_path / "figures.json", tmp_path / "performance.md"
    done = subprocess.run([sys.executable, str(root / "benchmarks" / "run.py"), "--render-only",
                           "--figures", str(figures), "--page", str(page)], capture_output=True, text=True,
                          env={**os.environ, "PYTHONPATH": str(root)})
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert done.stderr.splitlines()[-1].endswith(f"no saved figures in {figures}: measure them first (without "
                                                 "--render-only)")
    assert not page.exists()
