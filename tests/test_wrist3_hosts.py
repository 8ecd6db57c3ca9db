"""The generated routine of a machine with a three-axis (spherical) wrist, robots/tricept_wrist3.yaml,
in DELMIA's plugin and the C library (templates/wrist.c.j2's three-axis branch) against kingen's
numpy reference (kingen.kinematics.hybrid.wrist): every posture's joints to 1e-9 and the same warnings
over poses drawn round the verification home, at the gimbal lock and at non-finite T6; the C
library's forward gives the whole tool pose back to 1e-9."""

import numpy as np

from conftest import random_t6
from test_wrist_hosts import assert_both_hosts_answer_as_the_reference, forward_from_reference
from kingen.conventions import matrix_from_t6, t6_from_pose
from kingen.hosts.c.build import build_library
from kingen.hosts.c.loader import Library
from kingen.kinematics.reference import solve
from kingen.kinematics.routine import WARNINGS
from kingen.kinematics.hybrid.wrist import rotation_about
from kingen.robot.model import load_robot, resolve_robot_path

FILE = resolve_robot_path("tricept_wrist3")
SPECIAL = [(0, 0, -1300, 180, 0, 0),  # the tool along Ax4 (Ax5 at 0): the gimbal lock
           (20, -30, -1250, 150, 20, 70),
           (np.nan, 0, -1300, 170, 0, 0), (1e300, 0, -1300, 170, 0, 0)]


def _poses(robot):
    """The special poses and 300 drawn round the verification home."""
    _, drawn = random_t6(robot, 300, seed=41)
    return np.concatenate([t6_from_pose(np.array(SPECIAL, dtype=float)), drawn])


def test_delmia_and_the_c_library_answer_as_the_reference(tmp_path):
    robot = load_robot(FILE)
    t6 = _poses(robot)
    expected = solve(robot, t6).warnings
    assert np.all(expected[0] == WARNINGS["WARN_SINGULAR_SOLUTION"])
    assert np.all(expected[2:4] == WARNINGS["WARN_UNREACHABLE"])
    assert np.sum(expected == WARNINGS["WARN_GOOD_SOLUTION"]) > 300
    assert_both_hosts_answer_as_the_reference(robot, t6, tmp_path)


def test_the_c_librarys_forward_returns_the_whole_tool_pose(tmp_path):
    """Forward from the reference's joints of every regular posture, seeded 1 mm and 1 degree
    off: the whole tool T6 to 1e-9 (mm, and its rotation's entries); its inverse gives the joints back."""
    loaded, t6, expected, good, posture, found = forward_from_reference(load_robot(FILE), tmp_path)
    found_t6 = np.swapaxes(found.reshape(-1, 4, 4), 1, 2)
    assert np.max(np.abs(found_t6 - t6[good])) <= 1e-9
    back, _, _ = loaded.inverse(found)
    assert np.max(np.abs(back[np.arange(len(good)), :, posture] - expected.joints[good, :, posture])) <= 1e-9


def _moved(t6, twist, step):
    """``t6`` (4, 4, transposed) moved by ``step`` along the unit tool twist ``twist`` (0..5:
    translations along base x, y, z, then rotations about them through the base origin)."""
    moved = t6.copy()
    if twist < 3:
        moved[3, twist] += step
        return moved
    turn = rotation_about(np.eye(3)[twist - 3], np.array([step]))[0]
    moved[:3, :3] = t6[:3, :3] @ turn.T
    moved[3, :3] = turn @ t6[3, :3]
    return moved


def test_the_c_librarys_jacobian_is_the_references_central_difference(tmp_path):
    """Every row of the C library's Jacobian (the three legs' and the three wrist joints', per
    unit twist of the tool) against central differences (step 1e-6 mm or rad) of the
    reference's joints of the same posture, at 20 regular poses in both wrist branches: to 1e-5."""
    robot = load_robot(FILE)
    library = build_library(robot, tmp_path)
    loaded = Library(library.library, library.routine, robot)
    _, t6 = random_t6(robot, 20, seed=45)
    expected = solve(robot, t6)
    checked = 0
    for index, posture in zip(*np.nonzero(expected.warnings == WARNINGS["WARN_GOOD_SOLUTION"])):
        rows, warning = loaded.jacobian(matrix_from_t6(t6[index]).reshape(16), int(posture))
        assert warning == 0 and rows.shape == (6, 6)
        for twist in range(6):
            ahead = solve(robot, _moved(t6[index], twist, 1e-6)[None]).joints[0, :, posture]
            behind = solve(robot, _moved(t6[index], twist, -1e-6)[None]).joints[0, :, posture]
            assert np.max(np.abs(rows[:, twist] - (ahead - behind) / 2e-6)) <= 1e-5
        checked += 1
    assert checked >= 30


def test_the_c_library_of_three_legs_and_a_three_axis_wrist_exports_no_direct_index():
    """Six joints are not six force lines: the direct index is a six-limb robot's (the header
    and source of tricept_wrist3 have none, the hexapod's have it)."""
    from kingen.hosts.c.render import render

    for name, limbs in (("tricept_wrist3", 3), ("hexapod", 6)):
        robot = load_robot(name)
        assert (robot.dof, robot.joint_count) == ((3, 6) if limbs == 3 else (6, 6))
        texts = "".join(render(robot).values())
        assert ("_direct_index(" in texts) == (limbs == 6)
