"""A robot name whose C library names (kingen_<name>_..., KINGEN_<NAME>_...) would collide with
the names the library's own C uses is refused when the file is read (exit 2, one line at the
name), never a compiler's error; other names build."""

import re

import pytest

from kingen.cli import main
from kingen.hosts.c import CHost, shared_names
from kingen.robot.model import resolve_robot_path


def _named(tmp_path, name):
    path = tmp_path / f"{name}.yaml"
    path.write_text(re.sub(r"^name: .*$", f"name: {name}", resolve_robot_path("hexapod").read_text(), count=1,
                           flags=re.M))
    return path


def test_solve_would_name_a_helper_and_is_refused_at_its_line(tmp_path, capsys):
    path = _named(tmp_path, "solve")
    assert main(["build", str(path), "--host", "c", "-o", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err.strip()
    assert error.startswith(f"kingen: error: {path}:2: name: gives the C library's names the prefix 'kingen_solve_'")
    assert "\n" not in error and not (tmp_path / "out").exists()


def test_every_helper_names_prefix_is_refused_and_only_those():
    """For each name the C uses, kingen_<a>_<b> or KINGEN_<A>_<B>, the robot name <a> (each
    split at an underscore) is refused; names no helper starts with are not."""
    host = CHost()
    for name in shared_names():
        parts = name.split("_")[1:]
        for cut in range(1, len(parts)):
            robot = "_".join(parts[:cut])
            if re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", robot):
                assert host.name_problem(robot if name.startswith("kingen") else robot.lower()), (name, robot)
    for robot in ("hexapod", "leg", "rail", "crank", "c_batch_x", "geometry"):
        assert host.name_problem(robot) is None, robot


@pytest.mark.parametrize("name", ["leg", "geometry"])
def test_a_name_near_the_helpers_builds(tmp_path, name):
    assert main(["build", str(_named(tmp_path, name)), "--host", "c", "-o", str(tmp_path / "out")]) == 0
