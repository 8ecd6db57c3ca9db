"""The LinuxCNC host: kingen's kinematics module for every shipped robot with six limbs or a
translating platform builds warning-free, loads through the HAL stand-in as LinuxCNC's motion
controller would, and passes verify (its inverse against the reference at the working
posture; its forward Newton from seeds a servo cycle and 10 mm / 5 degrees away); robots it
cannot drive are refused with a located error; its package's snippets hold the robot file's
numbers. LinuxCNC's headers come from Debian's linuxcnc-uspace-dev (.ci/run installs it)."""

import hashlib
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from conftest import FORGED, forging_constructor, require_linuxcnc_headers, require_tool
from kingen.cli import main
from kingen.conventions import t6_from_pose
from kingen.errors import KingenError
from kingen.hosts import get_host
from kingen.hosts.linuxcnc.build import build_module
from kingen.hosts.linuxcnc.loader import Module
from kingen.hosts.linuxcnc.package import render_package
from kingen.robot.model import load_robot
from kingen.kinematics.reference import solve
from kingen.runtime.resources import robots_dir
from kingen.verify import VerifyOptions, verify_library

LINUXCNC_ROBOTS = ["hexapod", "flexapod", "stewart_gough_example", "ceart", "iwf", "rus_optimized", "tau",
                   "linuxcnc_hexapod", "linear_delta", "rotary_delta"]
"""Every shipped robot with six limbs or a translating platform."""
STOCK = Path("/usr/lib/linuxcnc/modules")
"""LinuxCNC's own modules (Debian's linuxcnc-uspace)."""


def stock_report(robot_name, module, *arguments):
    """verify of LinuxCNC's stock ``module`` against a shipped robot at its sample geometry."""
    host = get_host("linuxcnc")
    units = next((value for flag, value in zip(arguments, arguments[1:]) if flag == "units"), None)
    setp = dict(pair for flag, pair in zip(arguments, arguments[1:]) if flag == "setp")
    host = host.configured(units=units, setp=tuple(setp.items()))
    seen = host.as_seen(load_robot(robot_name))
    report = verify_library(seen, STOCK / f"{module}.so", module, VerifyOptions(samples=3000), host=host)
    return report, {check.name: check for check in report.checks}


@pytest.fixture(autouse=True)
def linuxcnc_headers():
    require_linuxcnc_headers()


@pytest.fixture(scope="module")
def modules(tmp_path_factory):
    """modules(name) -> (robot, robot as LinuxCNC sees it, BuildResult), built once."""
    folder, cache = tmp_path_factory.mktemp("linuxcnc"), {}
    host = get_host("linuxcnc")

    def get(name):
        if name not in cache:
            robot = load_robot(name)
            cache[name] = (robot, host.as_seen(robot), host.build(robot, folder / name))
        return cache[name]

    return get


@pytest.mark.parametrize("name", LINUXCNC_ROBOTS)
def test_every_shipped_module_passes_verify(name, modules):
    _, seen, built = modules(name)
    report = verify_library(seen, built.library, built.routine, VerifyOptions(samples=3000), host=get_host("linuxcnc"))
    assert report.passed, [(check.name, check.detail) for check in report.failures]
    checks = {check.name: check.detail for check in report.checks}
    assert report.max_abs_error_mm <= 1e-9 and report.max_abs_error_rad <= 1e-9
    servo = re.search(r"a servo cycle away: (\d+) of (\d+) returned the pose, 0 failed", checks["forward"])
    assert servo and servo.group(1) == servo.group(2) and int(servo.group(2)) > 0
    assert "0 returned another pose; iterations mean" in checks["forward"]


def test_the_module_answers_the_working_posture(modules):
    robot, seen, built = modules("ceart")
    poses = np.array([robot.verification.home, [10, -20, robot.verification.home[2] + 15, 4, -3, 8]])
    module = Module(built.library, built.routine, seen)
    calls = module.call(t6_from_pose(poses))
    expected = solve(robot, t6_from_pose(poses))
    assert robot.working_posture == 63
    assert np.max(np.abs(calls.solutions[:, :, 0] - expected.joints[:, :, 63])) < 1e-12
    assert list(calls.warnings[:, 0]) == list(expected.warnings[:, 63]) and list(calls.returned) == [0, 0]


def test_geometry_parameters_change_the_module_without_recompiling(modules):
    robot, seen, built = modules("hexapod")
    home = t6_from_pose(np.array([robot.verification.home]))
    before = Module(built.library, built.routine, seen).call(home).solutions[0, :, 0]
    after = Module(built.library, built.routine, seen, setp={"hexapodkins.leg1.reference-length": 400.413}).call(home)
    assert after.solutions[0, 0, 0] == pytest.approx(before[0] - 1.0, abs=1e-12)
    assert np.array_equal(after.solutions[0, 1:, 0], before[1:])
    names = Module(built.library, built.routine, seen).hal_names()
    assert {"hexapodkins.leg1.base-point.x", "hexapodkins.leg6.platform-point.z", "hexapodkins.max-step",
            "hexapodkins.status", "hexapodkins.iterations"} <= set(names)


def test_the_forward_fails_rather_than_stray_far_from_the_pose_passed_in(modules):
    robot, seen, built = modules("hexapod")
    module = Module(built.library, built.routine, seen)
    home = np.array(robot.verification.home)
    world = np.zeros((3, 9))
    world[:, :3], world[:, 3:6] = home[:3], home[3:]
    joints, returns, _ = module.inverse(world[:1])
    assert returns[0] == 0
    world[1, 2] += 20.0  # within max-step (25 mm): converges back
    world[2, 2] += 60.0  # beyond it: fails with -3
    found, returns, iterations = module.forward(np.repeat(joints, 3, axis=0), world)
    assert list(returns) == [0, 0, -3]
    assert np.max(np.abs(found[:2, :6] - np.r_[home][None])) < 1e-9 and iterations[0] == 1


def test_a_forward_whose_tolerance_is_below_rounding_stops_at_roundings_floor(modules):
    """With .tolerance 0 no step is ever short enough: Newton stops where its steps no longer
    halve (rounding's floor, at most 1e-9 of the machine's size) and returns the pose."""
    robot, seen, built = modules("hexapod")
    module = Module(built.library, built.routine, seen, setp={"hexapodkins.tolerance": 0.0})
    rng = np.random.default_rng(7)
    world = np.zeros((200, 9))
    world[:, :6] = np.array(robot.verification.home) + rng.uniform(-1, 1, (200, 6)) * [20, 20, 20, 3, 3, 3]
    joints, returns, _ = module.inverse(world)
    assert np.all(returns == 0)
    seeds = world.copy()
    seeds[:, :6] += rng.uniform(-1, 1, (200, 6)) * [0.01, 0.01, 0.01, 0.001, 0.001, 0.001]
    found, returns, iterations = module.forward(joints, seeds)
    assert np.all(returns == 0) and np.max(iterations) < 20, (np.unique(returns), np.max(iterations))
    assert np.max(np.abs(found[:, :3] - world[:, :3])) < 1e-9 * robot.size_mm
    assert np.max(np.abs(np.radians(found[:, 3:6] - world[:, 3:6]))) < 1e-9


def test_a_wrong_inverse_fails_values_and_a_wrong_forward_fails_forward(modules, tmp_path, capsys):
    _, _, built = modules("hexapod")
    text = built.source.read_text()
    wrong = {"inverse": ("joint[i] = kingen_revolute[i] ? value / KINGEN_DEGREE : value;",
                         "joint[i] = (kingen_revolute[i] ? value / KINGEN_DEGREE : value) + (i == 2);"),
             "forward": ("residual[i] = value - measured[i];", "residual[i] = value - measured[i] * 1.000001;")}
    outputs = {}
    for name, (old, new) in wrong.items():
        assert old in text
        source = tmp_path / f"{name}kins.c"
        source.write_text(text.replace(old, new))
        code = main(["verify", "hexapod", "--host", "linuxcnc", "--source", str(source), "--routine", "hexapodkins",
                     "-o", str(tmp_path / name), "--samples", "2000"])
        outputs[name] = capsys.readouterr().out
        assert code == 1
    assert "FAILED values: max |error| 1 mm" in outputs["inverse"]
    assert "diagnosis: joint 2 (leg3) is off by a constant +1 mm on every pose" in outputs["inverse"]
    assert "ok     forward" in outputs["inverse"]  # its forward is right: it is fed the reference's joints
    assert "ok     values" in outputs["forward"] and "FAILED forward" in outputs["forward"]
    assert re.search(r"a servo cycle away: 0 of \d+ returned the pose", outputs["forward"])


@pytest.mark.parametrize("body, words", [
    ("for (;;) ;", "FAILED timeout: no progress for 2 s during loading the module"),
    ("exit(0);", "FAILED crash: the plugin ended the host process (exit status 0) during loading the module"),
    ("raise(SIGSEGV);", "FAILED crash: the plugin ended the host process (signal SIGSEGV) during loading the module"),
], ids=["spins", "exits", "signals"])
def test_a_module_whose_constructor_breaks_leaves_nothing_in_tmpdir(body, words, modules, tmp_path):
    """The module's copy is made in the child's temporary folder, which kingen's own process
    makes and removes, whatever the constructor does to the child."""
    _, _, built = modules("hexapod")
    source = tmp_path / "hexapodkins.c"
    source.write_text(built.source.read_text() + "#include <signal.h>\n#include <stdlib.h>\n"
                      f"__attribute__((constructor)) static void hostile(void) {{ {body} }}\n")
    temporary = tmp_path / "tmp"
    temporary.mkdir()
    result = subprocess.run([sys.executable, "-m", "kingen.cli", "verify", "hexapod", "--host", "linuxcnc", "--source",
                             str(source), "--routine", "hexapodkins", "-o", str(tmp_path / "out"), "--samples", "200",
                             "--timeout", "2"], capture_output=True, text=True, timeout=120,
                            env={**os.environ, "TMPDIR": str(temporary)})
    assert result.returncode == 1 and words in result.stdout, result.stdout + result.stderr
    assert list(temporary.iterdir()) == []


@pytest.mark.parametrize("name", FORGED)
def test_a_module_writing_into_kingens_channel_can_only_fail_its_own_run(name, modules, tmp_path):
    """As for a DELMIA plugin (tests/test_hostile.py): a module constructor that writes a pickle
    frame or a forged report into every descriptor fails its own run, and runs nothing in kingen."""
    _, _, built = modules("hexapod")
    source = tmp_path / "hexapodkins.c"
    source.write_text(built.source.read_text() + forging_constructor(FORGED[name]))
    result = subprocess.run([sys.executable, "-m", "kingen.cli", "verify", "hexapod", "--host", "linuxcnc", "--source",
                             str(source), "--routine", "hexapodkins", "-o", str(tmp_path / "out"), "--samples", "200"],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 1, result.stdout + result.stderr
    assert "FAILED crash: kingen's channel to the host process carried " in result.stdout, result.stdout
    assert "during loading the module" in result.stdout


@pytest.mark.parametrize("change, words", [
    (lambda text: text.replace("working_posture: 0\n", ""), ":1: working_posture: LinuxCNC's inverse kinematics has one"),
    (lambda text: text.replace("name: tau", "name: genhex"), ":2: name: the module name 'genhexkins' is LinuxCNC's own"),
])
def test_robots_linuxcnc_cannot_drive_are_refused(change, words, tmp_path, capsys):
    path = tmp_path / "robot.yaml"
    path.write_text(change((robots_dir() / "tau.yaml").read_text()))
    assert main(["build", str(path), "--host", "linuxcnc", "-o", str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1 and not (tmp_path / "b").exists()


def test_a_robot_that_neither_has_six_limbs_nor_translates_is_refused():
    with pytest.raises(KingenError, match=r"exechon.yaml:\d+: forward: LinuxCNC drives six-limb robots"):
        build_module(load_robot("exechon"))


def test_the_package_holds_the_robot_files_numbers(modules):
    robot, _, _ = modules("tau")
    files = render_package(robot)
    assert sorted(files) == ["SETUP.md", "taukins.c", "taukins.hal", "taukins.ini"]
    assert "setp taukins.carriage3.link-length 1499.775\n" in files["taukins.hal"]
    assert "setp taukins.carriage1.platform-point.x 224.999\n" in files["taukins.hal"]
    home = solve(robot, t6_from_pose(np.array([robot.verification.home]))).joints[0, :, 0]
    ini = files["taukins.ini"]
    assert "KINEMATICS = taukins\nJOINTS = 3\n" in ini
    assert f"[JOINT_0]\n# carriage1 (rail, mm)\nTYPE = LINEAR\nMIN_LIMIT = -1\nMAX_LIMIT = 2600\nHOME = {float(home[0])!r}\n" in ini
    assert "[TRAJ]\nHOME = -1200.0 -750.0 -1900.0 0.0 0.0 0.0\n" in ini
    assert "A B C U V W pass through to joints 3 to 8" in files["SETUP.md"]


def test_kingen_info_reads_the_module(modules, capsys):
    _, _, built = modules("iwf")
    assert main(["info", str(built.library)]) == 0
    out = capsys.readouterr().out
    assert "robot: iwf\nroutine: iwfkins\ndof: 6, postures: 1\n" in out and "format: ELF 64-bit shared object" in out
    assert "host: linuxcnc, the robot file's posture 63\n" in out


def test_the_module_compiles_warning_free_with_clang(modules, tmp_path, monkeypatch):
    require_tool("clang", "clang")
    robot, _, _ = modules("ceart")
    monkeypatch.setenv("CC", "clang")
    monkeypatch.setenv("KINGEN_CACHE", str(tmp_path / "cache"))
    assert build_module(robot, tmp_path / "clang").compiled


def test_lineardeltakins_agrees_with_the_reference_everywhere():
    report, checks = stock_report("linear_delta", "lineardeltakins")
    assert report.passed, [(check.name, check.detail) for check in report.failures]
    assert report.max_abs_error_mm <= 1e-12
    assert "no iteration count" in checks["forward"].detail


def test_rotarydeltakins_agrees_but_answers_a_nan_pose():
    report, checks = stock_report("rotary_delta", "rotarydeltakins")
    assert [check.name for check in report.failures] == ["inverse refusal"]
    assert checks["inverse refusal"].detail.startswith("returns 0 for x = NaN")
    assert report.max_abs_error_rad <= 1e-12


def test_genhexkins_agrees_with_absolute_strut_lengths_but_answers_non_finite_poses():
    report, checks = stock_report("linuxcnc_hexapod", "genhexkins")
    assert [check.name for check in report.failures] == ["inverse refusal"]
    assert checks["inverse refusal"].detail.startswith("returns 0 for x = NaN, x = inf")
    assert report.max_abs_error_mm <= 1e-9 * 25.4
    assert "the first call after loading (a switchable module starts it from the all-zero pose" in checks["forward"].detail


def test_genhexkins_on_a_mm_machine_names_its_max_error():
    robot = load_robot("linuxcnc_hexapod")
    setp = [("setp", (f"genhexkins.{kind}.{index}.{axis}", value)) for index, limb in enumerate(robot.limbs)
            for kind, point in (("base", limb.base_point), ("platform", limb.platform_point))
            for axis, value in zip("xyz", point)]
    report, checks = stock_report("linuxcnc_hexapod", "genhexkins", "units", "mm", *(item for pair in setp for item in pair))
    assert report.max_abs_error_mm <= 1e-9
    assert "returned -2" in checks["forward"].detail
    assert checks["forward"].diagnoses == [
        "genhexkins.max-error is 500 mm: the forward gives up (-2) once the joints' error exceeds it, a bound sized "
        "for inch machines; on a mm machine set it about 25.4 times larger (setp genhexkins.max-error 12700)"]


def test_genhexkins_against_extensions_is_told_it_reports_absolute_lengths():
    robot = load_robot("hexapod")
    setp = tuple((f"genhexkins.{kind}.{index}.{axis}", value) for index, limb in enumerate(robot.limbs)
                 for kind, point in (("base", limb.base_point), ("platform", limb.platform_point))
                 for axis, value in zip("xyz", point))
    host = get_host("linuxcnc").configured(setp=setp)
    report = verify_library(host.as_seen(robot), STOCK / "genhexkins.so", "genhexkins", VerifyOptions(samples=1000),
                            host=host)
    values = next(check for check in report.checks if check.name == "values")
    assert not values.passed and len(values.diagnoses) == 6
    assert values.diagnoses[0] == (
        "joint 0 (leg1) is off by a constant +399.413 mm on every pose and posture: the routine reports the leg's "
        "absolute strut length, not its extension from the reference length 399.413 mm (as LinuxCNC's genhexkins "
        "does): to verify it, set reference_length: 0")


def test_an_inch_machine_gets_its_module_in_inches(tmp_path):
    host = get_host("linuxcnc").configured(units="inch")
    robot = load_robot("hexapod")
    built = host.build(robot, tmp_path / "inch")
    report = verify_library(host.as_seen(robot), built.library, built.routine, VerifyOptions(samples=2000), host=host)
    assert report.passed, [(check.name, check.detail) for check in report.failures]
    files = render_package(robot, "inch")
    assert f"setp hexapodkins.leg1.reference-length {399.413 * (1 / 25.4)!r}\n" in files["hexapodkins.hal"]
    assert "X Y Z in inch" in files["hexapodkins.c"]
    # rounding's floor for the forward's Newton: 1e-9 of the robot's 515 mm (z 465 + 50), in inches
    assert f"#define KINGEN_STALL {515e-9 / 25.4!r} " in files["hexapodkins.c"]
    # Newton's tolerance: 1e-12 of the same 515 mm, in inches too
    assert f"setp hexapodkins.tolerance {515e-12 / 25.4!r}\n" in files["hexapodkins.hal"]


def test_towers_in_another_order_are_named(tmp_path):
    """rotarydeltakins against a robot file with hips 1 and 2 in the other order."""
    text = (robots_dir() / "rotary_delta.yaml").read_text()
    swapped = tmp_path / "rotary_delta.yaml"
    hips = ("{type: rotary_delta, platformradius: 10, thighlength: 10, shinlength: 14, footradius: 6, travel: [-45, 90]}")
    assert hips in text
    limbs = "\n".join(
        f"  - {{name: hip{index}, model: crank, pivot: [{float(10 * np.cos(np.radians(angle)))!r}, {float(10 * np.sin(np.radians(angle)))!r}, 0], "
        f"crank_direction: {angle}, crank_length: 10, rod_length: 14, "
        f"platform_point: [{float(6 * np.cos(np.radians(angle)))!r}, {float(6 * np.sin(np.radians(angle)))!r}, 0], travel: [-45, 90]}}"
        for index, angle in enumerate((-90.0, 150.0, 30.0)))
    swapped.write_text(text.replace("layout: " + hips, "limbs:\n" + limbs))
    host = get_host("linuxcnc")
    report = verify_library(host.as_seen(load_robot(swapped)), STOCK / "rotarydeltakins.so", "rotarydeltakins",
                            VerifyOptions(samples=1000), host=host)
    values = next(check for check in report.checks if check.name == "values")
    assert values.diagnoses[:2] == ["joint 1 (hip1) holds the values of reference joint 2 (hip2): joints swapped in the "
                                    "solutions array", "joint 2 (hip2) holds the values of reference joint 1 (hip1): "
                                    "joints swapped in the solutions array"]


def test_bench_times_a_module(tmp_path, capsys):
    assert main(["bench", "hexapod", "--host", "linuxcnc", "--calls", "2000", "-o", str(tmp_path / "b"),
                 "--json", str(tmp_path / "bench.json")]) == 0
    figures = __import__("json").loads((tmp_path / "bench.json").read_text())
    assert figures["routine"] == "hexapodkins" and figures["postures"] == 1 and figures["verify_passed"]
    assert figures["batch_ns_per_call"] > 0 and figures["cffi_ns_per_call"] > 0


@pytest.mark.parametrize("name", ["linear_delta", "rotary_delta", "linuxcnc_hexapod"])
def test_the_packages_setp_lines_give_back_the_verified_geometry(name, modules):
    """Every setp line of <name>kins.hal holds the module's own double: a module set from the
    package verifies as the built one does."""
    robot, seen, built = modules(name)
    host = get_host("linuxcnc")
    files = render_package(robot, host.machine_units(robot))
    setp = tuple((line.split()[1], float(line.split()[2])) for line in files[f"{built.routine}.hal"].splitlines()
                 if line.startswith("setp "))
    configured = host.configured(setp=setp)
    report = verify_library(seen, built.library, built.routine, VerifyOptions(samples=2000), host=configured)
    assert report.passed, [(check.name, check.detail) for check in report.failures]
    assert len(setp) > 4 * robot.dof


def test_a_name_past_linuxcncs_hal_limit_gets_a_shorter_hal_component_that_verifies(tmp_path):
    """linuxcnc_hexapod_calibrated (calibrate's name) would make 55-character pin names: its HAL
    component is cut to its module name's first characters and 4 hex digits of its sha256, every
    pin and parameter fits LinuxCNC's 47 characters, the package's setp lines name them, and the
    module verifies through the HAL stand-in (which refuses a longer name, as LinuxCNC does).
    The module (its file, loadrt, the .ini's KINEMATICS) has the component's name: LinuxCNC's
    halcmd unloads a realtime module by its component's name."""
    import hashlib

    path = tmp_path / "linuxcnc_hexapod_calibrated.yaml"
    path.write_text((robots_dir() / "linuxcnc_hexapod.yaml").read_text().replace(
        "name: linuxcnc_hexapod\n", "name: linuxcnc_hexapod_calibrated\n"))
    robot = load_robot(path)
    host = get_host("linuxcnc")
    longest = len(".strut0.platform-point.x")
    component = "linuxcnc_hexapod_calibratedkins"[:47 - longest - 5] + "-" + hashlib.sha256(
        b"linuxcnc_hexapod_calibratedkins").hexdigest()[:4]
    built = host.build(robot, tmp_path / "b")
    assert f'#define KINGEN_COMPONENT "{component}"' in built.source.read_text()
    assert built.routine == component and built.library.name == f"{component}.so"
    package = render_package(robot, host.machine_units(robot))
    assert f"loadrt {component}\n" in package[f"{component}.hal"]
    assert re.search(rf"^KINEMATICS = {re.escape(component)}$", package[f"{component}.ini"], re.M)
    setp = [line.split()[1] for line in package[f"{component}.hal"].splitlines() if line.startswith("setp ")]
    assert setp and all(name.startswith(f"{component}.") and len(name) <= 47 for name in setp)
    assert max(map(len, setp)) == 47
    module = host.load(built.library, built.routine, host.as_seen(robot))
    own = ["status", "iterations", "payload.mass", *(f"{part}.{axis}" for part in ("payload.centre", "gravity")
                                                     for axis in "xyz"), *(f"load.{index}" for index in range(6))]
    assert sorted(module.hal_names()) == sorted({*setp, *(f"{component}.{name}" for name in own)})
    report = verify_library(host.as_seen(robot), built.library, built.routine, VerifyOptions(samples=300), host=host)
    assert report.passed, [(check.name, check.detail) for check in report.failures]


def test_limb_names_no_hal_component_leaves_room_for_are_refused_in_one_line(tmp_path, capsys):
    path = tmp_path / "robot.yaml"
    path.write_text((robots_dir() / "linuxcnc_hexapod.yaml").read_text().replace(
        "name: strut0", "name: the_first_strut_of_the_hexapod_ab"))
    assert main(["build", str(path), "--host", "linuxcnc", "-o", str(tmp_path / "b")]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "Traceback" not in error
    cut = "linu-" + hashlib.sha256(b"linuxcnc_hexapodkins").hexdigest()[:4]
    longest = f"{cut}.the_first_strut_of_the_hexapod_ab.platform-point.x"
    assert (f"{path}:3: name: the HAL name '{longest}' has {len(longest)} "
            f"characters with the HAL component cut to its shortest; LinuxCNC takes at most 47: shorten the limbs' "
            f"names") in error


def test_golden_values_of_other_postures_are_said_to_be_unchecked(modules):
    _, seen, built = modules("tau")
    report = verify_library(seen, built.library, built.routine, VerifyOptions(samples=500), host=get_host("linuxcnc"))
    assert [check.name for check in report.checks if check.name.startswith("golden")] == ["golden[0]"]
    assert "golden [1], [2] not checked: at other postures than 0, the one the routine answers" in report.notices


@pytest.mark.parametrize("posture", [0, 7])
def test_leaning_rails_pass_forward_in_either_working_posture(tmp_path, posture):
    """The Gantry-Tau's rails leaned from -z to (0.28, 0, -0.96) (a unit vector), built in
    posture 0 (every carriage on branch 0) or 7 (branch 1), its published golden values left
    out (they are the vertical rails'), their travel widened to 2700 mm (posture 7's carriage3
    needs 2641 mm at home): the module's forward kinematics, whose Newton steps use each rail's
    transmission f . u of the working branch, returns every pose."""
    text = (robots_dir() / "tau.yaml").read_text()
    text = (text[:text.index("golden:")].replace("direction: [0, 0, -1]", "direction: [0.28, 0, -0.96]")
            .replace("travel: [-1, 2600]", "travel: [-1, 2700]"))
    path = tmp_path / "leaning_tau.yaml"
    path.write_text(text.replace("name: tau", "name: leaning_tau").replace("working_posture: 0",
                                                                          f"working_posture: {posture}"))
    robot = load_robot(path)
    host = get_host("linuxcnc")
    built = host.build(robot, tmp_path / "build")
    report = verify_library(host.as_seen(robot), built.library, built.routine, VerifyOptions(samples=2000), host=host)
    assert report.passed, [(check.name, check.detail) for check in report.failures]
    forward = next(check.detail for check in report.checks if check.name == "forward")
    servo = re.search(r"a servo cycle away: (\d+) of (\d+) returned the pose, 0 failed", forward)
    assert servo and servo.group(1) == servo.group(2) and int(servo.group(2)) > 100
    far = re.search(r"far away: (\d+) of (\d+) returned", forward)
    assert far and far.group(1) == far.group(2), forward
