"""Speed figures of kingen, printed as Markdown (for the README's 'Speed' section).

    python benchmarks/run.py [--calls N] [--verify-samples N] [--memory-samples N] [--robots ceart,hexapod,...]
                             [--pytest-runs N]

1. Each hand-written floor (benchmarks/floors/<robot>.c) must pass `kingen verify --source`.
2. `kingen bench <robot> --floor ...` times the generated routine against its floor in
   turns (C batch driver, ns per call, minimum and median of the rounds).
3. `kingen verify <robot> --samples N` wall time and peak memory (of kingen and its
   children; with --memory-samples, the first robot once more with that many poses), and
   the start-up of `kingen --version` and of a command that reads a robot (`kingen render`).
4. `pytest --kingen` on a copy of every shipped robot file (the pytest plugin, as a CI job
   runs it): wall time cold (a new, empty kingen cache each run) and warm (the cache one
   untimed run filled), in one process and with `-n 2` (when pytest-xdist is installed),
   the four taken in turns, ``--pytest-runs`` rounds (0: skipped).

Figures are printed, never asserted: the machine they ran on is printed with them.
"""

import argparse
import importlib.util
import json
import os
import platform
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
FLOORS = HERE / "floors"
ROBOTS = HERE.parent / "robots"
KINGEN = [sys.executable, "-m", "kingen.cli"]


def run(arguments):
    """(exit code, stdout, wall seconds, peak resident MiB of the command and its children)."""
    start = time.perf_counter()
    process = subprocess.Popen([*KINGEN, *arguments], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    output = process.stdout.read()
    _, status, usage = os.wait4(process.pid, 0)
    seconds = time.perf_counter() - start
    process.returncode = os.waitstatus_to_exitcode(status)
    return process.returncode, output, seconds, usage.ru_maxrss / 1024.0


def pytest_plugin_times(scratch, rounds):
    """{(cache, workers): [wall seconds]} and the item count of ``pytest --kingen`` on a copy of
    the shipped robot files, cold (a new empty cache per run) and warm (the cache one untimed
    run filled), serial and with ``-n 2`` (only when pytest-xdist is installed), taken in turns."""
    folder = Path(scratch) / "plugin"
    shutil.copytree(ROBOTS, folder / "robots")
    # The folder named twice: once for --kingen, once as what pytest collects (nothing else).
    command = [sys.executable, "-m", "pytest", "--kingen", "robots", "robots", "-q", "-p", "no:cacheprovider"]
    variants = [("cold", ()), ("warm", ())]
    if importlib.util.find_spec("xdist") is not None:
        variants += [("cold", ("-n", "2")), ("warm", ("-n", "2"))]
    warm_cache = folder / "warm-cache"
    times, items = {}, None
    for number in range(rounds + 1):  # run 0 fills the warm cache and is not counted
        for cache, workers in variants:
            cache_folder = warm_cache if cache == "warm" else Path(tempfile.mkdtemp(dir=folder))
            start = time.perf_counter()
            result = subprocess.run([*command, *workers], cwd=folder, capture_output=True, text=True,
                                    env={**os.environ, "KINGEN_CACHE": str(cache_folder)})
            seconds = time.perf_counter() - start
            if cache == "cold":
                shutil.rmtree(cache_folder)
            if result.returncode != 0:
                raise SystemExit(f"pytest --kingen failed (exit {result.returncode}):\n{result.stdout[-2000:]}")
            items = int(re.search(r"(\d+) passed", result.stdout).group(1))
            if number:
                times.setdefault((cache, workers), []).append(seconds)
    return times, items


def machine():
    model = next((line.split(":", 1)[1].strip() for line in Path("/proc/cpuinfo").read_text().splitlines()
                  if line.startswith("model name")), platform.processor())
    compiler = subprocess.run([os.environ.get("CC", "cc"), "--version"], capture_output=True, text=True).stdout
    return (f"{model}, {os.cpu_count()} cores, {platform.system()} {platform.release()}; "
            f"{compiler.splitlines()[0] if compiler else 'cc'}; Python {platform.python_version()}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=200000)
    parser.add_argument("--verify-samples", type=int, default=1000000)
    parser.add_argument("--robots", default=",".join(sorted(path.stem for path in FLOORS.glob("*.c"))))
    parser.add_argument("--memory-samples", type=int, default=0,
                        help="Also verify the first robot with this many poses (peak memory, e.g. 4000000).")
    parser.add_argument("--pytest-runs", type=int, default=5,
                        help="Rounds of pytest --kingen on the shipped robots, cold and warm (0: skip).")
    options = parser.parse_args()
    robots = options.robots.split(",")
    print(f"Machine: {machine()}\n")
    print("| robot | floor passes verify | floor ns/call (min / median) | generated ns/call (min / median) "
          "| ratio (min / median) |")
    print("| --- | --- | --- | --- | --- |")
    with tempfile.TemporaryDirectory() as scratch:
        for robot in robots:
            floor = FLOORS / f"{robot}.c"
            code, _, _, _ = run(["verify", robot, "--source", str(floor), "-o", f"{scratch}/{robot}-floor"])
            figures = Path(scratch) / f"{robot}.json"
            run(["bench", robot, "--floor", str(floor), "--calls", str(options.calls), "-o", f"{scratch}/{robot}",
                 "--json", str(figures)])
            against = json.loads(figures.read_text())["against_floor"]
            print(f"| {robot} | {'yes' if code == 0 else 'NO'} "
                  f"| {against['floor']['min']:.1f} / {against['floor']['median']:.1f} "
                  f"| {against['routine']['min']:.1f} / {against['routine']['median']:.1f} "
                  f"| {against['ratio_min']:.3f} / {against['ratio_median']:.3f} |", flush=True)
        print("\n| command | exit | wall s | peak MiB |")
        print("| --- | --- | --- | --- |")
        for robot in robots:
            run(["build", robot, "-o", f"{scratch}/{robot}-verify"])
            code, _, seconds, memory = run(["verify", robot, "--samples", str(options.verify_samples),
                                            "-o", f"{scratch}/{robot}-verify"])
            print(f"| kingen verify {robot} --samples {options.verify_samples} | {code} | {seconds:.2f} "
                  f"| {memory:.0f} |", flush=True)
        if options.memory_samples:
            code, _, seconds, memory = run(["verify", robots[0], "--samples", str(options.memory_samples),
                                            "-o", f"{scratch}/{robots[0]}-verify"])
            print(f"| kingen verify {robots[0]} --samples {options.memory_samples} | {code} | {seconds:.2f} "
                  f"| {memory:.0f} |", flush=True)
        for arguments in (["--version"], ["render", robots[0], "-o", f"{scratch}/{robots[0]}-render"]):
            starts = [run(arguments)[2] for _ in range(5)]
            print(f"| kingen {' '.join(arguments[:2])} (start-up, median of 5) | 0 | {statistics.median(starts):.2f} | |")
        if options.pytest_runs:
            times, items = pytest_plugin_times(scratch, options.pytest_runs)
            robot_files = len(list(ROBOTS.glob("*.yaml")))
            print(f"\n| `pytest --kingen robots robots -q -p no:cacheprovider`, {robot_files} robot files, {items} items "
                  f"| cold wall s (min / median of {options.pytest_runs}) | warm wall s (min / median) |")
            print("| --- | --- | --- |")
            for workers in ((), ("-n", "2")):
                if ("cold", workers) not in times:
                    continue
                cold, warm = times["cold", workers], times["warm", workers]
                print(f"| {' '.join(workers) or 'one process'} | {min(cold):.2f} / {statistics.median(cold):.2f} "
                      f"| {min(warm):.2f} / {statistics.median(warm):.2f} |", flush=True)


if __name__ == "__main__":
    main()
