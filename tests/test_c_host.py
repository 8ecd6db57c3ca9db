"""The C host (``--host c``): every shipped robot's library verifies through the shared
checks and the host's own (forward, c jacobian); the header and source compile warning-free
as C99 with gcc and clang and as C++17; a hand-written library with the same header is
verified with --plugin, and a wrong one fails; calibration fields are refused, the struct is
the library's calibration."""

import json
import subprocess
from pathlib import Path

import pytest
from kingen.cli import main
from kingen.hosts.c.render import render
from kingen.robot.model import load_robot

from conftest import require_tool

ROBOTS = sorted(path for path in Path(__file__).resolve().parent.parent.glob("robots/*.yaml")
                if not load_robot(path).task)
"""The shipped robots the C library takes: every one but the machines with task coordinates."""
STRICT_C = ("-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Werror")
STRICT_CXX = ("-x", "c++", "-std=c++17", "-Wall", "-Wextra", "-Werror")
COMPILED = ("tau.yaml", "rotary_delta.yaml", "hexapod.yaml", "exechon.yaml")
"""Robots whose library each compiler compiles: every limb model, one and many postures, a
general set of free coordinates."""


class Ran:
    def __init__(self, capsys, *arguments):
        self.exit_code = main([str(argument) for argument in arguments])
        out, err = capsys.readouterr()
        self.output = out + err


@pytest.mark.parametrize("robot", ROBOTS, ids=lambda path: path.stem)
def test_every_shipped_robot_verifies(robot, tmp_path, capsys):
    result = Ran(capsys, "verify", robot, "--host", "c", "--samples", "300", "-o", tmp_path)
    assert result.exit_code == 0, result.output
    checks = ("values", "warnings", "closure", "jacobian", "c jacobian", "round trip", "forward", "determinism")
    verdicts = {}
    for line in result.output.splitlines():
        words = line.split(None, 1)
        if len(words) == 2 and words[0] in ("ok", "FAILED") and ":" in words[1]:
            verdicts[words[1].split(":")[0]] = words[0]
    expected = checks + (("c direct index",) if load_robot(robot).dof == 6 else ())
    assert {check: verdicts.get(check) for check in expected} == {check: "ok" for check in expected}


@pytest.mark.parametrize("name", ["prs_head", "rps_table"])
def test_a_machine_with_task_coordinates_is_refused_in_one_line(name, tmp_path, capsys):
    result = Ran(capsys, "build", name, "--host", "c", "-o", tmp_path / "out")
    assert result.exit_code == 2 and result.output.count("\n") == 1, result.output
    assert result.output.endswith(f"{name}.yaml:{load_robot(name).line_of('task')}: task: the C library does not yet "
                                  "take a machine with task coordinates (its parasitic motion is solved by the delmia "
                                  "and linuxcnc hosts)\n")
    assert not (tmp_path / "out").exists()


def _written(robot_file, folder):
    files = render(load_robot(robot_file))
    for name, text in files.items():
        (folder / name).write_text(text)
    return folder / next(name for name in files if name.endswith(".c"))


@pytest.mark.parametrize("compiler, flags", [("gcc", STRICT_C), ("clang", STRICT_C), ("g++", STRICT_CXX),
                                             ("clang++", STRICT_CXX)])
def test_the_source_compiles_without_a_warning(compiler, flags, tmp_path):
    require_tool(compiler, {"gcc": "gcc", "clang": "clang", "g++": "g++", "clang++": "clang"}[compiler])
    for name in COMPILED:
        source = _written(Path(ROBOTS[0].parent, name), tmp_path)
        done = subprocess.run([compiler, *flags, "-O2", "-c", str(source), "-o", str(tmp_path / "out.o")],
                              capture_output=True, text=True, timeout=120)
        assert done.returncode == 0 and not done.stderr, f"{name}: {done.stderr}"


def test_only_math_h_and_no_mutable_global(tmp_path):
    source = _written(Path(ROBOTS[0].parent, "ceart.yaml"), tmp_path)
    text = source.read_text() + source.with_suffix(".h").read_text()
    assert sorted({line.split()[1] for line in text.splitlines() if line.startswith("#include")}) == [
        '"kingen_ceart.h"', "<math.h>"]
    for word in ("malloc", "printf", "FILE", "stdio"):
        assert word not in text
    nm = subprocess.run(["nm", "--defined-only", str(_object(source, tmp_path))], capture_output=True, text=True)
    writable = [line for line in nm.stdout.splitlines() if line.split()[1] in "BbDdCc"]
    assert writable == []  # no data a call could write: the geometry and tables are read-only


def _object(source, folder):
    out = folder / "library.o"
    subprocess.run(["cc", *STRICT_C, "-O2", "-c", str(source), "-o", str(out)], check=True, timeout=120)
    return out


def test_a_hand_written_library_is_verified_with_plugin(tmp_path, capsys):
    """The generated source, its built-in geometry changed (a carriage's link 1 mm longer), as a
    hand-written library: --plugin verifies it and values and closure fail; unchanged, it passes."""
    source = _written(Path(ROBOTS[0].parent, "tau.yaml"), tmp_path)
    good = tmp_path / "good.so"
    subprocess.run(["cc", "-std=c99", "-O2", "-fPIC", "-shared", str(source), "-o", str(good), "-lm"], check=True)
    result = Ran(capsys, "verify", Path(ROBOTS[0].parent, "tau.yaml"), "--host", "c", "--plugin", good, "--samples", "200")
    assert result.exit_code == 0, result.output
    text = source.read_text()
    assert text.count(" 1500.0, 0.0,") == 2
    source.write_text(text.replace(" 1500.0, 0.0,", " 1501.0, 0.0,", 1))
    wrong = tmp_path / "wrong.so"
    subprocess.run(["cc", "-std=c99", "-O2", "-fPIC", "-shared", str(source), "-o", str(wrong), "-lm"], check=True)
    result = Ran(capsys, "verify", Path(ROBOTS[0].parent, "tau.yaml"), "--host", "c", "--plugin", wrong, "--samples", "200")
    assert result.exit_code == 1
    assert "FAILED values" in result.output and "FAILED closure" in result.output


def test_a_library_without_the_header_functions_is_a_defect(tmp_path, capsys):
    source = tmp_path / "empty.c"
    source.write_text("int kingen_tau_inverse(void) { return 0; }\n")
    result = Ran(capsys, "verify", Path(ROBOTS[0].parent, "tau.yaml"), "--host", "c", "--source", source, "-o", tmp_path)
    assert result.exit_code != 0
    assert "does not export kingen_tau_inverse_posture" in result.output


def test_bench_states_the_median_and_the_worst_call(tmp_path, capsys):
    """The figures' presence and consistency, never their size: the worst call is at least the median."""
    json_path = tmp_path / "bench.json"
    result = Ran(capsys, "bench", Path(ROBOTS[0].parent, "tau.yaml"), "--host", "c", "--calls", "2000",
                 "-o", tmp_path, "--json", json_path)
    assert result.exit_code == 0, result.output
    assert "each call timed singly:" in result.output and "worst of 2,000 calls" in result.output
    figures = json.loads(json_path.read_text())
    assert figures["single_calls"] == 2000 and 0.0 < figures["median_call_ns"] <= figures["worst_call_ns"]
