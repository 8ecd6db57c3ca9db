"""Conventions: rotation order, T6 layout, angle wrapping."""

import numpy as np
import pytest

from kingen.conventions import (
    angle_difference, matrix_from_pose, matrix_from_t6, rotation_from_rpy, t6_from_pose, wrap_angle,
)


def rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def ry(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def test_rotation_is_rz_ry_rx_product():
    rng = np.random.default_rng(1)
    for roll, pitch, yaw in rng.uniform(-np.pi, np.pi, (50, 3)):
        expected = rz(yaw) @ ry(pitch) @ rx(roll)
        np.testing.assert_allclose(rotation_from_rpy(roll, pitch, yaw), expected, atol=1e-15)


def test_yaw_of_90_degrees_turns_x_into_y():
    matrix = matrix_from_pose([0, 0, 0, 0, 0, 90])
    np.testing.assert_allclose(matrix[:3, :3] @ [1, 0, 0], [0, 1, 0], atol=1e-15)


def test_t6_rows_are_n_o_a_p():
    pose = [10.0, -20.0, 30.0, 15.0, -25.0, 40.0]
    matrix = matrix_from_pose(pose)
    t6 = t6_from_pose(pose)
    np.testing.assert_array_equal(t6[3, :3], pose[:3])
    np.testing.assert_array_equal(t6[0, :3], matrix[:3, 0])
    np.testing.assert_array_equal(t6[2, :3], matrix[:3, 2])
    np.testing.assert_array_equal(t6[:, 3], [0, 0, 0, 1])


def test_t6_and_matrix_of_a_quarter_turn_written_out_by_hand():
    """Pose (1, 2, 3) turned 90 degrees about z: x goes to y, y to -x."""
    t6 = [[0, 1, 0, 0], [-1, 0, 0, 0], [0, 0, 1, 0], [1, 2, 3, 1]]
    matrix = [[0, -1, 0, 1], [1, 0, 0, 2], [0, 0, 1, 3], [0, 0, 0, 1]]
    np.testing.assert_allclose(t6_from_pose([1, 2, 3, 0, 0, 90]), t6, atol=1e-15)
    np.testing.assert_allclose(matrix_from_pose([1, 2, 3, 0, 0, 90]), matrix, atol=1e-15)
    np.testing.assert_array_equal(matrix_from_t6(np.array(t6, dtype=float)), matrix)


@pytest.mark.parametrize("angle, wrapped", [(np.pi, np.pi), (-np.pi, np.pi), (3 * np.pi, np.pi), (0.5, 0.5), (-4.0, 2 * np.pi - 4.0)])
def test_wrap_angle_maps_into_half_open_interval(angle, wrapped):
    assert wrap_angle(angle) == pytest.approx(wrapped, abs=1e-15)


def test_angle_difference_knows_pi_equals_minus_pi():
    assert abs(angle_difference(np.pi - 1e-12, -np.pi + 1e-12)) < 1e-11


def test_wrap_angle_takes_one_turn_exactly_as_the_generated_c():
    near = np.array([3.5, -3.5, 2 * np.pi + 1.0, -2 * np.pi - 1.0])
    assert np.array_equal(wrap_angle(near), near - np.sign(near) * 2.0 * np.pi)
    far = np.array([10.0, -10.0, 1e6])
    assert np.array_equal(wrap_angle(far), np.mod(far + np.pi, 2.0 * np.pi) - np.pi)
    assert np.all(np.isnan(wrap_angle(np.array([np.nan, np.inf, -np.inf]))))
