"""How long ``pytest --kingen`` takes on the shipped robot files, cold and warm (run.py's
pytest figures)."""

import importlib.util
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROBOTS = Path(__file__).resolve().parent.parent / "robots"


def pytest_plugin_times(scratch, rounds):
    """{(cache, workers): [wall seconds]} and the item count of ``pytest --kingen`` on a copy of
    the shipped robot files, cold (a new empty cache per run) and warm (the cache one untimed
    run filled), serial and with ``-n 2`` (only when pytest-xdist is installed), taken in turns."""
    folder = Path(scratch) / "plugin"
    shutil.copytree(ROBOTS, folder / "robots")
    # The folder named twice: once for --kingen, once as what pytest collects (nothing else).
    command = [sys.executable, "-m", "pytest", "--kingen", "robots", "robots", "-q", "-p", "no:cacheprovider"]
    variants = [("cold", ()), ("warm", ())]
    if importlib.util.find_spec("xdist") is not None:
        variants += [("cold", ("-n", "2")), ("warm", ("-n", "2"))]
    warm_cache = folder / "warm-cache"
    times, items = {}, None
    for number in range(rounds + 1):  # run 0 fills the warm cache and is not counted
        for cache, workers in variants:
            cache_folder = warm_cache if cache == "warm" else Path(tempfile.mkdtemp(dir=folder))
            start = time.perf_counter()
            result = subprocess.run([*command, *workers], cwd=folder, capture_output=True, text=True,
                                    env={**os.environ, "KINGEN_CACHE": str(cache_folder)})
            seconds = time.perf_counter() - start
            if cache == "cold":
                shutil.rmtree(cache_folder)
            if result.returncode != 0:
                raise SystemExit(f"pytest --kingen failed (exit {result.returncode}):\n{result.stdout[-2000:]}")
            items = int(re.search(r"(\d+) passed", result.stdout).group(1))
            if number:
                times.setdefault((cache, workers), []).append(seconds)
    return times, items
