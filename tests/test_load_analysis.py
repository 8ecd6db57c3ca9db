"""analyze judges loads: a tilt stops where the payload's load passes a leg's max_force (the
first step of the ladder where kingen.loads says so), every entry carries its largest load
fraction, and the smallest stiffness matches the platform's compliance built from a Jacobian of
central differences of the inverse kinematics."""

from pathlib import Path

import numpy as np
import pytest

import kingen
from kingen.conventions import t6_from_pose
from kingen.design.analysis import Settings, analyze, tilted_t6
from kingen.kinematics.loads import loads
from kingen.kinematics.reference import solve

HEXAPOD = Path(__file__).parents[1] / "robots" / "hexapod.yaml"
LEG = "reference_length: 399.413}"


def loaded(folder, fields):
    text = HEXAPOD.read_text().replace(LEG, "reference_length: 399.413, " + fields + "}")
    path = Path(folder) / "loaded.yaml"
    path.write_text(text.replace("verification:", "payload: {mass: 100, centre: [0, 0, 40]}\nverification:", 1))
    return kingen.load_robot(path)


def test_a_tilt_stops_at_the_first_step_whose_load_passes_max_force(tmp_path):
    robot = loaded(tmp_path, "max_force: 300")
    settings = Settings(tilt_step_deg=0.5, azimuth_step_deg=90.0, tilt_max_deg=30.0)
    result = analyze(robot, settings=settings)
    assert "available" in result["available"]["loads"]
    for row in result["tilt_limits"]:
        ladder = tilted_t6(robot, np.array([row["azimuth_deg"]]), settings.tilts, settings.tilt_convention)
        held = loads(robot, ladder.reshape(-1, 4, 4), postures=[0]).forces[:, 0]
        beyond = np.flatnonzero(np.max(np.abs(held), axis=1) > 300.0)
        if len(beyond):
            assert row["cause"] == "actuator_load"
            assert row["max_tilt_deg"] == pytest.approx(settings.tilts[beyond[0] - 1])


def test_sweeps_carry_the_load_fraction_and_the_least_stiffness(tmp_path):
    robot = loaded(tmp_path, "max_force: 1000, stiffness: 20000")
    result = analyze(robot, settings=Settings(tilt_step_deg=2.0, azimuth_step_deg=180.0, tilt_max_deg=10.0))
    home_entry = min(result["sweeps"]["x"], key=lambda entry: abs(entry["value"]))
    forces = kingen.loads(robot, [robot.verification.home]).forces[0, 0]
    assert home_entry["load_fraction"] == pytest.approx(np.max(np.abs(forces)) / 1000.0, rel=1e-9)
    assert home_entry["min_stiffness_n_per_mm"] == pytest.approx(least_stiffness(robot, 20000.0), rel=1e-5)


def test_the_least_stiffness_does_not_depend_on_the_limbs_masses(tmp_path):
    """Stiffness is the machine's (the passive joints rigid, the loads linear): the limbs' parts,
    whose weight the loads carry, leave it as the central differences give it."""
    parts = "parts: {actuator: {mass: 3.5, centre: 60}, link: {mass: 1.75, centre: 110}}"
    robot = loaded(tmp_path, f"max_force: 1000, stiffness: 20000, {parts}")
    result = analyze(robot, settings=Settings(tilt_step_deg=2.0, azimuth_step_deg=180.0, tilt_max_deg=10.0))
    home_entry = min(result["sweeps"]["x"], key=lambda entry: abs(entry["value"]))
    assert home_entry["min_stiffness_n_per_mm"] == pytest.approx(least_stiffness(robot, 20000.0), rel=1e-5)


def least_stiffness(robot, stiffness):
    """N/mm at home from K = J^T k J, J by central differences of the reference along the six
    unit twists (translations, then rotations about the base axes through the base origin)."""
    home = t6_from_pose(np.array([robot.verification.home], dtype=float))[0]
    step = 1e-4
    columns = []
    for axis in range(6):
        moved = []
        for sign in (-1.0, 1.0):
            t6 = home.copy()
            if axis < 3:
                t6[3, axis] += sign * step
            else:
                from scipy.spatial.transform import Rotation
                turn = Rotation.from_rotvec(np.eye(3)[axis - 3] * sign * step).as_matrix()
                t6[:3, :3] = (turn @ home[:3, :3].T).T
                t6[3, :3] = turn @ home[3, :3]
            moved.append(solve(robot, t6[None]).joints[0, :, 0])
        columns.append((moved[1] - moved[0]) / (2 * step))
    jacobian = np.array(columns).T  # joint rates per twist [v at the base origin; omega]
    compliance = np.linalg.inv(jacobian.T @ (stiffness * jacobian))
    origin = home[3, :3]
    cross = np.array([[0, -origin[2], origin[1]], [origin[2], 0, -origin[0]], [-origin[1], origin[0], 0]])
    to_wrench = np.vstack([np.eye(3), cross])  # a force at the platform origin as [F; p x F]
    to_origin = np.hstack([np.eye(3), -cross])  # twist -> velocity of the platform origin, v + omega x p
    translational = to_origin @ compliance @ to_wrench
    return 1.0 / np.max(np.linalg.eigvalsh(0.5 * (translational + translational.T)))


def test_optimize_judges_designs_with_their_actuator_loads(tmp_path):
    """A layout's max_torque reaches every crank; optimize's objective then stops tilts where the
    payload's torque passes it, through analyze's tilt limits (the compiled judge leaves such
    robots to them)."""
    from kingen.design.problem import Problem, evaluate
    from kingen.design.tilt_judge import judges
    from kingen.robot.reading import read_robot_file

    source = (Path(__file__).parents[1] / "robots" / "rus_optimized.yaml").read_text()
    text = source.replace("layout:\n", "layout:\n  max_torque: 120\n", 1).replace(
        "verification:", "payload: {mass: 300, centre: [0, 0, 50]}\nverification:", 1).replace(
        "tilt_step: 1, azimuth_step: 1, tilt_max: 120", "tilt_step: 2, azimuth_step: 90, tilt_max: 40")
    path = tmp_path / "rus_loaded.yaml"
    path.write_text(text)
    data, lines = read_robot_file(path)[:2]
    problem = Problem(data, path, lines)
    robot = problem.robot(problem.start())
    assert not judges(robot) and all(limb.max_torque == 120 for limb in robot.limbs)
    objective, table, _ = evaluate(problem, problem.start())
    assert {cause for _, cause in table} == {"actuator_load"}
    assert objective == min(tilt for tilt, _ in table) < 40


def test_the_report_draws_the_loads_and_names_their_worst_pose(tmp_path):
    """The slices carry each cell's load fraction and stiffness; the report's worst load fraction
    is kingen.loads' largest |force| / max_force over the sweeps' and slices' poses that only
    loads may stop, at the pose it names; the sweep and loads figures are drawn."""
    from kingen.design.figures import figures, report_html
    from kingen.design.load_figures import LOADED, load_extremes

    robot = loaded(tmp_path, "max_force: 600, stiffness: 20000")
    analysis = analyze(robot, settings=Settings(tilt_step_deg=2.0, azimuth_step_deg=180.0, tilt_max_deg=10.0))
    home = np.array(robot.verification.home, dtype=float)
    poses = []
    for name, entries in analysis["sweeps"].items():
        axis = ("x", "y", "z", "roll", "pitch", "yaw").index(name)
        for entry in entries:
            if entry["cause"] in LOADED:
                pose = home.copy()
                pose[axis] = entry["value"]
                poses.append(pose)
    for data in analysis["slices"].values():
        axes = [("x", "y", "z").index(axis) for axis in data["axes"]]
        for i, first in enumerate(data["first"]):
            for j, second in enumerate(data["second"]):
                if analysis_cause(data, i, j) in LOADED:
                    pose = home.copy()
                    pose[axes[0]], pose[axes[1]] = first, second
                    poses.append(pose)
    forces = kingen.loads(robot, np.array(poses)).forces[:, 0]
    fractions = np.max(np.abs(forces), axis=1) / 600.0
    worst = {item["key"]: item for item in load_extremes(analysis)}
    assert worst["load_fraction"]["value"] == pytest.approx(np.max(fractions), rel=1e-9)
    named = [float(word) for word in worst["load_fraction"]["where"].replace(",", " ").split()
             if word.lstrip("-").replace(".", "").isdigit()]
    best = np.array(poses)[np.argmax(fractions)]
    assert all(np.any(np.isclose(value, best[:3], atol=1e-3)) for value in named)
    assert worst["min_stiffness_n_per_mm"]["value"] > 0
    pngs = figures(analysis)
    assert {"sweeps.png", "loads.png"} <= set(pngs)
    html = report_html(robot, analysis, pngs, 1.0)
    assert "largest actuator load / its limit" in html and "least stiffness of the platform origin (N/mm)" in html


def analysis_cause(data, i, j):
    from kingen.design.analysis import CAUSES
    return CAUSES[data["causes"][i][j]]
