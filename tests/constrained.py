"""What the tests of machines with task coordinates share (tests/test_hybrid.py,
test_hybrid_axes.py, test_tricept.py): an independent Newton solver written here, not kingen's,
and the checks every such machine passes."""

import subprocess
import sys

import numpy as np

from kingen.conventions import t6_from_pose
from kingen.kinematics.parasitic import constraint_residuals, on_manifold
from kingen.kinematics.reference import solve
from kingen.kinematics.routine import WARNINGS
from kingen.robot.model import load_robot

UNREACHABLE = WARNINGS["WARN_UNREACHABLE"]


def newton_root(residual, start, tolerance=1e-13, steps=50):
    """The root of ``residual`` (a function of an (n,) array, n values) near ``start``: Newton's
    method with a central-difference Jacobian (steps of 1e-6), stopped when a step is below
    ``tolerance``."""
    unknown = np.array(start, dtype=float)
    for _ in range(steps):
        jacobian = np.column_stack([(residual(unknown + step) - residual(unknown - step)) / 2e-6
                                    for step in np.eye(len(unknown)) * 1e-6])
        move = np.linalg.solve(jacobian, -residual(unknown))
        unknown += move
        if np.max(np.abs(move)) < tolerance:
            break
    return unknown


def check_constraints_close_and_off_the_manifold_is_unreachable(name, seed):
    """400 seeded poses of ``name``'s region: the machine's pose for each closes the constraints
    to 1e-9; the drawn poses (off the manifold) are unreachable with the joints of the machine's
    pose for the same task coordinates; the machine's poses are answered."""
    robot = load_robot(name)
    region = robot.verification
    drawn = np.asarray(region.home) + np.random.default_rng(seed).uniform(-1, 1, (400, 6)) * np.asarray(region.range)
    moved = on_manifold(robot, drawn)
    residuals, radicand = constraint_residuals(robot, t6_from_pose(np.concatenate([drawn, moved])))
    assert np.all(radicand > 0.5) and np.max(np.abs(residuals)) < 1e-9
    off, on = solve(robot, t6_from_pose(drawn)), solve(robot, t6_from_pose(moved))
    assert np.all(off.warnings == UNREACHABLE)
    assert np.count_nonzero(on.warnings != UNREACHABLE) == len(moved)
    assert np.max(np.abs(off.joints - on.joints)) < 1e-9


def check_routine_equals_the_reference(name, host, folder):
    """`kingen verify name --host host` passes with every check such a machine has named ok."""
    result = subprocess.run([sys.executable, "-m", "kingen.cli", "verify", name, "--host", host, "--samples", "2000",
                             "--out-dir", str(folder)], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout + result.stderr
    checks = ("values", "warnings", "closure", "constraints", "jacobian", "round trip", "golden[0]", "golden[2]")
    for check in checks + (("forward",) if host == "linuxcnc" else ()):
        assert any(line.strip().startswith(f"ok     {check}") for line in result.stdout.splitlines()), check


def check_declaration_refused(name, old, new, words, folder):
    """``name``'s robot file with ``old`` replaced by ``new``: verify exits 2 with one line naming
    the file and holding ``words``, and writes nothing."""
    text = open(f"robots/{name}.yaml").read()
    assert old in text
    path = folder / "bad.yaml"
    path.write_text(text.replace(old, new, 1))
    result = subprocess.run([sys.executable, "-m", "kingen.cli", "verify", str(path), "--out-dir", str(folder / "o")],
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"kingen: error: {path}:") and words in lines[0], result.stderr
    assert not (folder / "o").exists()


def check_task_poses_match(robot, poses, independent_joints):
    """The machine's poses ``poses`` (n, 6; mm, degrees, from the test's own computation) are
    what kingen's on_manifold gives for their task coordinates alone, and the reference answers
    them with the test's ``independent_joints(robot, pose)`` to 1e-9."""
    asked = poses.copy()
    asked[:, 3:] = 0.0  # the task coordinates alone
    assert np.max(np.abs(on_manifold(robot, asked) - poses)) < 1e-9
    solution = solve(robot, t6_from_pose(poses))
    assert not np.any(solution.warnings == UNREACHABLE)
    expected = np.array([independent_joints(robot, pose) for pose in poses])
    assert np.max(np.abs(solution.joints[:, :, 0] - expected)) < 1e-9
