"""The hand-written floors of benchmarks/ honour the contract the generated routines do
(so comparing them is fair), and `kingen bench --floor` reports the comparison. Speeds
are printed by benchmarks/run.py, never asserted here."""

import json
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
