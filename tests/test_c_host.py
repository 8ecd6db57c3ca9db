"""The C host (``--host c``): every shipped robot's library verifies through the shared
checks and the host's own (forward, c jacobian); the header and source compile warning-free
as C99 with gcc and clang and as C++17; a hand-written library with the same header is
verified with --plugin, and a wrong one fails; calibration fields are refused, the struct is
the library's calibration."""

import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest
from kingen.cli import main
from kingen.conventions import matrix_from_pose, t6_from_pose
from kingen.hosts.c.build import build_library
from kingen.hosts.c.loader import Library
from kingen.hosts.c.render import render
from kingen.kinematics.home import judged_posture
from kingen.kinematics.hybrid.parasitic import on_manifold
from kingen.kinematics.reference import solve
from kingen.kinematics.routine import WARNINGS
from kingen.robot.model import load_robot

from conftest import require_tool

ROBOTS = sorted(Path(__file__).resolve().parent.parent.glob("robots/*.yaml"))
"""Every shipped robot, the machines with task coordinates among them."""
STRICT_C = ("-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Werror")
STRICT_CXX = ("-x", "c++", "-std=c++17", "-Wall", "-Wextra", "-Werror")
LEVELS = ("-O0", "-O1", "-O2", "-O3", "-Os")
"""The optimisation levels a controller's build may use (CMake's Release is -O3, MinSizeRel -Os)."""
EVERY_LEVEL = ("tau", "exechon_constrained", "tricept_wrist3")
"""Robots compiled at every level in CI's form: the closed-form forward of three rails, a machine
with task coordinates, a wrist; every other robot at -O3 (the level gcc's flow analysis warns
at). KINGEN_FULL_SWEEPS=1 compiles every robot at every level."""
FULL_SWEEPS = os.environ.get("KINGEN_FULL_SWEEPS") == "1"


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
    loaded = load_robot(robot)
    expected = (checks + (("c direct index",) if loaded.dof == 6 else ())
                + (("c machine pose",) if loaded.task and loaded.wrist is None else ()))
    assert {check: verdicts.get(check) for check in expected} == {check: "ok" for check in expected}


@pytest.mark.parametrize("name, moved", [("prs_head", (0, 1.0)), ("exechon_constrained", (3, 1.0)), ("tricept", (3, 1.0))])
def test_a_constrained_machine_reads_the_whole_pose_and_its_forward_gives_the_machines(name, moved, tmp_path):
    """The verification home on the machine's manifold (kingen's parasitic solution, in numpy),
    then moved off it (1 mm in x for the planes' family, 1 degree of roll for the axes' and the
    tube's): the library answers the reference's joints and warnings on it and WARN_UNREACHABLE
    for every posture off it, with the same joints (the machine's pose's); its forward from
    these joints, started at the pose off the manifold, returns the machine's pose; its machine
    pose of either is the pose on the manifold (status good), and of a pose holding NaN -1."""
    robot = load_robot(name)
    on = on_manifold(robot, np.array([robot.verification.home], dtype=float))
    off = on.copy()
    off[0, moved[0]] += moved[1]
    built = build_library(robot, tmp_path)
    library = Library(built.library, built.routine, robot)
    poses = matrix_from_pose(np.vstack([on, off])).reshape(-1, 16)
    joints, warnings, returns = library.inverse(poses)
    expected = solve(robot, t6_from_pose(on))
    assert joints[0] == pytest.approx(expected.joints[0], abs=1e-9)
    assert list(warnings[0]) == list(expected.warnings[0])
    assert list(warnings[1]) == [WARNINGS["WARN_UNREACHABLE"]] * robot.postures and list(returns) == [0, 1]
    assert np.array_equal(joints[1], joints[0])
    posture = judged_posture(robot).posture
    found, _, returned = library.forward(joints[:1, :, posture], np.array([posture]), poses[1:])
    assert int(returned[0]) == 0
    assert found[0] == pytest.approx(poses[0], abs=1e-9)
    not_finite = poses[1].copy()
    not_finite[5] = np.nan
    machines, statuses = library.machine_pose(np.vstack([poses, not_finite]))
    assert list(statuses) == [WARNINGS["WARN_GOOD_SOLUTION"]] * 2 + [-1]
    assert machines[0] == pytest.approx(poses[0], abs=1e-9) and machines[1] == pytest.approx(poses[0], abs=1e-9)
    assert np.all(np.isnan(machines[2]))  # not written


def _written(robot_file, folder):
    files = render(load_robot(robot_file))
    for name, text in files.items():
        (folder / name).write_text(text)
    return folder / next(name for name in files if name.endswith(".c"))


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    """{robot's stem: its library's source}, every shipped robot rendered once, each in its folder."""
    sources = {}
    for path in ROBOTS:
        sources[path.stem] = _written(path, tmp_path_factory.mktemp(path.stem))
    return sources


@pytest.mark.parametrize("compiler, flags", [("gcc", STRICT_C), ("clang", STRICT_C), ("g++", STRICT_CXX),
                                             ("clang++", STRICT_CXX)], ids=["gcc-c99", "clang-c99", "g++-c++17",
                                                                            "clang++-c++17"])
def test_the_source_compiles_without_a_warning_at_every_optimisation_level(compiler, flags, rendered, tmp_path):
    """Compiled, not only parsed: gcc's maybe-uninitialized needs the optimiser's flow analysis."""
    require_tool(compiler, {"gcc": "gcc", "clang": "clang", "g++": "g++", "clang++": "clang"}[compiler])
    failures = []
    for stem, source in rendered.items():
        for level in LEVELS:
            if not (FULL_SWEEPS or level == "-O3" or stem in EVERY_LEVEL):
                continue
            done = subprocess.run([compiler, *flags, level, "-c", str(source), "-o", str(tmp_path / "out.o")],
                                  capture_output=True, text=True, timeout=120)
            if done.returncode != 0 or done.stderr:
                failures.append(f"{stem} {level}: {done.stderr}")
    assert not failures, "\n".join(failures)


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


def test_a_robot_without_forward_kinematics_is_refused_in_one_line(tmp_path, capsys):
    """Three legs and no free coordinates: the C library's forward has nothing to solve for."""
    path = tmp_path / "legs.yaml"
    from conftest import THREE_LEGS

    path.write_text(THREE_LEGS)
    result = Ran(capsys, "build", path, "--host", "c", "-o", tmp_path / "out")
    assert result.exit_code == 2 and result.output == (
        f"kingen: error: {path}:1: forward: the C library's forward solves for as many pose coordinates as the robot "
        "has limbs; legs has 3 limbs and free coordinates all six\n")
    assert not (tmp_path / "out").exists()
