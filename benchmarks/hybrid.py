"""The call cost of a constrained machine's routine (parasitic x, y, yaw solved in closed form,
then the limbs) against the hexapod's, in kingen's batch driver, for each host; printed as a
Markdown table (docs/how-to/hybrid.md). The issue's goal: at most 3 times the hexapod's.

    python benchmarks/hybrid.py [--calls N] [--rounds N]

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

MACHINES = ("prs_head", "rps_table", "exechon_constrained", "tricept")
BASELINE = "hexapod"
HOSTS = ("delmia", "linuxcnc")


def batch_ns(robot, host, calls, scratch):
    """One run's batch driver figure (ns per call) of ``robot``'s routine for ``host``."""
    path = Path(scratch) / f"{robot}-{host}.json"
    subprocess.run([sys.executable, "-m", "kingen.cli", "bench", robot, "--host", host, "--calls", str(calls),
                    "-o", f"{scratch}/{robot}-{host}", "--json", str(path)], check=True, capture_output=True)
    return json.loads(path.read_text())["batch_ns_per_call"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=200000)
    parser.add_argument("--rounds", type=int, default=5)
    options = parser.parse_args()
    print("| host | robot | ns per call (median) | against the hexapod |")
    print("| --- | --- | --- | --- |")
    with tempfile.TemporaryDirectory() as scratch:
        for host in HOSTS:
            figures = {robot: float(np.median([batch_ns(robot, host, options.calls, scratch)
                                               for _ in range(options.rounds)]))
                       for robot in (BASELINE, *MACHINES)}
            for robot, value in figures.items():
                print(f"| {host} | {robot} | {value:.1f} | {value / figures[BASELINE]:.2f} |", flush=True)


if __name__ == "__main__":
    main()
