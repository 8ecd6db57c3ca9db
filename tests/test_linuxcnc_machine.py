"""kingen's modules in a real, headless LinuxCNC (Debian's linuxcnc-uspace): a machine made of
kingen's package (its [KINS] and [JOINT_n] sections) and LinuxCNC's simulated joints homes,
makes MDI moves and a joint jog; the joints LinuxCNC commands and the world positions it reads
back (through the module's forward) agree with kingen's reference within 1e-9 mm. The module
is loaded from LinuxCNC's module folder by bind-mounting a copy holding it over that folder in
a private mount namespace (unshare -m), so the machine's own folder is never touched: that
needs root, which CI has. In CI (KINGEN_REQUIRE_TOOLCHAINS=1) a missing LinuxCNC fails."""

import fcntl
import json
import os
import shutil
import subprocess
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from conftest import skip_or_fail
from kingen.conventions import t6_from_pose
from kingen.hosts import get_host
from kingen.hosts.linuxcnc.five_axis import axis_of_world, home_axis
from kingen.hosts.linuxcnc.package import render_package
from kingen.robot.model import load_robot
from kingen.kinematics.hybrid.parasitic import on_manifold
from kingen.kinematics.loads import loads
from kingen.kinematics.reference import solve
from kingen.robot.loads_schema import Payload

DRIVER = Path(__file__).parent / "linuxcnc" / "driver.py"
MODULES = Path("/usr/lib/linuxcnc/modules")
MACHINE = """[EMC]
VERSION = 1.1
MACHINE = kingen {name}
[DISPLAY]
DISPLAY = {driver}
[TASK]
TASK = milltask
CYCLE_TIME = 0.010
[RS274NGC]
PARAMETER_FILE = sim.var
[EMCMOT]
EMCMOT = motmod
COMM_TIMEOUT = 1.0
SERVO_PERIOD = 1000000
[HAL]
HALFILE = LIB:basic_sim.tcl
[TRAJ]
HOME = {home}
COORDINATES = {coordinates}
LINEAR_UNITS = {units}
ANGULAR_UNITS = degree
DEFAULT_LINEAR_VELOCITY = {velocity}
MAX_LINEAR_VELOCITY = {velocity}
DEFAULT_ANGULAR_VELOCITY = 20
MAX_ANGULAR_VELOCITY = 20
[EMCIO]
EMCIO = io
CYCLE_TIME = 0.100
TOOL_TABLE = sim.tbl
{axes}
{kins}
"""
PAYLOAD_KG = 50.0
"""The payload the load pins hold in a real LinuxCNC (at the platform origin)."""
CASES = {
    "linuxcnc_hexapod": {"moves": [[0.5, 0.3, 21, 2, -1, 3], [-0.4, 0.2, 19.5, -3, 2, -1]], "jog": 0.05},
    "linear_delta": {"moves": [[10, -5, 20], [-30, 25, 5]], "jog": 1.0},
    # z, A, B commanded; X, Y, C the machine's for them (the module reads z, A, B only)
    "prs_head": {"moves": [[0, 0, -370, 12, -7, 0], [0, 0, -430, -9, 6, 0]], "jog": 2.0},
    # X, Y, Z commanded; A, B, C the machine's for them (the module reads X, Y, Z only)
    "exechon_constrained": {"moves": [[80, -60, -1150, 0, 0, 0], [-120, 150, -1300, 0, 0, 0]], "jog": 2.0},
    "tricept": {"moves": [[200, -100, -1000, 0, 0, 0], [-250, 180, -1250, 0, 0, 0]], "jog": 2.0},
}
"""Per robot: MDI moves (the machine's coordinates, in its units and degrees) and a joint-0 jog;
a machine with task coordinates is sent its parasitic X, Y, C for them."""


def missing():
    """Why a real LinuxCNC cannot run here, or None."""
    if os.geteuid() != 0:
        return "needs root (a private mount namespace for LinuxCNC's module folder)"
    for tool in ("linuxcnc", "unshare", "halcmd"):
        if shutil.which(tool) is None:
            return f"{tool} is not installed (Debian package linuxcnc-uspace; .ci/run installs it)"
    if subprocess.run(["/usr/bin/python3", "-c", "import linuxcnc"], capture_output=True).returncode != 0:
        return "Debian's python3 has no linuxcnc module (linuxcnc-uspace)"
    return None


@pytest.fixture(autouse=True)
def linuxcnc_machine():
    reason = missing()
    if reason is not None:
        skip_or_fail(reason)


def machine_ini(robot, folder, kins_ini, units):
    """A simulated machine's .ini: kingen's [TRAJ] HOME, [KINS] and [JOINT_n] entries (their
    MAX_VELOCITY and MAX_ACCELERATION kingen's), with homing at the HOME kingen wrote (home to
    the current position, which reads as HOME)."""
    joints, home = [], None
    for section in kins_ini.split("\n[")[1:]:
        header, _, body = section.partition("]\n")
        if header == "TRAJ":
            home = body.split("HOME = ")[1].splitlines()[0]
            continue
        # HOME_OFFSET = HOME: the joint homes where it stands and reads HOME there, with no
        # move after homing (from 0 to a delta's 250 mm HOME that took 5 s).
        extra = ("HOME_SEQUENCE = 0\nHOME_SEARCH_VEL = 0\n"
                 f"HOME_LATCH_VEL = 0\nHOME_OFFSET = {body.split('HOME = ')[1].splitlines()[0]}\n"
                 if header.startswith("JOINT") else "")
        joints.append(f"[{header}]\n{body.rstrip()}\n{extra}")
    coordinates = ("X Y Z A C" if robot.wrist is not None and not robot.wrist.whole_pose
                   else "X Y Z A B C" if robot.dof == 6 or robot.task or robot.wrist is not None else "X Y Z")
    axes = "".join(f"[AXIS_{axis}]\nMIN_LIMIT = -5000\nMAX_LIMIT = 5000\nMAX_VELOCITY = 50\nMAX_ACCELERATION = 500\n"
                   for axis in coordinates.split())
    (folder / "sim.tbl").write_text("")
    (folder / "machine.ini").write_text(MACHINE.format(
        name=robot.name, driver=DRIVER, home=home, coordinates=coordinates,
        units=units, velocity=10 if units == "inch" else 100, axes=axes, kins="\n".join(joints)))
    return folder / "machine.ini"


def machine_moves(robot, moves):
    """The moves as sent: a machine with task coordinates gets its parasitic X, Y, C for them."""
    return on_manifold(robot, np.array(moves, dtype=float)).tolist() if robot.task else moves


def run_machine(name, tmp_path, case=None, units=None):
    """Run LinuxCNC on kingen's module for shipped robot ``name`` making the moves of ``case``
    (default CASES[name]) on a machine in ``units`` (LINEAR_UNITS; default the robot file's):
    (robot, the driver's result)."""
    case = CASES[name] if case is None else case
    robot = load_robot(name)
    units = units or robot.length_unit
    host = get_host("linuxcnc").configured(units=units)
    built = host.build(robot, tmp_path / "module")
    modules = tmp_path / "modules"
    shutil.copytree(MODULES, modules, symlinks=True)
    shutil.copy2(built.library, modules / built.library.name)
    ini = machine_ini(robot, tmp_path, render_package(robot, units)[f"{built.routine}.ini"], units)
    fifo = Path(tempfile.mkdtemp(prefix="kingen-rtapi-"))  # reachable by RTAPI_UID (pytest's folders are not)
    fifo.chmod(0o777)
    result = tmp_path / "result.json"
    environment = {**os.environ, "RTAPI_UID": "65534", "RTAPI_FIFO_PATH": str(fifo / "rtapi_fifo"),
                   "KINGEN_RESULT": str(result), "KINGEN_MOVES": json.dumps(machine_moves(robot, case["moves"])),
                   "KINGEN_JOG": str(case["jog"]), "KINGEN_MODULE": built.routine, "KINGEN_AXES": case.get("axes", "XYZABC"),
                   "KINGEN_FIRST_JOG": case.get("first_jog", ""), "KINGEN_PAYLOAD": str(PAYLOAD_KG)}
    with open("/tmp/kingen-linuxcnc-test.lock", "w") as lock:  # one LinuxCNC at a time on a machine
        fcntl.flock(lock, fcntl.LOCK_EX)
        run = subprocess.run(["unshare", "-m", "sh", "-c", f"mount --bind '{modules}' '{MODULES}' && exec linuxcnc '{ini}'"],
                             cwd=tmp_path, env=environment, capture_output=True, text=True, timeout=180)
    shutil.rmtree(fifo, ignore_errors=True)
    assert result.is_file(), f"exit {run.returncode}: " + run.stdout[-2000:] + run.stderr[-2000:]
    outcome = json.loads(result.read_text())
    assert outcome["log"] == [], outcome["log"]
    return robot, outcome


def in_mm(robot, joints):
    scale = 25.4 if robot.length_unit == "inch" else 1.0
    return np.array(joints[:robot.dof]) * np.where(robot.revolute, np.pi / 180.0, scale)


def pose_in_mm(robot, world):
    scale = 25.4 if robot.length_unit == "inch" else 1.0
    pose = np.zeros(6)
    pose[:3] = np.array(world[:3]) * scale
    if robot.dof == 6 or robot.task:
        pose[3:] = world[3:6]
    return pose


# One LinuxCNC runs at a time on a machine (run_machine's lock): under pytest-xdist's
# --dist loadgroup (pyproject.toml) both run on one worker, so that no other waits for the lock.
@pytest.mark.xdist_group("linuxcnc")
@pytest.mark.parametrize("name", sorted(CASES))
def test_linuxcnc_runs_kingens_module_to_the_reference(name, tmp_path):
    """LinuxCNC moves the machine where the reference says, jogs a joint and reads the pose back;
    after each move the load pins hold kingen's static loads for the commanded pose, the payload
    (PAYLOAD_KG at the platform origin) set with halcmd."""
    robot, outcome = run_machine(name, tmp_path)
    posture = robot.working_posture
    assert f"{name}kins.iterations" in outcome["pins"] and f"{name}kins.status" in outcome["pins"]
    held = replace(robot, payload=Payload(mass=PAYLOAD_KG, centre=(0.0, 0.0, 0.0), inertia=((0.0,) * 3,) * 3))
    for move in outcome["moves"]:
        pose = pose_in_mm(robot, move["pose"] + [0.0] * (6 - len(move["pose"])))
        expected = solve(robot, t6_from_pose(pose[None])).joints[0, :, posture]
        assert np.max(np.abs(in_mm(robot, move["joints"]) - expected)) <= 1e-9, move
        assert np.max(np.abs(pose_in_mm(robot, move["world"]) - pose)) <= 1e-9, move
        forces = loads(held, t6_from_pose(pose[None]), postures=[posture]).forces[0, 0]
        assert len(move["loads"]) == robot.dof and np.max(np.abs(forces)) > 1.0, move
        # halcmd prints a float pin with 7 significant digits
        assert np.max(np.abs(np.array(move["loads"]) - forces)) <= 1e-6 * np.max(np.abs(forces)), (move, forces)
    before, after = outcome["jog"]["before"], outcome["jog"]["after"]
    # LinuxCNC's free-mode planner ends an incremental jog within about 1e-9 of the increment.
    assert after["joints"][0] - before["joints"][0] == pytest.approx(CASES[name]["jog"], abs=1e-6)
    assert after["joints"][1:robot.dof] == before["joints"][1:robot.dof]
    world = pose_in_mm(robot, after["world"])
    assert np.max(np.abs(world - pose_in_mm(robot, before["world"]))) > 1e-3  # the platform moved
    back = solve(robot, t6_from_pose(world[None])).joints[0, :, posture]
    assert np.max(np.abs(back - in_mm(robot, after["joints"]))) <= 1e-9


WRIST_CASE = {"moves": [[30, 20, -1470, 12, 40], [-40, 90, -1420, 20, -60]], "axes": "XYZAC", "jog": 2.0,
              "first_jog": "4 10"}
"""The five-axis module of exechon_wrist: X Y Z (tool tip) A C (tool axis) moves, after a joint jog
of Ax5 by 10 degrees off the home, where the tool axis lies along Ax4 (the wrist's singularity,
which the module answers as singular)."""


def tool_t6(robot, world):
    """A tool T6 (1, 4, 4) with the tip and tool axis of the five-axis world X Y Z A C (mm, degrees)."""
    axis = axis_of_world(home_axis(robot), [world[3]], [world[4]])[0]
    x = np.cross([0.0, 1.0, 0.0], axis)
    x /= np.linalg.norm(x)
    t6 = np.eye(4)[None].copy()
    t6[0, 0, :3], t6[0, 1, :3], t6[0, 2, :3], t6[0, 3, :3] = x, np.cross(axis, x), axis, world[:3]
    return t6


WRIST3_CASE = {"moves": [[30, 20, -1270, 170, 10, 30], [-40, 90, -1320, 195, -8, -50]], "jog": 2.0,
               "first_jog": "4 10"}
"""The six-axis module of tricept_wrist3: X Y Z A B C (the tool pose: tip, roll, pitch, yaw) moves,
after a joint jog of ax5 by 10 degrees off the home, where the axis of ax6 lies along ax4 (the
gimbal lock, which the module answers as singular); A
stays near 180 (195 is roll -165) so that the straight move in A B C stays within the wrist's travel."""


WRIST_INCH_CASE = {"moves": [[1.2, 0.8, -57.9, 12, 40], [-1.6, 3.5, -55.9, 20, -60]], "axes": "XYZAC", "jog": 0.08,
                   "first_jog": "4 10"}
"""WRIST_CASE on an inch machine: X Y Z and the joint-0 jog in inches (near WRIST_CASE's mm)."""
WRIST3_INCH_CASE = {"moves": [[1.2, 0.8, -50.0, 170, 10, 30], [-1.6, 3.5, -52.0, 195, -8, -50]], "jog": 0.08,
                    "first_jog": "4 10"}
"""WRIST3_CASE on an inch machine."""


@pytest.mark.xdist_group("linuxcnc")
@pytest.mark.parametrize("name, case, units", [("exechon_wrist", WRIST_CASE, None),
                                               ("tricept_wrist3", WRIST3_CASE, None),
                                               ("exechon_wrist", WRIST_INCH_CASE, "inch"),
                                               ("tricept_wrist3", WRIST3_INCH_CASE, "inch")],
                         ids=["five_axis", "six_axis", "five_axis_inch", "six_axis_inch"])
def test_linuxcnc_runs_a_wrist_machines_module_to_the_reference(name, case, units, tmp_path):
    """The five-axis module (world X Y Z A C: B is not a coordinate) and the six-axis one (X Y Z A
    B C), on a mm machine and an inch one (X Y Z, the legs and the wrist's lengths in inches, the
    angles in degrees): the joints LinuxCNC commands for each move and the world it reads back,
    against the reference, to 1e-9 (machine units); a joint jog moves that joint alone."""
    robot, outcome = run_machine(name, tmp_path, case, units)
    scale = 25.4 if units == "inch" else 1.0
    jogged = outcome["first_jog"]["after"]["joints"]
    assert jogged[4] - outcome["first_jog"]["before"]["joints"][4] == pytest.approx(10.0, abs=1e-6)
    five_axis = len(robot.wrist.names) == 2
    for move in outcome["moves"]:
        pose = np.array(move["pose"], dtype=float)
        pose[:3] *= scale
        asked = tool_t6(robot, pose) if five_axis else t6_from_pose(pose[None])
        expected = solve(robot, asked).joints[0, :, robot.working_posture]
        joints = np.array(move["joints"][:robot.joint_count]) * np.where(robot.revolute, np.pi / 180.0, scale)
        assert np.max(np.abs(joints - expected)) <= 1e-9 * scale, move
        world = np.array(move["world"])[[0, 1, 2, 3, 5] if five_axis else slice(0, 6)]
        assert np.max(np.abs(world - move["pose"])) <= 1e-9, move
    before, after = outcome["jog"]["before"], outcome["jog"]["after"]
    assert after["joints"][0] - before["joints"][0] == pytest.approx(case["jog"], abs=1e-6)
    assert after["joints"][1:] == before["joints"][1:]


@pytest.mark.xdist_group("linuxcnc")
def test_a_shortened_module_loads_and_unloads_in_a_real_linuxcnc(tmp_path):
    """linuxcnc_hexapod_calibrated's module, its name cut to fit HAL's 47 characters, in a real
    LinuxCNC realtime environment: halcmd's loadrt finds its component (halcmd waits for a
    component of the module's name), its payload parameter reads the robot file's (none: 0),
    and unloadrt (by the component's name, as LinuxCNC's shutdown does) removes it."""
    path = tmp_path / "linuxcnc_hexapod_calibrated.yaml"
    path.write_text((Path(__file__).parent.parent / "robots" / "linuxcnc_hexapod.yaml").read_text().replace(
        "name: linuxcnc_hexapod\n", "name: linuxcnc_hexapod_calibrated\n"))
    robot = load_robot(path)
    built = get_host("linuxcnc").build(robot, tmp_path / "module")
    module = built.routine
    assert module.startswith("linuxcnc_hexapod_c-") and built.library.name == f"{module}.so"
    modules = tmp_path / "modules"
    shutil.copytree(MODULES, modules, symlinks=True)
    shutil.copy2(built.library, modules / built.library.name)
    (tmp_path / "run.hal").write_text(f"loadrt {module}\nshow comp {module}\ngetp {module}.payload.mass\n"
                                      f"unloadrt {module}\nshow comp {module}\n")
    fifo = Path(tempfile.mkdtemp(prefix="kingen-rtapi-"))
    fifo.chmod(0o777)
    environment = {**os.environ, "RTAPI_UID": "65534", "RTAPI_FIFO_PATH": str(fifo / "rtapi_fifo")}
    realtime = "/usr/lib/linuxcnc/realtime"
    with open("/tmp/kingen-linuxcnc-test.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        run = subprocess.run(["unshare", "-m", "sh", "-c", f"mount --bind '{modules}' '{MODULES}' && {realtime} start && "
                              f"halcmd -f run.hal; status=$?; {realtime} stop; exit $status"],
                             cwd=tmp_path, env=environment, capture_output=True, text=True, timeout=60)
    shutil.rmtree(fifo, ignore_errors=True)
    assert run.returncode == 0, run.stdout + run.stderr
    _, loaded, unloaded = run.stdout.split("Loaded HAL Components:")
    assert f" RT    {module} " in loaded and "\n0\n" in loaded, run.stdout
    assert module not in unloaded, run.stdout
