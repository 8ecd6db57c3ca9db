"""The C host's library against the other hosts' routines, printed as Markdown tables (for the
closing notes and docs/how-to/own-controller.md). Figures are printed, never asserted.

    python benchmarks/c_host.py [--calls N] [--single-calls N] [--robots tau,ceart,...] [--forward-poses N]
                                [--no-package]

1. Inverse: the C library's kingen_<name>_inverse against DELMIA's kin_<name> for the same
   robot, both through their host's C batch driver on the same poses, timed in turns
   (kingen.verify.bench.compare: ns per call, median of the rounds); goal C <= 1.15 x DELMIA.
   Beside it, each C call timed singly (--single-calls, a million by default): median and worst.
2. Forward: kingen_<name>_forward against LinuxCNC's module's kinematicsForward (kingen's own
   module for the robot) from the reference's joints of regular poses at the working posture,
   seeded a servo cycle away (0.01 mm, 0.01 degree), both from C over the batch; best of 5,
   ns per call; goal C <= 1.5 x LinuxCNC. Robots LinuxCNC drives only.
3. Package: `kingen package ROBOT --host c`, then cmake configure, build and run of the example
   (wall seconds of each), when cmake is installed.
"""

import argparse
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from kingen.conventions import matrix_from_t6, t6_from_pose
from kingen.hosts import get_host
from kingen.hosts.linuxcnc.checks.forward import regular_poses
from kingen.hosts.linuxcnc.render import robot_problem as linuxcnc_problem
from kingen.kinematics.poses import sample_poses
from kingen.robot.model import load_robot
from kingen.verify.bench import compare

ROBOTS = ("tau", "linear_delta", "rotary_delta", "hexapod", "linuxcnc_hexapod", "ceart", "iwf", "exechon")


def loaded(host_name, robot, folder):
    host = get_host(host_name)
    seen = host.as_seen(robot)
    built = host.build(robot, Path(folder) / host_name)
    return seen, host.load(built.library, built.routine, seen)


def inverse(robots, calls, single_calls, folder):
    print("| robot | postures | DELMIA ns/call | C ns/call | C / DELMIA (median) | (min) | C single call median | worst |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for name in robots:
        robot = load_robot(name)
        _, delmia = loaded("delmia", robot, folder)
        _, library = loaded("c", robot, folder)
        timings = compare(robot, {"delmia": delmia, "c": library}, calls=calls)
        single = library.call_times(t6_from_pose(sample_poses(robot, 20000, 0)), single_calls)
        ratio = timings["c"]["median"] / timings["delmia"]["median"]
        print(f"| {name} | {robot.postures} | {timings['delmia']['median']:.1f} | {timings['c']['median']:.1f} | "
              f"{ratio:.3f} | {timings['c']['min'] / timings['delmia']['min']:.3f} | {statistics.median(single):.0f} ns | {max(single):.0f} ns ({single_calls:,} calls) |")


def _best_ns(function, count, repeats=5):
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        best = min(best, time.perf_counter() - start)
    return best / count * 1e9


def forward(robots, poses_count, folder):
    print("\n| robot | poses | LinuxCNC ns/call | C ns/call | C / LinuxCNC | LinuxCNC failed | C failed |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for name in robots:
        robot = load_robot(name)
        if linuxcnc_problem(robot) is not None:
            continue
        seen, module = loaded("linuxcnc", robot, folder)
        _, library = loaded("c", robot, folder)
        poses, joints = regular_poses(seen, sample_poses(seen, poses_count, seed=1))
        generator = np.random.default_rng(0)
        seeds = poses + np.concatenate([generator.normal(size=(len(poses), 3)) * 0.01 / np.sqrt(3),
                                        generator.normal(size=(len(poses), 3)) * 0.01 / np.sqrt(3)], axis=1)
        seeds[:, 3:] *= np.any(seen.verification.range[3:])  # a translating platform keeps its angles
        machine = np.zeros((len(poses), 16))
        machine[:, :robot.dof] = joints / module.joint_scale()
        emc = np.zeros((len(poses), 9))
        emc[:, :3], emc[:, 3:6] = seeds[:, :3] / module.scale, seeds[:, 3:]
        homogeneous = matrix_from_t6(t6_from_pose(seeds)).reshape(-1, 16)
        postures = np.full(len(poses), robot.working_posture if robot.working_posture_given else 0)
        linuxcnc_returns = module.forward(machine, emc)[1]
        c_returns = library.forward(joints, postures, homogeneous)[2]
        linuxcnc_ns = _best_ns(lambda: module.forward(machine, emc), len(poses))
        c_ns = _best_ns(lambda: library.forward(joints, postures, homogeneous), len(poses))
        print(f"| {name} | {len(poses)} | {linuxcnc_ns:.0f} | {c_ns:.0f} | {c_ns / linuxcnc_ns:.3f} | "
              f"{int(np.count_nonzero(linuxcnc_returns))} | {int(np.count_nonzero(c_returns))} |")


def package(name, folder):
    if shutil.which("cmake") is None:
        print("\ncmake is not installed: the package's build was not measured")
        return
    package_dir, build = Path(folder) / "package", Path(folder) / "package-build"
    steps = [("kingen package", [sys.executable, "-m", "kingen.cli", "package", name, "--host", "c", "-o", str(package_dir)]),
             ("cmake configure", ["cmake", "-S", str(package_dir), "-B", str(build)]),
             ("cmake build", ["cmake", "--build", str(build)]),
             ("example run", [str(build / f"kingen_{name}_example")])]
    print(f"\n| step ({name}) | seconds |\n| --- | --- |")
    total = 0.0
    for label, command in steps:
        start = time.perf_counter()
        done = subprocess.run(command, capture_output=True, text=True)
        seconds = time.perf_counter() - start
        total += seconds
        print(f"| {label} | {seconds:.2f} |")
        if done.returncode != 0:
            print(f"\n{label} failed:\n{done.stdout}{done.stderr}")
            return
    print(f"| total | {total:.2f} |\n\nThe example printed:\n\n```\n{done.stdout}```")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=200000)
    parser.add_argument("--single-calls", type=int, default=1000000)
    parser.add_argument("--forward-poses", type=int, default=2000)
    parser.add_argument("--robots", default=",".join(ROBOTS))
    parser.add_argument("--no-package", action="store_true")
    arguments = parser.parse_args()
    robots = arguments.robots.split(",")
    with tempfile.TemporaryDirectory() as folder:
        inverse(robots, arguments.calls, arguments.single_calls, folder)
        forward(robots, arguments.forward_poses, folder)
        if not arguments.no_package:
            package(robots[0], folder)


if __name__ == "__main__":
    main()
