"""check-path's planner model against a real LinuxCNC, printed as Markdown, and with --json written
as plain data for benchmarks/run.py (the performance page's section).

    python benchmarks/planner.py [--json FILE]

A real, headless LinuxCNC (Debian's linuxcnc-uspace; root, as tests/test_check_path_planner.py
runs it) runs kingen's module for the linear delta on that test's programs, HAL's sampler
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
         "into one line; lines and half circles of 4 mm radius meeting tangentially in G64), HAL's sampler recording every servo period's line and joint velocities "
         "(`tests/test_check_path_planner.py` asserts the 5 % bound). Each joint's largest speed on each line, "
         "LinuxCNC's against check-path's planner model and against timing every move from rest to rest at [TRAJ]'s "
         "acceleration; the error is a joint's difference over LinuxCNC's peak (over the line's fastest joint's for "
         "a joint under a fifth of it).")


def errors(model, real):
    """{line: the largest relative error over the joints} of ``model``'s peaks against ``real``'s."""
    result = {}
    for line, measured in real.items():
        floor = np.where(measured >= 0.2 * np.max(measured), measured, np.max(measured))
        result[line] = float(np.max(np.abs(model[line] - measured) / floor)) if line in model else float("nan")
    return result


def measure():
    """Per program and line: LinuxCNC's, the planner model's and rest-to-rest's fastest joint peak (mm/s)
    and the two models' largest relative errors over the joints."""
    sys.path[:0] = [str(ROOT), str(ROOT / "tests")]  # here, not at import: rendering the page needs none of it
    import kingen.paths.check as check
    from kingen.paths.timing import profile
    from test_check_path_machine import ROBOTS, run_programs
    from test_check_path_planner import PROGRAMS, linuxcnc_peaks, model_peaks

    def rest_to_rest(moves, limits):
        """Every move timed on its own from rest to rest (timing.profile)."""
        return ((move, profile(move, limits)) for move in moves)

    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        paths = {program: folder / f"{program}.ngc" for program in PROGRAMS}
        for program, path in paths.items():
            path.write_text(PROGRAMS[program])
        ini, runs = run_programs(ROBOTS / "linear_delta.yaml", list(paths.values()), 1000.0, folder, sampled=True)
        figures = {}
        for (program, path), run in zip(paths.items(), runs):
            real = linuxcnc_peaks(run)
            planned = model_peaks(path, ini, folder)
            following = check.planned
            check.planned = rest_to_rest
            try:
                resting = model_peaks(path, ini, folder)
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
    lines = ["| program | line | fastest joint, LinuxCNC (mm/s) | planner model (mm/s) | rest to rest (mm/s) "
             "| planner model's largest error | rest to rest's largest error |", "| --- | --- | --- | --- | --- | --- | --- |"]
    for program, rows in figures.items():
        for row in rows:
            lines.append(f"| {program} | {row['line']} | {row['linuxcnc']:.2f} | {row['planner']:.2f} | "
                         f"{row['rest_to_rest']:.2f} | {100 * row['planner_error']:.1f} % | "
                         f"{100 * row['rest_to_rest_error']:.1f} % |")
    every = [row for rows in figures.values() for row in rows]
    lines += ["", f"Largest error over every joint and line: the planner model's {100 * max(r['planner_error'] for r in every):.1f} %, "
              f"rest to rest's {100 * max(r['rest_to_rest_error'] for r in every):.1f} %."]
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
