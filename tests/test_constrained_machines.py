"""What every machine with task coordinates of the Exechon and Tricept kind passes: the
constraints close at the machine's poses, a pose off its manifold is unreachable with the
machine pose's joints, and the generated routine equals the reference on both hosts."""

import subprocess
import sys

import numpy as np
import pytest

from kingen.conventions import t6_from_pose
from kingen.kinematics.hybrid.parasitic import constraint_residuals, on_manifold
from kingen.kinematics.reference import solve
from kingen.robot.model import load_robot

from constrained import UNREACHABLE

MACHINES = [("exechon_constrained", 11), ("tricept", 7)]
"""Each machine and the seed of its drawn poses."""


@pytest.mark.parametrize("name, seed", MACHINES)
def test_constraints_close_at_every_answered_pose_and_off_the_manifold_is_unreachable(name, seed):
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


@pytest.mark.parametrize("host", ["delmia", "linuxcnc"])
@pytest.mark.parametrize("name", [name for name, _ in MACHINES])
def test_generated_routine_equals_the_reference(name, host, tmp_path):
    """`kingen verify name --host host` passes with every check such a machine has named ok."""
    result = subprocess.run([sys.executable, "-m", "kingen.cli", "verify", name, "--host", host, "--samples", "2000",
                             "--out-dir", str(tmp_path)], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout + result.stderr
    checks = ("values", "warnings", "closure", "constraints", "jacobian", "round trip", "golden[0]", "golden[2]")
    for check in checks + (("forward",) if host == "linuxcnc" else ()):
        assert any(line.strip().startswith(f"ok     {check}") for line in result.stdout.splitlines()), check
