"""fk finds every assembly mode and says how it knows: the published counts (40 complex for a
general Stewart-Gough platform, 40 real for Dietmaier's), the pose the joints were made from
wherever it lies, and a cross-check against a wide multi-start search."""

import json

import numpy as np
import pytest

from kingen.kinematics import sgp
from kingen.cli import main
from kingen.conventions import matrix_from_pose, rpy_from_rotation, t6_from_pose
from kingen.kinematics.forward import _polished, assemblies, free_mask, newton, starts
from kingen.robot.model import load_robot
from kingen.kinematics.reference import solve

# Dietmaier (1998), "The Stewart-Gough platform of general geometry can have 40 real
# postures", as Martyushev's fkSGP restates it (genSGP.m, sgpType 100): base, platform, lengths.
DIETMAIER_BASE = [[0, 0, 0], [1.107915, 0, 0], [0.549094, 0.756063, 0], [0.735077, -0.223935, 0.525991],
                  [0.514188, -0.526063, -0.368418], [0.590473, 0.094733, -0.205018]]
DIETMAIER_PLATFORM = [[0, 0, 0], [0.542805, 0, 0], [0.956919, -0.528915, 0], [0.665885, -0.353482, 1.402538],
                      [0.478359, 1.158742, 0.107672], [-0.137087, -0.235121, 0.353913]]
DIETMAIER_LENGTHS = [1, 0.645275, 1.086284, 1.503439, 1.281933, 0.771071]
DIETMAIER_POSE_R = [[-0.040450357031281, -0.932229494397471, 0.359599691867884],
                    [0.983337493748685, 0.026695523074364, 0.179818582009314],
                    [-0.177231887661606, 0.360881585597300, 0.915616371179918]]
DIETMAIER_POSE_T = [0.955868038233880, -0.046995628998516, -0.290013283037649]


def _legs_file(path, base, platform, home):
    limbs = "\n".join(f"  - {{name: leg{i + 1}, model: leg, base_point: {b.tolist()}, platform_point: {p.tolist()}, "
                      f"reference_length: 0}}" for i, (b, p) in enumerate(zip(base, platform)))
    path.write_text(f"name: {path.stem}\ndescription: legs\nsource: the test\nlimbs:\n{limbs}\nverification:\n  home: {[float(v) for v in home]}\n"
                    f"  range: [10, 10, 10, 5, 5, 5]\n")
    return path


def test_dietmaier_geometry_has_40_real_assembly_modes(tmp_path):
    """Every one of the 40 solutions is real, and fk lists all 40, polished."""
    scale = 1000.0  # mm
    rotation = np.array(DIETMAIER_POSE_R)
    roll, pitch, yaw = rpy_from_rotation(rotation)
    home = [*(np.array(DIETMAIER_POSE_T) * scale), *np.degrees([roll, pitch, yaw])]
    robot_file = _legs_file(tmp_path / "dietmaier.yaml", np.array(DIETMAIER_BASE) * scale,
                            np.array(DIETMAIER_PLATFORM) * scale, home)
    out = tmp_path / "modes.json"
    joints = " ".join(f"{length * scale:.6f}" for length in DIETMAIER_LENGTHS)
    assert main(["fk", str(robot_file), "--joints", joints, "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["exhaustive"] is True
    assert "40 complex solutions, 0 at infinity, 0 lost: 40 real" in data["method"]
    assert len(data["solutions"]) == 40
    assert max(solution["residual_mm"] for solution in data["solutions"]) <= 1e-12 * scale * 10
    first = data["solutions"][0]["pose"]
    np.testing.assert_allclose(first[:3], np.array(DIETMAIER_POSE_T) * scale, atol=1e-3)  # rounded lengths


def test_a_general_geometry_has_40_complex_solutions_one_of_them_the_pose():
    rng = np.random.default_rng(7)
    base, platform = rng.uniform(-500, 500, (6, 3)), rng.uniform(-200, 200, (6, 3))
    rotation = matrix_from_pose([0, 0, 0, 20, -10, 30])[:3, :3]
    translation = np.array([30.0, -40.0, 600.0])
    lengths = np.linalg.norm(platform @ rotation.T + translation - base, axis=1)
    solutions = sgp.solve_platform(base, platform, lengths)
    assert (solutions.finite, solutions.infinite, solutions.failed) == (40, 0, 0)
    nearest = np.min(np.linalg.norm(solutions.candidates[:, :3] - translation, axis=1))
    assert nearest < 1e-6


@pytest.mark.parametrize("name", ["hexapod", "linuxcnc_hexapod", "ceart", "rus_optimized", "flexapod"])
def test_every_mode_a_wide_multi_start_finds_is_among_the_exhaustive_ones(name):
    robot = load_robot(name)
    home = np.array(robot.verification.home, dtype=float)
    joints = solve(robot, t6_from_pose(home[None])).joints[0, :, robot.working_posture]
    near = np.concatenate([home[:3], np.radians(home[3:])])
    modes = assemblies(robot, joints, near)
    assert modes.exhaustive and modes.method.startswith("exhaustive")
    np.testing.assert_allclose(modes.found[0].pose, near, atol=1e-6)
    free = free_mask(robot)
    begin = starts(robot, near, 8.0)
    ends, _ = newton(robot, begin, np.tile(joints, (len(begin), 1)), free)
    for other in _polished(robot, ends, joints, near, free):
        assert any(np.allclose(other.pose[:3], mode.pose[:3], atol=1e-5) for mode in modes.found)


def test_the_pose_the_joints_came_from_is_found_far_outside_the_region():
    """The old multi-start missed it in 42 of 200 trials at three times the region."""
    robot = load_robot("hexapod")
    rng = np.random.default_rng(3)
    region = robot.verification
    for _ in range(8):
        pose = np.array(region.home) + rng.uniform(-3.0, 3.0, 6) * np.array(region.range)
        joints = solve(robot, t6_from_pose(pose[None])).joints[0, :, 0]
        home = np.concatenate([region.home[:3], np.radians(region.home[3:])])
        found = assemblies(robot, joints, home).found
        target = np.concatenate([pose[:3], np.radians(pose[3:])])
        assert any(np.allclose(mode.pose, target, atol=1e-6) for mode in found)


def test_the_mirror_mode_appears_without_near(capsys):
    """LinuxCNC's sample hexapod at its home joints: the platform 508 mm (20 in) above the base
    and its mirror image below, with no --near."""
    robot = load_robot("linuxcnc_hexapod")
    joints = solve(robot, t6_from_pose(np.array([robot.verification.home]))).joints[0, :, 0] / robot.joint_scale()
    assert main(["fk", "linuxcnc_hexapod", "--joints", " ".join(f"{value:.9f}" for value in joints)]) == 0
    out = capsys.readouterr().out
    assert "exhaustive: 40 paths tracked" in out and ": 8 real" in out
    heights = [float(line.split()[3]) for line in out.splitlines()[2:]]
    assert min(heights) == pytest.approx(-508.0, abs=1e-6) and max(heights) == pytest.approx(508.0, abs=1e-6)


def test_where_no_method_is_exhaustive_the_search_region_is_stated(capsys):
    robot = load_robot("exechon")
    joints = solve(robot, t6_from_pose(np.array([robot.verification.home]))).joints[0, :, 0] / robot.joint_scale()
    text = " ".join(f"{value:.6f}" for value in joints)
    assert main(["fk", "exechon", "--joints", text]) == 0
    assert "not exhaustive: Newton from 258 starts over 2 x the verification region (z -1250 +- 400" in \
        capsys.readouterr().out
    assert main(["fk", "exechon", "--joints", text, "--search", "5"]) == 0
    assert "over 5 x the verification region (z -1250 +- 1000" in capsys.readouterr().out


def _hexagon(radius, z):
    """Six joints in pairs 20 degrees apart around a circle of ``radius`` (mm) at height z."""
    angles = np.radians([angle + offset for angle in (0, 120, 240) for offset in (-10, 10)])
    return np.column_stack([radius * np.cos(angles), radius * np.sin(angles), np.full(6, z)])


@pytest.mark.parametrize("coincident", [False, True], ids=["congruent-planar", "coincident-joints"])
def test_on_a_continuum_of_solutions_fk_says_not_exhaustive_and_gives_the_pose(tmp_path, capsys, coincident):
    """Congruent planar base and platform (an architecture singularity: the platform can move
    with every leg held), or two legs on the same joints: the 40 paths end on no real pose,
    yet the home pose solves the joints exactly. fk gives it and does not claim to be
    exhaustive."""
    base = _hexagon(150.0, 0.0)
    platform = _hexagon(150.0 if not coincident else 90.0, 0.0)
    if coincident:
        base[5], platform[5] = base[4], platform[4]
    robot_file = _legs_file(tmp_path / "continuum.yaml", base, platform, [0, 0, 300, 0, 0, 0])
    joints = np.linalg.norm(platform + [0, 0, 300] - base, axis=1)
    out = tmp_path / "modes.json"
    assert main(["fk", str(robot_file), "--joints", " ".join(f"{value:.12f}" for value in joints),
                 "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["exhaustive"] is False
    assert data["method"].startswith("not exhaustive: the geometry has a continuum of solutions (")
    assert "the closure Jacobian is singular at" in data["method"]
    assert any(np.allclose(solution["pose"], [0, 0, 300, 0, 0, 0], atol=1e-6) for solution in data["solutions"])
    assert capsys.readouterr().out.splitlines()[0] == data["method"]
