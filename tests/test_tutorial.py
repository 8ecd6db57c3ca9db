"""docs/tutorial.md, run as a user would: its robot file is written into an empty folder and
every ``$ kingen ...`` line of its console blocks is run there, in order (as ``python -m
kingen.cli ...``), and must exit 0. The output the page shows must be there too: each shown
line, ``...`` standing for anything and runs of spaces for any spacing, matches a line the
command printed. So the tutorial cannot go stale."""

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

from conftest import require_linuxcnc_headers

ROOT = Path(__file__).resolve().parent.parent
TUTORIAL = ROOT / "docs" / "tutorial.md"
FENCE = re.compile(r"^```(\w+)\n(.*?)^```$", re.M | re.S)


def blocks(kind):
    """The bodies of the page's fenced blocks of ``kind`` (yaml, console), in order."""
    return [body for language, body in FENCE.findall(TUTORIAL.read_text(encoding="utf-8")) if language == kind]


def robot_files():
    """(file name, text) of each YAML block, named by its first line, ``# NAME.yaml``."""
    files = []
    for body in blocks("yaml"):
        first = body.splitlines()[0]
        assert re.fullmatch(r"# [\w.-]+\.yaml", first), f"a tutorial YAML block starts with '# NAME.yaml', not {first!r}"
        files.append((first[2:], body))
    return files


def commands():
    """(command line, shown output lines) for each ``$ `` line of the console blocks."""
    steps = []
    for body in blocks("console"):
        for line in body.splitlines():
            if line.startswith("$ "):
                steps.append((line[2:], []))
            else:
                assert steps, f"output before any command in a console block: {line!r}"
                steps[-1][1].append(line)
    return steps


def normal(text):
    return " ".join(text.split())


def shown_pattern(line):
    """A shown output line as a regular expression: ``...`` any text, any spacing alike."""
    return re.compile(".*".join(re.escape(part) for part in normal(line).split("...")))


def test_the_tutorial_has_a_robot_file_and_commands():
    assert robot_files(), "docs/tutorial.md has no YAML robot file"
    assert all(command.startswith("kingen ") for command, _ in commands())
    assert len(commands()) >= 6


def test_the_tutorial_runs(tmp_path):
    for name, text in robot_files():
        (tmp_path / name).write_text(text, encoding="utf-8")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}
    for command, shown in commands():
        if "--host linuxcnc" in command:
            require_linuxcnc_headers()
        argv = [sys.executable, "-m", "kingen.cli", *shlex.split(command)[1:]]
        done = subprocess.run(argv, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
        assert done.returncode == 0, f"$ {command}\nexit {done.returncode}\n{done.stdout}\n{done.stderr}"
        printed = [normal(line) for line in done.stdout.splitlines()]
        for line in shown:
            if normal(line) in ("", "..."):
                continue
            pattern = shown_pattern(line)
            assert any(pattern.fullmatch(out) for out in printed), (
                f"$ {command}\nthe tutorial shows {line!r}, which the command did not print:\n{done.stdout}")
