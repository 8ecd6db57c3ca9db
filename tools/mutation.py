"""Mutation testing of the code that decides kingen's verdicts and generates its C: one small
change at a time, each mutant run against the test files that cover its file, results as a
table per file. Run on demand, not in CI (docs/developer/contributing.md):

    pip install -e ".[mutation]"
    python tools/mutation.py list                         # mutants per file
    nice -n 19 python tools/mutation.py run --sample 300 --seed 1 [--files GLOB ...] [--rerun-survivors [--only-survivors]]
    python tools/mutation.py table                        # the per-file table of the results so far
    python tools/mutation.py show KEY                     # one mutant's diff

Python modules are mutated by mutmut's operators (mutmut 2.x's library: numbers, strings,
operators, comparisons, keywords, arguments, assignments); the C templates by
tools/c_mutants.py. Each mutant is applied to a scratch copy of the repository
(build/mutation/work, the git-tracked and new files), never to the checkout; the tests
run there with ``pytest -x`` and a timeout of three times their unmutated time plus 60 s.
A C mutant the compiler refuses (rendered for the robot named in C_ROBOTS) is stillborn
and not counted. Results go to build/mutation/results.jsonl, one line per mutant, and a
rerun skips mutants already there (delete the file to start again). Mutants listed in
tools/mutation_equivalent.txt (key, then '#', then why no test can tell) are left out of
the score.
"""

import argparse
import fnmatch
import json
import os
import random
import shutil
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from c_mutants import c_mutants  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "build" / "mutation"
EQUIVALENT = Path(__file__).resolve().parent / "mutation_equivalent.txt"

_VERIFY = ["tests/test_verdicts.py", "tests/test_verify_bands.py", "tests/test_verify_columns.py"]
_REPORTS = ["tests/test_verify_reports.py::test_reports_are_those_recorded"]
"""verify's recorded reports: every check's detail, count and statistic word for word (a few seconds)."""
_CHILD = ["tests/test_verify_reports.py::test_a_dask_cluster_gives_the_report_local_processes_give",
          "tests/test_hostile.py::test_what_a_constructor_prints_is_a_notice_and_stays_out_of_the_output"]
"""A cluster's report against a local one, what a library prints as it loads (about 15 s)."""
_C = ["tests/test_templates.py", "tests/test_golden_values.py", "tests/test_calibration.py", "tests/test_plugin.py"]
TESTS = {
    # target (a glob of repository paths) -> the test files that cover it, fastest first
    "kingen/verify/tally.py": _VERIFY + ["tests/test_exercised.py"] + _REPORTS,
    "kingen/verify/boundaries.py": ["tests/test_exercised.py", "tests/test_verdicts.py"] + _REPORTS,
    "kingen/verify/checks/*.py": _VERIFY + ["tests/test_golden_lines.py", "tests/test_exercised.py",
                                            "tests/test_templates.py", "tests/test_forward.py", "tests/test_legacy.py"]
                                 + _REPORTS,
    "kingen/verify/[!t]*.py": _VERIFY + ["tests/test_verify_processes.py", "tests/test_exercised.py",
                                         "tests/test_legacy.py"] + _REPORTS + _CHILD,
    "kingen/kinematics/reference.py": ["tests/test_reference.py", "tests/test_certificate.py", "tests/test_verdicts.py",
                            "tests/test_golden_values.py", "tests/test_golden_lines.py", "tests/test_calibration.py",
                            "tests/test_verify_bands.py"] + _REPORTS,
    "kingen/kinematics/singularity.py": ["tests/test_numerics.py", "tests/test_singularity.py", "tests/test_verdicts.py",
                              "tests/test_reference.py", "tests/test_verify_columns.py", "tests/test_golden_values.py"]
                             + _REPORTS,
    "kingen/kinematics/certificate.py": ["tests/test_certificate.py", "tests/test_singularity.py", "tests/test_reference.py",
                              "tests/test_verdicts.py"],
    "kingen/kinematics/forward.py": ["tests/test_numerics.py", "tests/test_forward.py", "tests/test_assembly_modes.py"] + _REPORTS,
    "kingen/verify/diagnose.py": ["tests/test_diagnoses.py", "tests/test_legacy.py"],
    "kingen/robot/limbs/*.py": ["tests/test_reference.py", "tests/test_diagnoses.py", "tests/test_golden_values.py",
                          "tests/test_singularity.py", "tests/test_calibration.py", "tests/test_limb_registry.py",
                          "tests/test_setup_sheet.py"] + _REPORTS,
    "kingen/robot/reading.py": ["tests/test_numerics.py", "tests/test_model.py", "tests/test_limits.py"],
    "kingen/runtime/text.py": ["tests/test_model.py", "tests/test_hostile_outputs.py", "tests/test_limits.py"],
    "kingen/runtime/isolation.py": ["tests/test_hostile.py"],
    "templates/limbs/*.c.j2": _C + _REPORTS + ["tests/test_linuxcnc.py"],
    "kingen/hosts/delmia/templates/kin_robot.c.j2": _C + ["tests/test_exercised.py"] + _REPORTS,
    "templates/routine_helpers.c.j2": _C + ["tests/test_exercised.py"] + _REPORTS + ["tests/test_linuxcnc.py"],
}
C_ROBOTS = {"templates/limbs/leg.c.j2": "hexapod", "templates/limbs/rail.c.j2": "tau",
            "templates/limbs/crank.c.j2": "ceart", "kingen/hosts/delmia/templates/kin_robot.c.j2": "ceart",
            "templates/routine_helpers.c.j2": "ceart"}


def targets(patterns=None):
    """{path: tests} of every targeted file (``patterns``: globs narrowing them)."""
    found = {}
    for glob, tests in TESTS.items():
        for path in sorted(ROOT.glob(glob)):
            name = str(path.relative_to(ROOT))
            if name.endswith("__init__.py") and name != "kingen/verify/__init__.py" or name in found:
                continue
            if not patterns or any(fnmatch.fnmatch(name, pattern) for pattern in patterns):
                found[name] = [test for test in tests if (ROOT / test.partition("::")[0]).exists()]
    return found


def mutants_of(path):
    """[(key, apply(text) -> mutated text)] of one file."""
    text = (ROOT / path).read_text()
    if path.endswith(".j2"):
        return [(mutant.key, mutant.apply) for mutant in c_mutants(path, text)]
    from mutmut import Context, list_mutations, mutate

    found = []
    for mutation in list_mutations(Context(source=text, filename=path, dict_synonyms=[])):
        key = f"{path}:{mutation.line_number + 1}:{mutation.index}:{mutation.line.strip()[:60]}"

        def apply(source, mutation=mutation):
            mutated, count = mutate(Context(source=source, filename=path, mutation_id=mutation, dict_synonyms=[]))
            assert count == 1, key
            return mutated

        found.append((key, apply))
    return found


def equivalents():
    if not EQUIVALENT.exists():
        return {}
    listed = {}
    for line in EQUIVALENT.read_text().splitlines():
        if line.strip() and not line.startswith("#"):
            key, _, reason = line.partition(" # ")
            listed[key.strip()] = reason.strip()
    return listed


def _workspace():
    """A fresh scratch copy of the repository's tracked and new files."""
    work = OUT / "work"
    if work.exists():
        shutil.rmtree(work)
    names = subprocess.run(["git", "ls-files", "--cached", "--others", "--exclude-standard"], cwd=ROOT, check=True,
                           capture_output=True, text=True).stdout.split("\n")
    for name in filter(None, names):
        source = ROOT / name
        if source.is_file():
            (work / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, work / name)
    return work


def _environment(work):
    env = dict(os.environ, PYTHONPATH=str(work), OPENBLAS_NUM_THREADS="1", KINGEN_CACHE=str(OUT / "cache"),
               PYTHONDONTWRITEBYTECODE="1")
    (OUT / "cache").mkdir(parents=True, exist_ok=True, mode=0o700)
    return env


def _pytest(work, tests, timeout):
    command = [sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider", "-p", "no:xdist", *tests]
    started = time.monotonic()
    try:
        done = subprocess.run(command, cwd=work, env=_environment(work), capture_output=True, text=True,
                              timeout=timeout, start_new_session=True)
    except subprocess.TimeoutExpired:
        return "timeout", time.monotonic() - started, ""
    tail = (done.stdout + done.stderr).strip().splitlines()[-1:] or [""]
    return ("survived" if done.returncode == 0 else "killed"), time.monotonic() - started, tail[0][:200]


def _compiles(work, path):
    robot = C_ROBOTS[path]
    done = subprocess.run([sys.executable, "-m", "kingen.cli", "build", robot, "-o", str(OUT / "stillborn")],
                          cwd=work, env=_environment(work), capture_output=True, text=True, timeout=300)
    return done.returncode == 0


def load_results():
    results = {}
    path = OUT / "results.jsonl"
    if path.exists():
        for line in path.read_text().splitlines():
            if line.strip():
                entry = json.loads(line)
                results[entry["key"]] = entry
    return results


def run(arguments):
    chosen = targets(arguments.files)
    every = [(path, key, apply) for path in chosen for key, apply in mutants_of(path)]
    sample = random.Random(arguments.seed).sample(every, min(arguments.sample, len(every))) if arguments.sample else every
    done = load_results()
    survivors = {key for key, entry in done.items() if entry["status"] == "survived"}
    if arguments.rerun_survivors:  # the tests changed since: judge the survivors again
        done = {key: entry for key, entry in done.items() if entry["status"] != "survived"}
    todo = [item for item in sample if item[1] not in done]
    if arguments.only_survivors:  # and nothing else (listed equivalents stay as they are)
        todo = [item for item in every if item[1] in survivors and item[1].strip() not in equivalents()]
    print(f"{len(every)} mutants in {len(chosen)} files; sample {len(sample)}, {len(todo)} still to run", flush=True)
    if not todo:
        return table(arguments)
    work = _workspace()
    baseline = {}
    for path, tests in chosen.items():
        key = tuple(tests)
        if key in baseline or not any(item[0] == path for item in todo):
            continue
        status, seconds, tail = _pytest(work, tests, 3600)
        if status != "survived":
            sys.exit(f"the tests of {path} fail unmutated ({tail}): fix them first")
        baseline[key] = seconds
        print(f"baseline {seconds:6.1f} s  {' '.join(tests)}", flush=True)
    OUT.mkdir(parents=True, exist_ok=True)
    with open(OUT / "results.jsonl", "a") as results:
        for number, (path, key, apply) in enumerate(todo, 1):
            original = (work / path).read_text()
            try:
                (work / path).write_text(apply(original))
                if path.endswith(".j2") and not _compiles(work, path):
                    status, seconds, tail = "stillborn", 0.0, "does not compile"
                else:
                    tests = chosen[path]
                    status, seconds, tail = _pytest(work, tests, 3 * baseline[tuple(tests)] + 60)
            finally:
                (work / path).write_text(original)
            entry = {"key": key, "file": path, "status": status, "seconds": round(seconds, 1), "tail": tail}
            results.write(json.dumps(entry) + "\n")
            results.flush()
            print(f"[{number}/{len(todo)}] {status:9} {seconds:6.1f} s  {key}", flush=True)
    return table(arguments)


def table(arguments):
    results = load_results()
    listed = equivalents()
    rows = {}
    for entry in results.values():
        status = "equivalent" if entry["key"].strip() in listed and entry["status"] == "survived" else entry["status"]
        rows.setdefault(entry["file"], {}).setdefault(status, []).append(entry)
    print("| file | mutants | killed | timeout | survived | equivalent | stillborn | score | time |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    total = {}
    for path in sorted(rows):
        count = {status: len(entries) for status, entries in rows[path].items()}
        for status, value in count.items():
            total[status] = total.get(status, 0) + value
        seconds = sum(entry["seconds"] for entries in rows[path].values() for entry in entries)
        total["seconds"] = total.get("seconds", 0) + seconds
        print(_row(path, count, seconds))
    print(_row("**all**", total, total.get("seconds", 0)))
    if arguments.survivors:
        print("\nSurvivors:")
        for path in sorted(rows):
            for entry in rows[path].get("survived", []):
                print(f"  {entry['key']}")
        print("\nEquivalent (tools/mutation_equivalent.txt):")
        for path in sorted(rows):
            for entry in rows[path].get("equivalent", []):
                print(f"  {entry['key']}  # {listed[entry['key'].strip()]}")
    return 0


def _row(name, count, seconds):
    killed, timeout, survived = count.get("killed", 0), count.get("timeout", 0), count.get("survived", 0)
    judged = killed + timeout + survived
    score = f"{100 * (killed + timeout) / judged:.1f} %" if judged else "-"
    return (f"| {name} | {judged + count.get('equivalent', 0) + count.get('stillborn', 0)} | {killed} | {timeout} | "
            f"{survived} | {count.get('equivalent', 0)} | {count.get('stillborn', 0)} | {score} | {seconds:.0f} s |")


def list_mutants(arguments):
    print("| file | mutants | tests |\n| --- | --- | --- |")
    total = 0
    for path, tests in targets(arguments.files).items():
        count = len(mutants_of(path))
        total += count
        print(f"| {path} | {count} | {' '.join(Path(test).name for test in tests)} |")
    print(f"| **all** | {total} | |")
    return 0


def show(arguments):
    import difflib

    path = arguments.key.split(":")[0]
    for key, apply in mutants_of(path):
        if key == arguments.key:
            text = (ROOT / path).read_text()
            sys.stdout.writelines(difflib.unified_diff(text.splitlines(True), apply(text).splitlines(True), path, path))
            return 0
    sys.exit(f"no mutant {arguments.key}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    for name in ("list", "run", "table"):
        command = commands.add_parser(name)
        command.add_argument("--files", nargs="*", help="globs of repository paths (default: every target)")
        command.add_argument("--survivors", action="store_true", help="table: also list the surviving mutants")
        command.add_argument("--sample", type=int, default=0, help="run: a random sample of this many (0: all)")
        command.add_argument("--seed", type=int, default=1)
        command.add_argument("--rerun-survivors", action="store_true", help="run: judge surviving mutants again")
        command.add_argument("--only-survivors", action="store_true",
                             help="run: judge only the surviving mutants again (with --rerun-survivors)")
    commands.add_parser("show").add_argument("key")
    arguments = parser.parse_args()
    return {"list": list_mutants, "run": run, "table": table, "show": show}[arguments.command](arguments)


if __name__ == "__main__":
    sys.exit(main())
