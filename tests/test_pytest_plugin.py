"""kingen inside the user's own pytest: robot files as test files, golden values and
snapshots as items, stale libraries caught by their build information."""

import json
import os
import shutil

import pytest

from kingen.cli import main
from kingen.robot.model import robots_dir
from kingen.pytest_plugin import robot_scope

pytest_plugins = ["pytester"]


@pytest.fixture
def folder(pytester):
    """A fresh folder holding only a copy of a shipped robot file, as a user's repository."""
    shutil.copy(robots_dir() / "tau.yaml", pytester.path / "tau.yaml")
    return pytester


def run(pytester, *args):
    return pytester.runpytest_subprocess("--kingen", ".", "-p", "no:cacheprovider", "--kingen-samples", "300", *args)


def test_every_item_of_a_robot_file_passes(folder):
    result = run(folder, "-v")
    result.assert_outcomes(passed=9)
    for name in ("build", "interface", "values", "warnings", "closure", "jacobian", "golden[0]", "golden[1]",
                 "golden[2]"):
        assert f"tau.yaml::{name} PASSED" in result.stdout.str()


def test_a_changed_golden_joint_fails_exactly_its_item_at_its_line(folder):
    path = folder.path / "tau.yaml"
    path.write_text(path.read_text().replace("joints: [417.2158, 361.0962, 265.8219]",
                                             "joints: [417.2158, 361.0962, 265.9219]"))
    result = run(folder)
    result.assert_outcomes(passed=8, failed=1)
    assert "FAILED tau.yaml::golden[0]" in result.stdout.str()
    line = path.read_text().splitlines().index("golden:") + 2  # the first entry's "- source:" line
    assert f"{path}:{line}: golden[0]\ngolden[0]: DELMIA V5 methodology thesis, Table 6" in result.stdout.str()


def test_items_are_selected_by_keyword(folder):
    run(folder, "-k", "tau and golden").assert_outcomes(passed=3)


def test_a_snapshot_from_one_build_fails_after_a_geometry_change(folder, capsys):
    path = folder.path / "tau.yaml"
    assert main(["golden", "record", str(path), "-o", str(folder.path / "tau.golden.json"), "--samples", "30"]) == 0
    run(folder).assert_outcomes(passed=10)
    path.write_text(path.read_text().replace("link_length: 1499.775", "link_length: 1499.9"))
    result = run(folder)
    text = result.stdout.str()
    assert "FAILED tau.yaml::snapshot" in text and "joints beyond 1e-06 mm" in text
    assert "recorded from another definition" in text
    assert "FAILED tau.yaml::values" not in text  # the plugin still matches the (changed) reference


def test_a_library_built_before_an_edit_fails_the_definition_check(tmp_path, capsys):
    path = tmp_path / "tau.yaml"
    shutil.copy(robots_dir() / "tau.yaml", path)
    assert main(["build", str(path), "-o", str(tmp_path / "b")]) == 0
    path.write_text(path.read_text().replace("travel: [-1, 2600]", "travel: [-1, 2500]", 1))
    capsys.readouterr()
    code = main(["verify", str(path), "--plugin", str(tmp_path / "b" / "libtau.so"), "--samples", "200"])
    out = capsys.readouterr().out
    assert code == 1
    assert "FAILED definition: the library says it was built by kingen 0.1.0 from another definition of 'tau'" in out


def test_info_reads_a_library_without_loading_it(tmp_path, capsys):
    assert main(["build", "exechon", "-o", str(tmp_path)]) == 0
    capsys.readouterr()
    assert main(["info", str(tmp_path / "libexechon.so")]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[1].startswith("format: ELF 64-bit shared object")
    assert out[2:5] == ["robot: exechon", "routine: kin_exechon", "dof: 3, postures: 1"]
    assert out[5] == f"definition sha256: {__import__('hashlib').sha256((robots_dir() / 'exechon.yaml').read_bytes()).hexdigest()}"


@pytest.mark.parametrize("count, words", [("-5", "-5 poses: give at least 1"), ("0", "0 poses: give at least 1"),
                                          ("many", "'many' is not a whole number of poses")])
def test_a_bad_sample_count_is_a_usage_error(folder, count, words):
    result = folder.runpytest_subprocess("--kingen", ".", "-p", "no:cacheprovider", f"--kingen-samples={count}")
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    assert f"error: argument --kingen-samples: {words}" in result.stderr.str()


def test_a_robot_file_reached_twice_is_collected_once(folder):
    (folder.path / "loop").symlink_to(".")
    (folder.path / "twin.yaml").symlink_to("tau.yaml")
    result = folder.runpytest_subprocess("--kingen", ".", "-p", "no:cacheprovider", "--co", "-q")
    items = [line for line in result.stdout.lines if "::" in line]
    assert items == [f"tau.yaml::{name}" for name in ("build", "interface", "values", "warnings", "closure",
                                                       "jacobian", "golden[0]", "golden[1]", "golden[2]")]


UNREADABLE = {
    "gone.yaml": (lambda path: path.symlink_to("nowhere.yaml"), "the symlink's target nowhere.yaml does not exist"),
    "sub/lost.yml": (lambda path: path.symlink_to("/no/such/robot.yml"),
                     "the symlink's target /no/such/robot.yml does not exist"),
    "pipe.yaml": (os.mkfifo, "not a regular file (a FIFO); give the file itself"),
    "null.yml": (lambda path: path.symlink_to("/dev/null"), "not a regular file (a character device); give the file itself"),
}


def test_a_robot_file_that_cannot_be_read_is_a_failing_item(folder):
    """A dangling symlink, a FIFO or a device (which pytest passes over) is a failing build
    item naming the file: never a hang, never skipped in silence."""
    for name, (make, _) in UNREADABLE.items():
        (folder.path / name).parent.mkdir(exist_ok=True)
        make(folder.path / name)
    result = run(folder, "-k", "gone or lost or pipe or null")
    result.assert_outcomes(failed=len(UNREADABLE))
    text = result.stdout.str()
    for name, (_, words) in UNREADABLE.items():
        assert f"{folder.path / name}: {words}" in text and f"FAILED {name}::build" in text


COUNTING = """
import kingen.verify

calls = []
verify_library = kingen.verify.verify_library


def counting(*arguments, **keywords):
    calls.append(1)
    FAILING
    return verify_library(*arguments, **keywords)


kingen.verify.verify_library = counting


def pytest_unconfigure(config):
    with open("verify_calls.txt", "w") as stream:
        stream.write(str(len(calls)))
"""


def test_a_bad_snapshot_fails_the_snapshot_item_alone_and_verify_runs_once(folder):
    snapshot = folder.path / "tau.golden.json"
    assert main(["golden", "record", str(folder.path / "tau.yaml"), "-o", str(snapshot), "--samples", "5"]) == 0
    data = json.loads(snapshot.read_text())
    data["entries"][0]["warnings"][0] = 2 ** 70
    snapshot.write_text(json.dumps(data))
    folder.makeconftest(COUNTING.replace("FAILING", "pass"))
    result = run(folder)
    result.assert_outcomes(passed=9, failed=1)
    text = result.stdout.str()
    assert "FAILED tau.yaml::snapshot" in text and "Traceback" not in text and "internal error" not in text
    assert f"{snapshot}: entries.0.warnings.0: 1180591620717411303424 is not a warning code (0, 1, 2, 5)" in text
    assert (folder.path / "verify_calls.txt").read_text() == "1"


def test_an_error_inside_verify_is_reported_to_every_item_from_one_run(folder):
    folder.makeconftest(COUNTING.replace("FAILING", "raise RuntimeError('broken inside verify')"))
    result = run(folder)
    result.assert_outcomes(failed=9)
    assert result.stdout.str().count("RuntimeError: broken inside verify") >= 9
    assert (folder.path / "verify_calls.txt").read_text() == "1"


def test_a_second_session_builds_nothing(folder, tmp_path, monkeypatch):
    """Robots are built in kingen's cache, named by content: a warm session reuses the
    libraries (same bytes, same file) instead of compiling again."""
    monkeypatch.setenv("KINGEN_CACHE", str(tmp_path / "cache"))
    run(folder).assert_outcomes(passed=9)
    libraries = sorted((tmp_path / "cache" / "pytest-builds").glob("*/libtau.so"))
    assert len(libraries) == 1
    before = libraries[0].stat()
    run(folder).assert_outcomes(passed=9)
    after = libraries[0].stat()
    assert (after.st_ino, after.st_mtime_ns) == (before.st_ino, before.st_mtime_ns)



def test_what_a_session_holds_after_collection_is_frozen_out_of_the_garbage_collector(folder):
    """gc.freeze() once robot folders are collected (pytest's end-of-session collections then
    skip the imported modules and items); a session without them is left alone."""
    folder.makeconftest("import gc\n\n\ndef pytest_unconfigure(config):\n"
                        "    open('frozen.txt', 'w').write(str(gc.get_freeze_count()))\n")
    run(folder).assert_outcomes(passed=9)
    assert int((folder.path / "frozen.txt").read_text()) > 10000
    folder.makepyfile(test_plain="def test_nothing():\n    pass\n")
    folder.runpytest_subprocess("-p", "no:cacheprovider", "test_plain.py").assert_outcomes(passed=1)
    assert int((folder.path / "frozen.txt").read_text()) == 0


def test_under_xdist_each_robot_files_items_run_on_one_worker(folder):
    """``-n 2`` alone: the plugin's scheduler keeps a robot file's items together, so each
    robot is verified once, on one worker (pytest-xdist's own would spread them)."""
    shutil.copy(robots_dir() / "exechon.yaml", folder.path / "exechon.yaml")
    result = run(folder, "-n", "2", "-v")
    result.assert_outcomes(passed=17)
    workers = {}
    for line in result.stdout.lines:
        if " PASSED " in line and line.startswith("[gw"):
            workers.setdefault(line.split(" PASSED ")[1].split("::")[0], set()).add(line.split("]")[0])
    assert sorted(workers) == ["exechon.yaml", "tau.yaml"]
    assert all(len(used) == 1 for used in workers.values()), workers


@pytest.mark.parametrize("nodeid, scope", [("robots/tau.yaml::golden[1]", "robots/tau.yaml"),
                                           ("sub/lost.yml::build", "sub/lost.yml"),
                                           ("tests/test_cli.py::test_help", "tests/test_cli.py::test_help"),
                                           ("tests/a.yaml.py::test_x[b.yaml]", "tests/a.yaml.py::test_x[b.yaml]")])
def test_robot_scope_groups_a_robot_files_items_only(nodeid, scope):
    assert robot_scope(nodeid) == scope



@pytest.mark.parametrize("make, problem", [
    (os.mkfifo, "not a regular file (a FIFO); give the file itself"),
    (lambda path: path.symlink_to("/dev/zero"), "not a regular file (a character device); give the file itself"),
    (lambda path: path.symlink_to("gone.golden.json"), "cannot be read: No such file or directory")],
    ids=["fifo", "link-to-dev-zero", "dangling-link"])
def test_a_snapshot_that_cannot_be_read_fails_the_snapshot_item(folder, make, problem):
    make(folder.path / "tau.golden.json")
    result = run(folder)
    result.assert_outcomes(passed=9, failed=1)
    assert f"{folder.path / 'tau.golden.json'}: {problem}" in result.stdout.str()
    assert "FAILED tau.yaml::snapshot" in result.stdout.str()
