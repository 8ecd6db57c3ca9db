"""The command line: outputs, JSON contract, exit codes, one-line errors, no partial files."""

import json
import subprocess
import sys

import pytest

from kingen.cli import GC_FIRST_THRESHOLD, main

JSON_KEYS = {"robot", "samples", "postures", "max_abs_error_mm", "max_abs_error_rad", "warning_mismatches",
             "golden_checked", "golden_failed", "passed"}


def run(capsys, *argv):
    code = main(list(argv))
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_list_shows_every_shipped_robot(capsys):
    code, out, _ = run(capsys, "list")
    assert code == 0
    assert any(line.split()[:3] == ["ceart", "6", "64"] for line in out.splitlines())
    assert any(line.split()[:5] == ["tau", "3", "8", "3", "rail"] for line in out.splitlines())
    assert any(line.split()[:7] == ["tricept_wrist3", "6", "2", "3", "leg", "+", "3-axis"] for line in out.splitlines())


@pytest.mark.parametrize("columns", ["60", "80", "132"])
def test_list_fits_the_terminal_and_gives_pipes_whole_descriptions(capsys, monkeypatch, columns):
    from kingen.robot.model import load_robot

    monkeypatch.setenv("COLUMNS", columns)
    _, out, _ = run(capsys, "list")
    lead = out.splitlines()[0].index("description")  # 20 description characters at least
    assert max(len(line) for line in out.splitlines()) <= max(int(columns), lead + 20)
    assert "..." in out
    monkeypatch.delenv("COLUMNS")
    _, out, _ = run(capsys, "list")
    assert " ".join(load_robot("ceart").description.split()) in out


@pytest.mark.parametrize("argv", [["--version"], ["--help"], ["info", "--help"]])
def test_help_and_version_load_no_heavy_module(argv):
    """Start-up: the command line loads numpy, pydantic, jinja2 and cffi only for commands
    that use them."""
    probe = ("import sys; from kingen.cli import main; code = main(sys.argv[1:]); "
             "print(sorted(m for m in ('numpy', 'pydantic', 'jinja2', 'cffi', 'ruamel.yaml') if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", probe, *argv], capture_output=True, text=True, check=True)
    assert done.stdout.splitlines()[-1] == "[]"


@pytest.mark.parametrize("argv", [[], ["--help"]])
def test_help_is_multi_line_and_says_what_kingen_is(capsys, argv):
    """``kingen`` alone prints the same help as ``kingen --help``: line by line (no escaped
    newlines), naming both hosts and what else kingen does."""
    code, out, _ = run(capsys, *argv)
    assert code == 0 and "<U+000A>" not in out
    lines = out.splitlines()
    assert lines[0] == "Usage: kingen [OPTIONS] COMMAND [ARGS]..."
    text = " ".join(out.split())
    assert ("verified inverse-kinematics routines for DELMIA V5 / IGRIP, LinuxCNC and your own controller (a C "
            "library), with forward kinematics, analysis, design optimisation, calibration from measurements and path "
            "checking.") in text
    assert all(any(line.split()[:1] == [name] for line in lines) for name in ("optimize", "calibrate", "check-path"))


def test_a_robot_of_one_posture_is_counted_in_the_singular(capsys, tmp_path):
    """The hexapod has one posture: verify says '1 solution' and '1 posture', never '1 solutions'."""
    code, out, _ = run(capsys, "verify", "hexapod", "--samples", "200", "-o", str(tmp_path))
    assert code == 0
    assert "answers 'kin_hexapod' with 6 joints, 1 solution, hint 0" in out
    assert "worst error (1 posture: " in out
    assert "1 solutions" not in out and "1 postures" not in out


def test_the_executable_collects_garbage_rarely_and_freezes_it_before_exiting():
    """kingen.cli.run, the executable's entry point: the youngest generation collected every
    GC_FIRST_THRESHOLD allocations during the command, everything left frozen at its end,
    the command's exit code kept; main() (in-process callers) changes neither."""
    probe = ("import atexit, gc, sys; from kingen import cli; "
             "atexit.register(lambda: print(gc.get_threshold()[0], gc.get_freeze_count() > 0)); "
             "cli.main(['list']); print(gc.get_threshold()[0], gc.get_freeze_count()); cli.run()")
    done = subprocess.run([sys.executable, "-c", probe, "nosuchcommand"], capture_output=True, text=True)
    assert done.returncode == 2 and "nosuchcommand" in done.stderr
    assert done.stdout.splitlines()[-2:] == ["700 0", f"{GC_FIRST_THRESHOLD} True"]


def test_render_writes_only_the_source(capsys, tmp_path):
    code, out, _ = run(capsys, "render", "tau", "-o", str(tmp_path))
    assert code == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kin_tau.c"]
    assert "generated file, do not edit" in (tmp_path / "kin_tau.c").read_text().lower()


def test_build_writes_library_and_source_then_caches(capsys, tmp_path):
    code, out, _ = run(capsys, "build", "hexapod", "-o", str(tmp_path))
    assert code == 0 and "compiled" in out
    assert (tmp_path / "libhexapod.so").is_file() and (tmp_path / "kin_hexapod.c").is_file()
    code, out, _ = run(capsys, "build", "hexapod", "-o", str(tmp_path))
    assert code == 0 and "up to date" in out


def test_solve_tau_prints_eight_postures_with_reference(capsys, tmp_path):
    code, out, _ = run(capsys, "solve", "tau", "-o", str(tmp_path), "--pose", "-1200", "-750", "-1900", "0", "0", "0")
    assert code == 0
    rows = [line.split() for line in out.splitlines()[1:9]]
    assert [row[1] for row in rows] == ["000", "001", "010", "011", "100", "101", "110", "111"]
    for row in rows:
        assert row[2:6] == row[7:11]  # plugin columns equal the reference columns
    assert "routine returned 0" in out.splitlines()
    assert out.splitlines()[-1].startswith("direct index: not available (3 limbs")


def test_solve_accepts_t6(capsys, tmp_path):
    t6 = ["1", "0", "0", "0", "0", "1", "0", "0", "0", "0", "1", "0", "100", "50", "-1250", "1"]
    code, out, _ = run(capsys, "solve", "exechon", "-o", str(tmp_path), "--t6", *t6)
    assert code == 0
    published = [-24.8915, 36.1332, 5.6258]
    row = out.splitlines()[1].split()
    assert [float(v) for v in row[2:5]] == pytest.approx(published, abs=5e-5)
    assert row[2:5] == row[7:10]


def test_verify_json_contract(capsys, tmp_path):
    report = tmp_path / "report.json"
    code, out, _ = run(capsys, "verify", "exechon", "-o", str(tmp_path / "b"), "--samples", "500", "--json", str(report))
    assert code == 0 and "PASSED" in out
    data = json.loads(report.read_text())
    assert JSON_KEYS <= set(data)
    assert data["passed"] is True and data["samples"] == 500 and data["golden_checked"] == 2
    assert data["max_abs_error_mm"] <= 1e-9


def test_verify_gives_the_same_report_whatever_its_processes(capsys, tmp_path):
    reports = []
    for processes in ("1", "3"):
        path = tmp_path / f"{processes}.json"
        code, out, _ = run(capsys, "verify", "tau", "-o", str(tmp_path / "b"), "--samples", "20000",
                           "--processes", processes, "--json", str(path))
        assert code == 0, out
        data = json.loads(path.read_text())
        assert data["processes"] == int(processes) and f"{processes} process" in out
        reports.append({key: value for key, value in data.items() if key not in ("seconds", "poses_per_second",
                                                                                    "processes")})
    assert reports[0] == reports[1]


def test_verify_fails_with_exit_1_on_a_wrong_golden_value(capsys, tmp_path):
    from kingen.robot.model import robots_dir
    text = (robots_dir() / "exechon.yaml").read_text().replace("-24.8915", "-24.9915")
    path = tmp_path / "exechon.yaml"
    path.write_text(text)
    code, out, _ = run(capsys, "verify", str(path), "-o", str(tmp_path / "b"), "--samples", "100")
    assert code == 1
    assert "FAILED golden[0]: DELMIA V5 methodology thesis" in out and "FAILED (1 of " in out


BAD_CALLS = [
    (["verify", "nonexistent"], "no shipped robot of that name"),
    (["render", "nonexistent"], "no shipped robot of that name"),
    (["build", "nonexistent"], "no shipped robot of that name"),
    (["solve", "nonexistent", "--pose", "0", "0", "0", "0", "0", "0"], "no shipped robot of that name"),
    (["solve", "tau"], "give exactly one of --pose and --t6"),
    (["solve", "tau", "--pose", "1", "2"], "--pose"),
    (["verify", "tau", "--samples", "0"], "--samples"),
    (["verify", "tau", "--processes", "0"], "--processes"),
    (["verify", "tau", "--processes", "17"], "--processes"),
    (["frobnicate"], "No such command"),
    (["verify"], "Missing argument"),
]


@pytest.mark.parametrize("argv, fragment", BAD_CALLS, ids=[" ".join(c[0]) for c in BAD_CALLS])
def test_usage_and_input_errors_exit_2_with_one_line(capsys, argv, fragment):
    code, out, err = run(capsys, *argv)
    assert code == 2
    assert err.count("\n") == 1 and err.startswith("kingen: error: ") and fragment in err, err


@pytest.mark.parametrize("command", ["render", "build", "verify", "solve"])
def test_invalid_yaml_writes_nothing(capsys, tmp_path, command):
    path = tmp_path / "bad.yaml"
    path.write_text("name: bad\ndescription: x\nlimbs: []\nverification: {home: [0,0,0,0,0,0], range: [0,0,0,0,0,0]}\n")
    out_dir = tmp_path / "out"
    extra = ["--pose", "0", "0", "0", "0", "0", "0"] if command == "solve" else []
    code, _, err = run(capsys, command, str(path), "-o", str(out_dir), *extra)
    assert code == 2
    assert err.startswith(f"kingen: error: {path}:3: limbs: List should have at least 1 item")
    assert not out_dir.exists()


def test_missing_compiler_is_a_one_line_error(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("CC", "no-such-compiler-kingen")
    code, _, err = run(capsys, "build", "tau", "-o", str(tmp_path))
    assert code == 2
    assert "C compiler 'no-such-compiler-kingen' not found" in err and err.count("\n") == 1
    assert list(tmp_path.iterdir()) == []


def test_console_script_runs_without_traceback(tmp_path):
    result = subprocess.run([sys.executable, "-m", "kingen.cli", "verify", str(tmp_path / "missing.yaml")],
                            capture_output=True, text=True)
    assert result.returncode == 2
    assert "Traceback" not in result.stderr and result.stderr.count("\n") == 1
