"""Adding a host touches only its own files: a toy host, defined in tests/hosts/ with its own
template and routine interface and registered here, is rendered, built, loaded, verified
(kingen's shared checks and one of its own) and packaged through the unchanged commands."""

import json

import pytest

from hosts.toy import ToyHost
from kingen import hosts
from kingen.cli import main
from kingen.errors import KingenError

ROBOT = """\
name: octo
description: Six legs of a small Stewart-Gough platform, for the toy host.
layout:
  type: stewart_gough
  base_radius: 150
  platform_radius: 100
  base_pair_angle: 20
  platform_pair_angle: 100
  reference_length: 200
verification:
  home: [0, 0, 250, 0, 0, 0]
  range: [20, 20, 20, 5, 5, 5]
golden:
  - source: "By the law of cosines: at home every leg spans 40 degrees between its base point (r 150) and
      platform point (r 100) and rises 250 mm: sqrt(100^2 + 150^2 - 2 100 150 cos 40 + 250^2) - 200."
    pose: [0, 0, 250, 0, 0, 0]
    joints: [68.36293840, 68.36293840, 68.36293840, 68.36293840, 68.36293840, 68.36293840]
    tolerance: 1.0e-6
"""


@pytest.fixture
def toy(tmp_path):
    """The toy host, registered for the test; the robot file it builds."""
    host = hosts.register(ToyHost())
    path = tmp_path / "octo.yaml"
    path.write_text(ROBOT)
    try:
        yield host, path
    finally:
        hosts.unregister(host)


def run(capsys, *argv):
    code = main([str(arg) for arg in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_a_registered_host_builds_verifies_and_packages_through_the_commands(toy, tmp_path, capsys):
    host, robot = toy
    code, out, err = run(capsys, "build", robot, "--host", "toy", "-o", tmp_path / "build")
    assert (code, err) == (0, "") and "libtoy_octo.so (compiled; routine toy_octo" in out
    code, out, err = run(capsys, "verify", robot, "--host", "toy", "-o", tmp_path / "build", "--samples", "3000",
                         "--json", tmp_path / "report.json")
    assert code == 0, out + err
    report = json.loads((tmp_path / "report.json").read_text())
    names = [check["name"] for check in report["checks"]]
    assert names == ["definition", "toy return", "values", "warnings", "closure", "jacobian", "round trip",
                     "determinism", "machine", "golden[0]"]
    assert report["passed"] and report["samples"] == 3000 and report["max_abs_error_mm"] < 1e-9
    assert "built by kingen" in report["checks"][0]["detail"]
    code, out, err = run(capsys, "package", robot, "--host", "toy", "-o", tmp_path / "package")
    assert code == 0 and sorted(path.name for path in (tmp_path / "package").iterdir()) == [
        ".kingen-package", "README.txt", "libtoy_octo.so", "toy_octo.c"]


def test_a_wrong_toy_routine_fails_the_shared_checks(toy, tmp_path, capsys):
    host, robot = toy
    source = tmp_path / "wrong.c"
    text = host.render(__import__("kingen.robot.model", fromlist=["load_robot"]).load_robot(robot))["toy_octo.c"]
    source.write_text(text.replace("- row[6]", "- row[6] + 1e-6"))
    code, out, _ = run(capsys, "verify", robot, "--host", "toy", "--source", source, "-o", tmp_path / "b",
                       "--samples", "2000")
    assert code == 1
    assert "FAILED values: max |error| 1e-06 mm" in out and "FAILED closure" in out
    assert "FAILED golden[0]" not in out  # 1e-6 mm is inside the golden tolerance


def test_a_target_the_host_does_not_have_is_a_usage_error(toy, tmp_path, capsys):
    _, robot = toy
    code, _, err = run(capsys, "build", robot, "--host", "toy", "--target", "windows", "-o", tmp_path / "b")
    assert code == 2 and "host toy has no target windows" in err


def test_an_unknown_host_is_named(toy, capsys):
    _, robot = toy
    code, _, err = run(capsys, "verify", robot, "--host", "fanuc")
    assert code == 2 and err == "kingen: error: unknown host 'fanuc' (known: c, delmia, linuxcnc, toy, wasm)\n"
    with pytest.raises(KingenError, match="unknown host"):
        hosts.get_host("nowhere")


def test_a_host_the_tests_removed_is_gone(tmp_path):
    host = hosts.register(ToyHost())
    hosts.unregister(host)
    assert "toy" not in hosts.HOSTS and "delmia" in hosts.HOSTS


def test_host_help_names_every_registered_host(toy, capsys):
    """--host's help lists the hosts registered when it is shown, a plugin's included."""
    code, out, _ = run(capsys, "verify", "--help")
    assert code == 0
    said = " ".join(out.split())
    for name, host in hosts.HOSTS.items():
        assert f"{name}, {' '.join(host.description.split())}" in said, name
    assert {"c", "delmia", "linuxcnc", "toy", "wasm"} <= set(hosts.HOSTS)
