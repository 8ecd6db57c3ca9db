"""A serial wrist on the constrained Exechon (robots/exechon_wrist.yaml): the numpy reference's
inverse from the tool pose (kingen.kinematics.hybrid.wrist) against an independent computation written
here (Newton on the whole chain's tool tip and tool axis, the platform's rotation by Newton on its
constraint equations, rotations by scipy), its warnings, the wrist's forward (tool_t6, tool_turn),
and the one-line refusals of what this version does not solve."""


import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from kingen.conventions import t6_from_pose
from kingen.kinematics.routine import WARNINGS
from kingen.kinematics.reference import solve
from kingen.kinematics.hybrid.wrist import tool_t6, tool_turn
from kingen.robot.model import load_robot, resolve_robot_path

from conftest import refusal_of
from constrained import newton_root
from test_hybrid_axes import independent_joints, independent_pose

FILE = resolve_robot_path("exechon_wrist")
TOOL_POSES = [(30, 40, -1400, 170, 10, 30), (-60, 100, -1300, 160, -15, 0), (100, -50, -1350, -165, 5, -70),
              (-20, 120, -1500, 175, -20, 120)]
GOOD, SINGULAR = WARNINGS["WARN_GOOD_SOLUTION"], WARNINGS["WARN_SINGULAR_SOLUTION"]
UNREACHABLE, LIMITS = WARNINGS["WARN_UNREACHABLE"], WARNINGS["WARN_JOINT_LIMITS_EXCEEDED"]


def chain(robot, unknowns, pose_of=independent_pose):
    """(tool tip, tool axis, platform pose) of the whole chain for the wrist centre x, y, z and
    the wrist angles t4, t5 (rad): the platform's roll, pitch and yaw by Newton on its constraints
    (``pose_of(robot, x, y, z)``), then Rz(t4) Rx(t5) and the tool 200 mm down the tool's z axis,
    the platform's -z at zero."""
    platform = pose_of(robot, *unknowns[:3])
    rotation = Rotation.from_euler("ZYX", platform[[5, 4, 3]], degrees=True)
    turned = rotation * Rotation.from_rotvec([0, 0, unknowns[3]]) * Rotation.from_rotvec([unknowns[4], 0, 0])
    axis = turned.apply([0.0, 0.0, -1.0])
    return unknowns[:3] + 200.0 * axis, axis, platform


def independent_solution(robot, pose, start, pose_of=independent_pose, joints_of=independent_joints):
    """The legs' joints (mm) and the wrist's angles (rad) for the tool pose ``pose`` (mm,
    degrees): Newton on the tool tip (3 equations) and the tool axis's parts along two directions
    normal to the asked one (2), from the wrist centre 200 mm above the tip and (t4, t5) = ``start``; None
    when Newton finds the reversed tool axis."""
    asked = Rotation.from_euler("ZYX", pose[::-1][:3], degrees=True).as_matrix()
    tip, axis, across = np.asarray(pose[:3], dtype=float), asked[:, 2], asked[:, :2]

    def residual(unknowns):
        reached, reached_axis, _ = chain(robot, unknowns, pose_of)
        return np.concatenate([reached - tip, reached_axis @ across])

    unknowns = newton_root(residual, [*(tip + [0, 0, 200]), *start])
    reached, reached_axis, platform = chain(robot, unknowns, pose_of)
    assert np.max(np.abs(reached - tip)) < 1e-9 and abs(reached_axis @ axis) > 0.999999
    if reached_axis @ axis < 0:
        return None  # the tool axis reversed: a root of these equations, not of the asked pose
    return np.concatenate([joints_of(robot, platform), np.angle(np.exp(1j * unknowns[3:]))])


def independent_branches(robot, pose, pose_of=independent_pose, joints_of=independent_joints):
    """{branch: joints} of :func:`independent_solution` from t4 = 0 or pi, t5 = +/-0.3 (branch
    0: sin(t5) >= 0, the sign of g for this head); both branches must be found."""
    found = {}
    for start in ((0.0, 0.3), (0.0, -0.3), (np.pi, 0.3), (np.pi, -0.3)):
        joints = independent_solution(robot, pose, start, pose_of, joints_of)
        if joints is not None:
            found.setdefault(0 if joints[4] >= 0 else 1, joints)
    assert sorted(found) == [0, 1]
    return found


def test_the_inverse_from_the_tool_pose_matches_an_independent_newton_in_both_branches():
    robot = load_robot(FILE)
    solution = solve(robot, t6_from_pose(np.array(TOOL_POSES, dtype=float)))
    assert np.all(solution.warnings == GOOD)
    for index, pose in enumerate(TOOL_POSES):
        for branch, expected in independent_branches(robot.parallel, pose).items():
            assert np.max(np.abs(solution.joints[index, :, branch] - expected)) < 1e-9


def test_the_machine_tool_pose_has_the_asked_tip_and_axis_and_says_the_turn():
    robot = load_robot(FILE)
    asked = t6_from_pose(np.array(TOOL_POSES, dtype=float))
    solution = solve(robot, asked)
    turns = []
    for posture in range(robot.postures):
        tool = tool_t6(robot, solution.platform, solution.joints[:, robot.dof:, posture])
        assert np.max(np.abs(tool[:, 3, :3] - asked[:, 3, :3])) < 1e-9
        assert np.max(np.abs(tool[:, 2, :3] - asked[:, 2, :3])) < 1e-12
        turns.append(tool_turn(asked, tool))
        for row, turn in zip(range(len(asked)), turns[-1]):
            about = Rotation.from_rotvec(tool[row, 2, :3] * turn)
            assert np.max(np.abs(about.apply(tool[row, 0, :3]) - asked[row, 0, :3])) < 1e-12
    flip = np.angle(np.exp(1j * (turns[0] - turns[1])))
    assert np.allclose(np.abs(flip), np.pi)  # the A/C head's two branches: the tool turned by half a turn


def test_golden_values_are_the_independent_computation():
    robot = load_robot(FILE)
    assert len(robot.golden) == 2
    scale = np.radians(1.0)
    for entry in robot.golden:
        solution = solve(robot, t6_from_pose(np.array([entry.pose], dtype=float)))
        joints = np.array(entry.joints) * np.array([1, 1, 1, scale, scale])
        assert np.max(np.abs(solution.joints[0, :, entry.posture] - joints)) < entry.tolerance * scale
        expected = independent_branches(robot.parallel, entry.pose)[entry.posture]
        assert np.max(np.abs(expected - joints)) < entry.tolerance * scale


def test_warnings_the_wrist_singularity_its_limits_and_a_cone_it_cannot_reach(tmp_path):
    robot = load_robot(FILE)
    vertical, beyond = (0, 50, -1450, 180, 0, 0), (0, 50, -1300, 60, 0, 0)
    solution = solve(robot, t6_from_pose(np.array([vertical, beyond], dtype=float)))
    assert np.all(solution.warnings[0] == SINGULAR)  # the tool along Ax4: Ax4's angle is lost
    assert np.all(solution.warnings[1] == LIMITS)  # Ax5 beyond its travel of +/-110 degrees
    assert np.all(np.degrees(np.abs(solution.joints[1, 4])) > 110.0)
    nutating = tmp_path / "nutating.yaml"
    nutating.write_text(FILE.read_text().replace("{name: ax5, axis: [1, 0, 0]", "{name: ax5, axis: [0, 0.6, 0.8]"))
    horizontal = t6_from_pose(np.array([(0, 50, -1300, 90, 0, 0), (0, 50, -1300, 170, 0, 0)], dtype=float))
    solution = solve(load_robot(nutating), horizontal)
    assert np.all(solution.warnings[0] == UNREACHABLE) and solution.radicands[0, -1] < 0
    assert np.all(solution.warnings[1] == GOOD) and solution.radicands[1, -1] > 0
    nowhere = solve(robot, t6_from_pose(np.array([(np.nan, 0, -1300, 170, 0, 0), (1e300, 0, -1300, 170, 0, 0)])))
    assert np.all(nowhere.warnings == UNREACHABLE) and np.all(nowhere.joints == 0.0)


@pytest.mark.parametrize("old, new, words", [
    ("{name: ax5, axis: [1, 0, 0]", "{name: ax5, type: prismatic, axis: [1, 0, 0]", ":21: wrist[1].type: a prismatic "
                                                                                      "wrist joint is not solved: kingen"
                                                                                      " solves two or three revolute"),
    ("{name: ax4, axis: [0, 0, 1]", "{name: ax4, axis: [0, 0, 1], origin: [0, 0, 50]", ":20: wrist[0].origin: "),
    ("  - {name: ax5, axis: [1, 0, 0], travel: [-110, 110]}\n", "", ":19: wrist: a wrist of one joint is not solved"),
    ("{name: ax5, axis: [1, 0, 0]", "{name: ax5, axis: [0, 0, -1]", ":21: wrist[1].axis: parallel to the joint's before"),
    ("tool: [0, 0, -200, 180, 0, 0]", "tool: [10, 0, -200, 180, 0, 0]", ":22: tool: a two-joint wrist is solved with the tool tip"),
    ("tool: [0, 0, -200, 180, 0, 0]", "tool: [0, 0, -200, 0, 90, 0]", ":22: tool: the tool's z axis lies along"),
    ("{name: ax5, axis: [1, 0, 0]", "{name: ax4, axis: [1, 0, 0]", ":21: wrist[1].name: joint name 'ax4' is used twice"),
    ("{name: ax4, axis: [0, 0, 1]", "{name: leg1, axis: [0, 0, 1]", ":20: wrist[0].name: joint name 'leg1' is used twice"),
    ("wrist:\n  - {name: ax4, axis: [0, 0, 1], travel: [-270, 270]}\n  - {name: ax5, axis: [1, 0, 0], travel: [-110, 110]}\n",
     "", ":19: tool: a tool frame needs a wrist"),
    ("golden:\n", "golden:\n  - {source: s, pose: [0, 0, -1300, 0, 0, 0], joints: [0, 0, 0], tolerance: 1}\n",
     ":27: golden[0].joints: expected 5 joint values, got 3"),
])
def test_a_wrist_this_version_does_not_solve_is_refused_in_one_line(tmp_path, old, new, words):
    path, message = refusal_of(FILE, tmp_path, old, new)
    assert message.startswith(str(path)) and words in message and "\n" not in message, message
