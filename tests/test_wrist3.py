"""A three-axis spherical wrist on the Tricept-type machine (robots/tricept_wrist3.yaml): the numpy
reference's inverse from the whole tool pose (kingen.kinematics.hybrid.wrist) against an independent
computation written here (Newton on the whole chain's tool pose, six equations in the wrist
centre and the three wrist angles, the platform's rotation by tests/test_tricept.py's Newton on
the tube's direction, rotations by scipy), its golden values, its warnings, the wrist's forward
from every posture's joints back to the whole asked pose, and the one-line refusals."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from kingen.conventions import t6_from_pose
from kingen.hosts.c.checks import regular_pairs
from kingen.kinematics.poses import sample_poses
from kingen.kinematics.reference import solve
from kingen.kinematics.routine import WARNINGS
from kingen.kinematics.singularity import jacobian
from kingen.kinematics.hybrid.wrist import tool_t6
from kingen.kinematics.forward import poses_of
from kingen.kinematics.hybrid.wrist_forward import tool_rates
from kingen.kinematics.hybrid.wrist_rates import tool_jacobian
from kingen.robot.model import load_robot, resolve_robot_path

import test_tricept
from conftest import refusal_of
from constrained import newton_root

FILE = resolve_robot_path("tricept_wrist3")
TOOL_POSES = [(60, -40, -1250, 170, 10, 30), (-90, 120, -1330, -165, -8, -50), (120, 80, -1180, 172, -6, 100),
              (-40, -150, -1400, -170, 12, -140)]
GOOD, SINGULAR = WARNINGS["WARN_GOOD_SOLUTION"], WARNINGS["WARN_SINGULAR_SOLUTION"]
LIMITS = WARNINGS["WARN_JOINT_LIMITS_EXCEEDED"]
TIP = np.array([0.0, 0.0, 200.0])
"""The tool tip in the tool frame (the tool 200 mm along its own z axis, -z of the platform at zero)."""


def chain(unknowns):
    """(tool tip (3,), tool rotation (3, 3), platform pose (6,) mm and degrees) of the whole chain
    for the wrist centre x, y, z (mm) and the wrist angles t4, t5, t6 (rad): the platform's pose
    by Newton on the tube's direction, then Rz(t4) Rx(t5) Rz(t6) and the tool frame, turned by half
    a turn about x from the platform's at zero."""
    platform = test_tricept.independent_pose(*unknowns[:3])
    rotation = (Rotation.from_euler("ZYX", platform[[5, 4, 3]], degrees=True) * Rotation.from_rotvec([0, 0, unknowns[3]])
                * Rotation.from_rotvec([unknowns[4], 0, 0]) * Rotation.from_rotvec([0, 0, unknowns[5]])
                * Rotation.from_rotvec([np.pi, 0, 0])).as_matrix()
    return np.asarray(unknowns[:3]) + rotation @ TIP, rotation, platform


def independent_solution(robot, pose, start):
    """The legs' joints (mm) and the wrist's angles (rad) for the tool pose ``pose`` (mm, degrees,
    roll pitch yaw): Newton on the tool tip (3 equations) and the rotation's error (the rotation
    vector of reached^T asked, 3), from the wrist centre 200 mm above the tip and (t4, t5, t6) =
    ``start``; None where Newton does not converge from there."""
    asked = Rotation.from_euler("ZYX", pose[::-1][:3], degrees=True).as_matrix()
    tip = np.asarray(pose[:3], dtype=float)

    def residual(unknowns):
        reached_tip, reached, _ = chain(unknowns)
        return np.concatenate([reached_tip - tip, Rotation.from_matrix(reached.T @ asked).as_rotvec()])

    try:
        unknowns = newton_root(residual, [*(tip + [0, 0, 200]), *start])
        reached_tip, reached, platform = chain(unknowns)
    except (AssertionError, np.linalg.LinAlgError):
        return None
    if not (np.max(np.abs(reached_tip - tip)) < 1e-9 and np.max(np.abs(reached - asked)) < 1e-9):
        return None
    return np.concatenate([test_tricept.independent_joints(robot, platform), np.angle(np.exp(1j * unknowns[3:]))])


def independent_branches(robot, pose):
    """{branch: joints} of :func:`independent_solution` from t4 and t6 in quarter turns, t5 =
    +/-0.3 (branch 0: t5 <= 0, the sign of the documented g = c.(a1 x a2) = -sin t5 for this
    wrist); both must be found."""
    found = {}
    quarters = np.pi / 2 * np.arange(4)
    for start in [(first, sign * 0.3, last) for first in quarters for last in quarters for sign in (1, -1)]:
        joints = independent_solution(robot, pose, start)
        if joints is not None:
            found.setdefault(0 if joints[4] <= 0 else 1, joints)
        if len(found) == 2:
            break
    assert sorted(found) == [0, 1]
    return found


@pytest.fixture(scope="module")
def robot():
    return load_robot(FILE)


def test_the_inverse_from_the_whole_tool_pose_matches_an_independent_newton_in_both_branches(robot):
    assert robot.joint_names[3:] == ("ax4", "ax5", "ax6") and robot.postures == 2 and robot.wrist.whole_pose
    solution = solve(robot, t6_from_pose(np.array(TOOL_POSES, dtype=float)))
    assert np.all(solution.warnings == GOOD)
    for index, pose in enumerate(TOOL_POSES):
        for branch, expected in independent_branches(robot.parallel, pose).items():
            assert np.max(np.abs(solution.joints[index, :, branch] - expected)) < 1e-9


def test_golden_values_are_the_independent_computation(robot):
    assert len(robot.golden) == 2
    scale = np.array([1, 1, 1] + [np.radians(1.0)] * 3)
    for entry in robot.golden:
        assert "Independent computation (tests/test_wrist3.py)" in entry.source
        expected = independent_branches(robot.parallel, entry.pose)[entry.posture]
        assert np.max(np.abs(expected - np.array(entry.joints) * scale)) < entry.tolerance * scale[-1]


def test_the_wrists_forward_from_every_postures_joints_gives_the_whole_pose_back(robot):
    rng = np.random.default_rng(3)
    poses = np.column_stack([rng.uniform(-200, 200, (50, 2)), rng.uniform(-1400, -1100, 50),
                             rng.uniform(150, 210, 50), rng.uniform(-20, 20, (50, 2))])
    t6 = t6_from_pose(poses)
    solution = solve(robot, t6)
    regular = np.abs(solution.radicands[:, robot.dof:]).min(axis=1) > 1e-3
    assert regular.sum() > 40
    for posture in range(robot.postures):
        back = tool_t6(robot, solution.platform, solution.joints[:, robot.dof:, posture])
        assert np.max(np.abs(back - t6)[regular]) < 1e-9


def test_warnings_gimbal_lock_and_travel(robot, tmp_path):
    solution = solve(robot, t6_from_pose(np.array([(0, 0, -1300, 180, 0, 40), (0, 50, -1300, 60, 0, 0)], dtype=float)))
    assert np.all(solution.warnings[0] == SINGULAR)  # the tool along Ax4: Ax6 turns with Ax4 (the gimbal lock)
    assert np.all(solution.warnings[1] == LIMITS)  # Ax5 beyond its travel of +/-110 degrees
    assert np.all(np.degrees(np.abs(solution.joints[1, 4])) > 110.0)
    nowhere = solve(robot, t6_from_pose(np.array([(np.nan, 0, -1300, 170, 0, 0)])))
    assert np.all(nowhere.warnings == WARNINGS["WARN_UNREACHABLE"]) and np.all(nowhere.joints == 0.0)


def test_any_tool_frame_is_solved_with_three_joints(tmp_path):
    path = tmp_path / "offset.yaml"
    path.write_text(FILE.read_text().replace("tool: [0, 0, -200, 180, 0, 0]", "tool: [30, -20, -200, 170, 15, 5]"))
    robot = load_robot(path)
    t6 = t6_from_pose(np.array(TOOL_POSES, dtype=float))
    solution = solve(robot, t6)
    for posture in range(robot.postures):
        assert np.max(np.abs(tool_t6(robot, solution.platform, solution.joints[:, robot.dof:, posture]) - t6)) < 1e-9


@pytest.mark.parametrize("old, new, words", [
    ("{name: ax6, axis: [0, 0, 1]", "{name: ax6, type: prismatic, axis: [0, 0, 1]",
     ":28: wrist[2].type: a prismatic wrist joint is not solved: kingen solves two or three revolute wrist joints"),
    ("{name: ax6, axis: [0, 0, 1]", "{name: ax6, axis: [0, 0, 1], origin: [0, 0, 50]", ":28: wrist[2].origin: off the "
                                                                                        "wrist centre"),
    ("{name: ax6, axis: [0, 0, 1]", "{name: ax6, axis: [1, 0, 0]", ":28: wrist[2].axis: parallel to the joint's before"),
    ("  - {name: ax6", "  - {name: ax7, axis: [0, 1, 0]}\n  - {name: ax6", ":25: wrist: "),
])
def test_a_three_axis_wrist_kingen_does_not_solve_is_refused_in_one_line(tmp_path, old, new, words):
    path, message = refusal_of(FILE, tmp_path, old, new)
    assert message.startswith(str(path)) and words in message and "\n" not in message, message


def test_joint_rates_closed_form_forward_differences_and_inverse_differences_agree(robot):
    """Three computations of the joint rates per tool twist (all six twists, no free turn): the
    closed form (tool_jacobian), the forward map's central differences inverted (tool_rates) and
    central differences of the reference's inverse along each unit twist."""
    t6 = t6_from_pose(sample_poses(robot, 40, 0))
    pose_index, _, joints, _, wrenches, transmissions = regular_pairs(robot, t6)
    tool = t6[pose_index]
    platform = solve(robot, tool).platform
    closed = tool_jacobian(robot, tool, platform, joints, jacobian(wrenches, transmissions))
    differences = tool_rates(robot, joints, poses_of(platform), 1e-5 * robot.size_mm, 1e-5)
    assert len(pose_index) >= 20 and np.all(np.isfinite(closed))
    units = np.array([1.0] * 3 + [1.0 / robot.size_mm] * 3)
    scale = np.max(np.abs(closed) * units, axis=-1)
    assert np.max(np.max(np.abs(closed - differences) * units, axis=-1) / scale) <= 1e-8
    inverse = np.zeros_like(closed)
    step = 1e-4
    for twist in range(6):
        moved = []
        for sign in (1.0, -1.0):
            motion = np.zeros(6)
            motion[twist] = sign * step
            turn = Rotation.from_rotvec(motion[3:]).as_matrix()
            frames = np.swapaxes(tool, 1, 2).copy()  # column-form frames
            frames[:, :3, :3] = turn @ frames[:, :3, :3]
            frames[:, :3, 3] = frames[:, :3, 3] @ turn.T + motion[:3]
            solved = solve(robot, np.swapaxes(frames, 1, 2))
            moved.append(solved.joints[np.arange(len(tool)), :, _postures_of(solved, joints)])
        inverse[:, :, twist] = (moved[0] - moved[1]) / (2 * step)
    assert np.max(np.max(np.abs(closed - inverse) * units, axis=-1) / scale) <= 1e-6


def _postures_of(solved, joints):
    """(m,) the posture of ``solved`` whose joints are nearest ``joints`` (m, joint_count)."""
    return np.argmin(np.max(np.abs(solved.joints - joints[:, :, None]), axis=1), axis=1)
