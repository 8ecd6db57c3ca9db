"""Golden values of every shipped robot, from sources independent of kingen's code, through
the compiled plugin and the reference:

- the leg robots and LinuxCNC's stock robots: LinuxCNC's own genhexkins, lineardeltakins and
  rotarydeltakins (tools/golden_linuxcnc.py);
- the 6-RUS robots: the CEART simulator's CAE crank angles (the thesis), and an independent
  inverse (tools/golden_cranks.py: the thesis's layout equations and a root of each crank's
  closure, no closed form), itself checked here against the CAE angles;
- the optimised 6-RUS design's direct index at home, 137.2 mm, published by the thesis
  (/work/shared/optimisation.md, 'Published results');
- the CEART tilt limit about +Y, 23.9 degrees (tests/test_analysis.py), from the same
  independent inverse: the cranks reach at 23.9 degrees and not at 24.0.

Every entry in a robot file says where its numbers come from (its ``source``)."""

import math
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from kingen.conventions import t6_from_pose
from kingen.robot.model import load_robot, shipped_robots
from kingen.kinematics.reference import solve
from kingen.verify.checks.golden import check_golden

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tools"))
import golden_cranks  # noqa: E402

SOURCES = ("thesis", "Table", "LinuxCNC", "Independent 6-RUS inverse", "Derived by hand",
           "Independent computation (tests/test_hybrid.py)", "Independent computation (tests/test_hybrid_axes.py)",
           "Independent computation (tests/test_tricept.py)", "Independent computation (tests/test_wrist.py)",
           "Independent computation (tests/test_wrist_verify.py)", "Independent computation (tests/test_wrist3.py)")


@pytest.mark.parametrize("name", shipped_robots())
def test_every_shipped_robot_has_a_sourced_golden_value_at_a_non_symmetric_pose(name):
    robot = load_robot(name)
    assert robot.golden, f"{name} has no golden value"
    assert all(any(word in entry.source for word in SOURCES) for entry in robot.golden)
    # Off every symmetry axis; a six-limb platform also turned about all three axes (the
    # Exechon's and Tau's published poses are translations, as their theses give them).
    asymmetric = [entry for entry in robot.golden
                  if entry.pose[0] != 0 and entry.pose[1] != 0 and (robot.dof < 6 or all(entry.pose[3:]))]
    assert asymmetric, f"{name}: every golden pose is symmetric"


@pytest.mark.parametrize("name", shipped_robots())
def test_golden_values_hold_in_the_plugin_and_the_reference(plugin, name):
    robot, loaded = plugin(name)

    class Reference:
        def reset_host(self):
            pass

        def call(self, t6):
            return SimpleNamespace(solutions=solve(robot, t6).joints)

    for routine in (loaded, Reference()):
        results = check_golden(robot, routine)
        assert len(results) == len(robot.golden) and all(result.passed for result in results)


def test_the_independent_crank_inverse_reproduces_the_cae_angles():
    """robots/ceart.yaml golden[0]: the CAE model's -43.394 and 32.345 degrees at (0, 0, -450)."""
    angles = golden_cranks.crank_angles("ceart", [0, 0, -450, 0, 0, 0], 63)
    np.testing.assert_allclose(angles, [-43.394, 32.345] * 3, atol=5e-4)


def test_the_optimised_design_has_the_published_direct_index_at_home():
    """The thesis's optimum: direct index 137.2 mm at home (its branch pattern is posture 21)."""
    robot = load_robot("rus_optimized")
    index = solve(robot, t6_from_pose([robot.verification.home]), indices=True).direct_index[0]
    assert robot.working_posture == 21
    assert index[21] == pytest.approx(137.2, abs=0.05)


def _ceart_reaches(pitch_deg):
    geometry, _ = golden_cranks.layout("ceart")
    pivots, points = golden_cranks.pivots_and_points(geometry)
    placed = points @ golden_cranks.rotation(0.0, pitch_deg, 0.0).T + np.array([0.0, 0.0, -450.0])
    try:
        for i in range(6):
            golden_cranks.crank_roots(pivots[i], math.radians(geometry["crank_directions"][i]),
                                      geometry["crank_length"], geometry["rod_length"], placed[i])
    except AssertionError:  # fewer than two roots: the crank cannot reach
        return False
    return True


def test_ceart_tilted_about_y_turns_unreachable_between_23_9_and_24_degrees():
    assert _ceart_reaches(23.9) and not _ceart_reaches(24.0)
