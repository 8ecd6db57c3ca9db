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

from conftest import require_tool, skip_or_fail

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


def page_text(site, page):
    """The built page's article as text: tags stripped, entities decoded, spaces collapsed."""
    source = (site / page / "index.html").read_text(encoding="utf-8")
    article = source[source.index("<article"):source.index("</article>")]
    inline = re.sub(r"</?(code|a|span|em|strong)\b[^>]*>", "", article)
    return " ".join(html.unescape(re.sub(r"<[^>]+>", " ", inline)).split())


def command_paths():
    """Every command path as typed after ``kingen`` ([] for kingen itself), hidden ones left out."""
    import click

    from kingen.cli import cli

    def walk(command, path):
        yield path
        if isinstance(command, click.Group):
            for name in command.list_commands(click.Context(command)):
                child = command.get_command(click.Context(command), name)
                if not child.hidden:
                    yield from walk(child, [*path, name])

    return list(walk(cli, []))


def help_of(path):
    """(description paragraphs, [(option and metavar, help)]) as ``kingen PATH --help`` prints
    them on a terminal wide enough that no help wraps."""
    from click.testing import CliRunner

    from kingen.cli import cli

    done = CliRunner().invoke(cli, [*path, "--help"], terminal_width=100000, max_content_width=100000)
    assert done.exit_code == 0, done.output
    head, _, options = done.output.partition("\nOptions:\n")
    description = head.split("\n\n", 1)[1] if "\n\n" in head else ""
    paragraphs = [" ".join(block.split()) for block in description.split("\n\n") if block.strip()]
    rows = []
    for line in options.split("\n\n")[0].splitlines():
        if line.startswith("  -"):
            names, _, text = line.strip().partition("  ")
            rows.append([names, text.strip()])
        elif line.strip():
            rows[-1][1] = (rows[-1][1] + " " + line.strip()).strip()
    return paragraphs, [(names, " ".join(text.split())) for names, text in rows]


def test_the_command_reference_shows_each_option_as_help_prints_it(site):
    text = page_text(site, "reference/commands")
    assert "Sentinel" not in text and "UNSET" not in text
    for path in command_paths():
        command = " ".join(["kingen", *path])
        start = text.index(f"{command}¶")
        section = text[start:]
        paragraphs, rows = help_of(path)
        for paragraph in paragraphs:  # `code` in a help is shown as code, without the backticks
            paragraph = paragraph.replace("`", "")
            assert paragraph in section, f"{command}: the page lacks its help {paragraph!r}"
        for names, help_text in rows:
            assert f"{names} {help_text}" in section, f"{command}: the page lacks {names} {help_text!r}"
    # Placeholders in angle brackets are shown, not swallowed as HTML tags.
    assert "Output folder [default: build/<name>/analysis]." in text
    assert "(kin_<name>.c for DELMIA)" in text


def test_the_command_list_gives_whole_sentences(site):
    source = (site / "reference" / "commands" / "index.html").read_text(encoding="utf-8")
    items = re.findall(r'<li><a href="#(kingen-[\w-]+)">[\w-]+</a>: (.*?)</li>', source)
    paths = {"-".join(["kingen", *path]): path for path in command_paths()}
    assert sorted(anchor for anchor, _ in items) == sorted(paths)[1:], "one list entry per subcommand"
    for anchor, summary in items:
        summary = " ".join(html.unescape(re.sub(r"<[^>]+>", "", summary)).split())
        paragraphs, _ = help_of(paths[anchor])
        paragraphs = [paragraph.replace("`", "") for paragraph in paragraphs]
        assert summary[-1] in ".?!", f"{anchor}: the summary {summary!r} stops mid-sentence"
        assert paragraphs[0].startswith(summary), f"{anchor}: {summary!r} is not how its help begins"


def test_the_api_page_shows_no_raw_roles(site):
    text = page_text(site, "reference/python-api")
    assert not re.search(r":(func|meth|class|mod|data|attr|exc|obj):", text), "a Sphinx role is shown raw"
    source = (site / "reference" / "python-api" / "index.html").read_text(encoding="utf-8")
    assert 'href="#kingen.load_robot"><code>load_robot</code></a>' in source, "a role links to what it names"


# The elements the pages' Markdown and the theme put in an article; any other tag is text such
# as <name> that Markdown took for HTML and swallowed.
ELEMENTS = set("""a abbr article autoref b blockquote br button code col colgroup dd del details div
dl dt em figcaption figure h1 h2 h3 h4 h5 h6 hr i img input ins kbd label li mark ol p path pre
s small span strong sub summary sup svg table tbody td tfoot th thead tr u ul""".split())


def test_no_page_swallows_a_placeholder(site):
    for page in sorted(site.rglob("index.html")):
        source = page.read_text(encoding="utf-8")
        article = source[source.find("<article"):source.find("</article>")]
        unknown = set(re.findall(r"</?([A-Za-z][\w-]*)", article)) - ELEMENTS
        assert not unknown, f"{page.relative_to(site)}: text taken for HTML tags: {sorted(unknown)}"


CHROMIUM = ["chromium", "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
            "--disable-background-networking", "--disable-component-update", "--disable-sync"]


def test_the_robot_file_tables_never_break_a_field_name(site, tmp_path):
    """Chromium lays the page out at a laptop's width; each field name of a table's first column
    must stand on one line (a name broken mid-word draws as two boxes)."""
    require_tool("chromium", "chromium")
    page = site / "reference" / "robot-file" / "index.html"
    probe = page.with_name("probe.html")  # beside the page, so its stylesheets load
    probe.write_text(page.read_text(encoding="utf-8").replace("</body>", """<script>
window.addEventListener("load", function () {
  var names = document.querySelectorAll(".md-typeset table td:first-child code");
  var broken = Array.prototype.filter.call(names, function (code) {
    return code.textContent.indexOf(" ") < 0 && code.getClientRects().length > 1; });
  document.body.setAttribute("data-names", names.length + ":" + broken.map(function (code) {
    return code.textContent; }).join(","));
});
</script></body>"""), encoding="utf-8")
    dom = subprocess.run([*CHROMIUM, f"--user-data-dir={tmp_path / 'profile'}", "--window-size=1280,900",
                          "--virtual-time-budget=5000", "--dump-dom", probe.as_uri()],
                         capture_output=True, text=True, timeout=120)
    found = re.search(r'data-names="(\d+):([^"]*)"', dom.stdout)
    assert found, dom.stderr[-2000:]
    assert int(found.group(1)) > 50, "the page's tables were not found"
    assert found.group(2) == "", f"field names broken across lines: {found.group(2)}"
