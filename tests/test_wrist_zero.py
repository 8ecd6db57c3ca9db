"""Wrist joints' zero offsets (kingen.robot.wrist.WristJoint.zero_offset): a joint reads its
geometric angle less its offset, wrapped to (-180, 180]. Variants of robots/exechon_wrist.yaml
and robots/tricept_wrist3.yaml with offsets: the reference's readings are the plain robot's less
the offsets (a cross-check between two robots), its golden values shifted likewise still hold,
the wrist's forward and rates take readings, travel applies to the reading, and verify passes
for DELMIA, the C library and LinuxCNC's five- and six-axis modules."""

import numpy as np
import pytest
import yaml

from conftest import require_linuxcnc_headers
from kingen.conventions import t6_from_pose, wrap_angle
from kingen.hosts import get_host
from kingen.kinematics.poses import sample_poses
from kingen.kinematics.reference import solve
from kingen.kinematics.routine import WARNINGS
from kingen.kinematics.hybrid.wrist import tool_t6
from kingen.kinematics.hybrid.wrist_rates import tool_jacobian
from kingen.robot.model import load_robot
from kingen.runtime.resources import robots_dir
from kingen.verify import VerifyOptions, verify_library

OFFSETS = {"exechon_wrist": [7.5, -3.25], "tricept_wrist3": [-4.0, 2.5, 170.0]}
"""Degrees; the last of the three-axis wrist's makes its readings wrap."""
LIMITS = WARNINGS["WARN_JOINT_LIMITS_EXCEEDED"]


def offset_robot(name, folder, offsets=None):
    """(plain robot, the robot with ``offsets`` (degrees) on its wrist joints) of shipped robot
    ``name``; the variant's golden wrist joints are the file's less the offsets, wrapped."""
    offsets = OFFSETS[name] if offsets is None else offsets
    document = yaml.safe_load((robots_dir() / f"{name}.yaml").read_text())
    document["name"] = f"{name}_zero"
    for joint, offset in zip(document["wrist"], offsets):
        joint["zero_offset"] = offset
    legs = len(document["golden"][0]["joints"]) - len(offsets)
    for entry in document["golden"]:
        wrist = np.array(entry["joints"][legs:]) - offsets
        entry["joints"] = entry["joints"][:legs] + [float(value) for value in (wrist + 180.0) % 360.0 - 180.0]
    path = folder / f"{name}_zero.yaml"
    path.write_text(yaml.safe_dump(document, sort_keys=False))
    return load_robot(name), load_robot(path)


@pytest.mark.parametrize("name", sorted(OFFSETS))
def test_the_readings_are_the_geometric_angles_less_the_offsets(name, tmp_path):
    plain, shifted = offset_robot(name, tmp_path)
    zero = np.radians(OFFSETS[name])
    t6 = t6_from_pose(sample_poses(plain, 300, 0))
    before, after = solve(plain, t6), solve(shifted, t6)
    finite = before.finite
    assert finite.sum() > 250
    dof = plain.dof
    assert np.array_equal(after.joints[:, :dof], before.joints[:, :dof])
    expected = wrap_angle(before.joints[finite, dof:] - zero[None, :, None])
    assert np.max(np.abs(after.joints[finite, dof:] - expected)) <= 1e-12
    assert np.all(np.abs(after.joints[:, dof:]) <= np.pi)
    for entry in shifted.golden:  # the golden values shifted by the offsets still hold
        solution = solve(shifted, t6_from_pose(np.array([entry.pose], dtype=float)))
        got = solution.joints[0, :, entry.posture]
        scale = np.where(np.arange(shifted.joint_count) < dof, 1.0, np.degrees(1.0))
        assert np.max(np.abs(got * scale - entry.joints)) <= entry.tolerance
    for posture in range(shifted.postures):  # the wrist's forward takes readings back to the tool
        rows = finite & (after.warnings[:, posture] == 0)
        reached = tool_t6(shifted, after.platform[rows], after.joints[rows, dof:, posture])
        assert np.max(np.abs(reached[:, 3, :3] - t6[rows, 3, :3])) <= 1e-9
        assert np.max(np.abs(reached[:, 2, :3] - t6[rows, 2, :3])) <= 1e-12


def test_the_rates_do_not_change_with_the_offsets(tmp_path):
    plain, shifted = offset_robot("exechon_wrist", tmp_path)
    t6 = t6_from_pose(sample_poses(plain, 40, 1))
    leg_rows = np.zeros((len(t6), plain.dof, 6))  # the wrist's rows do not read the legs'
    rates = []
    for robot in (plain, shifted):
        solution = solve(robot, t6)
        rates.append(tool_jacobian(robot, t6, solution.platform, solution.joints[:, :, 0], leg_rows)[:, robot.dof:])
    regular = np.all(np.isfinite(rates[0]), axis=(1, 2))
    assert regular.sum() > 30
    assert np.max(np.abs(rates[1][regular] - rates[0][regular])) <= 1e-9


def test_travel_applies_to_the_reading(tmp_path):
    plain, shifted = offset_robot("exechon_wrist", tmp_path, [0.0, 100.0])
    t6 = t6_from_pose(sample_poses(plain, 300, 2))
    before, after = solve(plain, t6), solve(shifted, t6)
    lower, upper = shifted.travel_limits()
    beyond = np.any((after.joints < lower[None, :, None]) | (after.joints > upper[None, :, None]), axis=1)
    judged = before.finite[:, None] & np.isin(after.warnings, [0, LIMITS])
    assert np.array_equal(after.warnings[judged] == LIMITS, beyond[judged])
    moved = judged & beyond & (before.warnings == 0)  # beyond only as read: Ax5 reads 100 degrees less
    assert moved.sum() > 20
HOSTS = [("delmia", "exechon_wrist"), ("c", "exechon_wrist"), ("linuxcnc", "exechon_wrist"),
         ("delmia", "tricept_wrist3"), ("c", "tricept_wrist3"), ("linuxcnc", "tricept_wrist3")]


@pytest.mark.parametrize("host_name, name", HOSTS)
def test_verify_passes_with_offsets(host_name, name, tmp_path):
    if host_name == "linuxcnc":
        require_linuxcnc_headers()
    _, robot = offset_robot(name, tmp_path)
    host = get_host(host_name)
    seen = host.as_seen(robot)
    built = host.build(seen if host_name == "linuxcnc" else robot, tmp_path / host_name)
    report = verify_library(seen, built.library, built.routine, VerifyOptions(samples=2000), host=host)
    assert report.passed, [(check.name, check.detail) for check in report.failures]
    assert report.max_abs_error_mm <= 1e-9 and report.max_abs_error_rad <= 1e-9


def test_the_machine_check_judges_the_wrists_readings_at_the_home(tmp_path):
    """At the verification home's tool pose every wrist joint stands at its geometric 0 and reads
    minus its zero_offset: Ax5 with an offset of 150 degrees reads -150 there, beyond its travel
    of +/-110, which the machine check says; with 100 it reads -100, within."""
    from kingen.verify.checks.machine import machine_check

    _, beyond = offset_robot("exechon_wrist", tmp_path, [0.0, 150.0])
    home = solve(beyond, t6_from_pose(np.array([beyond.verification.home])))
    assert np.degrees(home.joints[0, 4, 0]) == pytest.approx(-150.0, abs=1e-9)
    check = machine_check(beyond)
    assert not check.passed and "ax5" in check.detail and "reading 0, -150 deg" in check.detail
    _, within = offset_robot("exechon_wrist", tmp_path, [0.0, 100.0])
    check = machine_check(within)
    assert check.passed and check.detail.endswith("(reading 0, -100 deg) lie within travel")
