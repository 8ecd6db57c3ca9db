"""The WebAssembly host: the C library compiled for wasm32-wasi (clang, lld, wasi-libc, the wasm32
compiler-rt; a missing part skips, or fails under KINGEN_REQUIRE_TOOLCHAINS=1), its JavaScript
glue run by Node against the reference, and the one-line error of a missing toolchain."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest
from kingen.conventions import t6_from_pose
from kingen.errors import KingenError
from kingen.hosts.c.render import render
from kingen.hosts.wasm.build import GLUE, compile_wasm, module_meta, wasm_toolchain
from kingen.kinematics.reference import solve
from kingen.kinematics.routine import WARNING_NAMES
from kingen.robot.model import load_robot

from conftest import random_t6, require_tool, skip_or_fail

GLUE_FAMILIES = ("tau", "hexapod", "exechon_wrist")
"""Three rails and a closed-form forward, six legs and Newton's forward, a parallel part with a wrist."""
NODE_SCRIPT = """
const KingenWasm = require(process.argv[1]);
const input = JSON.parse(require("fs").readFileSync(0, "utf8"));
const kin = KingenWasm.create(require("fs").readFileSync(input.module), input.meta);
const out = input.poses.map((pose) => ({all: kin.inverseAll(pose),
    one: kin.inverse(pose, input.posture), forward: kin.forward(kin.inverse(pose, input.posture).joints, input.posture, pose)}));
process.stdout.write(JSON.stringify(out));
"""


def require_wasm():
    toolchain = wasm_toolchain()
    if not toolchain.ready:
        skip_or_fail(toolchain.problem)


@pytest.mark.parametrize("name", GLUE_FAMILIES)
def test_the_javascript_glue_answers_as_the_reference(name):
    require_wasm()
    require_tool("node", "nodejs")
    robot = load_robot(name)
    poses, t6 = random_t6(robot, 12, seed=5)
    expected = solve(robot, t6)
    posture = int(np.argmax(np.sum(expected.warnings == 0, axis=0)))
    given = {"module": str(compile_wasm(robot)), "meta": module_meta(robot), "poses": poses.tolist(), "posture": posture}
    ran = subprocess.run(["node", "-e", NODE_SCRIPT, str(GLUE)], input=json.dumps(given), capture_output=True,
                         text=True, timeout=60, check=True)
    answers = json.loads(ran.stdout)
    for index, answer in enumerate(answers):
        warnings = [WARNING_NAMES[code] for code in expected.warnings[index]]
        assert answer["all"]["warnings"] == warnings, (name, poses[index])
        assert answer["one"]["warning"] == warnings[posture], (name, poses[index])
        reachable = expected.warnings[index] != 2
        all_joints = np.array(answer["all"]["joints"]).T  # (dof, postures)
        np.testing.assert_allclose(all_joints[:, reachable], expected.joints[index][:, reachable], rtol=0, atol=1e-9,
                                   err_msg=f"{name} pose {poses[index]}")
        if expected.warnings[index, posture] == 0:
            np.testing.assert_allclose(answer["one"]["joints"], expected.joints[index, :, posture], rtol=0, atol=1e-9)
            assert answer["forward"]["status"] == 0
            compared = slice(2, 4) if robot.wrist is not None else slice(0, 4)  # a wrist's turn about the tool is free
            np.testing.assert_allclose(np.array(answer["forward"]["matrix"]).reshape(4, 4).T[compared], t6[index][compared],
                                       atol=1e-6)


MACHINE_POSE_SCRIPT = """
const KingenWasm = require(process.argv[1]);
const input = JSON.parse(require("fs").readFileSync(0, "utf8"));
const kin = KingenWasm.create(require("fs").readFileSync(input.module), input.meta);
process.stdout.write(JSON.stringify(input.poses.map((pose) => kin.machinePose(pose))));
"""


@pytest.mark.parametrize("name", ["exechon_constrained", "tau"])
def test_the_glue_gives_a_machines_pose_for_its_task_coordinates(name):
    """A machine with task coordinates: machinePose is the reference's machine pose (its
    parasitic coordinates solved) where that is good; null for a robot without task coordinates."""
    require_wasm()
    require_tool("node", "nodejs")
    from kingen.kinematics.parasitic import solve_parasitic

    robot = load_robot(name)
    poses, t6 = random_t6(robot, 12, seed=7)
    given = {"module": str(compile_wasm(robot)), "meta": module_meta(robot), "poses": poses.tolist()}
    ran = subprocess.run(["node", "-e", MACHINE_POSE_SCRIPT, str(GLUE)], input=json.dumps(given), capture_output=True,
                         text=True, timeout=60, check=True)
    answers = json.loads(ran.stdout)
    if not robot.task:
        assert answers == [None] * len(poses)
        return
    expected = solve_parasitic(robot, t6)
    good = [index for index, answer in enumerate(answers) if answer["status"] == 0]
    assert len(good) >= len(poses) // 2, answers
    for index in good:
        np.testing.assert_allclose(np.array(answers[index]["matrix"]).reshape(4, 4).T, expected.t6[index],
                                   rtol=0, atol=1e-9, err_msg=f"{name} pose {poses[index]}")


def test_a_missing_compiler_is_one_line_naming_its_package(monkeypatch):
    monkeypatch.setenv("KINGEN_WASM_CC", "/nonexistent/clang")
    toolchain = wasm_toolchain()
    assert not toolchain.ready
    assert "/nonexistent/clang is not installed (Debian package clang" in toolchain.problem
    with pytest.raises(KingenError) as raised:
        compile_wasm(load_robot("tau"))
    assert str(raised.value) == toolchain.problem and "\n" not in toolchain.problem


def test_a_missing_wasi_libc_is_named(monkeypatch, tmp_path):
    require_wasm()
    monkeypatch.setenv("KINGEN_WASM_CC", f"clang --sysroot={tmp_path}")
    problem = wasm_toolchain().problem
    assert problem.startswith("WebAssembly toolchain: wasi-libc is not installed (Debian package wasi-libc)"), problem
    assert "math.h" in problem and "\n" not in problem


VERIFIED_FAMILIES = ("hexapod", "ceart", "exechon_wrist", "tricept_wrist3")
"""Verified through the API here; tau through the real command line."""
SHARED_CHECKS = ("values", "warnings", "closure", "jacobian", "c jacobian", "round trip", "forward", "determinism")


def require_wasmtime():
    try:
        import wasmtime  # noqa: F401
    except ImportError:
        skip_or_fail("verify --host wasm needs the Python package wasmtime (pip install -e '.[test]' installs it)")


def kingen_process(*arguments, cwd, env=None):
    return subprocess.run([sys.executable, "-m", "kingen.cli", *map(str, arguments)], cwd=cwd, capture_output=True,
                          text=True, timeout=120, env={**os.environ, **(env or {})})


def verdicts(output):
    """{check name: "ok" or "FAILED"} of a verify report's lines."""
    found = {}
    for line in output.splitlines():
        words = line.split(None, 1)
        if len(words) == 2 and words[0] in ("ok", "FAILED") and ":" in words[1]:
            found[words[1].split(":")[0]] = words[0]
    return found


def test_verify_host_wasm_passes_on_the_command_line(tmp_path):
    require_wasm()
    require_wasmtime()
    result = kingen_process("verify", "tau", "--host", "wasm", "--samples", "400", "-o", tmp_path / "out", cwd=tmp_path)
    assert result.returncode == 0, result.stdout + result.stderr
    assert result.stdout.startswith(f"verify tau: 400 poses x 8 postures, {tmp_path / 'out' / 'kingen_tau.wasm'}")
    assert {check: verdicts(result.stdout).get(check) for check in (*SHARED_CHECKS, "c loads")} == \
        {check: "ok" for check in (*SHARED_CHECKS, "c loads")}


@pytest.mark.parametrize("name", VERIFIED_FAMILIES)
def test_verify_host_wasm_passes_through_the_api(name, tmp_path, monkeypatch):
    require_wasm()
    require_wasmtime()
    import kingen

    monkeypatch.chdir(tmp_path)
    robot = load_robot(name)
    report = kingen.verify_library(robot, host="wasm", samples=150)
    results = {check.name: check.passed for check in report.checks}
    assert report.passed, [(check.name, check.detail) for check in report.checks if not check.passed]
    expected = (*SHARED_CHECKS, *(("c direct index",) if robot.dof == 6 else ()))
    assert {check: results.get(check) for check in expected} == {check: True for check in expected}
    assert (tmp_path / "build" / name / "wasm" / f"kingen_{name}.wasm").is_file()


def planted_source(tmp_path, right, wrong, before=""):
    """tau's C library rendered into tmp_path/planted, ``right`` (which must stand in it) replaced
    by ``wrong`` and ``before`` put at its top: the source's path."""
    planted = tmp_path / "planted"
    planted.mkdir()
    for file_name, text in render(load_robot("tau")).items():
        (planted / file_name).write_text(text)
    source = planted / "kingen_tau.c"
    assert right in source.read_text()
    source.write_text(before + source.read_text().replace(right, wrong))
    return source


def test_a_wrong_sign_in_the_compiled_source_fails_values(tmp_path):
    """The C source edited before compiling (one limb's rail point added instead of subtracted):
    the module built from it with --source fails values, the diagnosis naming that limb's joint."""
    require_wasm()
    require_wasmtime()
    source = planted_source(tmp_path, "w[1] = point[1] - rail->rail_point[1]", "w[1] = point[1] + rail->rail_point[1]")
    result = kingen_process("verify", "tau", "--host", "wasm", "--source", source, "--samples", "200",
                            "-o", tmp_path / "out", cwd=tmp_path)
    assert result.returncode == 1, result.stdout + result.stderr
    assert verdicts(result.stdout)["values"] == "FAILED"
    assert "joint 1 (carriage2) disagrees" in result.stdout


INVERSE_BODY = "        double solutions[][NUM_SOLUTIONS], int warnings[])\n{\n"


def test_a_module_that_traps_fails_crash(tmp_path):
    """A module executing ``unreachable`` on half the region's poses: check ``crash`` names the trap, exit 1."""
    require_wasm()
    require_wasmtime()
    source = planted_source(tmp_path, INVERSE_BODY, INVERSE_BODY + "    if (pose[3] > -1200.0) __builtin_trap();\n")
    result = kingen_process("verify", "tau", "--host", "wasm", "--source", source, "--samples", "200",
                            "-o", tmp_path / "out", cwd=tmp_path)
    assert result.returncode == 1, result.stdout + result.stderr
    assert ("  FAILED crash: the module trapped in kingen_c_inverse_batch: wasm trap: wasm `unreachable` instruction "
            "executed\n") in result.stdout


def test_a_module_importing_anything_but_wasi_fails_load(tmp_path):
    require_wasm()
    require_wasmtime()
    source = planted_source(tmp_path, INVERSE_BODY, INVERSE_BODY + "    phone_home();\n",
                            before='__attribute__((import_module("env"), import_name("phone_home"))) '
                                   'extern void phone_home(void);\n')
    result = kingen_process("verify", "tau", "--host", "wasm", "--source", source, "--samples", "200",
                            "-o", tmp_path / "out", cwd=tmp_path)
    assert result.returncode == 1, result.stdout + result.stderr
    assert "  FAILED load: the module imports env.phone_home: a routine may import only WASI functions\n" in result.stdout


def test_a_missing_toolchain_stops_verify_in_one_line(tmp_path):
    result = kingen_process("verify", "tau", "--host", "wasm", "-o", tmp_path / "out", cwd=tmp_path,
                            env={"KINGEN_WASM_CC": "/nonexistent/clang"})
    assert result.returncode == 2
    assert result.stderr == ("kingen: error: WebAssembly toolchain: /nonexistent/clang is not installed "
                             "(Debian package clang; or set $KINGEN_WASM_CC)\n")
    assert not (tmp_path / "out").exists()


def test_the_package_runs_its_example_in_node(tmp_path):
    require_wasm()
    require_tool("node", "nodejs")
    result = kingen_process("package", "hexapod", "--host", "wasm", "-o", tmp_path / "package", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert sorted(path.name for path in (tmp_path / "package").iterdir() if not path.name.startswith(".")) == \
        ["SETUP.md", "example.js", "kingen_hexapod.h", "kingen_hexapod.wasm", "kingen_wasm.js"]
    ran = subprocess.run(["node", "example.js"], cwd=tmp_path / "package", capture_output=True, text=True, timeout=60,
                         check=True)
    robot = load_robot("hexapod")
    home = np.array(robot.verification.home, dtype=float)
    lines = dict(line.split(": ", 1) for line in ran.stdout.splitlines())
    posture = int(next(key for key in lines if key.startswith("inverse")).split()[-1])
    inverse = json.loads(lines[f"inverse, posture {posture}"])
    expected = solve(robot, t6_from_pose(home[None]))
    assert inverse["warning"] == WARNING_NAMES[expected.warnings[0, posture]]
    np.testing.assert_allclose(inverse["joints"], expected.joints[0, :, posture], rtol=0, atol=1e-9)
    forward = json.loads(lines["forward"])
    assert forward["status"] == 0
    np.testing.assert_allclose(forward["pose"], home, rtol=0, atol=1e-7)


def test_without_wasmtime_verify_says_what_to_install(tmp_path):
    require_wasm()
    blocker = tmp_path / "blocked" / "wasmtime"
    blocker.mkdir(parents=True)
    (blocker / "__init__.py").write_text("raise ImportError('no wasmtime here')\n")
    result = kingen_process("verify", "tau", "--host", "wasm", "--samples", "50", "-o", tmp_path / "out", cwd=tmp_path,
                            env={"PYTHONPATH": str(tmp_path / "blocked")})
    assert result.returncode == 2, result.stdout + result.stderr
    assert result.stderr == ("kingen: error: --host wasm: loading a module needs the Python package wasmtime "
                             "(pip install 'kingen[wasm]')\n")


def test_a_file_that_is_no_kingen_module_fails_load(tmp_path):
    """Given with --plugin: bytes that are no WebAssembly binary, and a module of the library linked
    without kingen's exports (its memory's free start, the batch driver): check ``load``, exit 1."""
    require_wasm()
    require_wasmtime()
    from kingen.hosts.wasm.build import TARGET_FLAGS, wasm_compiler

    junk = tmp_path / "junk.wasm"
    junk.write_text("(module)\n")  # the text format, which wasmtime itself would read
    source = planted_source(tmp_path, INVERSE_BODY, INVERSE_BODY)
    bare = tmp_path / "bare.wasm"
    subprocess.run([*wasm_compiler(), *TARGET_FLAGS, "-O2", "-Wl,--export=kingen_tau_inverse", str(source), "-o",
                    str(bare), "-lm"], check=True, capture_output=True, timeout=120)
    for module, said in ((junk, "the module cannot be loaded: not a WebAssembly binary (it does not start with \\0asm)"),
                         (bare, "the module does not export __heap_base (kingen build --host wasm exports it)")):
        result = kingen_process("verify", "tau", "--host", "wasm", "--plugin", module, "--samples", "50", cwd=tmp_path)
        assert result.returncode == 1, result.stdout + result.stderr
        assert f"  FAILED load: {said}\n" in result.stdout
