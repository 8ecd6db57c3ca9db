"""The WebAssembly host: the C library compiled for wasm32-wasi (clang, lld, wasi-libc, the wasm32
compiler-rt; a missing part skips, or fails under KINGEN_REQUIRE_TOOLCHAINS=1), its JavaScript
glue run by Node against the reference, and the one-line error of a missing toolchain."""

import json
import subprocess

import numpy as np
import pytest
from kingen.conventions import t6_from_pose
from kingen.errors import KingenError
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
