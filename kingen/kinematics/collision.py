"""Clearances between a robot's links, as cylinders of the robot file's ``collision`` radii.

Two models, chosen by name:

- ``segments`` (kingen's): every pair of passive links as segments (base-side point to
  platform point), and every pair of actuator segments (cranks) at their actual angle.
- ``thesis`` (the 6-RUS thesis's program): only the limb pairs (1, 6), (2, 3), (4, 5); rods
  as infinite lines through the crank tip and the platform point; cranks as segments at
  angle 0 (a static property of the design). Defined for six limbs only.

A clearance is the distance between the two axes less both radii (mm): negative means the
cylinders overlap.
"""

import numpy as np

MODELS = {
    "segments": "segments: every pair of passive links and of cranks, cranks at their angle",
    "thesis": "thesis: limb pairs (1, 6), (2, 3), (4, 5); rods as infinite lines; cranks at angle 0",
}
THESIS_PAIRS = ((0, 5), (1, 2), (3, 4))


def model_problem(robot, model):
    """Why ``model`` cannot judge ``robot`` (one line), or None."""
    if model == "thesis" and robot.dof != 6:
        return f"the thesis's collision model pairs six limbs; {robot.name} has {robot.dof}"
    return None


def clearances(robot, points, joints, model="segments"):
    """(rods, cranks) (n,): the least clearance (mm) between passive links and between
    crank segments under ``model`` for limb points (n, limbs, 3) and joints (n, dof) in the
    base frame; NaN where the robot declares no radii or has fewer than two such segments."""
    count = len(points)
    rods = np.full(count, np.nan)
    cranks = np.full(count, np.nan)
    if robot.collision is None:
        return rods, cranks
    crank_joints = np.zeros_like(joints) if model == "thesis" else joints
    links, link_radii, arms, arm_radii = [], [], [], []
    for index, limb in enumerate(robot.limbs):
        start = limb.base_side_point(points[:, index], joints[:, index])
        links.append((start, points[:, index]))
        link_radii.append(robot.collision.get(limb.passive_radius, 0.0))
        segment = limb.actuator_segment(crank_joints[:, index])
        arms.append(segment)
        arm_radii.append(robot.collision.get("crank_radius", 0.0))
    if model == "thesis":
        pairs = THESIS_PAIRS
        rod_distance = line_distance
    else:
        pairs = [(i, j) for i in range(len(links)) for j in range(i + 1, len(links))]
        rod_distance = segment_distance
    return (_least(links, link_radii, pairs, rod_distance, rods),
            _least(arms, arm_radii, pairs, segment_distance, cranks))


def _least(segments, radii, pairs, distance, empty):
    best = empty.copy()
    for i, j in pairs:
        if segments[i] is None or segments[j] is None:
            continue
        best = np.fmin(best, distance(*segments[i], *segments[j]) - radii[i] - radii[j])
    return best


def segment_distance(p1, q1, p2, q2):
    """Distances (n,) between segments p1-q1 and p2-q2 (n, 3 each): closest points clamped
    to both segments (Ericson, Real-Time Collision Detection, 5.1.9), vectorised."""
    d1, d2, r = q1 - p1, q2 - p2, p1 - p2
    a, e = np.sum(d1 * d1, -1), np.sum(d2 * d2, -1)
    f, c, b = np.sum(d2 * r, -1), np.sum(d1 * r, -1), np.sum(d1 * d2, -1)
    denominator = a * e - b * b
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(denominator > 1e-12 * a * e, np.clip((b * f - c * e) / denominator, 0.0, 1.0), 0.0)
        t = np.where(e > 0, (b * s + f) / e, 0.0)
        s = np.where(t < 0.0, np.where(a > 0, np.clip(-c / a, 0.0, 1.0), 0.0), np.where(
            t > 1.0, np.where(a > 0, np.clip((b - c) / a, 0.0, 1.0), 0.0), s))
    t = np.clip(t, 0.0, 1.0)
    return np.linalg.norm(p1 + d1 * s[:, None] - (p2 + d2 * t[:, None]), axis=-1)


def line_distance(p1, q1, p2, q2):
    """Distances (n,) between the infinite lines through p1, q1 and through p2, q2 (n, 3
    each); for parallel lines, the distance of p2 from the first line."""
    d1, d2, r = q1 - p1, q2 - p2, p2 - p1
    normal = np.cross(d1, d2)
    length = np.linalg.norm(normal, axis=-1)
    parallel = length <= 1e-12 * np.linalg.norm(d1, axis=-1) * np.linalg.norm(d2, axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        skew = np.abs(np.sum(r * normal, -1)) / length
        along = np.linalg.norm(np.cross(r, d1), axis=-1) / np.linalg.norm(d1, axis=-1)
    return np.where(parallel, along, skew)
