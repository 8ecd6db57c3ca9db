"""The generated routine of a robot with a serial wrist, in DELMIA's plugin and the C library
(templates/wrist.c.j2 through templates/postures_body.c.j2), against kingen's numpy reference
(kingen.kinematics.hybrid.wrist): every posture's joints to 1e-9 and the same warnings, at the
wrist's own warnings (its singularity, its travel, a cone a nutating wrist cannot reach), at
non-finite T6 and over poses drawn round the verification home."""

import numpy as np
import pytest

from conftest import random_t6
from kingen.conventions import matrix_from_t6, t6_from_pose
from kingen.hosts.c.build import build_library
from kingen.hosts.c.loader import Library
from kingen.hosts.delmia.build import build_plugin
from kingen.hosts.delmia.loader import Plugin
from kingen.kinematics.reference import solve
from kingen.kinematics.routine import WARNINGS
from kingen.kinematics.singularity import branch_table, representative_postures
from kingen.robot.model import load_robot, resolve_robot_path

FILE = resolve_robot_path("exechon_wrist")
SINGULAR, UNREACHABLE = WARNINGS["WARN_SINGULAR_SOLUTION"], WARNINGS["WARN_UNREACHABLE"]
LIMITS = WARNINGS["WARN_JOINT_LIMITS_EXCEEDED"]
SPECIAL = [(0, 50, -1450, 180, 0, 0),  # the tool along Ax4: singular
           (0, 50, -1300, 60, 0, 0),  # Ax5 beyond its travel
           (0, 50, -1300, 90, 0, 0),  # horizontal: the nutating wrist cannot reach it
           (0, 50, -1300, 170, 0, 0),
           (50, -20, -1380, 165, 8, 40)]


def _poses(robot):
    """The special poses, a NaN and an overflowing one, and 300 drawn round the home with
    tilts up to 90 degrees."""
    _, drawn = random_t6(robot, 300, seed=41)
    special = t6_from_pose(np.array(SPECIAL, dtype=float))
    nowhere = t6_from_pose(np.array([(np.nan, 0, -1300, 170, 0, 0), (1e300, 0, -1300, 170, 0, 0)]))
    rng = np.random.default_rng(7)
    tilted = t6_from_pose(np.column_stack([rng.uniform(-100, 100, (100, 2)), rng.uniform(-1400, -1200, 100),
                                           rng.uniform(90, 270, 100), rng.uniform(-90, 90, 100),
                                           rng.uniform(-180, 180, 100)]))
    return np.concatenate([special, nowhere, drawn, tilted])


def _robots(tmp_path):
    """The shipped exechon_wrist and a nutating variant (Ax5 at 53 degrees to Ax4: a cone of
    tool axes it cannot reach, a1.a2 not zero)."""
    nutating = tmp_path / "exechon_wrist.yaml"
    nutating.write_text(FILE.read_text().replace("{name: ax5, axis: [1, 0, 0]", "{name: ax5, axis: [0, 0.6, 0.8]")
                        .replace("golden:", "golden_unused:").split("golden_unused:")[0])
    return [load_robot(FILE), load_robot(nutating)]


def assert_both_hosts_answer_as_the_reference(robot, t6, folder):
    """DELMIA's routine and the C library of ``robot``, built in ``folder``, give the reference's
    warnings exactly and its joints to 1e-9 (mm, rad) at every posture of the tool T6 ``t6``."""
    expected = solve(robot, t6)
    built = build_plugin(robot, folder / "delmia")
    calls = Plugin(built.library, built.routine).call(t6)
    library = build_library(robot, folder / "c")
    joints, warnings, _ = Library(library.library, library.routine, robot).inverse(matrix_from_t6(t6).reshape(-1, 16))
    for answered_joints, answered_warnings in ((calls.solutions, calls.warnings), (joints, warnings)):
        assert np.array_equal(answered_warnings, expected.warnings)
        assert np.max(np.abs(answered_joints - expected.joints)) <= 1e-9


@pytest.mark.parametrize("which", [0, 1], ids=["shipped", "nutating"])
def test_delmia_and_the_c_library_answer_as_the_reference(which, tmp_path):
    robot = _robots(tmp_path)[which]
    t6 = _poses(robot)
    expected = solve(robot, t6).warnings
    if which:  # the horizontal tool axis lies in the cone the nutating wrist cannot reach
        assert np.all(expected[2] == UNREACHABLE)
    else:
        assert np.all(expected[0] == SINGULAR) and np.all(expected[1] == LIMITS)
    assert np.all(expected[5:7] == UNREACHABLE)
    assert_both_hosts_answer_as_the_reference(robot, t6, tmp_path)


def forward_from_reference(robot, folder):
    """(library, t6, expected, good, posture, found): ``robot``'s C library built in ``folder``,
    200 drawn tool T6 (seed 43) and the reference's answer, the (pose, posture) pairs answered
    WARN_GOOD_SOLUTION (more than 200, both postures among them), and the library's forward of
    each pair's joints seeded 1 mm and 1 degree off (flat row-major H, 16 a row; every call
    returned 0 within 20 Newton steps)."""
    library = build_library(robot, folder)
    loaded = Library(library.library, library.routine, robot)
    poses, t6 = random_t6(robot, 200, seed=43)
    expected = solve(robot, t6)
    good, posture = np.nonzero(expected.warnings == WARNINGS["WARN_GOOD_SOLUTION"])
    assert len(good) > 200 and set(posture) == {0, 1}
    seeds = matrix_from_t6(t6_from_pose(poses[good] + np.array([1.0, -1.0, 1.0, 1.0, -1.0, 1.0]))).reshape(-1, 16)
    found, iterations, returns = loaded.forward(expected.joints[good, :, posture], posture, seeds)
    assert np.all(returns == 0) and iterations.max() <= 20
    return loaded, t6, expected, good, posture, found


def test_the_c_librarys_forward_returns_the_tool_tip_and_axis_and_its_jacobian_answers(tmp_path):
    """Forward from the reference's joints of every regular posture, seeded 1 mm and 1 degree
    off: the tool tip to 1e-9 mm and the tool axis to 1e-9 (the turn about it is free); the
    inverse of what it found gives the joints back; the Jacobian there answers the posture's
    warning with finite rows for all five joints (its values: tests/test_wrist_rates.py)."""
    loaded, t6, expected, good, posture, found = forward_from_reference(load_robot(FILE), tmp_path)
    found_t6 = np.swapaxes(found.reshape(-1, 4, 4), 1, 2)
    assert np.max(np.abs(found_t6[:, 3, :3] - t6[good, 3, :3])) <= 1e-9
    assert np.max(np.abs(found_t6[:, 2, :3] - t6[good, 2, :3])) <= 1e-9
    back, _, _ = loaded.inverse(found)
    assert np.max(np.abs(back[np.arange(len(good)), :, posture] - expected.joints[good, :, posture])) <= 1e-9
    rows, warning = loaded.jacobian(found[0], int(posture[0]))
    assert warning == 0 and rows.shape == (5, 6) and np.all(np.isfinite(rows)) and np.any(rows[3:] != 0.0)


def test_branch_tables_count_the_whole_machines_joints_with_the_wrist_branch_last():
    """Posture = 2 * parallel posture + wrist branch: the one-branch legs take branch 0 in
    both postures, each wrist joint its posture's last bit; each joint's first posture per
    branch stands for it (what the hosts' branch summaries and verify's columns read)."""
    robot = load_robot(FILE)
    assert branch_table(robot).tolist() == [[0, 0, 0, 0, 0], [0, 0, 0, 1, 1]]
    assert representative_postures(robot).tolist() == [[0, 0]] * 3 + [[0, 1]] * 2
    assert branch_table(robot.parallel).tolist() == [[0, 0, 0]]
