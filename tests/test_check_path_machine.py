"""check-path against a real, headless LinuxCNC (Debian's linuxcnc-uspace) running kingen's module
for LinuxCNC's sample hexapod with travel limits: three programs, one that runs clean, one that
leaves a joint's travel at a known line, one whose feed needs more joint speed than the .ini
allows. Where LinuxCNC stops, check-path names the same line before running; where LinuxCNC
runs through, check-path passes; the world positions LinuxCNC passes through lie on the path
check-path samples (within 0.01 mm). The machine is set up as in test_linuxcnc_machine.py
(root, a private mount namespace); in CI (KINGEN_REQUIRE_TOOLCHAINS=1) a missing LinuxCNC fails."""

import fcntl
import json
import os
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import pytest
import yaml

from conftest import skip_or_fail
from kingen.cli import main
from kingen.hosts import get_host
from kingen.hosts.linuxcnc.package import render_package
from kingen.robot.model import load_robot
from test_linuxcnc_machine import MODULES, machine_ini, missing

DRIVER = Path(__file__).parent / "linuxcnc" / "program_driver.py"
ROBOTS = Path(__file__).resolve().parent.parent / "robots"
MACHINES = {
    "linuxcnc_hexapod": {
        "travel": [28.5, 31.0], "joint_speed": 0.5,
        "programs": {
            "clean": "G21 G90 G61\nG1 X5 Y0 Z508 F400\nG3 X-5 Y0 I-5 J0\nG1 X0 Y3 A1 B-0.5\nG1 Z512\n"
                     "G1 X0 Y0 Z508 A0 B0\nM2\n",
            "speed": "G21 G90 G61\nG1 Z510 F600\nG1 Z530 F2000\nG1 Z508 F900\nM2\n",
            "travel": "G21 G90 G61\nG1 Z515 F600\nG1 X5\nG1 Z560\nG1 Z508\nM2\n"}},
    "linear_delta": {
        "travel": None, "joint_speed": 20.0,
        "programs": {
            "clean": "G21 G90 G61\nG1 X8 Y0 Z15 F450\nG2 X-8 Y0 I-8 J0\nG1 X0 Y5 Z22\nG1 X0 Y0 Z15\nM2\n",
            "speed": "G21 G90 G61\nG1 Z20 F600\nG1 Z50 F3000\nG1 Z15 F900\nM2\n",
            "travel": "G21 G90 G61\nG1 Z30 F600\nG1 X5\nG1 Z200\nG1 Z15\nM2\n"}},
}
"""Per robot: the travel every joint is given (None: the robot file's; the sample hexapod's
struts are 29.75 in at home), every joint's MAX_VELOCITY in the .ini (machine units/s), and
three programs: "clean" runs within every limit, "travel" leaves a joint's travel at line 4,
"speed" asks more joint speed than allowed at line 3, which LinuxCNC's planner, judging only
world coordinates, commands all the same."""
SAMPLER = """loadrt sampler depth=120000 cfg={types}
addf sampler.0 servo-thread
setp sampler.0.enable 0
net kingen-line motion.program-line => sampler.0.pin.0
{nets}
"""
"""HAL's sampler recording, every servo period, the line motion executes and each joint's commanded
velocity (program_driver.py enables it while a program runs and reads it after)."""
CASES_IN_ORDER = ("clean", "speed", "travel")
"""The order LinuxCNC runs them in, one after the other: the first two end where they start."""
CASES = [(robot, case) for robot in sorted(MACHINES) for case in CASES_IN_ORDER]


@pytest.fixture(autouse=True)
def linuxcnc_machine():
    reason = missing()
    if reason is not None:
        skip_or_fail(reason)


def robot_file(name, folder):
    """The robot file the machine runs: shipped, or a copy with MACHINES' travel."""
    travel = MACHINES[name]["travel"]
    if travel is None:
        return ROBOTS / f"{name}.yaml"
    document = yaml.safe_load((ROBOTS / f"{name}.yaml").read_text())
    for limb in document["limbs"]:
        limb["travel"] = travel
    path = folder / f"limited_{name}.yaml"
    path.write_text(yaml.safe_dump(document))
    return path


def run_programs(robot_path, programs, joint_speed, folder, sampled=False, blending=""):
    """Run ``programs`` one after the other in one LinuxCNC on kingen's module for the robot file
    at ``robot_path``, every joint at most ``joint_speed``, X Y Z at most [TRAJ]'s acceleration:
    (the .ini, each program's run). ``sampled``: each run also holds every servo period's program
    line and joint velocities (HAL's sampler, program_driver.py); ``blending``: [TRAJ] lines added."""
    robot = load_robot(str(robot_path))
    units = robot.length_unit
    host = get_host("linuxcnc")
    built = host.build(robot, folder / "module")
    modules = folder / "modules"
    shutil.copytree(MODULES, modules, symlinks=True)
    shutil.copy2(built.library, modules / built.library.name)
    ini = machine_ini(robot, folder, render_package(robot, units)[f"{built.routine}.ini"], units)
    text = re.sub(r"(\[JOINT_\d+\][^\[]*?)MAX_VELOCITY = [^\n]*\nMAX_ACCELERATION = [^\n]*\n",
                  rf"\g<1>MAX_VELOCITY = {joint_speed}\nMAX_ACCELERATION = 500\n", ini.read_text())
    text = text.replace(f"DISPLAY = {Path(__file__).parent / 'linuxcnc' / 'driver.py'}", f"DISPLAY = {DRIVER}")
    acceleration = 20 if units == "inch" else 300
    text = text.replace("[TRAJ]\n", f"[TRAJ]\nMAX_LINEAR_ACCELERATION = {acceleration}\n{blending}", 1)
    text = text.replace("MAX_VELOCITY = 50\nMAX_ACCELERATION = 500\n", f"MAX_VELOCITY = 50\nMAX_ACCELERATION = {acceleration}\n")
    if sampled:
        (folder / "sampler.hal").write_text(SAMPLER.format(
            types="s" + "f" * robot.joint_count,
            nets="\n".join(f"net kingen-v{joint} joint.{joint}.vel-cmd => sampler.0.pin.{joint + 1}"
                           for joint in range(robot.joint_count))))
        text = text.replace("HALFILE = LIB:basic_sim.tcl\n", "HALFILE = LIB:basic_sim.tcl\nHALFILE = sampler.hal\n")
    ini.write_text(text)
    fifo = Path(tempfile.mkdtemp(prefix="kingen-rtapi-"))
    fifo.chmod(0o777)
    result = folder / "result.json"
    environment = {**os.environ, "RTAPI_UID": "65534", "RTAPI_FIFO_PATH": str(fifo / "rtapi_fifo"),
                   "KINGEN_RESULT": str(result), "KINGEN_PROGRAMS": json.dumps([str(path) for path in programs]),
                   "KINGEN_SAMPLER": "1" if sampled else ""}
    with open("/tmp/kingen-linuxcnc-test.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        run = subprocess.run(["unshare", "-m", "sh", "-c",
                              f"mount --bind '{modules}' '{MODULES}' && exec linuxcnc '{ini}'"],
                             cwd=folder, env=environment, capture_output=True, text=True, timeout=300)
    shutil.rmtree(fifo, ignore_errors=True)
    assert result.is_file(), f"exit {run.returncode}: " + run.stdout[-2000:] + run.stderr[-2000:]
    outcome = json.loads(result.read_text())
    assert outcome["log"] == [], outcome["log"]
    return ini, outcome["programs"]


@pytest.fixture(scope="module")
def machines(tmp_path_factory):
    """Per robot, run once: (robot file, .ini, {case: (program, LinuxCNC's run)})."""
    done = {}

    def machine(name):
        if name not in done:
            folder = tmp_path_factory.mktemp(name)
            robot_path = robot_file(name, folder)
            programs = {}
            for case in CASES_IN_ORDER:
                programs[case] = folder / f"{case}.ngc"
                programs[case].write_text(MACHINES[name]["programs"][case])
            ini, runs = run_programs(robot_path, list(programs.values()), MACHINES[name]["joint_speed"], folder)
            done[name] = (robot_path, ini, {case: (programs[case], run) for case, run in zip(programs, runs)})
        return done[name]
    return machine


def distance_to_path(points, path):
    """(n,) each point's distance to the polyline through ``path`` (m, 3), mm."""
    start, step = path[:-1], np.diff(path, axis=0)
    length = np.maximum(np.sum(step * step, axis=1), 1e-30)
    distances = []
    for point in points:
        along = np.clip(np.sum((point - start) * step, axis=1) / length, 0.0, 1.0)
        distances.append(np.min(np.linalg.norm(start + along[:, None] * step - point, axis=1)))
    return np.array(distances)


def measured_speeds(machine):
    """(lines, speeds): at each poll, the line motion is executing and each joint's speed
    (units/s) as LinuxCNC's motion computes it, the change of the joint's commanded position over
    one servo period divided by the period's nominal length: motion's own time base. Positions
    differenced over wall-clock poll times move with the machine's load (how old the status is,
    how late the servo thread runs); these do not, and change smoothly from poll to poll (by under
    0.1 % of the peak), so they need no smoothing."""
    samples = machine["samples"]
    lines = np.array([sample["line"] for sample in samples])
    speeds = np.abs(np.array([sample["velocities"] for sample in samples]))
    return lines, speeds


@pytest.mark.xdist_group("linuxcnc")
@pytest.mark.parametrize("name, case", CASES)
def test_check_path_names_the_line_where_linuxcnc_stops(name, case, machines, tmp_path, capsys):
    robot_path, ini, runs = machines(name)
    program, machine = runs[case]
    joint_speed = MACHINES[name]["joint_speed"]
    code = main(["check-path", str(robot_path), str(program), "--ini", str(ini), "--json", str(tmp_path / "r.json"),
                 "--csv", str(tmp_path / "samples.csv")])
    capsys.readouterr()
    report = json.loads((tmp_path / "r.json").read_text())
    lines = sorted({problem["line"] for problem in report["problems"]})
    stopped = [int(re.search(r"on line (\d+)", error["text"]).group(1)) for error in machine["errors"]
               if re.search(r"on line (\d+)", error["text"])]
    motion_lines, speeds = measured_speeds(machine)
    too_fast = sorted(set(motion_lines[np.any(speeds > joint_speed * 1.1, axis=1)]))
    if case == "clean":
        assert machine["finished"] and too_fast == [] and code == 0 and lines == []
    elif case == "travel":
        assert not machine["finished"] and stopped[0] == 4 and code == 1 and lines[0] == 4
    else:  # LinuxCNC's planner ignores joint speeds in world mode: it commands them, the drives cannot follow
        assert machine["finished"] and too_fast == [3] and code == 1 and lines == [3]
        peak = max(problem["value"] for problem in report["problems"] if problem["kind"] == "joint speed")
        scale = 25.4 if load_robot(str(robot_path)).length_unit == "inch" else 1.0
        assert peak / scale == pytest.approx(np.max(speeds), rel=0.01)
    samples = np.genfromtxt(tmp_path / "samples.csv", delimiter=",", names=True)
    path = np.column_stack([samples[axis] for axis in ("x", "y", "z")])
    scale = 25.4 if load_robot(str(robot_path)).length_unit == "inch" else 1.0
    world = np.array([sample["world"][:3] for sample in machine["samples"]]) * scale
    assert np.max(distance_to_path(world, path)) <= 0.01
