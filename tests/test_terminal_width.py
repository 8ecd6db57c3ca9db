"""solve and verify fit their lines to the terminal's width ($COLUMNS); --wide and a pipe keep
solve's full table."""

import pytest

from kingen.cli import main
from kingen.cli.common import table_lines

TAU_POSE = ["--pose", "-1200", "-750", "-1900", "0", "0", "0"]


def run(capsys, *argv):
    code = main(list(argv))
    return code, capsys.readouterr().out


def test_solve_fits_80_columns(capsys, monkeypatch, tmp_path):
    monkeypatch.setenv("COLUMNS", "80")
    code, out = run(capsys, "solve", "hexapod", "-o", str(tmp_path), "--pose", "0", "0", "1000", "0", "0", "0")
    assert code == 0
    lines = out.splitlines()
    assert max(map(len, lines)) <= 80
    assert lines[0].split() == ["posture", "branches", *[f"leg{i}" if j % 2 == 0 else "(mm)"
                                                         for i in range(1, 5) for j in range(2)]]
    assert "max |plugin - reference|" in out and "reference warning" in out
    assert "routine returned 0" in lines
    assert any(line.startswith("direct index: 0 at a direct (platform) singularity") for line in lines)


def test_solve_switch_prediction_fits_80_columns(capsys, monkeypatch, tmp_path):
    monkeypatch.setenv("COLUMNS", "80")
    code, out = run(capsys, "solve", "tau", "-o", str(tmp_path), *TAU_POSE, "--switch", "0", "7")
    assert code == 0
    assert max(map(len, out.splitlines())) <= 80
    assert "switch 0 -> 7: the joints move by carriage1 +1822.449573 mm" in out


def test_solve_wide_gives_the_full_table(capsys, monkeypatch, tmp_path):
    monkeypatch.setenv("COLUMNS", "80")
    code, wide = run(capsys, "solve", "tau", "-o", str(tmp_path), *TAU_POSE, "--wide")
    assert code == 0
    header = wide.splitlines()[0]
    assert len(header) > 80 and "| reference" in header and header.endswith("min inverse index")
    monkeypatch.delenv("COLUMNS")
    code, piped = run(capsys, "solve", "tau", "-o", str(tmp_path), *TAU_POSE)
    assert code == 0 and piped == wide  # not a terminal, no $COLUMNS: the full table, as before


def test_verify_fits_80_columns_keeping_each_checks_first_words(capsys, monkeypatch, tmp_path):
    monkeypatch.setenv("COLUMNS", "80")
    monkeypatch.chdir(tmp_path)  # a short library path: a path is never split
    code, out = run(capsys, "verify", "exechon", "-o", "b", "--samples", "200")
    assert code == 0
    lines = out.splitlines()
    assert max(map(len, lines)) <= 80
    for name in ("values", "warnings", "round trip", "machine"):
        assert any(line.startswith(f"  ok     {name}: ") for line in lines)
    assert lines[-1].startswith("PASSED")
    continued = [line for line in lines if line.startswith("         ") and not line.strip().startswith("diagnosis")]
    assert continued  # long details wrap onto indented lines


def test_table_wraps_into_blocks_led_by_the_first_column():
    rows = [["k", "a" * 30, "b" * 30, "c" * 30], ["0", "1", "2", "3"]]
    lines = table_lines(rows, 70)
    assert lines == ["k  " + "a" * 30 + "  " + "b" * 30, "0  1" + " " * 31 + "2", "", "k  " + "c" * 30, "0  3"]
    assert table_lines(rows, None) == table_lines(rows, 200)
    assert len(table_lines(rows, None)) == 2


@pytest.mark.parametrize("columns", ["", "0", "wide"])
def test_unusable_columns_mean_no_limit(capsys, monkeypatch, tmp_path, columns):
    monkeypatch.setenv("COLUMNS", columns)
    code, out = run(capsys, "solve", "tau", "-o", str(tmp_path), *TAU_POSE)
    assert code == 0 and "| reference" in out.splitlines()[0]
