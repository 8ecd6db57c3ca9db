"""The design optimiser on the 6-RUS thesis's problem (robots/rus_optimized.yaml), printed as
Markdown for docs/how-to/optimize.md and the closing notes.

    python benchmarks/optimize.py [--part objective|speedup|full|seeds] [--seeds 1 2 3 4 5]

- objective: the thesis's optimum under the thesis's checks (1-degree steps): the least tilt,
  what ends it, the tilt about Y, the poses judged and the judge's time a pose.
- speedup: the same short search (swarm 30, 20 iterations, no refinement) on 1 and 2
  workers: designs a second, the speed-up, and designs a second per core.
- full: the thesis's full search, 30 particles x 3000 iterations without early stop (patience
  3000), then the refinement: wall time and result.
- seeds: from random starts with the file's settings (early stop after 300 iterations without
  improvement), each seed's best.
"""

import argparse
import io
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from ruamel.yaml import YAML

from kingen.design.problem import Problem, evaluate
from kingen.robot.model import resolve_robot_path
from kingen.robot.reading import read_robot_file

PATH = resolve_robot_path("rus_optimized")


def objective():
    problem = Problem(read_robot_file(PATH)[0], PATH)
    value, table, judged = evaluate(problem, problem.start())
    started = time.perf_counter()
    for _ in range(20):
        evaluate(problem, problem.start())
    seconds = (time.perf_counter() - started) / 20
    first = min((azimuth for azimuth, row in enumerate(table) if row[0] == value))
    print(f"| thesis optimum, 1-degree steps | least tilt {value:g} deg (azimuth {first}, {table[first][1]}) | "
          f"about Y {table[90][0]:g} deg ({table[90][1]}) | {judged} poses, {seconds * 1000:.1f} ms an evaluation, "
          f"{seconds / judged * 1e9:.0f} ns a pose |")


def _file(folder, **search):
    data = read_robot_file(PATH)[0]
    data["optimize"]["search"] = {**data["optimize"]["search"], **search}
    if search.pop("no_refine", False):
        data["optimize"]["refine"] = {"method": "none"}
    data["optimize"]["search"].pop("no_refine", None)
    path = Path(folder) / "rus_bench.yaml"
    buffer = io.StringIO()
    YAML().dump({**data, "name": "rus_bench"}, buffer)
    path.write_text(buffer.getvalue())
    return path


def _optimize(path, folder, *options):
    started = time.perf_counter()
    subprocess.run([sys.executable, "-m", "kingen.cli", "optimize", str(path), "-o", str(folder), *options],
                   check=True, capture_output=True)
    wall = time.perf_counter() - started
    return json.loads((Path(folder) / "optimization.json").read_text()), wall


def speedup():
    """Designs a second through the executor on 1 and 2 workers: 120 designs near the thesis's
    optimum (what a converging swarm evaluates), and a short search from random starts."""
    from kingen.runtime.executors import executor

    problem = Problem(read_robot_file(PATH)[0], PATH)
    rng = np.random.default_rng(0)
    designs = [np.clip(problem.start() + rng.normal(0, 0.01, 10) * (problem.upper - problem.lower),
                       problem.lower, problem.upper) for _ in range(120)]
    rates = {}
    for workers in (1, 2):
        with executor(workers) as opened:
            pool = opened.pool
            list(pool.map(evaluate, [problem] * workers, designs[:workers]))  # start the workers
            started = time.perf_counter()
            list(pool.map(evaluate, [problem] * len(designs), designs))
            rates[workers] = len(designs) / (time.perf_counter() - started)
        print(f"| near the optimum, {workers} worker(s) | {rates[workers]:.1f} designs/s | "
              f"{rates[workers] / workers:.1f} designs/s a core |")
    print(f"| speed-up 1 -> 2 workers near the optimum | {rates[2] / rates[1]:.2f} |")
    with tempfile.TemporaryDirectory() as folder:
        path = _file(folder, iterations=20, patience=20, no_refine=True)
        for workers in (1, 2):
            result, wall = _optimize(path, Path(folder) / f"w{workers}", "--workers", str(workers), "--seed", "1")
            rates[workers] = result["evaluations"] / result["seconds"]
            print(f"| random starts, 20 iterations, {workers} worker(s) | {rates[workers]:.1f} designs/s | "
                  f"{rates[workers] / workers:.1f} designs/s a core |")
        print(f"| speed-up 1 -> 2 workers from random starts | {rates[2] / rates[1]:.2f} |")


def full():
    with tempfile.TemporaryDirectory() as folder:
        path = _file(folder, iterations=3000, patience=3000)
        result, wall = _optimize(path, Path(folder) / "full", "--seed", "1")
        print(f"| full search (30 x 3000, then trust-constr), seed 1 | {result['objective_deg']:g} deg | "
              f"{result['evaluations']} designs | {wall / 60:.1f} min wall | {result['workers']} |")


def seeds(values):
    for seed in values:
        with tempfile.TemporaryDirectory() as folder:
            result, wall = _optimize(PATH, Path(folder) / "run", "--seed", str(seed))
            print(f"| seed {seed} | {result['objective_deg']:g} deg | {result['iterations']} iterations "
                  f"({result['stopped_by']}) | {result['evaluations']} designs | {wall:.0f} s |")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--part", choices=["objective", "speedup", "full", "seeds"], action="append")
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3, 4, 5])
    options = parser.parse_args()
    for part in options.part or ["objective", "speedup", "seeds", "full"]:
        if part == "seeds":
            seeds(options.seeds)
        else:
            globals()[part]()


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
