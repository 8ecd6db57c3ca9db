"""The limbs' moving parts in the loads, held to computations that share no code with
kingen.kinematics.limb_parts: the parts' positions written here from the robot file's geometry
and the reference's joints; statics by virtual work (central differences of the inverse
kinematics and of the parts' potential energy), dynamics by the parts' accelerations from
central differences of their positions along the motion (Newton's second law for point masses,
d'Alembert's virtual work)."""

import math
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest

from kingen.kinematics.loads import Motion, loads, machine_t6
from kingen.kinematics.reference import solve
from kingen.robot.loads_schema import LimbParts
from kingen.robot.model import load_robot
from test_loads import (HEXAPOD, PAYLOAD, comparable, free_coordinates, in_internal_units, moved, platform_at,
                        poses_of, virtual_work_forces)

PARTS = {"actuator": {"mass": 3.5, "centre": 60.0}, "link": {"mass": 1.75, "centre": 110.0}}
FAMILIES = ["hexapod", "ceart", "tau", "rotary_delta", "exechon_constrained"]


def with_parts(name, payload=PAYLOAD):
    robot = load_robot(name)
    limbs = tuple(limb.model_copy(update={"parts": LimbParts(**PARTS)}) for limb in robot.limbs)
    return replace(robot, limbs=limbs, payload=payload)


def part_positions(robot, t6, joints):
    """(m, 2, 3) each limb's actuator part and link part (mm, base frame) at T6 (4, 4) with the
    joints (m,) of one posture, from the file's fields (robot file reference, 'Leg', 'Crank', 'Rail')."""
    positions = []
    for limb, joint in zip(robot.limbs, joints):
        platform = t6[:3, :3].T @ np.array(limb.platform_point) + t6[3, :3]
        if limb.model == "leg":
            base = np.array(limb.base_point, dtype=float)
        elif limb.model == "crank":
            theta, beta = joint + math.radians(limb.zero_offset), math.radians(limb.crank_direction)
            pivot = np.array(limb.pivot, dtype=float)
            base = pivot + limb.crank_length * np.array([math.cos(theta) * math.cos(beta),
                                                         math.cos(theta) * math.sin(beta), -math.sin(theta)])
        else:  # a rail's carriage
            base = (np.array(limb.rail_point) + np.array(limb.carriage_offset)
                    + (joint + limb.origin) * np.array(limb.direction))
        along = (platform - base) / np.linalg.norm(platform - base)
        if limb.model == "leg":
            actuator = base + PARTS["actuator"]["centre"] * along
        elif limb.model == "crank":
            actuator = pivot + PARTS["actuator"]["centre"] / limb.crank_length * (base - pivot)
        else:
            actuator = base + PARTS["actuator"]["centre"] * np.array(limb.direction)
        positions.append([actuator, platform - PARTS["link"]["centre"] * along])
    return np.array(positions)


def masses():
    return np.array([PARTS["actuator"]["mass"], PARTS["link"]["mass"]])


def positions_at(robot, t6, posture):
    return part_positions(robot, t6, solve(robot, t6[None]).joints[0, :robot.dof, posture])


def gravity_work(robot, posture, payload_mass=PAYLOAD.mass):
    """The work (N mm) gravity does on the payload (PAYLOAD's centre, ``payload_mass``) and the
    parts, the platform moved between T6s."""
    def work(before, after):
        centres = [t6[:3, :3].T @ PAYLOAD.centre + t6[3, :3] for t6 in (before, after)]
        parts = positions_at(robot, after, posture) - positions_at(robot, before, posture)
        return np.dot(robot.gravity, payload_mass * (centres[1] - centres[0])
                      + np.einsum("k,mki->i", masses(), parts))
    return work


@pytest.mark.parametrize("name", FAMILIES)
def test_the_parts_weight_is_the_virtual_work_of_their_potential_energy(name):
    robot = with_parts(name)
    poses = poses_of(robot, 2, seed=FAMILIES.index(name))
    result = loads(robot, machine_t6(robot, poses))
    bare = loads(replace(robot, limbs=load_robot(name).limbs), machine_t6(robot, poses))
    compared = 0
    for index, pose in enumerate(poses):
        for posture in range(min(robot.postures, 8)):
            if not comparable(robot, result, index, posture):
                continue
            expected = virtual_work_forces(robot, pose, posture, gravity_work(robot, posture))
            got = in_internal_units(robot, result.forces[index, posture])
            assert np.max(np.abs(got - expected)) <= 1e-6 * np.max(np.abs(expected)), (pose, posture)
            change = got - in_internal_units(robot, bare.forces[index, posture])
            assert np.max(np.abs(change)) > 1e-3 * np.max(np.abs(expected))  # the parts count
            compared += 1
    assert compared >= 2


@pytest.mark.parametrize("name", ["hexapod", "ceart", "tau", "exechon_constrained"])
def test_moving_parts_add_their_dalembert_forces(name):
    robot = with_parts(name, payload=None)
    motion = Motion(velocity=np.array([120.0, -80.0, 60.0, 0.4, -0.3, 0.5]),
                    acceleration=np.array([900.0, 500.0, -1500.0, 2.0, 3.0, -1.5]))
    pose = poses_of(robot, 1, seed=11)[0]
    t6 = machine_t6(robot, pose[None])
    result = loads(robot, t6, motion=motion)
    posture = robot.working_posture
    step = 1e-3  # s
    path = [positions_at(robot, platform_at(t6[0], motion, k * step), posture) for k in (-1, 0, 1)]
    acceleration = (path[2] - 2 * path[1] + path[0]) / step ** 2 / 1000.0  # (m, 2, 3) m/s^2
    force = masses()[None, :, None] * acceleration
    gravity = gravity_work(robot, posture, payload_mass=0.0)

    def work(before, after):
        moves = positions_at(robot, after, posture) - positions_at(robot, before, posture)
        return gravity(before, after) - np.einsum("mki,mki->", force, moves)

    expected = virtual_work_forces(robot, pose, posture, work)
    got = in_internal_units(robot, result.forces[0, posture])
    assert np.max(np.abs(got - expected)) <= 1e-6 * np.max(np.abs(expected))
    at_rest = in_internal_units(robot, loads(robot, t6).forces[0, posture])
    assert np.max(np.abs(got - at_rest)) > 1e-2 * np.max(np.abs(expected))  # the motion counts


def test_kingen_loads_reads_a_layouts_parts_and_refuses_a_negative_mass(tmp_path):
    text = HEXAPOD.read_text()
    path = tmp_path / "parts.yaml"
    path.write_text(text.replace("reference_length: 399.413}",
                                 "reference_length: 399.413, parts: {actuator: {mass: 2, centre: 50}, "
                                 "link: {mass: 1, centre: 80}}}"))
    run = [sys.executable, "-m", "kingen.cli", "loads", str(path), "--pose", "0", "0", "465", "0", "0", "0"]
    result = subprocess.run(run, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    for bad, fragment in (("mass: -2", "mass: Input should be greater than 0"), ("mass: .nan", "finite number"),
                          ("mass: 2, centre: -5", "centre: Input should be greater than or equal to 0")):
        path.write_text(text.replace("reference_length: 399.413}",
                                     f"reference_length: 399.413, parts: {{actuator: {{{bad}}}}}}}", 1))
        refused = subprocess.run(run, capture_output=True, text=True, timeout=120)
        assert refused.returncode == 2 and refused.stderr.count("\n") == 1, refused.stderr
        assert fragment in refused.stderr and "parts.actuator" in refused.stderr, refused.stderr


def test_the_c_librarys_static_loads_hold_the_payload_alone_when_the_limbs_have_parts(tmp_path):
    """The C library's static loads hold the payload alone: verify's 'c loads' compares them with
    kingen's for massless limbs, and passes on a robot file whose legs have parts."""
    path = tmp_path / "parts.yaml"
    path.write_text(HEXAPOD.read_text().replace(
        "reference_length: 399.413}", "reference_length: 399.413, parts: {actuator: {mass: 2, centre: 50}}}"))
    result = subprocess.run([sys.executable, "-m", "kingen.cli", "verify", str(path), "--host", "c", "--samples", "300",
                             "--out-dir", str(tmp_path / "out")], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "ok     c loads:" in result.stdout
