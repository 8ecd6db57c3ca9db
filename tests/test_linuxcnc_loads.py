"""The LinuxCNC module's static-load pins: held to kingen's loads by verify (a planted error
fails), read through the HAL stand-in against an independent statics of a centred payload,
built against LinuxCNC's real headers."""

import subprocess
import sys

import numpy as np
import pytest

from conftest import require_linuxcnc_headers
from kingen.hosts import get_host
from kingen.hosts.linuxcnc.render import render
from kingen.robot.model import load_robot
from kingen.runtime.resources import robots_dir


@pytest.fixture(autouse=True)
def linuxcnc_headers():
    require_linuxcnc_headers()


@pytest.mark.parametrize("name", ["tau", "linuxcnc_hexapod", "prs_head", "tricept", "rotary_delta", "exechon_wrist",
                                  "tricept_wrist3"])
def test_the_load_pins_are_held_to_the_reference_and_a_wrong_one_fails(tmp_path, name):
    """verify --host linuxcnc reads load.N after each inverse (a translating platform, a hexapod in
    inches, a 3-PRS head, a Tricept, revolute cranks, five- and six-axis wrists); a module whose
    loads are 1e-4 off fails its
    'hal loads' check."""
    robot = load_robot(name)
    host = get_host("linuxcnc")
    (source_name, source), = render(robot, host.machine_units(robot)).items()
    weight = "        weight[i] = mass * gravity[i];"
    assert source.count(weight) == 1
    for text, verdict in ((source, 0), (source.replace(weight, weight.replace("mass *", "1.0001 * mass *")), 1)):
        (tmp_path / source_name).write_text(text)
        result = subprocess.run([sys.executable, "-m", "kingen.cli", "verify", name, "--host", "linuxcnc", "--source",
                                 str(tmp_path / source_name), "--samples", "300", "--out-dir", str(tmp_path / "out")],
                                capture_output=True, text=True, timeout=300)
        assert result.returncode == verdict, result.stdout + result.stderr
        assert ("FAILED hal loads:" if verdict else "ok     hal loads:") in result.stdout


def test_a_centred_payload_loads_each_hexapod_leg_with_m_g_over_six_cos_tilt(tmp_path):
    """The pins through the HAL stand-in, the payload set through the module's parameters: at
    the verification home (no rotation) a payload at the platform origin loads each leg of the
    symmetric hexapod with m g / (6 cos theta), theta the leg's tilt from vertical (from the
    robot file's points), pushing up (positive: the legs lengthen upwards); a failed inverse,
    a payload of mass 0 and a weight past a double's range write 0."""
    robot = load_robot("hexapod")
    host = get_host("linuxcnc")
    built = host.build(robot, tmp_path / "b")
    module = host.load(built.library, built.routine, host.as_seen(robot))
    home = np.array(robot.verification.home, dtype=float)
    assert np.all(home[3:] == 0)
    legs = np.array([np.add(limb.platform_point, home[:3]) - limb.base_point for limb in robot.limbs])
    cosine = legs[:, 2] / np.linalg.norm(legs, axis=1)
    mass = 120.0
    world = np.zeros((2, 9))
    world[:, :3] = home[:3]
    world[1, 0] = np.nan
    loads, returns = module.static_loads(world, (mass, (0.0, 0.0, 0.0), (0.0, 0.0, -9.81)))
    assert returns[0] == 0 and returns[1] != 0
    assert np.allclose(loads[0], mass * 9.81 / (6 * cosine), rtol=1e-12, atol=0)
    assert np.all(loads[1] == 0.0)
    unloaded, _ = module.static_loads(world[:1], (0.0, (0.0, 0.0, 0.0), (0.0, 0.0, -9.81)))
    assert np.all(unloaded == 0.0)
    # a weight past a double's range (m g = 9.81e307 * 9.81): no inf or NaN on the pins, 0
    beyond, returned = module.static_loads(world[:1], (9.81e307, (0.0, 0.0, 0.0), (0.0, 0.0, -9.81)))
    assert returned[0] == 0 and np.all(beyond == 0.0)


def test_the_payload_parameters_default_to_the_robot_files_in_the_machines_units(tmp_path):
    """linuxcnc_hexapod is in inches: the robot file's payload centre (its own units) is the
    parameters' default in the module's inches, its mass and gravity as given."""
    path = tmp_path / "loaded.yaml"
    path.write_text((robots_dir() / "linuxcnc_hexapod.yaml").read_text().replace(
        "name: linuxcnc_hexapod\n", "name: loaded\npayload: {mass: 7.5, centre: [1.0, -0.5, 2.0]}\ngravity: [0, 0.5, -9.8]\n"))
    robot = load_robot(path)
    host = get_host("linuxcnc")
    assert host.machine_units(robot) == "inch"
    built = host.build(robot, tmp_path / "b")
    module = host.load(built.library, built.routine, host.as_seen(robot))
    read = {name: module.parameter(f"loadedkins.{name}") for name in
            ("payload.mass", "payload.centre.x", "payload.centre.y", "payload.centre.z", "gravity.x", "gravity.y",
             "gravity.z")}
    assert read == pytest.approx({"payload.mass": 7.5, "payload.centre.x": 1.0, "payload.centre.y": -0.5,
                                  "payload.centre.z": 2.0, "gravity.x": 0.0, "gravity.y": 0.5, "gravity.z": -9.8},
                                 rel=1e-15, abs=1e-15)


def test_a_module_whose_wrist_torques_alone_are_wrong_fails_hal_loads(tmp_path):
    """The wrist joints' pins are judged as well as the legs': a module whose wrist torques have
    the opposite sign (tau_j = +z_j . M_c), its legs' loads right, fails 'hal loads' alone."""
    robot = load_robot("tricept_wrist3")
    host = get_host("linuxcnc")
    (source_name, source), = render(robot, host.machine_units(robot)).items()
    line = "            torques[j] += (fixed[0][k]"
    assert source.count(line) == 1
    (tmp_path / source_name).write_text(source.replace(line, line.replace("+=", "-=")))
    result = subprocess.run([sys.executable, "-m", "kingen.cli", "verify", "tricept_wrist3", "--host", "linuxcnc",
                             "--source", str(tmp_path / source_name), "--samples", "300", "--out-dir", str(tmp_path / "out")],
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 1, result.stdout + result.stderr
    assert "FAILED hal loads:" in result.stdout and "FAILED (1 of " in result.stdout, result.stdout
