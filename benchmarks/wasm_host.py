"""The WebAssembly module (``--host wasm``) against the C library it is compiled from, printed as
Markdown tables, and with --json written as plain data for benchmarks/run.py (the performance
page's section). Figures are printed, never asserted.

    python benchmarks/wasm_host.py [--robots tau,hexapod] [--rounds N] [--calls N] [--json FILE]

1. verify: wall seconds of the whole `kingen verify ROBOT --host c` and `--host wasm` processes
   (default samples; both built once before, so no compile is timed), run in turns, median and
   range of the rounds; goal: wasm about as long as c.
2. Inverse: ns per call of the C library's and the module's kingen_<name>_inverse, both through
   the batch driver (the module's compiled into it, run by wasmtime) on the same poses, timed in
   turns (kingen.verify.bench.compare: median of the rounds).
"""

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from c_host import _table, loaded
from kingen.robot.model import load_robot
from kingen.verify.bench import compare

ABOUT = ("The robot's C library compiled to WebAssembly (`--host wasm`, run by wasmtime) against the same library "
         "as a shared object (`--host c`) ([Kinematics in a browser](how-to/webassembly.md)). Goal: "
         "`kingen verify --host wasm` about as long as `--host c`.")
"""What the section measures, for the performance page (links relative to docs/)."""
ROBOTS = ("tau", "hexapod")
HOSTS = ("c", "wasm")


def verify_seconds(robots, rounds, folder):
    """Per robot and host: the wall seconds of each round's `kingen verify`, hosts in turns."""
    rows = []
    for name in robots:
        command = {host: [sys.executable, "-m", "kingen.cli", "verify", name, "--host", host, "-o",
                          str(Path(folder) / name / host)] for host in HOSTS}
        for host in HOSTS:  # build once, untimed
            subprocess.run(command[host], capture_output=True, check=True)
        seconds = {host: [] for host in HOSTS}
        for _ in range(rounds):
            for host in HOSTS:
                start = time.perf_counter()
                subprocess.run(command[host], capture_output=True, check=True)
                seconds[host].append(time.perf_counter() - start)
        rows.append({"robot": name, **seconds})
    return rows


def inverse(robots, calls, folder):
    """Per robot: the C library's and the module's ns per inverse call (median and minimum of the rounds)."""
    rows = []
    for name in robots:
        robot = load_robot(name)
        routines = {host: loaded(host, robot, folder)[1] for host in HOSTS}
        rows.append({"robot": name, "postures": robot.postures,
                     **compare(robot, routines, calls=calls)})
    return rows


def markdown(figures):
    """The figures as Markdown: verify's wall seconds, then ns per inverse call."""
    return "\n\n".join([
        f"`kingen verify ROBOT --host c` and `--host wasm` (10,000 poses), whole processes in turns, "
        f"{figures['rounds']} rounds; wall seconds, median (least, most):",
        _table(["robot", "c", "wasm", "wasm / c (medians)"],
               [[row["robot"], *(f"{statistics.median(row[host]):.2f} ({min(row[host]):.2f}, {max(row[host]):.2f})"
                                 for host in HOSTS),
                 f"{statistics.median(row['wasm']) / statistics.median(row['c']):.2f}"] for row in figures["verify"]]),
        f"Inverse through the batch driver on the same poses, {figures['calls']:,} calls, timed in turns "
        "(ns per call, median and minimum of the rounds):",
        _table(["robot", "postures", "c ns/call", "wasm ns/call", "wasm / c (median)", "(min)"],
               [[row["robot"], str(row["postures"]), f"{row['c']['median']:.1f}", f"{row['wasm']['median']:.1f}",
                 f"{row['wasm']['median'] / row['c']['median']:.2f}", f"{row['wasm']['min'] / row['c']['min']:.2f}"]
                for row in figures["inverse"]]),
    ]) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", default=",".join(ROBOTS))
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--calls", type=int, default=200000)
    parser.add_argument("--json", type=Path, help="Also write the figures to this file as JSON.")
    arguments = parser.parse_args()
    robots = arguments.robots.split(",")
    figures = {"rounds": arguments.rounds, "calls": arguments.calls}
    with tempfile.TemporaryDirectory() as folder:
        figures["verify"] = verify_seconds(robots, arguments.rounds, folder)
        figures["inverse"] = inverse(robots, arguments.calls, folder)
    print(markdown(figures))
    if arguments.json:
        arguments.json.write_text(json.dumps(figures, indent=1) + "\n")


if __name__ == "__main__":
    main()
