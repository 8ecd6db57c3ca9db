"""Calibration without recompiling: parameters read from the dialog's Length i / Offset i."""

import numpy as np
import pytest

from conftest import random_t6
from kingen.conventions import joint_errors, t6_from_pose
from kingen.errors import KingenError
from kingen.robot.model import load_robot
from kingen.kinematics.reference import solve
from kingen.kinematics.routine import WARNINGS


def test_a_calibrated_reference_length_shifts_the_joint_exactly(plugin):
    robot, loaded = plugin("exechon")
    t6 = t6_from_pose([[100, 50, -1250, 0, 0, 0]])
    loaded.reset_host()
    plain = loaded.call(t6).solutions[0, :, 0]
    calibrated = loaded.call(t6, link_lengths=[800.0, 0, 0, 0, 0, 0]).solutions[0, :, 0]
    assert calibrated[0] - plain[0] == pytest.approx(803.887 - 800.0, abs=1e-12)
    np.testing.assert_array_equal(calibrated[1:], plain[1:])
    np.testing.assert_array_equal(calibrated, solve(robot, t6, [800.0, 0, 0, 0, 0, 0]).joints[0, :, 0])


@pytest.mark.parametrize("name", ["exechon", "tau", "ceart"])
def test_plugin_and_reference_agree_under_random_calibration(plugin, name):
    robot, loaded = plugin(name)
    rng = np.random.default_rng(4)
    _, t6 = random_t6(robot, 300, seed=8)
    for _ in range(5):
        lengths = np.where(rng.random(6) < 0.3, 0.0, rng.uniform(0.98, 1.02, 6) * 1500.0)
        if name == "exechon":
            lengths = np.where(lengths > 0, lengths - 700.0, 0.0)
        offsets = np.where(rng.random(6) < 0.3, 0.0, rng.uniform(-40.0, 40.0, 6))
        loaded.reset_host()
        calls = loaded.call(t6, lengths, offsets)
        expected = solve(robot, t6, lengths, offsets)
        assert joint_errors(calls.solutions, expected.joints, robot.revolute).max() <= 1e-9
        np.testing.assert_array_equal(calls.warnings, expected.warnings)


def test_zero_and_non_finite_fields_keep_the_built_in_values(plugin):
    robot, loaded = plugin("tau")
    _, t6 = random_t6(robot, 50, seed=2)
    loaded.reset_host()
    plain = loaded.call(t6)
    for lengths in ([0.0] * 6, [np.nan, np.inf, -np.inf, 0.0, 0.0, 0.0]):
        calls = loaded.call(t6, lengths, [0.0] * 6)
        np.testing.assert_array_equal(calls.solutions, plain.solutions)
        np.testing.assert_array_equal(solve(robot, t6, lengths).joints, solve(robot, t6).joints)


def test_crank_zero_offset_in_degrees_shifts_the_angle(plugin):
    robot, loaded = plugin("ceart")
    t6 = t6_from_pose([robot.verification.home])
    loaded.reset_host()
    plain = loaded.call(t6).solutions[0]
    shifted = loaded.call(t6, link_offsets=[10.0, 0, 0, 0, 0, 0]).solutions[0]
    difference = plain[0] - shifted[0]
    np.testing.assert_allclose(difference, np.radians(10.0), atol=1e-12)
    np.testing.assert_array_equal(plain[1:], shifted[1:])


def test_rail_origin_moves_the_carriage_zero(plugin):
    robot, loaded = plugin("tau")
    t6 = t6_from_pose([robot.verification.home])
    loaded.reset_host()
    plain = loaded.call(t6).solutions[0]
    moved = loaded.call(t6, link_offsets=[0, 0, 25.0, 0, 0, 0]).solutions[0]
    np.testing.assert_allclose(plain[2] - moved[2], 25.0, atol=1e-12)


CASES = [
    ("calibrate: {reference_length: length1}", "calibrate: {colour: length1}",
     "calibrate: 'colour' cannot be calibrated on a leg (choose from reference_length)"),
    ("calibrate: {reference_length: length1}", "calibrate: {reference_length: length7}",
     "calibrate.reference_length: String should match pattern"),
    ("calibrate: {reference_length: length2}", "calibrate: {reference_length: length1}",
     "limbs[1].calibrate.reference_length: dialog field length1 is already read for leg1.reference_length"),
]


@pytest.mark.parametrize("old, new, fragment", CASES, ids=[c[2][:40] for c in CASES])
def test_bad_calibration_is_located(tmp_path, old, new, fragment):
    from kingen.runtime.resources import robots_dir
    text = (robots_dir() / "exechon.yaml").read_text()
    assert old in text
    path = tmp_path / "exechon.yaml"
    path.write_text(text.replace(old, new, 1))
    with pytest.raises(KingenError, match=None) as raised:
        load_robot(str(path))
    assert fragment in str(raised.value)


def test_verify_passes_with_calibration_on_the_command_line(capsys, tmp_path):
    import json

    from kingen.cli import main
    report = tmp_path / "r.json"
    code = main(["verify", "tau", "-o", str(tmp_path / "b"), "--samples", "2000", "--json", str(report),
                 "--link-lengths", "1501", "1499", "0", "0", "0", "0", "--link-offsets", "10", "0", "-20", "0", "0", "0"])
    capsys.readouterr()
    assert code == 0
    assert json.loads(report.read_text())["link_lengths"] == [1501, 1499, 0, 0, 0, 0]


def test_a_calibrated_crank_length_is_the_dialogs_value_in_mm(tmp_path):
    """CEART with its crank lengths also on the dialog's length fields (a copy of its file): given
    lengths 2 % or less off its own, the plugin and the reference agree on every posture the
    reference reaches (the fields in mm, as given: scale 1), and the fields do move the joints."""
    from kingen.hosts.delmia.build import build_plugin
    from kingen.hosts.delmia.loader import Plugin
    from kingen.runtime.resources import robots_dir

    text = (robots_dir() / "ceart.yaml").read_text()
    old = "    zero_offset: [offset1, offset2, offset3, offset4, offset5, offset6]\n"
    assert old in text
    path = tmp_path / "ceart_lengths.yaml"
    path.write_text(text.replace(old, old + "    crank_length: [length1, length2, length3, length4, length5, length6]\n")
                    .replace("name: ceart", "name: ceart_lengths"))
    robot = load_robot(path)
    built = build_plugin(robot, tmp_path / "build")
    loaded = Plugin(built.library, built.routine)
    _, t6 = random_t6(robot, 200, seed=8)
    crank = robot.limbs[0].crank_length
    lengths = crank * np.array([1.01, 0.99, 1.02, 0.98, 1.0, 1.015])
    loaded.reset_host()
    calls = loaded.call(t6, lengths, np.zeros(6))
    expected = solve(robot, t6, lengths, np.zeros(6))
    assert not np.allclose(expected.joints, solve(robot, t6).joints, equal_nan=True)
    reachable = expected.warnings != WARNINGS["WARN_UNREACHABLE"]
    assert reachable.sum() > 1000
    errors = joint_errors(calls.solutions, expected.joints, robot.revolute)
    assert errors[np.broadcast_to(reachable[:, None, :], errors.shape)].max() <= 1e-9
    np.testing.assert_array_equal(calls.warnings, expected.warnings)
