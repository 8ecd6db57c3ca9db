"""kingen check-path's figures, printed as Markdown, and with --json written as plain data for
benchmarks/run.py (the performance page's section).

    python benchmarks/check_path.py [--samples N] [--moves N] [--json FILE]

1. Speed and memory: a CSV program of straight moves 100 mm long around the robot's home,
   N samples in all at the default chord (0.1 mm), on the hexapod and on CEART, each checked
   in a fresh process: samples per second, the process's peak resident memory, and the same
   for a program ten times shorter (memory flat: the peak does not grow with the program);
   and a program of N/10 moves of 0.1 mm (a CAM program's short segments).
2. Nothing missed between samples: seeded straight moves (1 to 40 mm around home) along
   which the quantity judged is least inside the move, each given a limit that the path
   crosses only between two regular samples, by half of what the nearest regular sample
   misses it by: every other move a hexapod strut's lower travel limit (strut 0 .. 5 in turn),
   the others CEART's direct-index threshold (at its working posture). The true least value along the move is
   found by scipy's bounded minimisation on the numpy reference. Counted: grazes found at the
   default chord, and problems found at a ten times finer chord that the default missed.
"""

import argparse
import json
import math
import subprocess
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy.optimize import minimize_scalar

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from kingen.conventions import t6_from_pose  # noqa: E402
from kingen.kinematics.reference import solve  # noqa: E402
from kingen.paths.check import Settings, check_program  # noqa: E402
from kingen.robot.model import load_robot  # noqa: E402
from kingen.robot.one_posture import at_posture  # noqa: E402

MOVE_MM = 100.0
ABOUT = ("How fast [check-path](how-to/check-path.md) checks a long program and whether its memory stays flat, "
         "on the hexapod and on CEART (CEART at its working posture, with the exact direct index at every sample), "
         "and whether a limit crossed only between two regular samples is found. Goals: a million samples of the "
         "hexapod in at most 20 s, of CEART in at most 60 s; every graze found, nothing more at a ten times finer "
         "chord.")
"""What the section measures, for the performance page (links relative to docs/)."""
CHILD = """
import json, resource, sys, time
import numpy as np
np.seterr(all="ignore")
from kingen.robot.model import load_robot
from kingen.paths.check import Settings, check_program
robot = load_robot(sys.argv[1])
settings = Settings(host="delmia", routine=True, out_dir=sys.argv[4]) if sys.argv[3] == "routine" else Settings()
if settings.routine:
    from kingen.paths.routine import RoutineSolver
    RoutineSolver(robot, "delmia", robot.working_posture, sys.argv[4])  # the routine built before the timing
started = time.perf_counter()
outcome = check_program(robot, sys.argv[2], settings)
seconds = time.perf_counter() - started
print(json.dumps({"samples": outcome.findings.samples, "moves": outcome.findings.moves, "seconds": seconds, "problems": len(outcome.findings.worst),
                  "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""


def speed_program(robot, samples, path):
    """A CSV of straight 100 mm moves (and up to 2 degrees of turn) around the robot's home,
    within a third of its verification range (or 100 mm), until ``samples`` regular samples
    at chord 0.1 mm."""
    home, reach = np.array(robot.verification.home), np.array(robot.verification.range) / 3.0
    generator = np.random.default_rng(7)
    rows, pose, count = [home.copy()], home.copy(), 0
    while count < samples:
        direction = generator.normal(size=3)
        direction /= np.linalg.norm(direction)
        target = pose.copy()
        target[:3] += MOVE_MM * direction
        if np.any(np.abs(target[:3] - home[:3]) > np.maximum(reach[:3], MOVE_MM)):
            target[:3] = home[:3] + 0.5 * MOVE_MM * direction
        target[3:] = home[3:] + generator.uniform(-1.0, 1.0, 3) * np.minimum(reach[3:], 2.0)
        count += math.ceil(max(np.linalg.norm(target[:3] - pose[:3]), np.max(np.abs(target[3:] - pose[3:]))) / 0.1)
        rows.append(target)
        pose = target
    path.write_text("x,y,z,roll,pitch,yaw\n" + "\n".join(",".join(f"{v:.9f}" for v in row) for row in rows) + "\n")


def short_moves_program(robot, moves, path):
    """A CSV of ``moves`` moves of 0.1 mm or less along a helix around the robot's home (radius
    30 mm, 1 mm a turn), at 1200 mm/min: a CAM program's short segments, one sample each."""
    home = np.array(robot.verification.home)
    turn = np.linspace(0.0, moves * 0.1 / 30.0, moves + 1)
    rows = np.column_stack([home[0] + 30.0 * np.cos(turn), home[1] + 30.0 * np.sin(turn),
                            home[2] + turn / (2.0 * np.pi), np.tile(home[3:], (moves + 1, 1)),
                            np.full(moves + 1, 1200.0)])
    path.write_text("x,y,z,roll,pitch,yaw,feed\n" + "\n".join(",".join(f"{v:.9f}" for v in row) for row in rows)
                    + "\n")


def _checked(name, program, routine=None):
    """The figures of one check of ``program`` on robot ``name`` in a fresh process; with
    ``routine`` (a build folder) its joints from the DELMIA routine (``--routine``), built first."""
    extra = ["routine", str(routine)] if routine is not None else ["reference", ""]
    printed = subprocess.run([sys.executable, "-c", CHILD, name, str(program), *extra], capture_output=True, text=True,
                             check=True, cwd=ROOT, env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"})
    return json.loads(printed.stdout)


def speed(names, samples):
    """Per robot: the figures of a program of ``samples`` regular samples ("long"; and with
    --routine, "long_routine"), of one ten times shorter ("short") and of samples/10 moves of
    0.1 mm ("short_moves")."""
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for name in names:
            robot = load_robot(name)
            row = {"robot": name}
            for key, count in (("long", samples), ("short", samples // 10)):
                program = Path(folder) / f"{name}-{count}.csv"
                speed_program(robot, count, program)
                row[key] = _checked(name, program)
                if key == "long":
                    row["long_routine"] = _checked(name, program, Path(folder) / f"build-{name}")
            short = Path(folder) / f"{name}-short.csv"
            short_moves_program(robot, samples // 10, short)
            row["short_moves"] = _checked(name, short)
            rows.append(row)
    return rows


def least_along(values, start, end):
    """(u, value): the least of ``values(poses)`` (n,) along the straight move, by a dense scan
    (2001 points) and scipy's bounded minimisation around its least point."""
    def at(u):
        u = np.atleast_1d(u)
        return values(start + u[:, None] * (end - start))

    scan = np.linspace(0.0, 1.0, 2001)
    scanned = at(scan)
    best = int(np.argmin(scanned))
    low, high = scan[max(best - 1, 0)], scan[min(best + 1, len(scan) - 1)]
    found = minimize_scalar(lambda u: float(at(u)[0]), bounds=(low, high), method="bounded",
                            options={"xatol": 1e-12})
    return (found.x, found.fun) if found.fun < scanned[best] else (scan[best], scanned[best])


def _quantity(robot, joint):
    """values(poses) (n,): strut ``joint``'s length (mm), or (joint None) the direct index (mm),
    of ``robot`` at one posture."""
    def values(poses):
        solution = solve(robot, t6_from_pose(np.atleast_2d(poses)), indices=True)
        return solution.branch_joints[:, joint, 0] if joint is not None else solution.direct_index[:, 0]
    return values


def _move_with_a_dip(values, home, generator, square):
    """(start, end) of a seeded straight move (1 to 40 mm) whose ``values`` are least inside the
    move, not at an end. ``square``: the move is square to the gradient of the values (a strut is
    shortest where the platform moves square to it), with up to 1 degree of turn; else a seeded
    direction over position and orientation (0.3 degrees per mm)."""
    for _ in range(1000):
        middle = home + generator.uniform(-1.0, 1.0, 6) * np.array([20, 20, 20, 3, 3, 3])
        if square:
            steps = np.vstack([middle + np.concatenate([step, np.zeros(3)]) for step in 1e-4 * np.eye(3)])
            gradient = (values(steps) - values(middle)) / 1e-4
            direction = np.cross(gradient, generator.normal(size=3))
            direction = np.concatenate([direction / np.linalg.norm(direction), generator.uniform(-0.05, 0.05, 3)])
        else:
            direction = generator.normal(size=6) * np.array([1, 1, 1, 0.3, 0.3, 0.3])
            direction /= np.linalg.norm(direction[:3])
        before, after = generator.uniform(0.5, 20.0, 2)
        start, end = middle - before * direction, middle + after * direction
        scanned = values(start + np.linspace(0, 1, 201)[:, None] * (end - start))
        if np.all(np.isfinite(scanned)) and 0 < np.argmin(scanned) < 200:
            return start, end
    raise RuntimeError("no move with a dip found in 1000 seeded tries")


def grazing(moves):
    """The experiment of part 2: counts of grazes set up, seen by the regular samples alone,
    found at the default chord, and found more at a ten times finer chord."""
    generator = np.random.default_rng(2024)
    robots = {name: load_robot(name) for name in ("hexapod", "ceart")}
    counts = {"set up": 0, "found": 0, "more at finer chord": 0, "regular samples alone": 0}
    with tempfile.TemporaryDirectory() as folder:
        program = Path(folder) / "move.csv"
        for index in range(moves):
            name, joint = ("hexapod", index // 2 % 6) if index % 2 == 0 else ("ceart", None)
            base = robots[name]
            values = _quantity(at_posture(base, base.working_posture), joint)
            start, end = _move_with_a_dip(values, np.array(base.verification.home), generator, joint is not None)
            program.write_text("x,y,z,roll,pitch,yaw\n" + "\n".join(",".join(repr(float(v)) for v in p)
                                                                 for p in (start, end)) + "\n")
            count = math.ceil(max(np.linalg.norm(end[:3] - start[:3]), np.max(np.abs(end[3:] - start[3:]))) / 0.1)
            grid = values(start + np.linspace(0, 1, count + 1)[:, None] * (end - start))
            _, least = least_along(values, start, end)
            if not np.min(grid) > least:
                continue  # the least value is at a regular sample: no graze between samples to set
            limit = least + 0.5 * (np.min(grid) - least)
            robot = _with_limit(base, joint, limit)
            counts["set up"] += 1
            counts["regular samples alone"] += int(np.min(grid) <= limit)
            planted = ("direct index", None) if joint is None else ("travel", robot.joint_names[joint])
            found = []
            for chord in (0.1, 0.01):
                outcome = check_program(robot, program, Settings(chord=chord))
                found.append(set(outcome.findings.worst))
            counts["found"] += int(planted in found[0])
            counts["more at finer chord"] += int(bool(found[1] - found[0]))
    return counts


def _with_limit(robot, joint, limit):
    """``robot`` with strut ``joint``'s lower travel limit at ``limit`` (mm), or (joint None)
    its direct-index threshold at ``limit`` (mm)."""
    if joint is None:
        return replace(robot, direct_index_min=float(limit))
    limbs = list(robot.limbs)
    limbs[joint] = limbs[joint].model_copy(update={"travel": [float(limit), 1e5]})
    return replace(robot, limbs=tuple(limbs))


def markdown(figures):
    """The figures as Markdown: the speed and memory table and the grazing experiment's counts."""
    lines = ["Each program checked in a fresh process: straight moves of 100 mm around the robot's home at the default "
             "chord (0.1 mm); the peak is the process's resident memory; the short moves are a helix of 0.1 mm moves "
             "at 1200 mm/min (a CAM program's segments); `--routine` solves the regular samples' joints by the robot's "
             "DELMIA routine in a child process per batch besides the reference (a cross-check, not a shortcut).", "",
             "| robot | samples | seconds | samples/s | peak memory | a program ten times shorter: samples, peak memory "
             "| moves of 0.1 mm: moves, seconds | with `--routine` (DELMIA's): seconds |",
             "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for row in figures["speed"]:
        long, short, moves = row["long"], row["short"], row["short_moves"]
        lines.append(f"| {row['robot']} | {long['samples']} | {long['seconds']:.1f} | "
                     f"{long['samples'] / long['seconds']:,.0f} | {long['peak_mb']:.0f} MB | {short['samples']}, "
                     f"{short['peak_mb']:.0f} MB | {moves['moves']} in {moves['seconds']:.1f} s | "
                     f"{row['long_routine']['seconds']:.1f} |")
    counts = figures["grazing"]
    lines += ["", f"Nothing missed between samples: {figures['moves']} seeded moves (every other one a hexapod strut's "
              "lower travel limit, the others CEART's direct-index threshold, each crossed only between two regular "
              f"samples); grazes set up: {counts['set up']}; seen by the regular samples alone: "
              f"{counts['regular samples alone']}; found by check-path at the default chord: {counts['found']}; "
              f"found more at a ten times finer chord: {counts['more at finer chord']}."]
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=1_000_000)
    parser.add_argument("--moves", type=int, default=100)
    parser.add_argument("--json", type=Path, help="Also write the figures to this file as JSON.")
    arguments = parser.parse_args()
    np.seterr(all="ignore")
    figures = {"samples": arguments.samples, "moves": arguments.moves,
               "speed": speed(("hexapod", "ceart"), arguments.samples), "grazing": grazing(arguments.moves)}
    print(markdown(figures))
    if arguments.json:
        arguments.json.write_text(json.dumps(figures, indent=1) + "\n")


if __name__ == "__main__":
    main()
