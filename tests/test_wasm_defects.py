"""The WebAssembly host against what would break it: a hand-written library that allocates or is
named otherwise than its routine, hostile modules (each a failed check, exit 1, never an internal
error), the JavaScript glue given wrong lengths or finding no pose, a calibrated geometry passed
through the glue, and a toolchain missing one part (that part named)."""

import json
import os
import shutil
import subprocess

import numpy as np
import pytest
from kingen.hosts.c.render import file_names, render
from kingen.hosts.wasm.build import GLUE, compile_wasm, module_meta, wasm_toolchain
from kingen.kinematics.reference import solve
from kingen.kinematics.routine import WARNING_NAMES
from kingen.robot.model import load_robot

from conftest import random_t6, require_tool
from test_wasm_host import INVERSE_BODY, kingen_process, planted_source, require_wasm, require_wasmtime, verdicts

ALLOCATES = ("    { double *scratch = malloc(4096 * sizeof(double)); int n;\n"
             "      if (scratch) { for (n = 0; n < 4096; n++) scratch[n] = 1e300; free(scratch); } }\n")
"""Planted at the top of the inverse: a block of the module's heap allocated, filled and freed."""


def test_a_source_named_otherwise_that_allocates_passes(tmp_path):
    """tau's correct library with a malloc planted in its inverse, saved as hand.c and given
    --routine kingen_tau: the module exports the routine's names and verify passes (exit 0)."""
    require_wasm()
    require_wasmtime()
    planted = planted_source(tmp_path, INVERSE_BODY, INVERSE_BODY + ALLOCATES, before="#include <stdlib.h>\n")
    hand = planted.with_name("hand.c")
    planted.rename(hand)
    result = kingen_process("verify", "tau", "--host", "wasm", "--source", hand, "--routine", "kingen_tau",
                            "--samples", "200", "-o", tmp_path / "out", cwd=tmp_path)
    assert result.returncode == 0, result.stdout + result.stderr
    assert result.stdout.startswith(f"verify tau: 200 poses x 8 postures, {tmp_path / 'out' / 'hand.wasm'} (kingen_tau)")
    assert {check: verdicts(result.stdout).get(check) for check in ("values", "warnings", "forward", "determinism")} == \
        dict.fromkeys(("values", "warnings", "forward", "determinism"), "ok")


def test_the_glue_answers_as_the_reference_from_a_library_that_allocates(tmp_path):
    """The same allocating library, compiled with build_source and driven by the JavaScript glue
    in Node: its buffers come from the module's malloc, so every posture's joints are the reference's."""
    require_wasm()
    require_tool("node", "nodejs")
    from kingen.hosts.wasm.build import build_source
    from test_wasm_host import NODE_SCRIPT

    planted = planted_source(tmp_path, INVERSE_BODY, INVERSE_BODY + ALLOCATES, before="#include <stdlib.h>\n")
    robot = load_robot("tau")
    poses, t6 = random_t6(robot, 12, seed=3)
    expected = solve(robot, t6)
    given = {"module": str(build_source(planted, tmp_path / "out")), "meta": module_meta(robot), "poses": poses.tolist(),
             "posture": 0}
    ran = subprocess.run(["node", "-e", NODE_SCRIPT, str(GLUE)], input=json.dumps(given), capture_output=True,
                         text=True, timeout=60, check=True)
    for index, answer in enumerate(json.loads(ran.stdout)):
        assert answer["all"]["warnings"] == [WARNING_NAMES[code] for code in expected.warnings[index]]
        reachable = expected.warnings[index] != 2
        np.testing.assert_allclose(np.array(answer["all"]["joints"]).T[:, reachable], expected.joints[index][:, reachable],
                                   rtol=0, atol=1e-9, err_msg=f"pose {poses[index]}")


def hostile_module(memory="(memory 1)", table="(table 8 funcref)", malloc="i32.const 1024",
                   inverse='(func (export "kingen_tau_inverse") (param i32 i32 i32 i32) (result i32) i32.const 0)'):
    """The text of a module exporting every name verify tau --host wasm looks up, each doing nothing."""
    functions = [inverse, f'(func (export "malloc") (param i32) (result i32) {malloc})', '(func (export "free") (param i32))',
                 *(f'(func (export "kingen_tau_{name}") (param {"i32 " * count}) (result i32) i32.const 0)'
                   for name, count in (("inverse_posture", 4), ("forward", 6), ("jacobian", 4), ("static_loads", 5))),
                 *(f'(func (export "kingen_c_{name}") (param {"i32 " * count}))'
                   for name, count in (("inverse_batch", 9), ("forward_batch", 10), ("machine_pose_batch", 5),
                                       ("timed_batch", 8)))]
    return (f'(module {memory[:7]} (export "memory") {memory[7:]} {table[:6]} (export "__indirect_function_table") '
            f'{table[6:]} (global (export "kingen_tau_default_geometry") i32 (i32.const 16)) {" ".join(functions)})')


HOSTILE = {
    "capped": (hostile_module(memory="(memory 1 1)", malloc="i32.const 65000"),
               "load: the module's malloc({size}) is 65000, not the address of {size} bytes of the module's memory"),
    "top": (hostile_module(malloc="i32.const -256"),
            "load: the module's malloc({size}) is 4294967040, not the address of {size} bytes of the module's memory"),
    "null": (hostile_module(malloc="i32.const 0"),
             "load: the module's malloc({size}) is 0, not the address of {size} bytes of the module's memory"),
    "fixed table": (hostile_module(table="(table 8 8 funcref)"),
                    "load: the module's function table cannot take kingen_tau_inverse: failed to grow table by `1`"),
    "global for a function": (hostile_module(inverse='(global (export "kingen_tau_inverse") i32 (i32.const 0))'),
                              "load: the module's export kingen_tau_inverse is a global, not a function"),
    "wrong signature": (hostile_module(memory="(memory 100)").replace(
        '"kingen_tau_jacobian") (param i32 i32 i32 i32 )', '"kingen_tau_jacobian") (param i32)'),
        "crash: the module trapped in kingen_tau_jacobian: too many parameters provided: given 4, expected 1"),
}


@pytest.mark.parametrize("case", HOSTILE)
def test_a_hostile_module_fails_a_check(case, tmp_path):
    """Memory it cannot give, a malloc answering outside memory or NULL, a table that cannot
    grow, an export of the wrong kind, a function of the wrong signature: FAILED, exit 1."""
    require_wasmtime()
    import wasmtime

    text, said = HOSTILE[case]
    module = tmp_path / "hostile.wasm"
    module.write_bytes(wasmtime.wat2wasm(text))
    result = kingen_process("verify", "tau", "--host", "wasm", "--plugin", module, "--samples", "30", cwd=tmp_path)
    assert result.returncode == 1, result.stdout + result.stderr
    assert "internal error" not in result.stdout + result.stderr
    failed = [line.strip()[len("FAILED "):] for line in result.stdout.splitlines() if line.strip().startswith("FAILED ")]
    size = failed[0].split("malloc(")[1].split(")")[0] if "malloc(" in failed[0] else ""
    assert failed[0] == said.format(size=size), result.stdout


GLUE_SCRIPT = """
const KingenWasm = require(process.argv[1]);
const input = JSON.parse(require("fs").readFileSync(0, "utf8"));
const kin = KingenWasm.create(require("fs").readFileSync(input.module), input.meta);
const refused = (call) => { try { call(); return null; } catch (error) { return error.name + ": " + error.message; } };
const out = {
    shortPose: refused(() => kin.inverse([1, 2, 3], 0)),
    shortJoints: refused(() => kin.forward(input.joints.slice(1), 0, input.pose)),
    good: kin.forward(input.joints, 0, input.pose),
    failed: kin.forward([NaN, ...input.joints.slice(1)], 0, input.pose),
    before: kin.inverseAll(input.pose),
};
kin.setGeometry(kin.defaultGeometry(input.size));
kin.inverse(input.pose, 0);  // the glue's buffers written: the copy must survive them
out.copied = kin.inverseAll(input.pose);
kin.setGeometry(new Uint8Array(input.size));
out.zeroed = kin.inverseAll(input.pose);
process.stdout.write(JSON.stringify(out));
"""


def geometry_size(robot, folder):
    """sizeof the robot's geometry struct, by the system compiler from its header (ints and
    doubles only: the same on wasm32 as on the machine's own ABI)."""
    for name, text in render(robot).items():
        (folder / name).write_text(text)
    (folder / "size.c").write_text(f'#include <stdio.h>\n#include "{file_names(robot)[0]}"\n'
                                   f'int main(void) {{ printf("%zu", sizeof({file_names(robot)[0][:-2]}_geometry)); return 0; }}\n')
    subprocess.run(["cc", "-o", str(folder / "size"), str(folder / "size.c")], check=True, timeout=60)
    return int(subprocess.run([str(folder / "size")], capture_output=True, text=True, check=True).stdout)


def test_the_glue_refuses_wrong_lengths_and_gives_no_stale_pose(tmp_path):
    """A pose of 3 numbers or joints one short: RangeError. A forward that fails (NaN joint):
    pose and matrix null, not the previous call's. A copy of the default geometry passed with
    setGeometry gives the reference's joints; a zeroed one does not."""
    require_wasm()
    require_tool("node", "nodejs")
    robot = load_robot("tau")
    poses, t6 = random_t6(robot, 40, seed=11)
    expected = solve(robot, t6)
    index = int(np.flatnonzero(expected.warnings[:, 0] == 0)[0])
    given = {"module": str(compile_wasm(robot)), "meta": module_meta(robot), "pose": poses[index].tolist(),
             "joints": expected.joints[index, :, 0].tolist(), "size": geometry_size(robot, tmp_path)}
    ran = subprocess.run(["node", "-e", GLUE_SCRIPT, str(GLUE)], input=json.dumps(given), capture_output=True,
                         text=True, timeout=60, check=True)
    out = json.loads(ran.stdout)
    assert out["shortPose"] == "RangeError: pose: give 6 numbers, not 3"
    assert out["shortJoints"] == "RangeError: joints: give 3 numbers, not 2"
    assert out["good"]["status"] == 0
    np.testing.assert_allclose(out["good"]["pose"], poses[index], rtol=0, atol=1e-7)
    assert out["failed"]["status"] != 0 and out["failed"]["pose"] is None and out["failed"]["matrix"] is None
    warnings = [WARNING_NAMES[code] for code in expected.warnings[index]]
    reachable = expected.warnings[index] != 2
    for answer in (out["before"], out["copied"]):
        assert answer["warnings"] == warnings
        np.testing.assert_allclose(np.array(answer["joints"]).T[:, reachable], expected.joints[index][:, reachable],
                                   rtol=0, atol=1e-9)
    assert out["zeroed"]["joints"] != out["copied"]["joints"]


def test_a_sysroot_without_libraries_names_wasi_libc(tmp_path, monkeypatch):
    """wasi-libc's headers present but not its libraries: the linker's complaint names wasi-libc, not lld."""
    require_wasm()
    headers = next((path for path in ("/usr/include/wasm32-wasi", "/usr/share/wasi-sysroot/include/wasm32-wasi")
                    if os.path.isdir(path)), None)
    if headers is None:
        pytest.skip("wasi-libc's headers are not where Debian puts them")
    (tmp_path / "include").mkdir()
    (tmp_path / "include" / "wasm32-wasi").symlink_to(headers)
    monkeypatch.setenv("KINGEN_WASM_CC", f"clang --sysroot={tmp_path}")
    problem = wasm_toolchain().problem
    assert problem.startswith("WebAssembly toolchain: wasi-libc is not installed (Debian package wasi-libc)"), problem


def test_a_missing_linker_names_lld(tmp_path, monkeypatch):
    """clang run from a folder without wasm-ld beside it or on PATH: lld is named."""
    require_wasm()
    (tmp_path / "clang").symlink_to(os.path.realpath(shutil.which("clang")))
    monkeypatch.setenv("PATH", str(tmp_path))
    monkeypatch.setenv("KINGEN_WASM_CC", str(tmp_path / "clang"))
    problem = wasm_toolchain().problem
    assert problem.startswith("WebAssembly toolchain: wasm-ld is not installed (Debian package lld)"), problem


def test_a_compiler_too_slow_is_said_so_and_not_remembered():
    """A probe that cannot finish in its time: the problem says so (not "not installed"), and
    nothing is kept of it (the next probe runs the compiler again)."""
    require_wasm()
    from kingen.hosts.wasm.build import _probe

    kept = _probe.cache_info().currsize
    problem = wasm_toolchain(timeout=0.001).problem
    assert "did not finish in 0.001 s" in problem and "not installed" not in problem, problem
    assert _probe.cache_info().currsize == kept


def test_build_debug_is_refused_in_one_line(tmp_path):
    result = kingen_process("build", "tau", "--host", "wasm", "--debug", "-o", tmp_path / "out", cwd=tmp_path)
    assert result.returncode == 2
    assert result.stderr == "kingen: error: --debug: --host wasm has no debug build (the module cannot print)\n"
    assert not (tmp_path / "out").exists()
