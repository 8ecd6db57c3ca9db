"""What loads cost: kingen.kinematics.loads over a million poses against the reference's own
cost for their joints, and check-path with the load checks (joint_limits, max_force) against
the same program without them. Printed as Markdown, and with --json written as plain data for
benchmarks/run.py (the performance page's section).

    python benchmarks/loads.py [--poses N] [--rows N] [--rounds N] [--json FILE]

Each machine's poses are drawn uniformly in its verification region (seed 0); a round times
``kingen.kinematics.reference.solve`` on them, then ``loads`` in the machine's working posture
(which solves the reference itself: the ratio is the whole cost against the joints alone), in
turns; figures are medians over the rounds. The check-path pair runs ``kingen check-path`` on a
CSV of ``--rows`` poses along a circle about the hexapod's home at a feed of 600 mm/min, once with
the hexapod's file as shipped and once with a payload and every leg's joint_limits, max_force and
max_power (power needs the feed's timing), in turns.
"""

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ABOUT = ("What [loads](how-to/loads.md) cost: actuator forces, constraint wrenches and passive-joint angles over a "
         "million poses against the reference's own cost for their joints, and check-path with its `joint angle`, "
         "`actuator load` and `actuator power` checks against the same program without them. Goal: loads within 2 times the reference's "
         "cost.")
"""What the section measures, for the performance page (links relative to docs/)."""
MACHINES = ("hexapod", "ceart", "tau", "exechon_constrained", "tricept_wrist")
ROBOTS = Path(__file__).resolve().parent.parent / "robots"
LIMITS = "payload: {mass: 100, centre: [0, 0, 40]}\nverification:"
LEG = "reference_length: 399.413}"


def time_loads(name, count, rounds):
    """{robot, poses, reference_s, loads_s, ratio}: medians over ``rounds``."""
    from kingen.conventions import t6_from_pose
    from kingen.kinematics.loads import loads, machine_t6
    from kingen.kinematics.reference import solve
    from kingen.robot.loads_schema import Payload
    from kingen.robot.model import load_robot

    robot = replace(load_robot(name), payload=Payload(mass=100.0, centre=(10.0, -5.0, 40.0),
                                                      inertia=((2.0, 0, 0), (0, 2.0, 0), (0, 0, 3.0))))
    home, span = np.array(robot.verification.home, float), np.array(robot.verification.range, float)
    poses = home + np.random.default_rng(0).uniform(-0.5, 0.5, (count, 6)) * span
    t6 = t6_from_pose(poses) if robot.wrist is not None else machine_t6(robot, poses)
    reference, computed = [], []
    for _ in range(rounds):
        started = time.perf_counter()
        solve(robot, t6)
        reference.append(time.perf_counter() - started)
        started = time.perf_counter()
        loads(robot, t6, postures=[robot.working_posture])
        computed.append(time.perf_counter() - started)
    ratios = [b / a for a, b in zip(reference, computed)]
    return {"robot": name, "poses": count, "postures": robot.postures, "reference_s": statistics.median(reference),
            "loads_s": statistics.median(computed), "ratio": statistics.median(ratios)}


def time_check_path(rows, rounds):
    """{rows, plain_s, loads_s, ratio}: ``kingen check-path`` on the hexapod without and with load limits."""
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        text = (ROBOTS / "hexapod.yaml").read_text()
        limited = text.replace(LEG, "reference_length: 399.413, max_force: 2000, max_power: 1000, "
                                      "joint_limits: {base: 30, platform: 30}}")
        (folder / "plain.yaml").write_text(text.replace("name: hexapod", "name: hexapod_plain", 1))
        (folder / "limited.yaml").write_text(limited.replace("verification:", LIMITS, 1))
        angles = np.linspace(0.0, 2.0 * np.pi, rows)
        program = folder / "circle.csv"
        program.write_text("x,y,z,roll,pitch,yaw,feed\n" + "".join(
            f"{20 * np.cos(a):.6f},{20 * np.sin(a):.6f},465,{3 * np.sin(a):.6f},{3 * np.cos(a):.6f},0,600\n"
            for a in angles))
        seconds = {"plain": [], "limited": []}
        for _ in range(rounds):
            for label in seconds:
                started = time.perf_counter()
                done = subprocess.run([sys.executable, "-m", "kingen.cli", "check-path", str(folder / f"{label}.yaml"),
                                       str(program)], capture_output=True, text=True)
                seconds[label].append(time.perf_counter() - started)
                if done.returncode not in (0, 1):
                    raise SystemExit(f"check-path failed: {done.stderr.strip()}")
    plain, limited = statistics.median(seconds["plain"]), statistics.median(seconds["limited"])
    return {"rows": rows, "plain_s": plain, "loads_s": limited, "ratio": limited / plain}


def markdown(figures):
    """The section's Markdown (no heading)."""
    lines = ["| robot | postures | poses | reference (s) | loads, working posture (s) | ratio |",
             "| --- | --- | --- | --- | --- | --- |"]
    for row in figures["loads"]:
        lines.append(f"| `{row['robot']}` | {row['postures']} | {row['poses']:,} | {row['reference_s']:.2f} | "
                     f"{row['loads_s']:.2f} | {row['ratio']:.2f} |")
    path = figures["check_path"]
    lines += ["", f"`kingen check-path` on the hexapod, a CSV of {path['rows']:,} poses along a circle: "
                  f"{path['plain_s']:.2f} s without load limits, {path['loads_s']:.2f} s with a payload and every "
                  f"leg's `joint_limits`, `max_force` and `max_power` ({path['ratio']:.2f} times)."]
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--poses", type=int, default=1_000_000)
    parser.add_argument("--rows", type=int, default=2000)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--json", type=Path, default=None)
    options = parser.parse_args()
    figures = {"loads": [time_loads(name, options.poses, options.rounds) for name in MACHINES],
               "check_path": time_check_path(options.rows, options.rounds)}
    if options.json is not None:
        options.json.write_text(json.dumps(figures, indent=1) + "\n")
    print(markdown(figures), end="")


if __name__ == "__main__":
    main()
