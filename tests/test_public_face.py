"""kingen's public face (kingen/__init__.py): what a notebook user calls, documented in
numpydoc with shapes and units, cheap to import, and giving what the packages behind it give."""

import subprocess
import sys

import numpy as np
import pytest

import kingen
from kingen.conventions import t6_from_pose
from kingen.kinematics.reference import solve as reference_solve
from kingen.robot.model import load_robot


def test_importing_kingen_loads_nothing_heavy():
    probe = "import sys, kingen; print(sorted(m for m in ('numpy', 'pydantic', 'jinja2', 'cffi') if m in sys.modules))"
    result = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == "[]"


@pytest.mark.parametrize("name", kingen.__all__)
def test_every_public_function_says_its_parameters_and_returns_in_numpydoc(name):
    text = getattr(kingen, name).__doc__
    assert "Returns\n    -------" in text
    assert "Parameters\n    ----------" in text or name == "shipped_robots"


def test_solve_gives_the_references_joints_for_poses_in_mm_and_degrees():
    robot = kingen.load_robot("hexapod")
    poses = np.array([[0.0, 0.0, 800.0, 0.0, 0.0, 0.0], [10.0, -5.0, 790.0, 2.0, -1.0, 3.0]])
    solution = kingen.solve(robot, poses)
    expected = reference_solve(load_robot("hexapod"), t6_from_pose(poses))
    assert solution.joints.shape == (2, robot.dof, robot.postures)
    assert np.array_equal(solution.joints, expected.joints) and np.array_equal(solution.warnings, expected.warnings)


def test_assembly_modes_find_the_pose_the_joints_were_solved_at():
    robot = kingen.load_robot("hexapod")
    pose = np.array([10.0, -5.0, 790.0, 2.0, -1.0, 3.0])
    joints = kingen.solve(robot, [pose]).joints[0, :, 0]
    modes = kingen.assembly_modes(robot, joints)
    found = np.array([np.r_[mode.pose[:3], np.degrees(mode.pose[3:])] for mode in modes.found])
    assert modes.exhaustive and np.min(np.max(np.abs(found - pose), axis=1)) < 1e-6


def test_build_and_verify_pass_a_shipped_robot(tmp_path):
    robot = kingen.load_robot("tau")
    built = kingen.build(robot, out_dir=tmp_path)
    report = kingen.verify_library(robot, built.library, samples=500)
    assert built.library.parent == tmp_path and report.passed and report.samples == 500


def test_analyze_gives_one_row_per_azimuth():
    rows = kingen.analyze(kingen.load_robot("hexapod"), tilt_step=1.0, azimuth_step=90.0, tilt_max=30.0)
    assert [row["azimuth_deg"] for row in rows] == [0.0, 90.0, 180.0, 270.0]
    assert all(0.0 <= row["max_tilt_deg"] <= 30.0 for row in rows)


def test_no_package_hides_a_public_function():
    """A subpackage imported later becomes an attribute of kingen: none may share a public name."""
    import types

    import kingen.design  # noqa: F401
    import kingen.hosts  # noqa: F401
    import kingen.verify  # noqa: F401

    assert [name for name in kingen.__all__ if isinstance(getattr(kingen, name), types.ModuleType)] == []
