"""The performance page's further sections: each one script of benchmarks/ that measures one
concern and hands its figures to run.py as plain data.

A section's script takes ``--json FILE`` besides its own settings (it writes its figures there
as JSON, and prints the same figures as Markdown) and defines ``markdown(figures)``, the
Markdown of those figures without a heading, and ``ABOUT``, a paragraph saying what it
measures (links relative to docs/). Adding a section is one row of SECTIONS; run.py
runs it, keeps its figures in benchmarks/results/performance.json under ``sections`` and
renders it after the page's fixed text, with the command, machine, date and time behind it.
"""

import datetime
import importlib.util
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent

SECTIONS = {
    # name: (script in benchmarks/, its arguments, the page's heading)
    "calibrate": ("calibrate.py", [], "Calibration"),
    "calibrate_montecarlo": ("calibrate_montecarlo.py", ["--seeds", "30", "--poses", "50"],
                             "Calibration's stated deviations (Monte-Carlo)"),
    "c_host": ("c_host.py", [], "The C host"),
    "wasm_host": ("wasm_host.py", [], "The WebAssembly host"),
    "hybrid": ("hybrid.py", ["--calls", "200000", "--rounds", "5"], "Constrained machines"),
    "check_path": ("check_path.py", ["--samples", "1000000", "--moves", "100"], "Path checking"),
    "loads": ("loads.py", ["--poses", "1000000", "--rows", "2000", "--rounds", "3"], "Loads"),
    "ncfiles": ("ncfiles.py", [], "LinuxCNC's sample programs"),
    "planner": ("planner.py", [], "Timing as LinuxCNC's planner moves"),
    "view": ("view.py", ["--changes", "300"], "The 3D view"),
}


def machine():
    """The machine figures are measured on: processor, cores, system, C compiler, Python."""
    model = next((line.split(":", 1)[1].strip() for line in Path("/proc/cpuinfo").read_text().splitlines()
                  if line.startswith("model name")), platform.processor())
    compiler = subprocess.run([os.environ.get("CC", "cc"), "--version"], capture_output=True, text=True).stdout
    return (f"{model}, {os.cpu_count()} cores, {platform.system()} {platform.release()}; "
            f"{compiler.splitlines()[0] if compiler else 'cc'}; Python {platform.python_version()}")


def measure(name):
    """Run section ``name``'s script; its figures with the command, machine, date and wall seconds."""
    script, arguments, _ = SECTIONS[name]
    with tempfile.TemporaryDirectory() as scratch:
        path = Path(scratch) / f"{name}.json"
        started = time.perf_counter()
        done = subprocess.run([sys.executable, str(HERE / script), *arguments, "--json", str(path)])
        seconds = time.perf_counter() - started
        if done.returncode != 0:
            raise SystemExit(f"benchmarks/{script} failed (exit {done.returncode})")
        figures = json.loads(path.read_text())
    return {"command": " ".join(["python", f"benchmarks/{script}", *arguments]), "date": datetime.date.today().isoformat(),
            "machine": machine(), "seconds": seconds, "figures": figures}


def _script(script):
    """A section's script as a module (loaded from its file, under a name of its own): its ABOUT and markdown."""
    spec = importlib.util.spec_from_file_location(f"benchmarks_{Path(script).stem}", HERE / script)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def render(saved):
    """Every section of SECTIONS, in order, from its saved run (or a line saying it was not run)."""
    blocks = []
    for name, (script, _, title) in SECTIONS.items():
        module = _script(script)
        blocks += [f"## {title}", module.ABOUT]
        run = saved.get(name)
        if run is None:
            blocks.append(f"Not measured yet: `python benchmarks/run.py --only {name}`.")
            continue
        blocks.append(f"`{run['command']}`, run on {run['date']} in {run['seconds']:.0f} s; machine: {run['machine']}.")
        blocks.append(module.markdown(run["figures"]).rstrip("\n"))
    return "\n\n".join(blocks) + "\n"
