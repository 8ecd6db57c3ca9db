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
TRAVEL = [28.5, 31.0]
"""inch: every strut's travel (the sample hexapod's struts are 29.75 in at home)."""
JOINT_SPEED = 0.5
"""inch/s: every strut's MAX_VELOCITY in the .ini."""
PROGRAMS = {
    "clean": "G21 G90 G61\nG1 X10 Y0 Z508 F400\nG3 X-10 Y0 I-10 J0\nG1 X0 Y5 A2 B-1\nG1 Z515\nG1 X0 Y0 Z508 A0 B0\nM2\n",
    "travel": "G21 G90 G61\nG1 Z515 F600\nG1 X5\nG1 Z560\nG1 Z508\nM2\n",
    "speed": "G21 G90 G61\nG1 Z512 F300\nG1 Z540 F2000\nG1 Z508 F300\nM2\n",
}
"""The programs: "travel" leaves the struts' 31 in at line 4; "speed" asks about 0.9 in/s of the
struts at line 3 (2000 mm/min along Z), which LinuxCNC's planner, judging only world
coordinates, commands all the same."""


@pytest.fixture(autouse=True)
def linuxcnc_machine():
    reason = missing()
    if reason is not None:
        skip_or_fail(reason)


def limited_robot(folder):
    document = yaml.safe_load((ROBOTS / "linuxcnc_hexapod.yaml").read_text())
    for limb in document["limbs"]:
        limb["travel"] = TRAVEL
    path = folder / "limited_hexapod.yaml"
    path.write_text(yaml.safe_dump(document))
    return path


def run_program(robot_file, program, tmp_path):
    """Run ``program`` in LinuxCNC on kingen's module for ``robot_file``: (the .ini, the driver's result)."""
    robot = load_robot(str(robot_file))
    host = get_host("linuxcnc")
    built = host.build(robot, tmp_path / "module")
    modules = tmp_path / "modules"
    shutil.copytree(MODULES, modules, symlinks=True)
    shutil.copy2(built.library, modules / built.library.name)
    ini = machine_ini(robot, tmp_path, render_package(robot, "inch")[f"{built.routine}.ini"], "inch")
    text = ini.read_text().replace("MAX_VELOCITY = 50\nMAX_ACCELERATION = 500\nHOME_SEQUENCE",
                                   f"MAX_VELOCITY = {JOINT_SPEED}\nMAX_ACCELERATION = 500\nHOME_SEQUENCE")
    text = text.replace(f"DISPLAY = {Path(__file__).parent / 'linuxcnc' / 'driver.py'}", f"DISPLAY = {DRIVER}")
    text = text.replace("[TRAJ]\n", "[TRAJ]\nMAX_LINEAR_ACCELERATION = 20\n", 1)
    ini.write_text(text)
    fifo = Path(tempfile.mkdtemp(prefix="kingen-rtapi-"))
    fifo.chmod(0o777)
    result = tmp_path / "result.json"
    environment = {**os.environ, "RTAPI_UID": "65534", "RTAPI_FIFO_PATH": str(fifo / "rtapi_fifo"),
                   "KINGEN_RESULT": str(result), "KINGEN_PROGRAM": str(program)}
    with open("/tmp/kingen-linuxcnc-test.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        run = subprocess.run(["unshare", "-m", "sh", "-c",
                              f"mount --bind '{modules}' '{MODULES}' && exec linuxcnc '{ini}'"],
                             cwd=tmp_path, env=environment, capture_output=True, text=True, timeout=300)
    shutil.rmtree(fifo, ignore_errors=True)
    assert result.is_file(), f"exit {run.returncode}: " + run.stdout[-2000:] + run.stderr[-2000:]
    outcome = json.loads(result.read_text())
    assert outcome["log"] == [], outcome["log"]
    return ini, outcome


WINDOW = 25


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
    """(lines, speeds): the line motion was on (midway) and each strut's speed (in/s) between polls
    WINDOW apart, as LinuxCNC commanded the joints (the status it reads is up to one task cycle,
    10 ms, old: over WINDOW polls of 10 ms that is a few per cent)."""
    samples = machine["samples"]
    times = np.array([sample["time"] for sample in samples])
    joints = np.array([sample["joints"][:6] for sample in samples])
    lines = np.array([sample["line"] for sample in samples])
    speeds = np.abs(joints[WINDOW:] - joints[:-WINDOW]) / (times[WINDOW:] - times[:-WINDOW])[:, None]
    return lines[WINDOW // 2:WINDOW // 2 + len(speeds)], speeds


@pytest.mark.xdist_group("linuxcnc")
@pytest.mark.parametrize("name", sorted(PROGRAMS))
def test_check_path_names_the_line_where_linuxcnc_stops(name, tmp_path, capsys):
    robot_file = limited_robot(tmp_path)
    program = tmp_path / f"{name}.ngc"
    program.write_text(PROGRAMS[name])
    ini, machine = run_program(robot_file, program, tmp_path)
    code = main(["check-path", str(robot_file), str(program), "--ini", str(ini), "--json", str(tmp_path / "r.json"),
                 "--csv", str(tmp_path / "samples.csv")])
    capsys.readouterr()
    report = json.loads((tmp_path / "r.json").read_text())
    lines = sorted({problem["line"] for problem in report["problems"]})
    stopped = [int(re.search(r"on line (\d+)", error["text"]).group(1)) for error in machine["errors"]
               if re.search(r"on line (\d+)", error["text"])]
    motion_lines, speeds = measured_speeds(machine)
    too_fast = sorted(set(motion_lines[np.any(speeds > JOINT_SPEED * 1.1, axis=1)]))
    if name == "clean":
        assert machine["finished"] and too_fast == [] and code == 0 and lines == []
    elif name == "travel":
        assert not machine["finished"] and stopped[0] == 4 and code == 1 and lines[0] == 4
    else:  # LinuxCNC's planner ignores joint speeds in world mode: it commands them, the drives cannot follow
        assert machine["finished"] and too_fast == [3] and code == 1 and lines == [3]
        peak = max(problem["value"] for problem in report["problems"] if problem["kind"] == "joint speed")
        assert peak / 25.4 == pytest.approx(np.max(speeds), rel=0.1)
    samples = np.genfromtxt(tmp_path / "samples.csv", delimiter=",", names=True)
    path = np.column_stack([samples[axis] for axis in ("x", "y", "z")])
    world = np.array([sample["world"][:3] for sample in machine["samples"]]) * 25.4
    assert np.max(distance_to_path(world, path)) <= 0.01
