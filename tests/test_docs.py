"""The documentation site, built by the very command CI runs (the mkdocs line of .ci/run) on a
copy of docs/ and mkdocs.yml: it builds, it fails when a page links to an anchor that does not
exist, and the generated reference pages read as a user needs them to."""

import html
import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import skip_or_fail

ROOT = Path(__file__).resolve().parent.parent
pytestmark = pytest.mark.xdist_group("docs")


def ci_build_command(site):
    """(argv, environment) of the ``mkdocs build`` line of .ci/run, its ``$site`` made
    ``site`` and its ``python`` this interpreter."""
    lines = [line for line in (ROOT / ".ci" / "run").read_text(encoding="utf-8").splitlines()
             if "mkdocs build" in line and not line.lstrip().startswith("#")]
    assert len(lines) == 1, f".ci/run should build the site on one line, not {lines}"
    words = shlex.split(lines[0].replace('"$site"', str(site)))
    environment = dict(os.environ)
    while "=" in words[0]:
        name, value = words.pop(0).split("=", 1)
        environment[name] = value
    assert words[0] == "python", f".ci/run builds the site with {words[0]}, not python"
    return [sys.executable, *words[1:]], environment


def copy_of_docs(folder):
    """A copy of what the site is built from (docs/, mkdocs.yml, the changelog it includes),
    with this checkout's kingen beside it for the reference pages to read."""
    for name in ("docs", "mkdocs.yml", "CHANGELOG.md"):
        source = ROOT / name
        (shutil.copytree if source.is_dir() else shutil.copy)(source, folder / name)
    (folder / "kingen").symlink_to(ROOT / "kingen", target_is_directory=True)
    return folder


def build(folder, site):
    """Run CI's build in ``folder``; the finished process (output as text)."""
    argv, environment = ci_build_command(site)
    return subprocess.run(argv, cwd=folder, env=environment, capture_output=True, text=True, timeout=300)


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """The site CI builds, from a copy of this checkout's docs; its folder."""
    try:
        import mkdocs  # noqa: F401
    except ImportError:
        skip_or_fail("mkdocs is not installed (pip install -e '.[docs]'; .ci/run installs it)")
    folder = copy_of_docs(tmp_path_factory.mktemp("docs"))
    out = tmp_path_factory.mktemp("site")
    done = build(folder, out)
    assert done.returncode == 0, f"CI's docs build failed:\n{done.stdout}{done.stderr}"
    return out


def test_a_broken_anchor_fails_the_ci_build(site, tmp_path):
    folder = copy_of_docs(tmp_path / "docs")
    page = folder / "docs" / "index.md"
    page.write_text(page.read_text(encoding="utf-8")
                    + "\nSee [the limits](reference/limits.md#no-such-anchor).\n", encoding="utf-8")
    done = build(folder, tmp_path / "site")
    said = done.stdout + done.stderr
    assert done.returncode != 0, f"CI's docs build passed with a broken anchor:\n{said}"
    assert "no-such-anchor" in said, f"the failing build does not name the anchor:\n{said}"
