"""The call cost of a constrained machine's routine (parasitic x, y, yaw solved in closed form,
then the limbs) against the hexapod's, in kingen's batch driver, for each host; printed as a
Markdown table, and with --json written as plain data for benchmarks/run.py (the performance
page's section). The issue's goal: at most 3 times the hexapod's.

    python benchmarks/hybrid.py [--calls N] [--rounds N] [--json FILE]

Each figure is the median of ``rounds`` runs of ``kingen bench ROBOT --host HOST --calls N``
(its batch_ns_per_call: the routine called from C over N poses of the verification region).
"""

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ABOUT = ("The call cost of a lower-mobility machine's routine (its parasitic coordinates in closed form, then the "
         "limbs) against the hexapod's, for each host ([Lower-mobility machines](how-to/hybrid.md)). Goal: at most 3 "
         "times the hexapod's.")
"""What the section measures, for the performance page (links relative to docs/)."""
MACHINES = ("prs_head", "rps_table", "exechon_constrained", "tricept", "exechon_wrist")
BASELINE = "hexapod"
HOSTS = ("delmia", "linuxcnc")
NOT_BUILT = {"linuxcnc": ("exechon_wrist",)}
"""Per host, the machines it does not build yet (a wrist: LinuxCNC's five-axis module is separate)."""


def batch_ns(robot, host, calls, scratch):
    """One run's batch driver figure (ns per call) of ``robot``'s routine for ``host``."""
    path = Path(scratch) / f"{robot}-{host}.json"
    subprocess.run([sys.executable, "-m", "kingen.cli", "bench", robot, "--host", host, "--calls", str(calls),
                    "-o", f"{scratch}/{robot}-{host}", "--json", str(path)], check=True, capture_output=True)
    return json.loads(path.read_text())["batch_ns_per_call"]


def measure(calls, rounds):
    """The figures as plain data: per host, each robot's median ns per call over the rounds."""
    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        for host in HOSTS:
            for robot in (robot for robot in (BASELINE, *MACHINES) if robot not in NOT_BUILT.get(host, ())):
                rows.append({"host": host, "robot": robot,
                             "ns": float(np.median([batch_ns(robot, host, calls, scratch) for _ in range(rounds)]))})
                print(rows[-1], file=sys.stderr, flush=True)
    return {"calls": calls, "rounds": rounds, "baseline": BASELINE, "rows": rows}


def markdown(figures):
    """The figures as a Markdown table, each robot against the baseline of its host."""
    baseline = {row["host"]: row["ns"] for row in figures["rows"] if row["robot"] == figures["baseline"]}
    lines = [f"Median of {figures['rounds']} runs of `kingen bench ROBOT --host HOST --calls {figures['calls']}` "
             "(the routine called from kingen's C batch driver over the verification region's poses).", "",
             f"| host | robot | ns per call | against the {figures['baseline']} |", "| --- | --- | --- | --- |"]
    lines += [f"| {row['host']} | {row['robot']} | {row['ns']:.1f} | {row['ns'] / baseline[row['host']]:.2f} |"
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
