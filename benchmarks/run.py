"""Speed and accuracy figures of kingen: writes the documentation's performance page, docs/performance.md, whole.

    python benchmarks/run.py [--calls N] [--verify-samples N] [--memory-samples N] [--robots ceart,hexapod,...]
                             [--pytest-runs N] [--page PATH] [--figures PATH] [--only NAME[,NAME]]
    python benchmarks/run.py --render-only      (the page again from the saved figures)

The run's figures (machine, date, tables) go to benchmarks/results/performance.json, and the
page is rendered from them and from the fixed text below (PAGE), so docs/performance.md is the
one place where run dates and figures are: edit the text here, never the page. The page has
sections: ``core`` (1 to 4 below) and those of benchmarks/sections.py (SECTIONS: a script each,
run with its arguments, its figures rendered by its own ``markdown``); ``--only`` measures the
sections named and keeps the others' saved figures.

1. Each hand-written floor (benchmarks/floors/<robot>.c) must pass `kingen verify --source`.
2. `kingen bench <robot> --floor ...` times the generated routine against its floor in
   turns (C batch driver, ns per call, minimum and median of the rounds).
3. `kingen verify <robot> --samples N` wall time and peak memory (of kingen and its
   children; with --memory-samples, the first robot once more with that many poses), and
   the start-up of `kingen --version` and of a command that reads a robot (`kingen render`).
4. `pytest --kingen` on a copy of every shipped robot file (the pytest plugin, as a CI job
   runs it, benchmarks/pytest_times.py): wall time cold (a new, empty kingen cache each run)
   and warm (the cache one untimed run filled), in one process and with `-n 2` (when
   pytest-xdist is installed), the four taken in turns, ``--pytest-runs`` rounds (0: skipped).

Figures are written, never asserted: the machine they ran on is written with them.
"""

import argparse
import datetime
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest_times
import sections

HERE = Path(__file__).resolve().parent
FLOORS = HERE / "floors"
ROBOTS = HERE.parent / "robots"
KINGEN = [sys.executable, "-m", "kingen.cli"]
PAGE_PATH = HERE.parent / "docs" / "performance.md"
FIGURES_PATH = HERE / "results" / "performance.json"
ROBOT_NOTES = {
    "ceart": "CEART (6 cranks, 64 postures, direct index, calibration)",
    "iwf": "IWF (6 cranks, 64 postures, direct index)",
    "rus_optimized": "optimised 6-RUS (6 cranks, 64 postures, direct index)",
    "exechon": "Exechon (3 legs, travel limits, calibration)",
    "hexapod": "hexapod (6 legs, direct index)",
    "flexapod": "Flexapod (6 legs, direct index)",
    "tau": "Gantry-Tau (3 rails, 8 postures, limits, calibration)",
}
"""What each benchmarked robot exercises, for the page's floor table."""


def run(arguments):
    """(exit code, stdout, wall seconds, peak resident MiB of the command and its children)."""
    start = time.perf_counter()
    process = subprocess.Popen([*KINGEN, *arguments], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    output = process.stdout.read()
    _, status, usage = os.wait4(process.pid, 0)
    seconds = time.perf_counter() - start
    process.returncode = os.waitstatus_to_exitcode(status)
    return process.returncode, output, seconds, usage.ru_maxrss / 1024.0


def measure(options):
    """Run every benchmark; the figures as plain data (what the page is rendered from)."""
    robots = options.robots.split(",")
    started = time.perf_counter()
    figures = {"date": datetime.date.today().isoformat(), "machine": sections.machine(), "calls": options.calls,
               "floors": [], "verify": [], "startup": [], "pytest": None}
    with tempfile.TemporaryDirectory() as scratch:
        for robot in robots:
            floor = FLOORS / f"{robot}.c"
            code, _, _, _ = run(["verify", robot, "--source", str(floor), "-o", f"{scratch}/{robot}-floor"])
            path = Path(scratch) / f"{robot}.json"
            run(["bench", robot, "--floor", str(floor), "--calls", str(options.calls), "-o", f"{scratch}/{robot}",
                 "--json", str(path)])
            against = json.loads(path.read_text())["against_floor"]
            figures["floors"].append({"robot": robot, "floor_passes_verify": code == 0,
                                      "floor": against["floor"], "routine": against["routine"],
                                      "ratio_min": against["ratio_min"], "ratio_median": against["ratio_median"]})
            print(figures["floors"][-1], flush=True)
        verifies = [(robot, options.verify_samples) for robot in robots]
        if options.memory_samples:
            verifies.append((robots[0], options.memory_samples))
        for robot, samples in verifies:
            run(["build", robot, "-o", f"{scratch}/{robot}-verify"])
            code, _, seconds, memory = run(["verify", robot, "--samples", str(samples),
                                            "-o", f"{scratch}/{robot}-verify"])
            figures["verify"].append({"command": f"kingen verify {robot} --samples {samples}", "exit": code,
                                      "seconds": seconds, "peak_mib": memory})
            print(figures["verify"][-1], flush=True)
        for arguments in (["--version"], ["render", robots[0], "-o", f"{scratch}/{robots[0]}-render"]):
            starts = [run(arguments)[2] for _ in range(5)]
            figures["startup"].append({"command": f"kingen {' '.join(arguments[:2])}",
                                       "seconds": statistics.median(starts)})
        if options.pytest_runs:
            times, items = pytest_times.pytest_plugin_times(scratch, options.pytest_runs)
            rows = [{"workers": " ".join(workers) or "one process",
                     "cold": [min(times["cold", workers]), statistics.median(times["cold", workers])],
                     "warm": [min(times["warm", workers]), statistics.median(times["warm", workers])]}
                    for workers in ((), ("-n", "2")) if ("cold", workers) in times]
            figures["pytest"] = {"robot_files": len(list(ROBOTS.glob("*.yaml"))), "items": items,
                                 "runs": options.pytest_runs, "rows": rows}
    figures["seconds"] = time.perf_counter() - started
    return figures


def _ns(value):
    return f"{value:.0f}" if value >= 1000 else f"{value:.1f}"


def render(figures):
    """docs/performance.md from the figures of one run and the fixed text of PAGE."""
    floors = ["| robot | floor ns/call (min / median) | generated ns/call (min / median) "
              "| generated / floor (min / median) |", "| --- | --- | --- | --- |"]
    for row in figures["floors"]:
        name = ROBOT_NOTES.get(row["robot"], row["robot"])
        if not row["floor_passes_verify"]:
            name += " (its floor FAILED kingen verify --source)"
        floors.append(f"| {name} | {_ns(row['floor']['min'])} / {_ns(row['floor']['median'])} "
                      f"| {_ns(row['routine']['min'])} / {_ns(row['routine']['median'])} "
                      f"| {row['ratio_min']:.2f} / {row['ratio_median']:.2f} |")
    worst_min = max(figures["floors"], key=lambda row: row["ratio_min"])
    worst_median = max(figures["floors"], key=lambda row: row["ratio_median"])
    worst = (f"The largest ratio in this run: {worst_min['ratio_min']:.3f} by minimum "
             f"({ROBOT_NOTES.get(worst_min['robot'], worst_min['robot']).split(' (')[0]}) and "
             f"{worst_median['ratio_median']:.3f} by median "
             f"({ROBOT_NOTES.get(worst_median['robot'], worst_median['robot']).split(' (')[0]}).")
    verify = ["| command | wall s | peak MiB (largest process) |", "| --- | --- | --- |"]
    for row in figures["verify"]:
        failed = "" if row["exit"] == 0 else f" (exit {row['exit']})"
        verify.append(f"| `{row['command']}`{failed} | {row['seconds']:.2f} | {row['peak_mib']:.0f} |")
    for row, what in zip(figures["startup"], ("start-up", "a command that reads a robot")):
        verify.append(f"| `{row['command']}` ({what}, median of 5) | {row['seconds']:.2f} | |")
    pytest = ""
    if figures.get("pytest"):
        plugin = figures["pytest"]
        pytest = "\n".join([
            f"| `pytest --kingen`, {plugin['robot_files']} robot files, {plugin['items']} items "
            f"| cold wall s (min / median of {plugin['runs']}) | warm wall s (min / median) |",
            "| --- | --- | --- |",
            *(f"| {'`' + row['workers'] + '`' if row['workers'].startswith('-') else row['workers']} "
              f"| {row['cold'][0]:.2f} / {row['cold'][1]:.2f} | {row['warm'][0]:.2f} / {row['warm'][1]:.2f} |"
              for row in plugin["rows"])])
    return PAGE.format(date=figures["date"], machine=figures["machine"], seconds=figures["seconds"],
                       calls=figures["calls"], floor_table="\n".join(floors), worst=worst,
                       verify_table="\n".join(verify), pytest_table=pytest or "(not run)",
                       sections=sections.render(figures.get("sections", {})))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=200000)
    parser.add_argument("--verify-samples", type=int, default=1000000)
    parser.add_argument("--robots", default=",".join(sorted(path.stem for path in FLOORS.glob("*.c"))))
    parser.add_argument("--memory-samples", type=int, default=0,
                        help="Also verify the first robot with this many poses (peak memory, e.g. 4000000).")
    parser.add_argument("--pytest-runs", type=int, default=5,
                        help="Rounds of pytest --kingen on the shipped robots, cold and warm (0: skip).")
    parser.add_argument("--page", type=Path, default=PAGE_PATH, help="The page to write (default docs/performance.md).")
    parser.add_argument("--figures", type=Path, default=FIGURES_PATH,
                        help="Where the run's figures are saved as JSON (default benchmarks/results/performance.json).")
    parser.add_argument("--render-only", action="store_true",
                        help="Measure nothing: write the page again from the saved figures.")
    parser.add_argument("--only", metavar="NAME[,NAME]",
                        help=f"Measure only these sections ({', '.join(['core', *sections.SECTIONS])}), "
                             "keeping the others' saved figures.")
    options = parser.parse_args()
    names = options.only.split(",") if options.only else ["core", *sections.SECTIONS]
    unknown = sorted(set(names) - {"core", *sections.SECTIONS})
    if unknown:
        parser.error(f"--only: no section {', '.join(unknown)} (sections: core, {', '.join(sections.SECTIONS)})")
    keep = options.render_only or options.only
    figures = json.loads(options.figures.read_text()) if keep and options.figures.exists() else {}
    if "floors" not in figures and options.render_only:
        parser.error(f"no saved figures in {options.figures}: measure them first (without --render-only)")
    if "floors" not in figures and "core" not in names:
        parser.error(f"no saved figures in {options.figures}: measure the core section too (--only core,...)")
    if not options.render_only:
        if "core" in names:
            figures.update(measure(options))
        for name in names:
            if name in sections.SECTIONS:
                figures.setdefault("sections", {})[name] = sections.measure(name)
        options.figures.parent.mkdir(parents=True, exist_ok=True)
        options.figures.write_text(json.dumps(figures, indent=1) + "\n")
    options.page.write_text(render(figures))
    print(f"wrote {options.page} ({options.figures})")


PAGE = """\
<!-- Written by benchmarks/run.py from benchmarks/results/performance.json: edit the text in
     benchmarks/run.py (PAGE), then run it, or run it with --render-only. -->

# Performance

How fast the generated routines are, measured against hand-written ones, what `kingen
verify` and the pytest plugin cost in time and memory, and what calibration, the C host and
the constrained machines achieve. `python benchmarks/run.py` writes this page: the figures
below are its runs', on the machine named with them (`--robots`, `--calls`,
`--verify-samples` and `--pytest-runs` choose what it measures, `--only calibrate,hybrid`
measures some sections again and keeps the others'; the figures themselves are kept in
`benchmarks/results/performance.json`). No test asserts a speed. The machine is shared, so
its speed drifts between runs: read the ratios, which move much less than the absolute
figures.

## The run

Machine: {machine}. Run on {date}; {seconds:.0f} s in all, for the figures from here to the
pytest plugin's (`--only core`); each section after it names its own run.

## The generated routine against a hand-written floor

`kingen bench ROBOT --floor benchmarks/floors/ROBOT.c` times one robot's generated routine
against its floor; this page has every robot that has one. The floors are tight
hand-written routines with the same contract as the generated code (host math through the
header, calibration fields, singular band, travel limits, direct index, NaN and overflow
safety), one per limb family and one for every robot with a direct-index threshold
(`six_rus.h` and `six_legs.h` hold the routines, each robot's file its geometry). Each passes
`kingen verify --source` (`tests/test_benchmarks.py`, and this run checks it again), so the
comparison is fair. They use every idea the generated code uses and the ones a careful
engineer adds by hand: loops over limbs unrolled so that table rows fold into constants, one
reciprocal per limb, the direct-index test without division vectorised over postures
(`FLOOR_DIRECT_MARGIN`), CEART's triples summed from pair sums, postures filled in blocks.

Both routines are timed through the C batch driver in 9 interleaved rounds of {calls:,}
calls each, so that the machine's drift hits both alike. Every call writes the same
`solutions[][]` and `warnings[]`, as a host's calls do. A minimum ratio is the ratio of two
minima, each of which one lucky round sets.

{floor_table}

{worst}

How far the ratios move on this machine: while other jobs ran, single `kingen bench --floor`
runs gave minimum ratios between 0.78 and 1.27, and medians between 0.89 and 1.15; absolute
figures move by 20 % or more between runs. The Exechon's routine takes 20 to 35 ns, so a
ratio of 1.1 is a difference of 2 to 3 ns a call. The hexapod's and the Flexapod's floors sum
the six force lines into M as they go; the generated routine first writes each limb's answer,
point and force line into a table.

What makes the generated code that fast while its source stays tables plus one helper per
limb model: the routine calls each model's helper once per limb with a fixed table row, and
`KINGEN_INLINE` (GCC/Clang `always_inline`, MSVC `__forceinline`) lets the compiler fold the
row into constants, so a field a robot does not calibrate costs nothing; components are
written out, not looped; one finiteness test of the sum of all joints guards the fast path
(T6 is examined only when it fails); postures are filled in blocks fixed by each joint's
digit; robots without travel limits compute one severity for all postures; angles wrap with
one 2 pi step before falling back to `fmod`. The direct index dominates where it is asked for
(CEART: 64 tests of 6 x 6 matrices per call, hexapod: one). Each is six signs of polynomials
in the matrix's entries, with no division and no branch ([Conventions](explanation/conventions.md), 'Force lines and
the direct index'), evaluated for all postures in one loop that the compiler vectorises.

## verify: wall time and memory

The wall time of the whole command and the peak memory of its largest process (each
comparing process uses about that much, sharing what was there when the others were forked),
with one comparing process per core and the poses beside the warnings' boundaries included.
On this two-core machine the second core gives much less than the first: two copies of one
CPU-bound Python loop started together took 1.76 and 2.71 s against 1.45 s for one alone, so
two comparing processes do about 1.3 to 1.9 times the work of one, varying from run to run.

{verify_table}

Of a hexapod verify's time, the command's start is about 0.3 s (imports about 0.2 s: numpy,
pydantic with the robot schema, ruamel.yaml, jinja2, cffi), reading the robot 0.06 to 0.1 s,
the build check 0.04 to 0.06 s, loading the plugin and the one-off checks (Jacobian, a round
trip of about 4096 postures, determinism, golden values) about 0.08 s; the rest is the
sampled poses. `kingen --version` and `--help` load click only. verify does not load scipy:
only `kingen fk`'s Stewart-Gough solver needs it.

### How verify spreads the work

Peak memory does not grow with `--samples`: poses are drawn chunk by chunk from one seeded
generator, the same poses whatever the chunk size. A chunk holds about 2 million joint
entries (5208 poses for CEART, about 2000 for IWF and the optimised 6-RUS, 7168 for the
hexapods, 8192 for the others), fewer where the reference builds each posture's 6 x 6 matrix
of the direct index. Before the first chunk, verify's child process forks one comparing
process per further core (`--processes`; by default as many as there are cores this process
may run on, fewer when a container's CPU quota, cgroup v2 `cpu.max` or v1
`cpu.cfs_quota_us`, allows less, at most 16, and never more than there are chunks; they die
with kingen). With P processes, process j (the child itself is 0) compares chunks j, j + P,
j + 2P, ..., drawing only those poses itself (it moves the generator past the others without
drawing them, so the poses stay the same, bit for bit), and only its results travel back, a
pipe each. The totals are merged in chunk order, into the report one process gives
(`tests/test_verify_processes.py`: 1, 2, 3 and 4 processes). A million hexapod poses took
2.76 s with `--processes 1` and 1.78 s with 2 (separate measurements, one run each); 4 processes on 2 cores took
2.08 to 2.25 s: more processes than cores cost little. If the routine crashes or exits in another
process, the first draws and runs that chunk again, so the crash is named with its poses as
always; if it runs to the end there, verify fails all the same (check `crash`, with the
signal or exit status and the poses), since a routine that crashes in one process and not in
another has crashed (`tests/test_legacy.py`).

Where one machine is not enough, `kingen verify ROBOT --scheduler tcp://scheduler:8786`
compares the chunks on a Dask cluster (`pip install 'kingen[cluster]'`, workers started with
`dask worker tcp://scheduler:8786`, each with kingen installed). Each chunk is one job: the
library's bytes travel with it (the workers need no build folder; each loads the library
once), the worker draws the chunk's poses itself from the seeded generator and sends back
only its totals, at most four jobs per worker thread are in flight, and the totals are merged
in chunk order, so the report is the one local processes give
(`tests/test_verify_reports.py` compares the JSON of a run on a `distributed.LocalCluster`
with a local one, timing aside). Plugin code then runs in the workers' processes, never in
kingen's. A job that fails (the routine crashed its worker, the cluster lost it) is compared
again in verify's own child, where a crash is named with its poses as always; if it runs to
the end there, verify fails (check `crash`, naming what failed and the poses).

### Where the time goes

Per pose, one comparing process spends (hexapod / CEART, microseconds of processor time,
measured separately from this script's run, in one process with verify's memory settings and
chunk sizes, means over 10 to 20 chunks): drawing the pose and its T6 0.2 / 0.2; the plugin call 0.3 / 2.8 (the guarded
buffers and, for CEART, the summary by branch included: every output is pre-filled, copied
out and its sentinel page compared after each call); the reference 1.0 / 5.1 to 5.6 (for
CEART the certificate 2.7 and its force lines 0.7); the comparison 0.4 / about 2.6 (for
CEART the closure residuals 0.8, deciding and reading the branch columns 0.1). verify also
compares up to 96 poses beside the warnings' boundaries, found with a few thousand reference
solves: a fixed cost, not one per sampled pose (hexapod 0.01 s; CEART 0.16 s, median over
seeds 0 to 39, of which 0.07 s for the rays and the rest for the descent that finds its
direct-index threshold, which no ray meets; at most 0.9 s over seeds 0 to 99).

- **The reference** keeps the poses on the fast axis throughout: platform points are (limb,
  coordinate, pose) in memory, force lines (limb, branch, component, pose), so numpy's loops
  run along contiguous rows. For the warnings only the side of `direct_index_min` matters.
  Where it can, the reference proves that side without forming any matrix
  (`kingen/kinematics/certificate.py`): it bounds the index from below by |det W| / ((F /
  3)^(3/2) T / 2) (W the posture's six line wrenches, F and T the traces of M's force and
  moment blocks), det W by Laplace's expansion over the two limb triples (20 minors per triple
  and branch combination, one batched 8 x 20 by 20 x 8 product per pose), with its rounding
  bounded ([Conventions](explanation/conventions.md), 'A certificate for the direct index', proves both, and
  `tests/test_certificate.py` tests them at the bound). It settles every CEART posture in the
  verification region (the bound is within 1.9 to 5.2 of the index, which stays above 400 mm
  against a 29.3 mm threshold) and no posture of IWF, the optimised 6-RUS or the hexapods
  (loose by 19 to 350 times there), so each call tries it on 32 poses and keeps it only where
  it settles half of their postures, and only for robots with more than one posture (it forms
  all 64 branch combinations' determinants). Whether a robot's chunks need the 6 x 6 matrices
  is decided from the certificate on the region's first 32 poses
  (`reference.certificate_settles`). The other postures' 6 x 6 matrices are built as the C
  builds them (each force line's w w^T once, then two partial sums per pose, the postures in
  blocks of 8192), chunk-wide: forming the products 1,024 poses at a time is slower in
  verify's processes, which keep freed memory mapped. The Schur complement comes from the
  force block's LDL^T, the side from Sylvester's criterion on S - t^2 I (three leading
  minors, no eigenvalue), and LAPACK computes the index only within 1e-4 of the threshold. A
  float32 certificate would settle nothing: its rounding allowance (about 37 float32 unit
  roundoffs of the product of the rows' 1-norms, 1e18 for CEART's rows in mm) exceeds |det W|
  (about 6e8) at every one of 2,000 CEART poses' 64 branch combinations.
- **The comparison** compares joints once per limb branch when the routine's postures repeat
  each branch's values ([What verify proves](explanation/verify.md)): for CEART 12 values per pose instead of 384. The
  DELMIA host's guarded driver decides it in C as it copies each call's outputs, while they
  are in the cache (`kingen_host_summarise_branches`: each limb's two branch values, and
  whether every posture's value equals its branch's); the comparison then reads those instead
  of passing twice over the 3 KB a call (for other hosts, shifted views of the output, no
  gather). `tests/test_verify_columns.py` holds the C summary to the numpy test entry by
  entry and a summarised call to a plain one. The rest of the comparison and its tallies stay
  in numpy (`tally.py`, which the mutation study pins): about a quarter of a pose's time.
- **Memory:** verify's child asks glibc to keep freed memory mapped, as numpy's chunk-sized
  temporaries would otherwise be unmapped and faulted in again thousands of times.
- **Start-up:** the `kingen` executable (`kingen.cli.run`) lets Python's garbage collector
  run its youngest collection every 50,000 allocations instead of 700 (a command's imports
  create some 10^5 long-lived objects and almost no garbage; numpy's arrays are not tracked)
  and freezes what is left before the interpreter exits, whose final collections would walk
  it all. The build check renders the plugin's source again each time: a stale plugin after a
  code change would cost more than its 0.05 s.

More cores take more processes (`--processes`, one per core by default), each drawing only
its own chunks; more machines, a Dask cluster (`--scheduler`).

## The pytest plugin

`pytest --kingen` on a copy of the shipped robot files (2000 poses each; `pytest --kingen
robots robots -q -p no:cacheprovider`, the folder named again so that nothing else is
collected), cold (a new, empty kingen cache each run) and warm (the cache an untimed run
filled), in one process and with `-n 2` (pytest-xdist), the four taken in turns:

{pytest_table}

A warm run builds nothing; what it spends is Python and pytest starting (about 0.6 s of
processor time), reading the robot files (about 30 ms each) and verifying them (0.1 to 0.4 s
each). Once the robot folders are collected the plugin calls `gc.freeze()`: what the session
holds by then (imported modules, items) stays to its end anyway, and pytest's garbage
collections at the session's end would otherwise scan it (0.2 s of a warm run). `-n 2` pays two more of those starts:
pytest-xdist alone, on a file with one empty test, takes 1.8 s with `-n 2` against 0.6 s in
one process on this machine. So `-n 2` is about as fast as one process warm and pays off
cold, with more poses (`--kingen-samples`) or with more robots; on a machine whose second
core is busy it is slower (with another job on the machine: warm 2.7 s in one process, 4.2 s
with `-n 2`). Keep the cache between CI jobs (`~/.cache/kingen`, or `$KINGEN_CACHE`) to save
the builds.

{sections}"""


if __name__ == "__main__":
    main()
