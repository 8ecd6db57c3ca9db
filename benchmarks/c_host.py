"""The C host's library against the other hosts' routines, printed as Markdown tables (for the
closing notes and docs/how-to/own-controller.md). Figures are printed, never asserted.

    python benchmarks/c_host.py [--calls N] [--single-calls N] [--robots tau,ceart,...] [--forward-poses N]
                                [--no-package] [--callgrind]

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
4. With --callgrind (valgrind installed): instructions per inverse call, C against DELMIA, counted
   by callgrind over COUNTED_CALLS calls (inclusive, the routine's function): a figure that
   the machine's load cannot move, where wall time on a shared machine can.
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

COUNTED_CALLS = 2000
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


def count_one(host_name, name):
    """One batch of COUNTED_CALLS inverse calls (run under callgrind by instructions())."""
    robot = load_robot(name)
    with tempfile.TemporaryDirectory() as folder:
        _, routine = loaded(host_name, robot, folder)
        routine.batch_runner(t6_from_pose(sample_poses(robot, COUNTED_CALLS, 0)))()


def instructions(robots):
    if shutil.which("valgrind") is None:
        print("\nvalgrind is not installed: instructions were not counted")
        return
    print("\n| robot | DELMIA instructions/call | C instructions/call | C / DELMIA |\n| --- | --- | --- | --- |")
    for name in robots:
        counts = {}
        for host_name, function in (("delmia", f"kin_{name}"), ("c", f"kingen_{name}_inverse")):
            with tempfile.TemporaryDirectory() as folder:
                out = Path(folder) / "callgrind.out"
                subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", sys.executable,
                                __file__, "--count-one", host_name, name], capture_output=True, check=True)
                report = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100", str(out)],
                                        capture_output=True, text=True, check=True).stdout
            line = next(line for line in report.splitlines() if f":{function} [" in line)
            counts[host_name] = int(line.split()[0].replace(",", "")) / COUNTED_CALLS
        print(f"| {name} | {counts['delmia']:.0f} | {counts['c']:.0f} | {counts['c'] / counts['delmia']:.3f} |")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=200000)
    parser.add_argument("--single-calls", type=int, default=1000000)
    parser.add_argument("--forward-poses", type=int, default=2000)
    parser.add_argument("--robots", default=",".join(ROBOTS))
    parser.add_argument("--no-package", action="store_true")
    parser.add_argument("--callgrind", action="store_true", help="also count instructions per inverse call")
    parser.add_argument("--count-one", nargs=2, metavar=("HOST", "ROBOT"), help=argparse.SUPPRESS)
    arguments = parser.parse_args()
    if arguments.count_one:
        count_one(*arguments.count_one)
        return
    robots = arguments.robots.split(",")
    with tempfile.TemporaryDirectory() as folder:
        inverse(robots, arguments.calls, arguments.single_calls, folder)
        forward(robots, arguments.forward_poses, folder)
        if not arguments.no_package:
            package(robots[0], folder)
    if arguments.callgrind:
        instructions(robots)


if __name__ == "__main__":
    main()
