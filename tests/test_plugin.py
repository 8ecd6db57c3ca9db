"""Generated plugins: strict C89 with several compilers, the DELMIA contract, and agreement
with the reference through kingen's host emulator and through a separate plain-C client."""

import subprocess
from pathlib import Path

import numpy as np
import pytest

from conftest import SHIPPED, random_t6, require_tool
from kingen.abi import WARNINGS
from kingen.build import STRICT_C89, compiler_command, host_support
from kingen.conventions import joint_errors, t6_from_pose
from kingen.abi import UNWRITTEN_WARNING
from kingen.host import KinStat, Plugin, host_state
from kingen.model import load_robot
from kingen.render import render
from kingen.reference import solve

UNREACHABLE = WARNINGS["WARN_UNREACHABLE"]
COMPILERS = ["gcc", "clang", "tcc"]


@pytest.mark.parametrize("compiler", COMPILERS)
@pytest.mark.parametrize("name", SHIPPED)
@pytest.mark.parametrize("debug", [False, True], ids=["release", "debug"])
def test_source_compiles_as_strict_c89(compiler, name, debug, tmp_path):
    require_tool(compiler, compiler)
    (file_name, text), = render(load_robot(name)).items()
    source = tmp_path / file_name
    source.write_text(text)
    include, _ = host_support()
    command = [compiler, *STRICT_C89, f"-I{include}", "-c", str(source), "-o", str(tmp_path / "out.o")]
    if debug:
        command.append("-DKINGEN_DEBUG")
    result = subprocess.run(command, capture_output=True, text=True)
    assert result.returncode == 0 and result.stderr == "", result.stderr


@pytest.mark.parametrize("name", SHIPPED)
def test_generated_source_is_tables_plus_one_helper_per_model(name):
    robot = load_robot(name)
    (_, text), = render(robot).items()
    assert "do not edit" in text and robot.sha256 in text
    assert text == render(robot)[f"kin_{name}.c"], "rendering must be reproducible byte for byte"
    for model in robot.models:
        assert text.count(f"static void kingen_solve_{model}(") == 1
        assert f"static const kingen_{model} kingen_{model}s[] = {{" in text
    for model in {"leg", "rail", "crank"} - set(robot.models):
        assert f"kingen_solve_{model}" not in text
    assert f"#define NUM_DOFS {robot.dof}\n" in text and f"#define NUM_SOLUTIONS {robot.postures}\n" in text
    assert "long double" not in text and "pow(" not in text


@pytest.mark.parametrize("name", SHIPPED)
def test_plugin_matches_reference_on_random_poses(plugin, name):
    robot, loaded = plugin(name)
    poses, t6 = random_t6(robot, 3000, seed=11)
    loaded.reset_host()
    calls = loaded.call(t6)
    expected = solve(robot, t6)
    errors = joint_errors(calls.solutions, expected.joints, robot.revolute)
    worst = np.unravel_index(np.argmax(errors), errors.shape)
    assert errors.max() <= 1e-9, f"{name}: pose {poses[worst[0]]} joint {worst[1]} posture {worst[2]}: {errors.max()}"
    mismatch = np.argwhere(calls.warnings != expected.warnings)
    assert mismatch.size == 0, f"{name}: warnings differ at pose/posture {mismatch[:5].tolist()}"
    assert np.all(calls.returned == np.where(np.all(expected.warnings == UNREACHABLE, axis=1), 1, 0))


@pytest.mark.parametrize("name", ["hexapod", "tau", "ceart"])
def test_guarded_and_unguarded_drivers_agree(plugin, name):
    robot, loaded = plugin(name)
    _, t6 = random_t6(robot, 50, seed=5)
    loaded.reset_host()
    guarded = loaded.call(t6)
    _, _, solutions, warnings, returned = loaded.batch_runner(t6)()
    np.testing.assert_array_equal(guarded.solutions.reshape(50, -1), solutions.reshape(50, -1))
    np.testing.assert_array_equal(guarded.warnings.ravel(), warnings)
    np.testing.assert_array_equal(guarded.returned, returned)
    assert not np.any(guarded.faults)


def test_get_kin_config_answers_only_its_routine(plugin):
    robot, loaded = plugin("tau")
    assert (loaded.config.status, loaded.config.dof, loaded.config.solutions) == (0, 3, 8)
    assert loaded.kin_config("kin_hexapod").status == 1
    assert loaded.kin_config("kin_tau_").status == 1


def test_routine_checks_definition_first_and_stops_when_refused(plugin):
    robot, loaded = plugin("ceart")
    home = t6_from_pose([robot.verification.home])
    loaded.reset_host()
    loaded.call(home)
    assert host_state() == (1, 6, 64)
    loaded.reset_host(refuse=True)
    refused = loaded.call(home)
    assert refused.returned[0] == 1
    assert np.all(np.isnan(refused.solutions)) and np.all(refused.warnings == UNWRITTEN_WARNING)
    loaded.reset_host()


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_t6_gives_unreachable_finite_outputs_and_return_1(plugin, bad):
    robot, loaded = plugin("tau")
    t6 = t6_from_pose([robot.verification.home])
    t6[0, 1, 2] = bad
    loaded.reset_host()
    result = loaded.call(t6)
    assert result.returned[0] == 1
    assert np.all(result.solutions == 0.0)
    assert np.all(result.warnings == UNREACHABLE)


def test_singular_pose_is_flagged_by_plugin_and_reference(plugin):
    from test_reference import tau_singular_pose
    robot, loaded = plugin("tau")
    t6 = t6_from_pose([tau_singular_pose()])
    loaded.reset_host()
    assert np.all(loaded.call(t6).warnings == WARNINGS["WARN_SINGULAR_SOLUTION"])
    assert np.all(solve(robot, t6).warnings == WARNINGS["WARN_SINGULAR_SOLUTION"])


def test_debug_build_prints_pdata_t6_and_joints(built, tmp_path, capfd):
    robot = load_robot("exechon")
    from kingen.build import build_plugin
    result = build_plugin(robot, tmp_path / "debug", defines=("KINGEN_DEBUG",))
    loaded = Plugin(result.library, result.routine)
    assert loaded.config.data_hint == 1
    loaded.reset_host()
    loaded.call(t6_from_pose([[100, 50, -1250, 0, 0, 0]]), kinstat=KinStat(robot, joint_values=[1.5, 2.5, 3.5]))
    printed = capfd.readouterr().out
    assert "kin_exechon: dof_count 3, kin_mode 0" in printed
    assert "dof 2: type 1, value 3.5, travel [-225, 520]" in printed
    assert "kin_exechon: T6[3] = 100 50 -1250 1" in printed
    assert "kin_exechon: posture 0 warning 0: -24.891493 36.1332379 5.62579106" in printed


def test_release_build_prints_nothing(plugin, capfd):
    robot, loaded = plugin("exechon")
    loaded.reset_host()
    loaded.call(t6_from_pose([robot.verification.home]))
    assert capfd.readouterr().out == ""


@pytest.fixture(scope="session")
def abi_client(tmp_path_factory):
    folder = tmp_path_factory.mktemp("client")
    executable = folder / "abi_client"
    source = Path(__file__).parent / "c" / "abi_client.c"
    subprocess.run([*compiler_command(), "-std=c99", "-Wall", "-rdynamic", str(source), "-o", str(executable),
                    "-ldl", "-lm"], check=True)
    return executable


def run_client(executable, library, routine, t6):
    lines = "\n".join(" ".join(f"{v:.17g}" for v in matrix.ravel()) for matrix in t6)
    output = subprocess.run([str(executable), str(library), routine], input=lines, capture_output=True,
                            text=True, check=True).stdout.splitlines()
    return output[0].split(), [line.split() for line in output[1:]]


@pytest.mark.parametrize("name", SHIPPED)
def test_plain_c_client_agrees_with_reference(built, abi_client, name):
    robot, result = built(name)
    _, t6 = random_t6(robot, 200, seed=21)
    config, rows = run_client(abi_client, result.library, result.routine, t6)
    assert config[1:3] == [str(robot.dof), str(robot.postures)]
    expected = solve(robot, t6)
    postures = robot.postures
    for n, row in enumerate(rows):
        warnings = [int(w) for w in row[1:1 + postures]]
        joints = np.array([float(v) for v in row[1 + postures:]]).reshape(robot.dof, postures)
        assert warnings == expected.warnings[n].tolist(), f"{name} pose {n}"
        assert joint_errors(joints[None], expected.joints[n:n + 1], robot.revolute).max() <= 1e-9, f"{name} pose {n}"


def test_plain_c_client_reproduces_published_exechon_values(built, abi_client):
    robot, result = built("exechon")
    _, rows = run_client(abi_client, result.library, result.routine, t6_from_pose([[100, 50, -1250, 0, 0, 0]]))
    np.testing.assert_allclose([float(v) for v in rows[0][2:]], [-24.8915, 36.1332, 5.6258], atol=5e-5)
