"""Outputs are written only where -o, --json and -o FILE say: a symbolic link another user
planted in the output folder (or on the way to it) is refused in one line, before anything is
written, and the file it points at (root's, outside the folder) is untouched; so is another
user's FIFO, which would otherwise hold kingen forever. Links of one's own, and root's
(``/dev/stdout``), are written through as before (tests/test_hostile_outputs.py)."""

import os
import re

import pytest

from conftest import skip_or_fail
from kingen.cli import main

OTHER = 12345
"""A uid no account has: the other user."""


@pytest.fixture
def planted(tmp_path):
    """(the output folder, the victim: a file of root's outside it, plant(name): a link to the
    victim named ``name`` in the folder, owned by the other user)."""
    if os.getuid() != 0:
        skip_or_fail("only root can give a link to another user")
    folder, victim = tmp_path / "out", tmp_path / "victim"
    folder.mkdir()
    victim.write_text("root's own\n")

    def plant(name):
        link = folder / name
        link.symlink_to(victim)
        os.lchown(link, OTHER, OTHER)
        return link

    return folder, victim, plant


def _refused(capsys, link):
    error = capsys.readouterr().err.strip()
    assert len(error.splitlines()) == 1, error
    assert re.search(rf"{re.escape(str(link))} is a symbolic link of another user \(uid {OTHER}\): kingen writes "
                     r"its outputs only through links and special files of your own or root's", error), error


def test_render_refuses_another_users_link_and_writes_nothing(planted, capsys):
    folder, victim, plant = planted
    link = plant("kingen_hexapod.c")
    assert main(["render", "hexapod", "--host", "c", "-o", str(folder)]) == 2
    _refused(capsys, link)
    assert victim.read_text() == "root's own\n" and os.listdir(folder) == ["kingen_hexapod.c"]


def test_calibrate_refuses_another_users_link_and_writes_nothing(planted, tmp_path, capsys):
    folder, victim, plant = planted
    poses = tmp_path / "poses.csv"
    assert main(["calibrate", "plan", "hexapod", "--poses", "30", "-o", str(poses)]) == 0
    link = plant("calibration.json")
    assert main(["calibrate", "hexapod", "--measurements", str(poses), "-o", str(folder)]) == 2
    _refused(capsys, link)
    assert victim.read_text() == "root's own\n" and os.listdir(folder) == ["calibration.json"]


def test_a_report_file_or_folder_through_another_users_link_is_refused_before_the_work(planted, tmp_path, capsys):
    folder, victim, plant = planted
    link = plant("report.json")
    assert main(["analyze", "hexapod", "-o", str(tmp_path / "a"), "--json", str(link)]) == 2
    _refused(capsys, link)
    hop = tmp_path / "hop"
    hop.symlink_to(folder)
    os.lchown(hop, OTHER, OTHER)
    assert main(["render", "hexapod", "--host", "c", "-o", str(hop / "deeper")]) == 2
    _refused(capsys, hop)
    assert not (tmp_path / "a").exists() and not (folder / "deeper").exists()


def test_another_users_fifo_is_refused_not_waited_on(planted, capsys):
    folder, _, _ = planted
    fifo = folder / "kingen_hexapod.h"
    os.mkfifo(fifo, 0o666)
    os.chown(fifo, OTHER, OTHER)
    assert main(["render", "hexapod", "--host", "c", "-o", str(folder)]) == 2
    error = capsys.readouterr().err.strip()
    assert f"{fifo}: is a special file of another user (uid {OTHER})" in error and len(error.splitlines()) == 1


def test_ones_own_link_is_still_written_through(planted, tmp_path):
    folder, victim, _ = planted
    (folder / "kingen_hexapod.c").symlink_to(victim)
    assert main(["render", "hexapod", "--host", "c", "-o", str(folder)]) == 0
    assert victim.read_text().startswith("/*") and (folder / "kingen_hexapod.c").is_symlink()


@pytest.mark.parametrize("given, words", [(".", "is the folder you are in"), ("..", "is the folder you are in or "
                                                                                  "holds it")])
def test_a_package_into_the_current_folder_is_refused_and_leaves_nothing(tmp_path, monkeypatch, capsys, given, words):
    here = tmp_path / "here"
    here.mkdir()
    monkeypatch.chdir(here)
    assert main(["package", "hexapod", "--host", "c", "-o", given]) == 2
    error = capsys.readouterr().err.strip()
    assert error.startswith(f"kingen: error: {given}: {words}, which kingen cannot replace") and "\n" not in error
    assert os.listdir(here) == [] and os.listdir(tmp_path) == ["here"]
