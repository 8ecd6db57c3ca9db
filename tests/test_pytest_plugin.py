"""kingen inside the user's own pytest: robot files as test files, golden values and
snapshots as items, stale libraries caught by their build information."""

import shutil

import pytest

from kingen.cli import main
from kingen.model import robots_dir

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
    result.assert_outcomes(passed=8)
    for name in ("build", "interface", "values", "warnings", "closure", "jacobian", "golden[0]", "golden[1]"):
        assert f"tau.yaml::{name} PASSED" in result.stdout.str()


def test_a_changed_golden_joint_fails_exactly_its_item_at_its_line(folder):
    path = folder.path / "tau.yaml"
    path.write_text(path.read_text().replace("joints: [417.2158, 361.0962, 265.8219]",
                                             "joints: [417.2158, 361.0962, 265.9219]"))
    result = run(folder)
    result.assert_outcomes(passed=7, failed=1)
    assert "FAILED tau.yaml::golden[0]" in result.stdout.str()
    line = path.read_text().splitlines().index("golden:") + 2  # the first entry's "- source:" line
    assert f"{path}:{line}: golden[0]\ngolden[0]: DELMIA V5 methodology thesis, Table 6" in result.stdout.str()


def test_items_are_selected_by_keyword(folder):
    run(folder, "-k", "tau and golden").assert_outcomes(passed=2)


def test_a_snapshot_from_one_build_fails_after_a_geometry_change(folder, capsys):
    path = folder.path / "tau.yaml"
    assert main(["golden", "record", str(path), "-o", str(folder.path / "tau.golden.json"), "--samples", "30"]) == 0
    run(folder).assert_outcomes(passed=9)
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
