"""check-path's planner model against a real LinuxCNC, printed as Markdown, and with --json written
as plain data for benchmarks/run.py (the performance page's section).

    python benchmarks/planner.py [--json FILE]

A real, headless LinuxCNC (Debian's linuxcnc-uspace; root, as tests/test_check_path_planner.py
runs it) runs kingen's module for the linear delta on that test's programs and for the sample
hexapod on HEXAPOD's, HAL's sampler
recording every servo period's program line and joint velocities. For each line, each joint's
largest speed as LinuxCNC commands it, as check-path's planner model times the program, and as
the timing of every move from rest to rest at [TRAJ] MAX_LINEAR_ACCELERATION times it (what
check-path did before it followed the planner; timing.profile, still used for CSV rows).
"""

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent

ABOUT = ("How closely check-path's timing follows LinuxCNC's trajectory planner ([Timing](how-to/check-path.md#timing)): "
         "a real, headless LinuxCNC runs the linear delta on short programs (a polyline of 5 mm moves at 4800 mm/min "
         "blended in G64, the same with G64 P0.05 and in exact path G61; four nearly collinear moves that G64's Q merges "
         "into one line; lines and half circles of 4 mm radius meeting tangentially in G64; "
         "`tests/test_check_path_planner.py` asserts the 5 % bound on these) and the sample hexapod (inches) on a "
         "polyline in G64 and G61 and on moves turning A and B, HAL's sampler recording every servo period's line and "
         "joint velocities. Each joint's largest speed on each line, LinuxCNC's against check-path's planner model and "
         "against timing every move from rest to rest at [TRAJ]'s acceleration; the error is a joint's difference over "
         "LinuxCNC's peak (over the line's fastest joint's for a joint under a fifth of it).")


def errors(model, real):
    """{line: the largest relative error over the joints} of ``model``'s peaks against ``real``'s."""
    result = {}
    for line, measured in real.items():
        floor = np.where(measured >= 0.2 * np.max(measured), measured, np.max(measured))
        result[line] = float(np.max(np.abs(model[line] - measured) / floor)) if line in model else float("nan")
    return result


HEXAPOD = {
    "hexapod blends": "G21 G90 G64\nG1 X5 Y3 Z508 F6000\nG1 X10 Y0\nG1 X15 Y4\nG1 X5 Y-3 Z510\nG1 X0 Y0 Z508\nM2\n",
    "hexapod exact": "G21 G90 G61\nG1 X5 Y3 Z508 F6000\nG1 X10 Y0\nG1 X15 Y4\nG1 X5 Y-3 Z510\nG1 X0 Y0 Z508\nM2\n",
    "hexapod turning (parabolic)": "G21 G90 G64\nG1 X5 Y0 Z508 A1 F3000\nG1 X10 Y3 B-0.5\nG1 X5 Y5 A0\n"
                                   "G1 X0 Y0 Z508 B0\nM2\n",
}
"""The sample hexapod's programs (its .ini in inches, X Y Z at most 20 in/s^2, A B C 20 deg/s^2): a
polyline blended in G64 and in G61, and moves turning A and B, which LinuxCNC blends parabolically
(the model's approximation: kingen.paths.planner)."""
MACHINES = {"linear_delta": (0.0, 0.0, 15.0), "linuxcnc_hexapod": (0.0, 0.0, 508.0)}
"""Each robot run and its home (mm), where its programs start and end."""


def measure():
    """Per program and line: LinuxCNC's, the planner model's and rest-to-rest's fastest joint peak (the
    .ini's units per s) and the two models' largest relative errors over the joints."""
    sys.path[:0] = [str(ROOT), str(ROOT / "tests")]  # here, not at import: rendering the page needs none of it
    import kingen.paths.check as check
    from kingen.paths.timing import profile
    from test_check_path_machine import ROBOTS, run_programs
    from test_check_path_planner import PROGRAMS, linuxcnc_peaks, model_peaks

    def rest_to_rest(moves, limits):
        """Every move timed on its own from rest to rest (timing.profile)."""
        return ((move, profile(move, limits)) for move in moves)

    figures = {}
    for robot, programs in (("linear_delta", PROGRAMS), ("linuxcnc_hexapod", HEXAPOD)):
        with tempfile.TemporaryDirectory() as name:
            folder = Path(name)
            paths = {program: folder / f"{program.replace(' ', '_')}.ngc" for program in programs}
            for program, path in paths.items():
                path.write_text(programs[program])
            ini, runs = run_programs(ROBOTS / f"{robot}.yaml", list(paths.values()), 1000.0, folder, sampled=True)
            for (program, path), run in zip(paths.items(), runs):
                real = linuxcnc_peaks(run)
                planned = model_peaks(path, ini, folder, robot, MACHINES[robot])
                following = check.planned
                check.planned = rest_to_rest
                try:
                    resting = model_peaks(path, ini, folder, robot, MACHINES[robot])
                finally:
                    check.planned = following
                planner_errors, resting_errors = errors(planned, real), errors(resting, real)
                figures[program] = [{"line": line, "linuxcnc": float(np.max(real[line])),
                                     "planner": float(np.max(planned.get(line, [np.nan]))),
                                     "rest_to_rest": float(np.max(resting.get(line, [np.nan]))),
                                     "planner_error": planner_errors[line], "rest_to_rest_error": resting_errors[line]}
                                    for line in sorted(real)]
    return figures


def markdown(figures):
    """The figures as Markdown: per program, its lines' peaks and errors; the largest errors."""
    lines = ["| program | line | fastest joint, LinuxCNC | planner model | rest to rest "
             "| planner model's largest error | rest to rest's largest error |", "| --- | --- | --- | --- | --- | --- | --- |"]
    for program, rows in figures.items():
        for row in rows:
            lines.append(f"| {program} | {row['line']} | {row['linuxcnc']:.3g} | {row['planner']:.3g} | "
                         f"{row['rest_to_rest']:.3g} | {100 * row['planner_error']:.1f} % | "
                         f"{100 * row['rest_to_rest_error']:.1f} % |")
    followed = [row for program, rows in figures.items() if "parabolic" not in program for row in rows]
    parabolic = [row for program, rows in figures.items() if "parabolic" in program for row in rows]
    lines += ["", "Speeds in the .ini's units per s (the delta's mm/s, the hexapod's in/s). Largest error over every "
              f"joint and line of the programs the model follows: the planner model's "
              f"{100 * max(r['planner_error'] for r in followed):.1f} %, rest to rest's "
              f"{100 * max(r['rest_to_rest_error'] for r in followed):.1f} %."]
    if parabolic:
        lines.append(f"Where LinuxCNC blends parabolically (moves turning A and B) the model (each move at half "
                     f"acceleration, the next one's joint speeds at its start added where it has started) is off by "
                     f"up to {100 * max(r['planner_error'] for r in parabolic):.0f} % of a joint's peak, the fastest "
                     f"joint of each line by up to "
                     f"{100 * max(abs(r['planner'] / r['linuxcnc'] - 1) for r in parabolic):.0f} % (rest to rest at "
                     f"full acceleration: {100 * max(r['rest_to_rest_error'] for r in parabolic):.0f} %).")
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, help="Also write the figures to this file as JSON.")
    arguments = parser.parse_args()
    figures = measure()
    print(markdown(figures))
    if arguments.json:
        arguments.json.write_text(json.dumps(figures, indent=1) + "\n")


if __name__ == "__main__":
    main()
