"""The joint rates per tool twist of a machine with a wrist in closed form
(kingen.kinematics.hybrid.wrist_rates) against an independent computation, the machine's forward map
differentiated by central differences and inverted (kingen.kinematics.hybrid.wrist_forward.tool_rates);
and the C library's Jacobian against both: the same rates, and none for the twist about the tool
axis through the tool tip (the five-axis reading)."""

import numpy as np
import pytest

from kingen.conventions import matrix_from_t6, t6_from_pose
from kingen.hosts.c.build import build_library
from kingen.hosts.c.checks import regular_pairs
from kingen.hosts.c.loader import Library
from kingen.kinematics.poses import sample_poses
from kingen.kinematics.reference import solve
from kingen.kinematics.singularity import jacobian
from kingen.kinematics.forward import poses_of
from kingen.kinematics.hybrid.wrist_forward import tool_rates
from kingen.kinematics.hybrid.wrist_rates import tool_jacobian
from kingen.robot.model import load_robot

POSES = 60


@pytest.fixture(scope="module", params=["exechon_wrist", "tricept_wrist"])
def solved(request):
    """(robot, tool T6 (m, 4, 4), one regular posture per pose (m,), its joints, the closed form's rates)."""
    robot = load_robot(request.param)
    t6 = t6_from_pose(sample_poses(robot, POSES, 0))
    pose_index, posture, joints, _, wrenches, transmissions = regular_pairs(robot, t6)
    tool = t6[pose_index]
    rates = tool_jacobian(robot, tool, solve(robot, tool).platform, joints, jacobian(wrenches, transmissions))
    return robot, tool, posture, joints, rates


def relative(found, expected, robot):
    """The largest difference per joint row, rotations as mm of arc at the robot's size, relative
    to the row's largest entry."""
    units = np.array([1.0] * 3 + [1.0 / robot.size_mm] * 3)
    return float(np.max(np.max(np.abs(found - expected) * units, axis=-1) / np.max(np.abs(expected) * units, axis=-1)))


def tool_axis_twists(tool):
    """(m, 6) the unit twist about each tool axis w through the tool tip q: [q x w; w]."""
    tip, axis = tool[:, 3, :3], tool[:, 2, :3]
    return np.concatenate([np.cross(tip, axis), axis], axis=1)


def test_the_closed_form_equals_the_forward_maps_inverted_differences(solved):
    robot, tool, _, joints, rates = solved
    assert len(rates) >= POSES // 2
    platform = solve(robot, tool).platform
    differences = tool_rates(robot, joints, poses_of(platform), 1e-5 * robot.size_mm, 1e-5)
    assert relative(rates, differences, robot) <= 1e-8  # 3.9e-10 on both machines


def test_the_twist_about_the_tool_axis_moves_no_joint(solved):
    robot, tool, _, _, rates = solved
    moved = np.einsum("nji,ni->nj", rates, tool_axis_twists(tool))
    assert np.max(np.abs(moved)) <= 1e-12 * np.max(np.abs(rates))


def test_the_c_librarys_jacobian_is_the_closed_form(solved, tmp_path):
    robot, tool, posture, _, rates = solved
    built = build_library(robot, tmp_path)
    library = Library(built.library, built.routine, robot)
    answers = [library.jacobian(pose, int(k)) for pose, k in zip(matrix_from_t6(tool).reshape(-1, 16), posture)]
    rows = np.array([rows for rows, _ in answers])
    assert all(warning == 0 for _, warning in answers)
    assert relative(rows, rates, robot) <= 1e-12
    assert np.max(np.abs(np.einsum("nji,ni->nj", rows, tool_axis_twists(tool)))) <= 1e-12 * np.max(np.abs(rows))
