"""kingen check-path's collision check on CEART (the robot file gives rod and crank radii),
against clearances computed here: crank tips from the crank's own geometry (pivot + r (cos t
cos b, cos t sin b, -sin t)), rod ends from the pose, and the distance between two segments by
a ternary search along one of them (the distance from a point moving along a segment to
another segment is convex), not by kingen's closed form."""

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest

from kingen.cli import main
from kingen.conventions import matrix_from_pose
from kingen.robot.model import load_robot

ROBOTS = Path(__file__).resolve().parent.parent / "robots"
ROBOT = load_robot(str(ROBOTS / "ceart.yaml"))
PROGRAM = "0,0,-450,0,0,0\n0,0,-250,0,0,0\n0,0,-450,0,0,0\n"
"""Up 200 mm and back: the cranks turn toward each other as the platform rises."""
FAT_CRANKS = 90.0
"""A crank radius (mm) at which the cranks of this program overlap (the file's is 15.5)."""


def _point_to_segment(point, start, end):
    along = end - start
    t = np.clip(np.sum((point - start) * along, -1) / np.sum(along * along, -1), 0.0, 1.0)
    return np.linalg.norm(point - (start + t[..., None] * along), axis=-1)


def segment_gap(p1, q1, p2, q2, steps=200):
    """Distances (n,) between segments p1-q1 and p2-q2 (n, 3), by ternary search on the first."""
    low, high = np.zeros(len(p1)), np.ones(len(p1))
    for _ in range(steps):
        a, b = low + (high - low) / 3.0, high - (high - low) / 3.0
        left = _point_to_segment(p1 + a[:, None] * (q1 - p1), p2, q2)
        right = _point_to_segment(p1 + b[:, None] * (q1 - p1), p2, q2)
        low, high = np.where(left <= right, low, a), np.where(left <= right, b, high)
    middle = 0.5 * (low + high)
    return _point_to_segment(p1 + middle[:, None] * (q1 - p1), p2, q2)


def crank_segments(joints_degrees):
    """(pivots, tips) (limbs, n, 3) of CEART's cranks at joints (n, 6) in degrees."""
    pivots, tips = [], []
    for index, limb in enumerate(ROBOT.limbs):
        theta = np.radians(joints_degrees[:, index] + limb.zero_offset)
        beta = math.radians(limb.crank_direction)
        direction = np.stack([np.cos(theta) * math.cos(beta), np.cos(theta) * math.sin(beta), -np.sin(theta)], -1)
        pivots.append(np.broadcast_to(np.asarray(limb.pivot, dtype=float), direction.shape))
        tips.append(np.asarray(limb.pivot) + limb.crank_length * direction)
    return pivots, tips


def clearances_here(poses, joints_degrees, rod_radius, crank_radius):
    """(rods, cranks) (n,): least clearance (mm) between CEART's rods and between its cranks."""
    pivots, tips = crank_segments(np.asarray(joints_degrees, dtype=float))
    matrices = matrix_from_pose(np.asarray(poses, dtype=float))
    ends = [np.einsum("nij,j->ni", matrices[:, :3, :3], limb.platform_point) + matrices[:, :3, 3]
            for limb in ROBOT.limbs]
    rods = np.full(len(matrices), np.inf)
    cranks = np.full(len(matrices), np.inf)
    for i in range(6):
        for j in range(i + 1, 6):
            rods = np.minimum(rods, segment_gap(tips[i], ends[i], tips[j], ends[j]) - 2 * rod_radius)
            cranks = np.minimum(cranks, segment_gap(pivots[i], tips[i], pivots[j], tips[j]) - 2 * crank_radius)
    return rods, cranks


def check(tmp_path, capsys, robot):
    program = tmp_path / "up.csv"
    program.write_text(PROGRAM)
    code = main(["check-path", str(robot), str(program), "--json", str(tmp_path / "r.json"),
                 "--csv", str(tmp_path / "samples.csv")])
    captured = capsys.readouterr()
    with open(tmp_path / "samples.csv") as handle:
        rows = list(csv.DictReader(handle))
    names = ROBOT.joint_names
    samples = {"line": np.array([int(float(row["line"])) for row in rows]),
               "poses": np.array([[float(row[key]) for key in ("x", "y", "z", "roll", "pitch", "yaw")] for row in rows]),
               "joints": np.array([[float(row[name]) for name in names] for row in rows])}
    return code, captured, json.loads((tmp_path / "r.json").read_text()), samples


def test_the_files_radii_keep_the_program_clear_as_computed_here(tmp_path, capsys):
    code, captured, document, samples = check(tmp_path, capsys, "ceart")
    assert code == 0 and captured.err == ""
    assert document["checks"]["collision"] == "passed"
    radii = ROBOT.collision
    every = slice(None, None, 40)
    rods, cranks = clearances_here(samples["poses"][every], samples["joints"][every], radii["rod_radius"],
                                   radii["crank_radius"])
    assert np.all(rods > 0) and np.all(cranks > 0)


def test_overlapping_cranks_are_named_first_where_they_touch_and_worst_where_computed_here(tmp_path, capsys):
    text = (ROBOTS / "ceart.yaml").read_text()
    fat = tmp_path / "ceart_fat.yaml"
    fat.write_text(text.replace("crank_radius: 15.5", f"crank_radius: {FAT_CRANKS}"))
    code, captured, document, samples = check(tmp_path, capsys, fat)
    assert code == 1 and captured.err == ""
    assert document["checks"]["collision"] == "failed"
    collisions = [problem for problem in document["problems"] if problem["kind"] == "collision"]
    assert {(problem["line"], problem["between"]) for problem in collisions} == {(2, "cranks"), (3, "cranks")}
    assert {problem["source"] for problem in collisions} == {"0,0,-250,0,0,0", "0,0,-450,0,0,0"}
    (first,) = [place for place in document["first"] if place["kind"] == "collision"]
    (worst,) = [place for place in document["worst"] if place["kind"] == "collision"]
    _, cranks = clearances_here(samples["poses"], samples["joints"], 15.0, FAT_CRANKS)
    # every sample judged here: the first that overlaps lies within one chord after the place
    # kingen names first (where the clearance crosses 0, found by bisection)
    overlapping = np.flatnonzero(cranks < 0)
    first_here = samples["poses"][overlapping[0]]
    assert samples["line"][overlapping[0]] == first["line"] == 2
    assert 0.0 <= first_here[2] - first["pose"][2] <= 0.1 + 1e-9
    _, at_first = clearances_here([first["pose"]], [first["joints"]], 15.0, FAT_CRANKS)
    assert first["value"] == pytest.approx(at_first[0], abs=1e-6) and first["value"] == pytest.approx(0.0, abs=1e-6)
    assert first["limit"] == 0.0 and first["units"] == "mm"
    assert worst["value"] == pytest.approx(cranks.min(), abs=1e-6) and worst["value"] < -20.0
    _, at_worst = clearances_here([worst["pose"]], [worst["joints"]], 15.0, FAT_CRANKS)
    assert worst["value"] == pytest.approx(at_worst[0], abs=1e-6)


def test_a_robot_file_without_radii_does_not_exercise_the_collision_check(tmp_path, capsys):
    program = tmp_path / "still.csv"
    program.write_text("0,0,508,0,0,0\n0,0,510,0,0,0\n")
    code = main(["check-path", "linuxcnc_hexapod", str(program), "--json", str(tmp_path / "r.json")])
    capsys.readouterr()
    document = json.loads((tmp_path / "r.json").read_text())
    assert code == 0
    assert document["checks"]["collision"] == ("not exercised: the robot file gives no collision: radii "
                                               "(rod_radius, leg_radius, crank_radius)")
