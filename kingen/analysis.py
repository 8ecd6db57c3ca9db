"""Where the machine works: tilt limits, single-axis sweeps and workspace slices of one
posture (the robot's working posture), each pose judged by what stops it.

Causes, in this order: ``unreachable`` (a limb has no solution, or is at its own
singularity), ``joint_limits``, ``direct_singularity`` (the direct index at most the robot's
``direct_index_min``, or, with or without one, below ``CROSSING`` of its value at home: a
crossing of a direct singularity, never "no limit"), ``collision`` (two passive links, or two cranks, closer than their
radii allow: ``collision:`` in the robot file), else ``none``. Poses are mm and degrees;
tilts turn about horizontal axes through the home point. Everything is the numpy
reference's: no plugin runs here.
"""

from dataclasses import replace

import numpy as np

from .routine import WARNINGS
from .conventions import matrix_from_pose, t6_from_matrix
from .reference import solve
from .singularity import direct_index_of_entries, limb_wrenches, posture_gram_entries

CAUSES = ("unreachable", "joint_limits", "direct_singularity", "collision", "none")
TILT_AZIMUTHS = tuple(range(0, 360, 15))
TILT_MAX = 60.0
TILT_STEP = 0.1
SWEEP_ANGLES = np.arange(-60.0, 60.5, 1.0)
SWEEP_STEPS = 61
SLICE_CELLS = 81
SLICE_SPAN = 3.0
"""Slices cover the verification region's position range times this, around home."""
CROSSING = 0.05
"""A direct index below this fraction of its value at home stops a pose as a direct
singularity even where the robot file sets no ``direct_index_min``."""


def home_index(robot, posture):
    """The direct index (mm) of ``posture`` at the verification home, or NaN."""
    return float(evaluate(robot, t6_from_matrix(matrix_from_pose(np.array([robot.verification.home]))), posture,
                          np.nan)["direct_index_mm"][0])


def evaluate(robot, t6, posture, at_home=None):
    """Per pose of t6 (n, 4, 4), for ``posture``: a dict of arrays: cause (n,) index into
    CAUSES, warning, direct_index_mm (NaN: not available or unreachable), min_inverse_index,
    min_rod_distance_mm and min_crank_distance_mm (clearances; NaN when not configured or
    not applicable), joints (n, dof). ``at_home``: the posture's direct index at home
    (home_index; computed when not given) for the crossing rule."""
    if at_home is None:
        at_home = home_index(robot, posture) if robot.has_direct_index else np.nan
    plain = replace(robot, direct_index_min=None)
    expected = solve(plain, t6)
    joints = expected.joints[:, :, posture]
    warning = expected.warnings[:, posture].copy()
    count = len(t6)
    index = np.full(count, np.nan)
    reachable = warning != WARNINGS["WARN_UNREACHABLE"]
    if robot.has_direct_index and np.any(reachable):
        wrenches, _ = limb_wrenches(plain, expected.points[reachable], expected.branch_joints[reachable],
                                    with_transmissions=False)
        index[reachable] = direct_index_of_entries(posture_gram_entries(plain, wrenches)[:, :, posture],
                                                   robot.direct_index_min)
    rods, cranks = clearances(robot, expected.points, joints)
    cause = np.full(count, CAUSES.index("none"))
    candidates = [
        ("collision", (rods < 0.0) | (cranks < 0.0)),
        ("direct_singularity", (index <= (robot.direct_index_min if robot.direct_index_min is not None else -1.0))
         | (index < CROSSING * at_home)),
        ("joint_limits", warning == WARNINGS["WARN_JOINT_LIMITS_EXCEEDED"]),
        ("unreachable", ~reachable | (np.min(np.abs(expected.radicands), axis=1) <= 1e-5)),
    ]
    for name, mask in candidates:  # the last assigned wins: unreachable over limits over ...
        cause = np.where(mask, CAUSES.index(name), cause)
    return {"cause": cause, "warning": warning, "direct_index_mm": index,
            "min_inverse_index": np.where(np.isfinite(expected.min_inverse_index), expected.min_inverse_index, np.nan),
            "min_rod_distance_mm": rods, "min_crank_distance_mm": cranks, "joints": joints}


def clearances(robot, points, joints):
    """(rods, cranks) (n,): the least clearance (mm) between any two passive links and
    between any two crank segments, as cylinders of the robot's ``collision`` radii; NaN
    where the robot declares no radii or has fewer than two such segments."""
    count = len(points)
    rods = np.full(count, np.nan)
    cranks = np.full(count, np.nan)
    if robot.collision is None:
        return rods, cranks
    links, link_radii, arms, arm_radii = [], [], [], []
    for index, limb in enumerate(robot.limbs):
        start = limb.base_side_point(points[:, index], joints[:, index])
        links.append((start, points[:, index]))
        link_radii.append(robot.collision.get(limb.passive_radius, 0.0))
        segment = limb.actuator_segment(joints[:, index])
        if segment is not None:
            arms.append(segment)
            arm_radii.append(robot.collision.get("crank_radius", 0.0))
    return _least_clearance(links, link_radii, rods), _least_clearance(arms, arm_radii, cranks)


def _least_clearance(segments, radii, empty):
    best = empty.copy()
    for i in range(len(segments)):
        for j in range(i + 1, len(segments)):
            distance = segment_distance(*segments[i], *segments[j]) - radii[i] - radii[j]
            best = np.fmin(best, distance)
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


def tilted_t6(robot, azimuths, angles):
    """T6 (len(azimuths) * len(angles), 4, 4): home turned by each angle (degrees) about each
    horizontal axis (cos a, sin a, 0) through the home point."""
    home = matrix_from_pose(robot.verification.home)
    matrices = []
    for azimuth in np.radians(azimuths):
        axis = np.array([np.cos(azimuth), np.sin(azimuth), 0.0])
        for angle in np.radians(angles):
            turned = home.copy()
            turned[:3, :3] = _rotation(axis, angle) @ home[:3, :3]
            matrices.append(turned)
    return t6_from_matrix(np.array(matrices))


def _rotation(axis, angle):
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def tilt_limits(robot, posture):
    """[{azimuth_deg, max_tilt_deg, cause, min_direct_index_mm}]: the largest positive tilt
    before the posture stops, to TILT_STEP degrees; cause 'none' when nothing stops it within
    TILT_MAX; the least direct index along the tilt up to where it stops (None: not available)."""
    angles = np.arange(0.0, TILT_MAX + TILT_STEP / 2, TILT_STEP)
    evaluated = evaluate(robot, tilted_t6(robot, TILT_AZIMUTHS, angles), posture)
    causes = evaluated["cause"].reshape(len(TILT_AZIMUTHS), len(angles))
    indices = evaluated["direct_index_mm"].reshape(len(TILT_AZIMUTHS), len(angles))
    limits = []
    for azimuth, row, index in zip(TILT_AZIMUTHS, causes, indices):
        stops = np.nonzero(row != CAUSES.index("none"))[0]
        reached = index[:(int(stops[0]) if len(stops) else len(index))]
        least = float(np.nanmin(reached)) if np.any(np.isfinite(reached)) else None
        if not len(stops):
            limits.append({"azimuth_deg": float(azimuth), "max_tilt_deg": TILT_MAX, "cause": "none",
                           "min_direct_index_mm": least})
        else:
            first = int(stops[0])
            limits.append({"azimuth_deg": float(azimuth), "max_tilt_deg": round(float(angles[max(first - 1, 0)]), 1)
                           if first else 0.0, "cause": CAUSES[row[first]], "min_direct_index_mm": least})
    return limits


def sweeps(robot, posture):
    """{roll, pitch, yaw, x, y, z: [entries]}: single-coordinate sweeps from home (angles
    -60 to 60 degrees, positions over the verification range)."""
    home = np.array(robot.verification.home, dtype=float)
    result = {}
    for axis, name in enumerate(("x", "y", "z", "roll", "pitch", "yaw")):
        values = SWEEP_ANGLES + home[axis] if axis >= 3 else home[axis] + np.linspace(
            -1.0, 1.0, SWEEP_STEPS) * max(robot.verification.range[axis], 1.0)
        poses = np.tile(home, (len(values), 1))
        poses[:, axis] = values
        evaluated = evaluate(robot, t6_from_matrix(matrix_from_pose(poses)), posture)
        result[name] = [_entry(robot, float(value), evaluated, i) for i, value in enumerate(values)]
    return {name: result[name] for name in ("roll", "pitch", "yaw", "x", "y", "z")}


def _entry(robot, value, evaluated, i):
    def number(key):
        value = float(evaluated[key][i])
        return value if np.isfinite(value) else None

    scale = 1.0 / robot.joint_scale()
    return {"value": value, "warning": int(evaluated["warning"][i]), "cause": CAUSES[evaluated["cause"][i]],
            "direct_index_mm": number("direct_index_mm"), "min_inverse_index": number("min_inverse_index"),
            "min_rod_distance_mm": number("min_rod_distance_mm"),
            "min_crank_distance_mm": number("min_crank_distance_mm"),
            "joints": [float(v) for v in evaluated["joints"][i] * scale]}


def slices(robot, posture):
    """{'xy', 'xz'}: grids at home orientation, each {axes, first, second, causes} with
    causes (cells, cells) indices into CAUSES (x-y at home z, x-z at home y)."""
    home = np.array(robot.verification.home, dtype=float)
    result = {}
    for name, (first, second) in (("xy", (0, 1)), ("xz", (0, 2))):
        spans = [home[axis] + np.linspace(-1.0, 1.0, SLICE_CELLS) * SLICE_SPAN * max(robot.verification.range[axis], 1.0)
                 for axis in (first, second)]
        grid_first, grid_second = np.meshgrid(*spans, indexing="ij")
        poses = np.tile(home, (grid_first.size, 1))
        poses[:, first], poses[:, second] = grid_first.ravel(), grid_second.ravel()
        causes = evaluate(robot, t6_from_matrix(matrix_from_pose(poses)), posture)["cause"]
        result[name] = {"axes": ["xyz"[first], "xyz"[second]], "first": spans[0].tolist(),
                        "second": spans[1].tolist(), "causes": causes.reshape(grid_first.shape).tolist()}
    return result


def analyze(robot, posture=None, progress=None):
    """The analysis of ``posture`` (default: the robot's working posture, else 0) as JSON-ready
    data: {robot, posture, available, tilt_limits, sweeps, slices}."""
    posture = robot.working_posture if posture is None else posture
    step = progress or (lambda text: None)
    step("tilt limits")
    limits = tilt_limits(robot, posture)
    step("sweeps")
    swept = sweeps(robot, posture)
    step("workspace slices")
    sliced = slices(robot, posture)
    available = {
        "direct_index": "available" if robot.has_direct_index else
        f"not available: {robot.dof} limbs (the constraints that complete the platform are not modelled)",
        "direct_singularity": "available" if robot.direct_index_min is not None else
        "not available: no singularity: {direct_index_min} in the robot file",
        "collision": "available" if robot.collision is not None else
        "not available: no collision: {leg_radius, rod_radius, crank_radius} in the robot file",
    }
    settings = {"tilt_convention": "axis: rotations about (cos a, sin a, 0) through home",
                "azimuths_deg": list(TILT_AZIMUTHS), "tilt_step_deg": TILT_STEP, "tilt_max_deg": TILT_MAX,
                "sweep_angles_deg": [float(SWEEP_ANGLES[0]), float(SWEEP_ANGLES[-1])],
                "crossing_fraction": CROSSING, "direct_index_at_home_mm": _finite_or_none(home_index(robot, posture))
                if robot.has_direct_index else None,
                "collision": "segments: every pair of passive links and of cranks, cranks at their angle"}
    return {"robot": robot.name, "posture": posture, "available": available, "settings": settings,
            "tilt_limits": limits, "sweeps": swept, "slices": sliced, "direct_index_min_mm": robot.direct_index_min}


def _finite_or_none(value):
    return float(value) if np.isfinite(value) else None
