"""Actuator loads held to an independent computation: virtual work from central differences of
the reference's inverse kinematics, and the payload's rate of change of momentum from central
differences of its motion (Newton-Euler written nowhere in kingen). Neither uses force lines,
transmissions or the loads module's wrench algebra."""

import json
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from kingen.conventions import pose_from_t6, t6_from_pose
from kingen.kinematics.loads import Motion, loads, machine_t6
from kingen.kinematics.hybrid.parasitic import solve_parasitic
from kingen.kinematics.reference import solve
from kingen.kinematics.routine import WARNINGS
from kingen.robot.loads_schema import Payload
from kingen.robot.model import load_robot

FAMILIES = ["hexapod", "ceart", "tau", "linear_delta", "rotary_delta", "exechon", "exechon_constrained",
            "prs_head", "rps_table", "tricept", "flexapod"]
COORDINATES = ("x", "y", "z", "roll", "pitch", "yaw")
PAYLOAD = Payload(mass=120.0, centre=(15.0, -20.0, 40.0), inertia=((4.0, 0.3, -0.2), (0.3, 5.0, 0.1), (-0.2, 0.1, 7.0)))
STEP = 1e-3
"""Central differences' step: mm along a free coordinate, or mrad."""


def with_payload(name, gravity=(0.0, 0.0, -9.81)):
    return replace(load_robot(name), payload=PAYLOAD, gravity=gravity)


def free_coordinates(robot):
    return robot.task or robot.forward_free or COORDINATES


def moved(robot, pose, coordinate, step):
    """The machine's T6 with one free coordinate of ``pose`` (mm, degrees) moved by ``step`` (mm or rad)."""
    pose = np.array(pose, dtype=float)
    index = COORDINATES.index(coordinate)
    pose[index] += step if index < 3 else np.degrees(step)
    t6 = t6_from_pose(pose[None])
    return solve_parasitic(robot, t6).t6 if robot.task else t6


def rotation_vector_between(before, after):
    """The small rotation (rad, base frame) taking T6 ``before``'s orientation to ``after``'s."""
    return Rotation.from_matrix(after[:3, :3].T @ before[:3, :3]).as_rotvec()


def virtual_work_forces(robot, pose, posture, applied_work):
    """Actuator forces (N, N mm per rad) by virtual work: over each free coordinate's central
    difference, the actuators' work sum_i tau_i dq_i equals minus the applied wrench's work
    ``applied_work(before, after)`` (N mm, the platform moved from T6 ``before`` to ``after``)."""
    rates, work = [], []
    for coordinate in free_coordinates(robot):
        before, after = moved(robot, pose, coordinate, -STEP), moved(robot, pose, coordinate, STEP)
        joints = solve(robot, np.concatenate([before, after])).joints[:, :, posture]
        rates.append((joints[1] - joints[0]) / (2 * STEP))
        work.append(-applied_work(before[0], after[0]) / (2 * STEP))
    return np.linalg.solve(np.array(rates), np.array(work))


def weight_work(robot):
    """The work (N mm) gravity does on the payload when the platform moves from one T6 to another."""
    def work(before, after):
        centre = [t6[:3, :3].T @ PAYLOAD.centre + t6[3, :3] for t6 in (before, after)]
        return PAYLOAD.mass * np.dot(robot.gravity, centre[1] - centre[0])
    return work


def poses_of(robot, count, seed):
    home, span = np.array(robot.verification.home, float), np.array(robot.verification.range, float)
    poses = home + np.random.default_rng(seed).uniform(-0.5, 0.5, (count, 6)) * span
    t6 = t6_from_pose(poses)
    return pose_from_t6(solve_parasitic(robot, t6).t6 if robot.task else t6)


def comparable(robot, result, index, posture):
    """Whether a posture at a pose is a fair comparison: reached without warning, and well
    away from a singularity of loads (its forces below 1e6 N)."""
    return (result.warnings[index, posture] == WARNINGS["WARN_GOOD_SOLUTION"]
            and np.all(np.abs(result.forces[index, posture]) < 1e6))


def in_internal_units(robot, forces):
    """Forces as loads() reports them (N, N m) in virtual work's units (N, N mm per rad)."""
    return forces * np.where([t.wraps for t in robot.joint_types[:robot.dof]], 1000.0, 1.0)


@pytest.mark.parametrize("name", FAMILIES)
def test_static_loads_are_the_virtual_work_of_gravity(name):
    robot = with_payload(name)
    poses = poses_of(robot, 3, seed=FAMILIES.index(name))
    result = loads(robot, machine_t6(robot, poses))
    compared = 0
    for index, pose in enumerate(poses):
        for posture in range(min(robot.postures, 8)):
            if not comparable(robot, result, index, posture):
                continue
            expected = virtual_work_forces(robot, pose, posture, weight_work(robot))
            got = in_internal_units(robot, result.forces[index, posture])
            assert np.max(np.abs(got - expected)) <= 1e-6 * np.max(np.abs(expected)), (pose, posture)
            compared += 1
    assert compared >= 3


@pytest.mark.parametrize("name", ["hexapod", "ceart", "exechon_constrained", "tau"])
def test_an_external_wrench_is_the_virtual_work_of_its_force_and_moment(name):
    robot = replace(load_robot(name), payload=None)
    wrench = np.array([35.0, -60.0, 210.0, 4.0, -7.5, 2.5])  # N, N m at the platform origin, base frame
    pose = poses_of(robot, 1, seed=7)[0]
    result = loads(robot, machine_t6(robot, pose[None]), wrench=wrench)

    def work(before, after):
        return (np.dot(wrench[:3], after[3, :3] - before[3, :3])
                + 1000.0 * np.dot(wrench[3:], rotation_vector_between(before, after)))

    posture = robot.working_posture
    expected = virtual_work_forces(robot, pose, posture, work)
    got = in_internal_units(robot, result.forces[0, posture])
    assert np.max(np.abs(got - expected)) <= 1e-6 * np.max(np.abs(expected))


def platform_at(pose_t6, motion, time):
    """T6 of the platform at ``time`` s along a motion that starts at T6 ``pose_t6`` with the
    velocity and acceleration of ``motion``: p(t) = p + v t + a t^2 / 2, R(t) = exp([w t + alpha t^2 / 2]) R."""
    velocity, acceleration = np.asarray(motion.velocity), np.asarray(motion.acceleration)
    t6 = pose_t6.copy()
    t6[3, :3] = pose_t6[3, :3] + velocity[:3] * time + acceleration[:3] * time ** 2 / 2
    turn = Rotation.from_rotvec(velocity[3:] * time + acceleration[3:] * time ** 2 / 2).as_matrix()
    t6[:3, :3] = (turn @ pose_t6[:3, :3].T).T
    return t6


def inertial_work(robot, pose_t6, motion):
    """The work (N mm) of the payload's d'Alembert wrench -(dP/dt, dH/dt) along a virtual
    displacement, from central differences of its centre's position and its angular momentum
    along the motion (both over +/- 1 ms)."""
    step = 1e-3
    frames = [platform_at(pose_t6, motion, k * step) for k in (-2, -1, 0, 1, 2)]
    centres = [t6[:3, :3].T @ PAYLOAD.centre + t6[3, :3] for t6 in frames]  # mm
    acceleration = (centres[3] - 2 * centres[2] + centres[1]) / step ** 2 / 1000.0  # m/s^2
    momenta = []
    for k in (1, 3):
        rotation = frames[k][:3, :3].T
        spin = Rotation.from_matrix(frames[k + 1][:3, :3].T @ frames[k - 1][:3, :3]).as_rotvec() / (2 * step)
        momenta.append(rotation @ PAYLOAD.inertia_matrix @ rotation.T @ spin)
    torque = (momenta[1] - momenta[0]) / (2 * step)  # N m about the centre
    force = PAYLOAD.mass * acceleration

    def work(before, after):
        centre = [t6[:3, :3].T @ PAYLOAD.centre + t6[3, :3] for t6 in (before, after)]
        return -(np.dot(force, centre[1] - centre[0]) + 1000.0 * np.dot(torque, rotation_vector_between(before, after)))
    return work


@pytest.mark.parametrize("name", ["hexapod", "ceart", "exechon_constrained", "prs_head"])
def test_dynamic_loads_add_the_payloads_momentum_rate(name):
    robot = with_payload(name)
    motion = Motion(velocity=np.array([120.0, -80.0, 60.0, 0.4, -0.3, 0.5]),
                    acceleration=np.array([900.0, 500.0, -1500.0, 2.0, 3.0, -1.5]))
    pose = poses_of(robot, 1, seed=11)[0]
    t6 = machine_t6(robot, pose[None])
    result = loads(robot, t6, motion=motion)
    gravity, inertia = weight_work(robot), inertial_work(robot, t6[0], motion)
    posture = robot.working_posture
    expected = virtual_work_forces(robot, pose, posture, lambda b, a: gravity(b, a) + inertia(b, a))
    got = in_internal_units(robot, result.forces[0, posture])
    assert np.max(np.abs(got - expected)) <= 1e-6 * np.max(np.abs(expected))


def test_a_hexapod_under_a_centred_payload_loads_each_leg_with_m_g_over_6_cos_tilt():
    robot = replace(load_robot("hexapod"), payload=Payload(mass=100.0, centre=(0.0, 0.0, 0.0), inertia=((0,) * 3,) * 3))
    home = np.array(robot.verification.home, dtype=float)
    result = loads(robot, machine_t6(robot, home[None]))
    for index, limb in enumerate(robot.limbs):
        leg = np.array(limb.platform_point) + home[:3] - np.array(limb.base_point)
        cosine = leg[2] / np.linalg.norm(leg)
        assert result.forces[0, 0, index] == pytest.approx(100.0 * 9.81 / (6 * cosine), rel=1e-12)


def test_the_constraints_carry_what_the_actuators_do_not():
    """On a constrained machine, the actuators' wrench, the constraints' and the payload's
    weight balance; on a six-limb machine the constraints carry nothing."""
    for name, carries in (("exechon_constrained", True), ("hexapod", False)):
        robot = with_payload(name)
        result = loads(robot, machine_t6(robot, np.array(robot.verification.home, float)[None]))
        force = result.constraint[0, robot.working_posture, :3]
        assert (np.linalg.norm(force) > 1.0) == carries
        if not carries:
            assert np.max(np.abs(result.constraint)) < 1e-9


def test_joint_angles_are_zero_at_home_and_the_angle_of_the_leg_elsewhere():
    robot = load_robot("hexapod")
    home = np.array(robot.verification.home, dtype=float)
    pose = home + np.array([30.0, -20.0, 10.0, 4.0, -3.0, 5.0])
    result = loads(robot, machine_t6(robot, np.stack([home, pose])))
    assert np.max(np.abs(result.base_angles[0])) < 1e-7
    t6 = t6_from_pose(pose[None])[0]
    for index, limb in enumerate(robot.limbs):
        at_home = np.array(limb.platform_point) + home[:3] - np.array(limb.base_point)
        there = t6[:3, :3].T @ np.array(limb.platform_point) + t6[3, :3] - np.array(limb.base_point)
        expected = np.arccos(np.dot(at_home, there) / np.linalg.norm(at_home) / np.linalg.norm(there))
        assert result.base_angles[1, 0, index] == pytest.approx(expected, abs=1e-12)


STIFF = 2e5
"""N/mm: stiff enough that the deflection (about 10 um) is first order to 1e-3."""


def test_deflection_is_the_wrench_through_the_actuators_compliance():
    """With every leg's stiffness k, the platform moves so that each leg's change of length is
    minus its force over k: the deflection's joint changes (the reference at the deflected
    pose) equal the loads divided by the stiffness, to first order."""
    robot = with_payload("hexapod")
    stiff = tuple(limb.model_copy(update={"stiffness": STIFF}) for limb in robot.limbs)
    robot = replace(robot, limbs=stiff)
    home = np.array(robot.verification.home, dtype=float)
    result = loads(robot, machine_t6(robot, home[None]))
    move = result.deflection[0, 0]
    deflected = t6_from_pose(home[None])[0]
    deflected[:3, :3] = (Rotation.from_rotvec(move[3:]).as_matrix() @ deflected[:3, :3].T).T
    deflected[3, :3] += move[:3]
    change = solve(robot, np.stack([t6_from_pose(home[None])[0], deflected])).joints[:, :, 0]
    expected = -result.forces[0, 0] / STIFF
    assert np.max(np.abs(change[1] - change[0] - expected)) <= 1e-3 * np.max(np.abs(expected))


HEXAPOD = Path(__file__).parents[1] / "robots" / "hexapod.yaml"
LEG1 = "reference_length: 399.413}"


def loaded_hexapod(folder, leg_fields, payload="payload: {mass: 100, centre: [0, 0, 0]}\n"):
    """robots/hexapod.yaml with ``leg_fields`` added to every leg and ``payload`` added, in ``folder``."""
    text = HEXAPOD.read_text().replace(LEG1, "reference_length: 399.413, " + leg_fields + "}")
    path = Path(folder) / "loaded.yaml"
    path.write_text(text.replace("verification:", payload + "verification:", 1))
    return path


def test_kingen_loads_prints_and_writes_each_postures_loads_against_their_limits(tmp_path):
    path = loaded_hexapod(tmp_path, "max_force: 170, joint_limits: {base: 4}")
    report = tmp_path / "loads.json"
    result = subprocess.run([sys.executable, "-m", "kingen.cli", "loads", str(path), "--pose", "0", "0", "465", "0", "0",
                             "0", "--json", str(report)], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    cosine = 393.345 / 399.413  # each leg's vertical over its length at home
    document = json.loads(report.read_text())
    assert [entry["posture"] for entry in document["postures"]] == [0]
    entry = document["postures"][0]
    assert entry["units"] == ["N"] * 6
    assert entry["forces"] == pytest.approx([100 * 9.81 / (6 * cosine)] * 6, rel=1e-5)
    assert entry["joint_angles"]["base"] == pytest.approx([0.0] * 6, abs=1e-6)
    assert "leg1" in result.stdout and "166.0" in result.stdout

    tilted = subprocess.run([sys.executable, "-m", "kingen.cli", "loads", str(path), "--pose", "40", "0", "465", "0",
                             "0", "0"], capture_output=True, text=True, timeout=120)
    assert tilted.returncode == 1
    assert "BEYOND LIMIT posture 0: leg" in tilted.stdout and "base joint" in tilted.stdout


def test_verify_fails_a_payload_beyond_the_legs_max_force_naming_the_leg(tmp_path):
    from kingen.verify.checks.machine import machine_check

    held = machine_check(load_robot(loaded_hexapod(tmp_path, "max_force: 170")))
    assert held.passed and "holds its payload (100 kg)" in held.detail
    refused = machine_check(load_robot(loaded_hexapod(tmp_path, "max_force: 150")))
    assert not refused.passed
    assert "leg1 166.022 N (limit 150)" in refused.detail


@pytest.mark.parametrize("leg_fields, payload, fragment", [
    ("max_force: 0", "", "max_force: Input should be greater than 0"),
    ("max_torque: 10", "", "a prismatic joint's actuator limit is max_force, not max_torque"),
    ("joint_limits: {base: 180}", "", "less than 180"),
    ("stiffness: .nan", "", "finite number"),
    ("", "payload: {mass: -1}\n", "mass: Input should be greater than 0"),
    ("", "payload: {mass: 1, inertia: [[1, 0.5, 0], [0, 1, 0], [0, 0, 1]]}\n", "must be symmetric"),
    ("", "payload: {mass: 1, inertia: [1, -1, 1]}\n", "positive definite"),
    ("", "gravity: [0, 0, 1e9]\n", "gravity's components must be within"),
])
def test_bad_load_fields_are_refused_in_one_line(tmp_path, capsys, leg_fields, payload, fragment):
    from kingen.cli import main

    text = HEXAPOD.read_text()
    if leg_fields:
        text = text.replace(LEG1, "reference_length: 399.413, " + leg_fields + "}", 1)
    path = tmp_path / "bad.yaml"
    path.write_text(text.replace("verification:", payload + "verification:", 1))
    assert main(["loads", str(path)]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and fragment in error and str(path) in error


def test_the_python_api_gives_the_loads_and_checks_what_the_command_line_checks():
    import kingen
    from kingen.errors import KingenError

    robot = with_payload("hexapod")
    pose = np.array([10.0, -5.0, 470.0, 2.0, -1.0, 3.0])
    result = kingen.loads(robot, [pose], wrench=[0, 0, -50, 0, 0, 0])
    direct = loads(robot, t6_from_pose(pose[None]), wrench=np.array([0, 0, -50.0, 0, 0, 0]))
    assert np.array_equal(result.forces, direct.forces)
    for bad in ({"poses": [[0, 0, np.nan, 0, 0, 0]]}, {"poses": [pose], "wrench": [1, 2, 3]},
                {"poses": [pose], "postures": [5]}):
        with pytest.raises(KingenError):
            kingen.loads(robot, **{"poses": bad.pop("poses"), **bad})


@pytest.mark.parametrize("name", ["tau", "hexapod", "prs_head", "exechon_constrained", "tricept", "tricept_wrist",
                                  "tricept_wrist3"])
def test_the_c_librarys_static_loads_are_held_to_the_reference_and_a_wrong_one_fails(tmp_path, name):
    """verify --host c compares the library's <prefix>_static_loads (a translating platform, a
    hexapod, each constrained family, two- and three-axis wrists) with kingen.kinematics.loads;
    a library whose loads are 1e-4 off fails its 'c loads' check."""
    from kingen.hosts.c.render import render

    robot = load_robot(name)
    source = render(robot)[f"kingen_{name}.c"]
    weight = "        weight[i] = mass * gravity[i];"
    assert source.count(weight) == 1
    for text, verdict in ((source, 0), (source.replace(weight, weight.replace("mass *", "1.0001 * mass *")), 1)):
        (tmp_path / f"kingen_{name}.h").write_text(render(robot)[f"kingen_{name}.h"])
        (tmp_path / "routine.c").write_text(text)
        result = subprocess.run([sys.executable, "-m", "kingen.cli", "verify", name, "--host", "c", "--source",
                                 str(tmp_path / "routine.c"), "--samples", "300", "--out-dir", str(tmp_path / "out")],
                                capture_output=True, text=True, timeout=300)
        assert result.returncode == verdict, result.stdout + result.stderr
        assert ("FAILED c loads:" if verdict else "ok     c loads:") in result.stdout


@pytest.mark.parametrize("name", ["tricept_wrist", "tricept_wrist3", "exechon_wrist"])
def test_a_wrist_machines_loads_are_the_virtual_work_of_the_payload_on_its_tool(name):
    """Coordinates: the wrist centre's x, y, z (the parallel part's task coordinates: its
    platform the machine's pose there) and the wrist's readings. The legs' joints by central
    differences of the parallel part's reference, the wrist's are the coordinates themselves;
    the payload's weight does its work at its centre on the tool the wrist's forward gives."""
    from kingen.kinematics.hybrid.wrist import tool_t6

    robot = replace(load_robot(name), payload=PAYLOAD)
    parallel, dof = robot.parallel, robot.dof
    home = np.array(robot.verification.home, dtype=float)
    tool = t6_from_pose(home[None] + np.array([[12.0, -8.0, 15.0, 4.0, -3.0, 6.0]]))
    result = loads(robot, tool)
    solution = solve(robot, tool)
    compared = 0
    for posture in range(robot.postures):
        if result.warnings[0, posture] != WARNINGS["WARN_GOOD_SOLUTION"]:
            continue
        start = np.concatenate([solution.platform[0, 3, :3], solution.joints[0, dof:, posture]])

        def state(coordinates):
            platform = solution.platform[0].copy()
            platform[3, :3] = coordinates[:3]
            platform = solve_parasitic(parallel, platform[None]).t6
            legs = solve(parallel, platform).joints[0, :, posture // 2]
            frame = tool_t6(robot, platform, coordinates[None, 3:])[0]
            return np.concatenate([legs, coordinates[3:]]), frame[:3, :3].T @ PAYLOAD.centre + frame[3, :3]

        rates, work = [], []
        for axis in range(len(start)):
            step = np.zeros(len(start))
            step[axis] = STEP
            (before, centre_before), (after, centre_after) = state(start - step), state(start + step)
            rates.append((after - before) / (2 * STEP))
            work.append(PAYLOAD.mass * np.dot(robot.gravity, centre_after - centre_before) / (2 * STEP))
        expected = np.linalg.solve(np.array(rates), -np.array(work))
        got = result.forces[0, posture] * np.r_[np.ones(dof), 1000.0 * np.ones(robot.joint_count - dof)]
        assert np.max(np.abs(got - expected)) <= 1e-6 * np.max(np.abs(expected)), posture
        compared += 1
    assert compared >= 1


def test_kingen_loads_answers_a_tricept_with_its_wrist_legs_then_wrist_torques(tmp_path):
    source = Path(__file__).parents[1] / "robots" / "tricept_wrist.yaml"
    path = tmp_path / "tricept_payload.yaml"
    path.write_text(source.read_text().replace("verification:", "payload: {mass: 20, centre: [0, 0, 40]}\nverification:", 1))
    report = tmp_path / "loads.json"
    result = subprocess.run([sys.executable, "-m", "kingen.cli", "loads", str(path), "--pose", "60", "-40", "-1250",
                             "170", "10", "30", "--json", str(report)], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    entries = json.loads(report.read_text())["postures"]
    assert [entry["posture"] for entry in entries] == [0, 1]
    assert entries[0]["units"] == ["N", "N", "N", "N m", "N m"]
    expected = loads(load_robot(path), t6_from_pose(np.array([[60.0, -40, -1250, 170, 10, 30]]))).forces[0]
    assert np.allclose([entry["forces"] for entry in entries], expected, rtol=1e-12, atol=0)


@pytest.mark.parametrize("name", ["exechon_constrained", "prs_head", "tricept", "rps_table"])
def test_a_task_machines_loads_do_not_depend_on_the_basis_of_its_tangents(name, monkeypatch):
    """The closed-form tangents (the constraints' best split) and the task coordinates' own
    twists (parasitic.task_twists) are two bases of the same tangent: the same loads."""
    from kingen.kinematics import platform_loads
    from kingen.kinematics.hybrid.parasitic import task_twists

    robot = with_payload(name)
    t6 = machine_t6(robot, poses_of(robot, 20, seed=5))
    fast = loads(robot, t6).forces
    monkeypatch.setattr(platform_loads, "free_twists", task_twists)
    slow = loads(robot, t6).forces
    both = np.isfinite(fast) & np.isfinite(slow)
    assert np.mean(both) > 0.5
    assert np.max(np.abs(fast[both] - slow[both])) <= 1e-9 * np.max(np.abs(slow[both]))


@pytest.mark.parametrize("name", ["exechon_constrained", "tricept_wrist"])
def test_a_hand_written_library_without_static_loads_verifies_with_c_loads_not_exercised(tmp_path, name):
    """<prefix>_static_loads is optional in a hand-written library (a constrained machine, a
    wrist): a library without it is not refused; its 'c loads' check judges nothing and says
    why, and every other check still runs."""
    from kingen.hosts.c.render import render

    robot = load_robot(name)
    files = render(robot)
    source = files[f"kingen_{name}.c"]
    definition = f"int kingen_{name}_static_loads("
    assert source.count(definition) == 1
    header = files[f"kingen_{name}.h"]
    declaration = header[header.index(f"int kingen_{name}_static_loads("):]
    declaration = declaration[:declaration.index(";") + 1]
    (tmp_path / f"kingen_{name}.h").write_text(header.replace(declaration, ""))
    (tmp_path / "routine.c").write_text(source.replace(definition, f"static __attribute__((unused)) int unused_loads("))
    result = subprocess.run([sys.executable, "-m", "kingen.cli", "verify", name, "--host", "c", "--source",
                             str(tmp_path / "routine.c"), "--samples", "300", "--out-dir", str(tmp_path / "out")],
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout + result.stderr
    line = next(line for line in result.stdout.splitlines() if "c loads:" in line)
    assert f"the library does not export kingen_{name}_static_loads (optional)" in line
    assert "ok     c jacobian:" in result.stdout


def test_a_c_library_whose_wrist_torques_alone_are_wrong_fails_c_loads(tmp_path):
    """The wrist joints' torques are judged as well as the legs' loads: a library whose wrist
    torques have the opposite sign (tau_j = +z_j . M_c), its legs' loads right, fails 'c loads'."""
    from kingen.hosts.c.render import render

    name = "tricept_wrist3"
    files = render(load_robot(name))
    line = "            torques[j] += (fixed[0][k]"
    assert files[f"kingen_{name}.c"].count(line) == 1
    (tmp_path / f"kingen_{name}.h").write_text(files[f"kingen_{name}.h"])
    (tmp_path / "routine.c").write_text(files[f"kingen_{name}.c"].replace(line, line.replace("+=", "-=")))
    result = subprocess.run([sys.executable, "-m", "kingen.cli", "verify", name, "--host", "c", "--source",
                             str(tmp_path / "routine.c"), "--samples", "300", "--out-dir", str(tmp_path / "out")],
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 1, result.stdout + result.stderr
    assert "FAILED c loads:" in result.stdout and "FAILED (1 of " in result.stdout, result.stdout


@pytest.mark.parametrize("name", ["hexapod", "exechon_constrained"])
def test_the_c_librarys_static_loads_give_no_inf_or_nan(tmp_path, name):
    """At the verification home the library's loads of a 120 kg payload are the reference's;
    a weight past a double's range (m g = 9.81e307 * 9.81) gives -2 and forces 0, never inf
    or NaN."""
    from kingen.hosts.c.build import build_library
    from kingen.hosts.c.loader import Library

    robot = load_robot(name)
    home = np.array([robot.verification.home], dtype=float)
    posture = int(np.flatnonzero(solve(robot, t6_from_pose(home)).warnings[0] == WARNINGS["WARN_GOOD_SOLUTION"])[0])
    built = build_library(robot, tmp_path)
    library = Library(built.library, built.routine, robot)
    pose = (t6_from_pose(home)[0]).T.reshape(16)
    held = replace(robot, payload=PAYLOAD)
    expected = loads(held, t6_from_pose(home)).forces[0, posture]
    forces, returned = library.static_loads(pose, posture, [PAYLOAD.mass, *PAYLOAD.centre, 0.0, 0.0, -9.81])
    assert returned == 0 and np.allclose(forces, expected, rtol=1e-9, atol=1e-9 * np.max(np.abs(expected)))
    forces, returned = library.static_loads(pose, posture, [9.81e307, *PAYLOAD.centre, 0.0, 0.0, -9.81])
    assert returned == -2 and np.all(forces == 0.0)
