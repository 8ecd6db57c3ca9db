"""The C host's library against the other hosts' routines, printed as Markdown tables, and with
--json written as plain data for benchmarks/run.py (the performance page's section). Figures
are printed, never asserted.

    python benchmarks/c_host.py [--calls N] [--single-calls N] [--robots tau,ceart,...] [--forward-poses N]
                                [--no-package] [--callgrind] [--json FILE]

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
import json
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

ABOUT = ("The C host's library (`--host c`) against the DELMIA routine and the LinuxCNC module of the same robot, "
         "and its CMake package's build ([Your own controller](how-to/own-controller.md)). Goals: inverse "
         "C <= 1.15 x DELMIA, forward C <= 1.5 x LinuxCNC.")
"""What the section measures, for the performance page (links relative to docs/)."""
COUNTED_CALLS = 2000
ROBOTS = ("tau", "linear_delta", "rotary_delta", "hexapod", "linuxcnc_hexapod", "ceart", "iwf", "exechon")


def loaded(host_name, robot, folder):
    host = get_host(host_name)
    seen = host.as_seen(robot)
    built = host.build(robot, Path(folder) / host_name)
    return seen, host.load(built.library, built.routine, seen)


def inverse(robots, calls, single_calls, folder):
    """Per robot: DELMIA's and C's ns per call (median and minimum of the rounds) and C's single calls."""
    rows = []
    for name in robots:
        robot = load_robot(name)
        _, delmia = loaded("delmia", robot, folder)
        _, library = loaded("c", robot, folder)
        timings = compare(robot, {"delmia": delmia, "c": library}, calls=calls)
        single = library.call_times(t6_from_pose(sample_poses(robot, 20000, 0)), single_calls)
        rows.append({"robot": name, "postures": robot.postures, "delmia": timings["delmia"], "c": timings["c"],
                     "single_median": float(statistics.median(single)), "single_worst": float(max(single))})
        print(rows[-1], file=sys.stderr, flush=True)
    return rows


def _best_ns(function, count, repeats=5):
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        best = min(best, time.perf_counter() - start)
    return best / count * 1e9


def forward(robots, poses_count, folder):
    """Per robot LinuxCNC drives: its module's and C's forward ns per call (best of 5) and failures."""
    rows = []
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
        rows.append({"robot": name, "poses": len(poses),
                     "linuxcnc": _best_ns(lambda: module.forward(machine, emc), len(poses)),
                     "c": _best_ns(lambda: library.forward(joints, postures, homogeneous), len(poses)),
                     "linuxcnc_failed": int(np.count_nonzero(linuxcnc_returns)),
                     "c_failed": int(np.count_nonzero(c_returns))})
    return rows


def package(name, folder):
    """The package's steps and their wall seconds, the failing step's output or the example's."""
    if shutil.which("cmake") is None:
        return {"robot": name, "steps": [], "not_measured": "cmake is not installed"}
    package_dir, build = Path(folder) / "package", Path(folder) / "package-build"
    steps = [("kingen package", [sys.executable, "-m", "kingen.cli", "package", name, "--host", "c", "-o", str(package_dir)]),
             ("cmake configure", ["cmake", "-S", str(package_dir), "-B", str(build)]),
             ("cmake build", ["cmake", "--build", str(build)]),
             ("example run", [str(build / f"kingen_{name}_example")])]
    figures = {"robot": name, "steps": []}
    for label, command in steps:
        start = time.perf_counter()
        done = subprocess.run(command, capture_output=True, text=True)
        figures["steps"].append([label, time.perf_counter() - start])
        if done.returncode != 0:
            figures["failed"] = f"{label} failed:\n{done.stdout}{done.stderr}"
            return figures
    figures["example"] = done.stdout
    return figures


def count_one(host_name, name):
    """One batch of COUNTED_CALLS inverse calls (run under callgrind by instructions())."""
    robot = load_robot(name)
    with tempfile.TemporaryDirectory() as folder:
        _, routine = loaded(host_name, robot, folder)
        routine.batch_runner(t6_from_pose(sample_poses(robot, COUNTED_CALLS, 0)))()


def instructions(robots):
    """Per robot: instructions per inverse call, DELMIA's and C's, counted by callgrind."""
    rows = []
    for name in robots:
        counts = {"robot": name}
        for host_name, function in (("delmia", f"kin_{name}"), ("c", f"kingen_{name}_inverse")):
            with tempfile.TemporaryDirectory() as folder:
                out = Path(folder) / "callgrind.out"
                subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", sys.executable,
                                __file__, "--count-one", host_name, name], capture_output=True, check=True)
                report = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100", str(out)],
                                        capture_output=True, text=True, check=True).stdout
            line = next(line for line in report.splitlines() if f":{function} [" in line)
            counts[host_name] = int(line.split()[0].replace(",", "")) / COUNTED_CALLS
        rows.append(counts)
    return rows


def _table(header, rows):
    return "\n".join([f"| {' | '.join(header)} |", "| " + " | ".join("---" for _ in header) + " |",
                      *(f"| {' | '.join(row)} |" for row in rows)])


def markdown(figures):
    """The figures as Markdown: inverse, forward, the package's steps, instructions when counted."""
    blocks = [f"Inverse: both through their host's C batch driver on the same poses, {figures['calls']:,} calls, "
              f"timed in turns (ns per call, median and minimum of the rounds); beside it, "
              f"{figures['single_calls']:,} C calls timed singly (median and worst).",
              _table(["robot", "postures", "DELMIA ns/call", "C ns/call", "C / DELMIA (median)", "(min)",
                      "C single call median", "worst"],
                     [[row["robot"], str(row["postures"]), f"{row['delmia']['median']:.1f}", f"{row['c']['median']:.1f}",
                       f"{row['c']['median'] / row['delmia']['median']:.3f}", f"{row['c']['min'] / row['delmia']['min']:.3f}",
                       f"{row['single_median']:,.0f} ns", f"{row['single_worst']:,.0f} ns"] for row in figures["inverse"]]),
              f"Forward: from the reference's joints of up to {figures['forward_poses']:,} regular poses at the working "
              "posture, seeded a servo cycle away (0.01 mm, 0.01 degree); best of 5, ns per call.",
              _table(["robot", "poses", "LinuxCNC ns/call", "C ns/call", "C / LinuxCNC", "LinuxCNC failed", "C failed"],
                     [[row["robot"], str(row["poses"]), f"{row['linuxcnc']:.0f}", f"{row['c']:.0f}",
                       f"{row['c'] / row['linuxcnc']:.3f}", str(row["linuxcnc_failed"]), str(row["c_failed"])]
                      for row in figures["forward"]])]
    built = figures.get("package")
    if built is None:
        blocks.append("The package's build was not measured (--no-package).")
    elif "not_measured" in built:
        blocks.append(f"The package's build was not measured: {built['not_measured']}.")
    else:
        steps = [[label, f"{seconds:.2f}"] for label, seconds in built["steps"]]
        blocks.append(f"`kingen package {built['robot']} --host c`, then its CMake build and example, wall seconds:")
        blocks.append(_table([f"step ({built['robot']})", "seconds"],
                             [*steps, ["total", f"{sum(seconds for _, seconds in built['steps']):.2f}"]]))
        blocks.append(f"```\n{built['failed']}```" if "failed" in built else
                      f"The example printed:\n\n```\n{built['example']}```")
    if figures.get("instructions") is None:
        blocks.append("Instructions per call were not counted in this run (`--callgrind` counts them with valgrind).")
    elif isinstance(figures["instructions"], str):
        blocks.append(f"Instructions were not counted: {figures['instructions']}.")
    else:
        blocks.append(f"Instructions per inverse call, counted by callgrind over {COUNTED_CALLS:,} calls "
                      "(inclusive, the routine's function): a figure the machine's load cannot move.")
        blocks.append(_table(["robot", "DELMIA instructions/call", "C instructions/call", "C / DELMIA"],
                             [[row["robot"], f"{row['delmia']:.0f}", f"{row['c']:.0f}", f"{row['c'] / row['delmia']:.3f}"]
                              for row in figures["instructions"]]))
    return "\n\n".join(blocks) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=200000)
    parser.add_argument("--single-calls", type=int, default=1000000)
    parser.add_argument("--forward-poses", type=int, default=2000)
    parser.add_argument("--robots", default=",".join(ROBOTS))
    parser.add_argument("--no-package", action="store_true")
    parser.add_argument("--callgrind", action="store_true", help="also count instructions per inverse call")
    parser.add_argument("--json", type=Path, help="Also write the figures to this file as JSON.")
    parser.add_argument("--count-one", nargs=2, metavar=("HOST", "ROBOT"), help=argparse.SUPPRESS)
    arguments = parser.parse_args()
    if arguments.count_one:
        count_one(*arguments.count_one)
        return
    robots = arguments.robots.split(",")
    figures = {"calls": arguments.calls, "single_calls": arguments.single_calls,
               "forward_poses": arguments.forward_poses, "package": None, "instructions": None}
    with tempfile.TemporaryDirectory() as folder:
        figures["inverse"] = inverse(robots, arguments.calls, arguments.single_calls, folder)
        figures["forward"] = forward(robots, arguments.forward_poses, folder)
        if not arguments.no_package:
            figures["package"] = package(robots[0], folder)
    if arguments.callgrind:
        figures["instructions"] = instructions(robots) if shutil.which("valgrind") else "valgrind is not installed"
    print(markdown(figures))
    if arguments.json:
        arguments.json.write_text(json.dumps(figures, indent=1) + "\n")


if __name__ == "__main__":
    main()
