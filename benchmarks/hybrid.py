"""The call cost of a constrained machine's routine (parasitic coordinates solved in closed form,
then the limbs; with a wrist, its two or three joints too) against the hexapod's, in kingen's
batch driver, for each host: DELMIA's routines and LinuxCNC's modules (a wrist robot's is the
five-axis module, or with a three-axis wrist the six-axis one). Printed as a Markdown table, and with --json written as plain data for
benchmarks/run.py (the performance page's section). The issue's goal: at most 3 times the
hexapod's.

    python benchmarks/hybrid.py [--calls N] [--rounds N] [--json FILE]

Each run is ``kingen bench ROBOT --host HOST --calls N`` (its batch_ns_per_call: the routine
called from C over N poses of the verification region). The runs are paired: each round runs
the hexapod, then every machine, on one host, so a machine's ratio is the median over the
rounds of its figure over the same round's hexapod figure (a load that comes and goes between
rounds shifts both); its ns per call is the median of its rounds' figures. The ratios are given
against the hexapod and against linuxcnc_hexapod (REFERENCE).
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ABOUT = ("The call cost of a lower-mobility machine's routine (its parasitic coordinates in closed form, then the "
         "limbs; with a wrist, the wrist's joints too: in LinuxCNC the five- or six-axis module) against the hexapod's, for "
         "each host ([Lower-mobility machines](how-to/hybrid.md)). Goal: at most 3 times the hexapod's.")
"""What the section measures, for the performance page (links relative to docs/)."""
MACHINES = ("prs_head", "rps_table", "exechon_constrained", "tricept", "exechon_wrist", "tricept_wrist",
            "tricept_wrist3")
BASELINE = "hexapod"
REFERENCE = "linuxcnc_hexapod"
"""A second hexapod each ratio is also given against: LinuxCNC's own hexapod's geometry
(benchmarks/linuxcnc.py), whose robot file sets no direct_index_min, so its routine skips the
direct-index check the hexapod's makes."""
HOSTS = ("delmia", "linuxcnc")


def batch_ns(robot, host, calls, scratch):
    """One run's batch driver figure (ns per call) of ``robot``'s routine for ``host``."""
    path = Path(scratch) / f"{robot}-{host}.json"
    subprocess.run([sys.executable, "-m", "kingen.cli", "bench", robot, "--host", host, "--calls", str(calls),
                    "-o", f"{scratch}/{robot}-{host}", "--json", str(path)], check=True, capture_output=True)
    return json.loads(path.read_text())["batch_ns_per_call"]


def measure(calls, rounds):
    """The figures as plain data: per host and robot, the median ns per call over the rounds and
    the medians of the rounds' ratios to the same round's baseline and reference figures (paired rounds)."""
    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        for host in HOSTS:
            runs = {robot: [] for robot in (BASELINE, REFERENCE, *MACHINES)}
            for _ in range(rounds):
                for robot in runs:
                    runs[robot].append(batch_ns(robot, host, calls, scratch))
            baseline, reference = np.asarray(runs[BASELINE]), np.asarray(runs[REFERENCE])
            for robot, figures in runs.items():
                rows.append({"host": host, "robot": robot, "ns": float(np.median(figures)),
                             "ratio": float(np.median(np.asarray(figures) / baseline)),
                             "reference_ratio": float(np.median(np.asarray(figures) / reference))})
                print(rows[-1], file=sys.stderr, flush=True)
    return {"calls": calls, "rounds": rounds, "baseline": BASELINE, "reference": REFERENCE, "rows": rows,
            "load_average": list(os.getloadavg())}


def markdown(figures):
    """The figures as a Markdown table, each robot against the baseline of its host (paired rounds)."""
    loads = ", ".join(f"{load:.2f}" for load in figures["load_average"])
    lines = [f"Median of {figures['rounds']} paired rounds of "
             f"`kingen bench ROBOT --host HOST --calls {figures['calls']}` (the routine called from kingen's C batch "
             f"driver over the verification region's poses; each round runs the {figures['baseline']} and the "
             f"{figures['reference']}, then every machine, on one host; a ratio is the median of the rounds' "
             "ratios). LinuxCNC's module of a robot with a wrist is its five-axis module (two wrist joints) or "
             f"six-axis module (three). Load average (1, 5, 15 minutes) at the end: {loads}.", ""]
    lines += [f"| host | robot | ns per call | against the {figures['baseline']} | against the {figures['reference']} |",
              "| --- | --- | --- | --- | --- |"]
    lines += [f"| {row['host']} | {row['robot']} | {row['ns']:.1f} | {row['ratio']:.2f} | {row['reference_ratio']:.2f} |"
              for row in figures["rows"]]
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=200000)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--json", type=Path, help="Also write the figures to this file as JSON.")
    options = parser.parse_args()
    figures = measure(options.calls, options.rounds)
    print(markdown(figures))
    if options.json:
        options.json.write_text(json.dumps(figures, indent=1) + "\n")


if __name__ == "__main__":
    main()
