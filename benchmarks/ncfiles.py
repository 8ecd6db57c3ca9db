"""kingen check-path on the sample programs LinuxCNC ships (Debian's linuxcnc-uspace installs them
in /usr/share/linuxcnc/ncfiles), printed as Markdown, and with --json written as plain data for
benchmarks/run.py (the performance page's section).

    python benchmarks/ncfiles.py [--robot NAME] [--json FILE]

Each program is checked on the robot (default linear_delta) in a fresh process, as a user runs
``kingen check-path ROBOT PROGRAM --json report.json`` (no ``.ini``: tools 1 .. 999 at no
offset, no work offset), and timed from start to exit; beside it, whether ``rs274 -g`` (LinuxCNC's
standalone interpreter, with its own default tool table) reads it without error, the motions
rs274 prints, kingen's moves judged and samples, and check-path's exit (0 runs, 1 does not run or
judged nothing, 2 bad input).
"""

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

NCFILES = Path("/usr/share/linuxcnc/ncfiles")
KINGEN = "import sys; from kingen.cli import main; sys.exit(main(sys.argv[1:]))"
"""kingen's command line in a fresh process of this Python."""
ABOUT = ("`kingen check-path linear_delta PROGRAM` on each sample program LinuxCNC ships "
         "(`/usr/share/linuxcnc/ncfiles`, Debian's linuxcnc-uspace), in a fresh process, without an `.ini`; "
         "rs274: whether `rs274 -g` reads the program without error (with its own default tool table, tools 1 to 3). "
         "Every program rs274 reads is judged (exit 0 or 1). Of those it refuses, kingen judges the ones whose only "
         "fault was a tool outside rs274's table or a cutter radius too large for an entry move (kingen's default "
         "table has tools 1 to 999, without diameter); the others are bad input to both. "
         "See [Will the program run?](how-to/check-path.md).")


def rs274_reads(program, scratch):
    """Whether ``rs274 -g`` reads ``program`` without error (a private HOME in ``scratch``)."""
    done = subprocess.run(["rs274", "-g", str(program)], cwd=program.parent, capture_output=True, timeout=120,
                          env={"HOME": str(scratch), "PATH": "/usr/bin:/bin"})
    return done.returncode == 0


def measure(robot):
    """[{program, rs274, exit, seconds, motions, moves, samples}] of every sample program."""
    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        for program in sorted(NCFILES.glob("*.ngc")):
            report = Path(scratch) / "report.json"
            report.unlink(missing_ok=True)
            started = time.perf_counter()
            done = subprocess.run([sys.executable, "-c", KINGEN, "check-path", robot, str(program), "--json",
                                   str(report)], capture_output=True, timeout=1200)
            seconds = time.perf_counter() - started
            document = json.loads(report.read_text()) if report.exists() else {}
            rows.append({"program": program.name, "rs274": rs274_reads(program, scratch), "exit": done.returncode,
                         "seconds": seconds, "motions": document.get("gcode", {}).get("rs274_motions"),
                         "moves": document.get("moves"), "samples": document.get("samples")})
    return {"robot": robot, "programs": rows}


def markdown(figures):
    rows = figures["programs"]
    read = [row for row in rows if row["rs274"]]
    judged = [row for row in read if row["exit"] in (0, 1)]
    lines = [f"On `{figures['robot']}`: {len(read)} of {len(rows)} programs read by rs274, {len(judged)} of them "
             f"judged; {sum(row['seconds'] for row in rows):.0f} s in all.", "",
             "| program | rs274 | exit | s | motions (rs274) | moves judged | samples |",
             "| --- | --- | --- | --- | --- | --- | --- |"]
    for row in rows:
        cells = [f"`{row['program']}`", "reads" if row["rs274"] else "refuses", str(row["exit"]),
                 f"{row['seconds']:.2f}",
                 "-" if row["motions"] is None else str(row["motions"]),
                 "-" if row["moves"] is None else str(row["moves"]),
                 "-" if row["samples"] is None else str(row["samples"])]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--robot", default="linear_delta")
    parser.add_argument("--json", type=Path, default=None)
    options = parser.parse_args()
    figures = measure(options.robot)
    if options.json is not None:
        options.json.write_text(json.dumps(figures, indent=1) + "\n")
    print(markdown(figures))


if __name__ == "__main__":
    main()
