"""What the tests of machines with task coordinates share (tests/test_hybrid.py,
test_hybrid_axes.py, test_tricept.py, test_constrained_machines.py): an independent Newton
solver written here, not kingen's, a refused declaration's check and the machine's poses'."""

import subprocess
import sys

import numpy as np

from kingen.conventions import t6_from_pose
from kingen.kinematics.forward import free_mask, newton
from kingen.kinematics.hybrid.parasitic import on_manifold
from kingen.kinematics.reference import solve
from kingen.kinematics.routine import WARNINGS

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


def check_forward_returns(robot, poses, joints, offset, angle_bound=1e-9):
    """kingen's forward kinematics from ``poses`` (n, 6; mm, degrees, the test's own) moved by
    ``offset`` (mm, radians), with the test's ``joints``, returns each pose: residual and
    position within 1e-9, angles within ``angle_bound`` (rad)."""
    target = np.concatenate([poses[:, :3], np.radians(poses[:, 3:])], axis=1)
    found, residual = newton(robot, target + offset, joints, free_mask(robot))
    assert np.max(residual) < 1e-9
    assert np.max(np.abs(found[:, :3] - target[:, :3])) < 1e-9
    assert np.max(np.abs(found[:, 3:] - target[:, 3:])) < angle_bound
