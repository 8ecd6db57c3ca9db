"""Where the machine works: tilt limits, single-coordinate sweeps and workspace slices of one
posture (the robot's working posture), each pose judged by what stops it.

Only the coordinates the robot can move are analysed (``forward.free``; all six for six
limbs): a delta is swept in x, y, z and never tilted. Causes, in this order:
``unreachable`` (a limb has no solution, or is at its own singularity), ``joint_limits``,
``direct_singularity`` (the direct index at most the robot's ``direct_index_min``; or, with
or without one, a singular pose (see SINGULAR) or a crossing: the index below ``CROSSING``
of its value at home, or the sign of the closure Jacobian's determinant over the free
coordinates differing from home's; a home that is itself singular stops every pose judged
from it at home, and the crossing rules then do not apply),
``collision`` (:mod:`kingen.kinematics.collision`, with the robot file's ``collision:`` radii),
``actuator_load`` and ``joint_angle`` (:mod:`kingen.design.load_analysis`), else ``none`` (CAUSES:
the compiled judge, kingen.design.tilt_judge, numbers the first five the same). Poses are mm and degrees. Everything is the numpy reference's: no plugin runs here.
"""

from dataclasses import asdict, dataclass, replace

import numpy as np

from ..kinematics.collision import MODELS, clearances
from ..conventions import matrix_from_pose, t6_from_matrix
from ..kinematics.forward import COORDINATES
from ..kinematics.home import SINGULAR, closure_square, equilibrated_det, singular_index_mm
from ..kinematics.loads import load_limited
from ..kinematics.hybrid.parasitic import solve_parasitic
from ..kinematics.reference import solve
from ..kinematics.routine import WARNINGS
from ..kinematics.singularity import direct_index_of_entries, limb_wrenches, posture_gram_entries
from ..kinematics.hybrid.wrist import rotation_about
from .load_analysis import LOAD_KEYS, load_quantities, loads_available, stiffness_given
from .wrist_analysis import at_pole, beyond_travel, radicand_stops, tool_moving, wrist_available

CAUSES = ("unreachable", "joint_limits", "direct_singularity", "collision", "none", "actuator_load", "joint_angle")
TILT_CONVENTIONS = {
    "axis": "axis: the platform turned by the tilt about the horizontal axis (cos a, sin a, 0) through home",
    "euler": "euler: roll = tilt cos a, pitch = tilt sin a (R = Rz(yaw) Ry(pitch) Rx(roll)), "
             "the 6-RUS thesis's polar graph",
}
SWEEP_STEP_DEG = 1.0
SWEEP_STEPS = 61
SLICE_CELLS = 81
SLICE_RAYS = 32
SLICE_DOUBLINGS = 12
"""A slice's window is the workspace's extent in its plane: along SLICE_RAYS rays from home,
doubling from the verification range up to 2**SLICE_DOUBLINGS times it, then bisected."""
TILT_CHUNK_POSES = 4096
"""Poses tilt_limits judges at once (about 10 MB of the reference's arrays)."""
CROSSING = 0.05
"""A direct index below this fraction of its value at home stops a pose as a direct
singularity even where the robot file sets no ``direct_index_min``."""


@dataclass(frozen=True)
class Settings:
    """What an analysis is asked for: the tilt convention (TILT_CONVENTIONS), the tilt step,
    azimuth step and cap (degrees; a tilt's limit is the largest multiple of the step up to
    which every step passes, without refinement), and the collision model (collision.MODELS)."""

    tilt_convention: str = "axis"
    tilt_step_deg: float = 0.1
    azimuth_step_deg: float = 15.0
    tilt_max_deg: float = 90.0
    collision: str = "segments"

    @property
    def azimuths(self):
        return np.arange(0.0, 360.0 - 1e-9, self.azimuth_step_deg)

    @property
    def tilts(self):
        return np.arange(round(self.tilt_max_deg / self.tilt_step_deg) + 1) * self.tilt_step_deg


@dataclass(frozen=True)
class Home:
    """A posture's values at the verification home: direct index (mm, NaN: not available),
    the sign of the closure Jacobian's determinant (0: singular or unreachable) and whether
    home itself is a singular pose (SINGULAR) and, with a wrist, lies at its pole
    (kingen.design.wrist_analysis.at_pole)."""

    index_mm: float
    det_sign: float
    singular: bool = False
    wrist_pole: bool = False


def free_coordinates(robot):
    """Indices into COORDINATES of what the robot can move (forward.free; all six otherwise)."""
    return [COORDINATES.index(name) for name in (robot.forward_free or COORDINATES)]


def home_values(robot, posture, settings=Settings()):
    """The posture's Home at the verification home (det_sign 0 where home is singular)."""
    evaluated = evaluate(robot, t6_from_matrix(matrix_from_pose(np.array([robot.verification.home]))), posture,
                         settings, Home(np.nan, 0.0))
    singular = bool(evaluated["singular"][0])
    return Home(float(evaluated["direct_index_mm"][0]), 0.0 if singular else float(evaluated["det_sign"][0]),
                singular, at_pole(robot))


def evaluate(robot, t6, posture, settings=Settings(), home=None):
    """Per pose of t6 (n, 4, 4), for ``posture``: a dict of arrays: cause (n,) index into
    CAUSES, warning, direct_index_mm (NaN: not available or unreachable), det_sign (sign of
    the closure Jacobian's determinant over the free coordinates; 0 where unreachable),
    min_inverse_index, min_rod_distance_mm and min_crank_distance_mm (clearances; NaN when
    not configured or not applicable), joints (n, dof), singular (n,) bool (SINGULAR).
    ``home``: the posture's Home (computed when not given) for the crossing rules. With a wrist,
    t6 are tool poses: the legs are judged at the platform pose the machine takes for them
    (kingen.design.wrist_analysis)."""
    home = home_values(robot, posture, settings) if home is None else home
    if robot.task:  # a constrained machine over its task coordinates: the pose it takes for them
        with np.errstate(all="ignore"):
            t6 = solve_parasitic(robot, t6).t6
    plain = replace(robot, direct_index_min=None)
    expected = solve(plain, t6)
    legs, platform = (robot.parallel, expected.platform) if robot.wrist is not None else (robot, t6)
    joints = expected.joints[:, :, posture]
    warning = expected.warnings[:, posture].copy()
    index = np.full(len(t6), np.nan)
    reachable = warning != WARNINGS["WARN_UNREACHABLE"]
    if robot.has_direct_index and np.any(reachable):
        wrenches, _ = limb_wrenches(plain, expected.points[reachable], expected.branch_joints[reachable],
                                    with_transmissions=False)
        index[reachable] = direct_index_of_entries(posture_gram_entries(plain, wrenches)[:, :, posture],
                                                   robot.direct_index_min)
    sign = np.where(reachable, _det_sign(legs, platform, expected.points, joints[:, :legs.dof]), 0.0)
    singular = reachable & ((index <= singular_index_mm(robot)) if robot.has_direct_index else (sign == 0.0))
    rods, cranks = clearances(legs, expected.points, joints[:, :legs.dof], settings.collision)
    threshold = robot.direct_index_min if robot.direct_index_min is not None else -1.0
    crossed = (index < CROSSING * home.index_mm) | ((home.det_sign != 0) & (sign != home.det_sign) & reachable)
    cause = np.full(len(t6), CAUSES.index("none"))
    held = load_quantities(robot, t6, posture, expected) if load_limited(robot) or stiffness_given(robot) else {}
    candidates = [
        ("joint_angle", held.get("joint_angle", False)),
        ("actuator_load", held.get("actuator_load", False)),
        ("collision", (rods < 0.0) | (cranks < 0.0)),
        ("direct_singularity", (index <= threshold) | crossed | singular),
        ("joint_limits", (warning == WARNINGS["WARN_JOINT_LIMITS_EXCEEDED"]) | beyond_travel(robot, joints)),
        ("unreachable", ~reachable | radicand_stops(robot, expected, home.wrist_pole)),
    ]
    for name, mask in candidates:  # the last assigned wins: unreachable over limits over ...
        cause = np.where(mask, CAUSES.index(name), cause)
    return {"cause": cause, "warning": warning, "direct_index_mm": index, "det_sign": sign,
            "min_inverse_index": np.where(np.isfinite(expected.min_inverse_index), expected.min_inverse_index, np.nan),
            "min_rod_distance_mm": rods, "min_crank_distance_mm": cranks, "joints": joints, "singular": singular,
            **{key: held.get(key, np.full(len(t6), np.nan)) for key in LOAD_KEYS}}


def _det_sign(robot, t6, points, joints):
    """Sign of det d(closure residuals)/d(free coordinates) (n,) (kingen.kinematics.home.closure_square);
    for robots without a direct index, 0 where that matrix is singular (SINGULAR)."""
    square = closure_square(robot, t6, points, joints)
    with np.errstate(invalid="ignore"):
        sign = np.nan_to_num(np.sign(np.linalg.det(square)))
        if not robot.has_direct_index:
            sign = np.where(np.abs(equilibrated_det(square)) <= SINGULAR ** 2, 0.0, sign)
    return sign


def tilted_t6(robot, azimuths, tilts, convention="axis"):
    """T6 (len(azimuths) * len(tilts), 4, 4): home tilted by each tilt (degrees) towards
    each azimuth (degrees) in ``convention`` (TILT_CONVENTIONS)."""
    home = np.array(robot.verification.home, dtype=float)
    if convention == "euler":
        poses = np.tile(home, (len(azimuths) * len(tilts), 1))
        a, k = np.meshgrid(np.radians(azimuths), tilts, indexing="ij")
        poses[:, 3] += (k * np.cos(a)).ravel()
        poses[:, 4] += (k * np.sin(a)).ravel()
        return t6_from_matrix(matrix_from_pose(poses))
    start = matrix_from_pose(home)
    matrices = []
    for azimuth in np.radians(azimuths):
        axis = np.array([np.cos(azimuth), np.sin(azimuth), 0.0])
        for angle in np.radians(tilts):
            turned = start.copy()
            turned[:3, :3] = rotation_about(axis, [angle])[0] @ start[:3, :3]
            matrices.append(turned)
    return t6_from_matrix(np.array(matrices))


def can_tilt(robot):
    """Whether the platform can tilt: roll and pitch are both free coordinates."""
    return {3, 4} <= set(free_coordinates(robot))


def tilt_limits(robot, posture, settings=Settings(), home=None):
    """[{azimuth_deg, max_tilt_deg, cause, min_direct_index_mm}] per azimuth: the largest
    multiple of the tilt step up to which every step passes; cause 'none' when nothing stops
    it up to the cap; the least direct index up to where it stops (None: not available).
    Empty when the platform cannot tilt."""
    if not can_tilt(robot):
        return []
    home = home_values(robot, posture, settings) if home is None else home
    tilts = settings.tilts
    first, causes, least = _first_stops(robot, posture, settings, home)
    return [{"azimuth_deg": round(float(azimuth), 6), "max_tilt_deg": round(float(tilts[max(stop - 1, 0)]), 6),
             "cause": CAUSES[cause], "min_direct_index_mm": _finite_or_none(index)}
            for azimuth, stop, cause, index in zip(settings.azimuths, first, causes, least)]


def _first_stops(robot, posture, settings, home):
    """(first stopping step (len(tilts): none), its cause, least direct index mm before it
    (NaN: none available)) per azimuth of ``settings``. The poses are judged in chunks of at
    most max(TILT_CHUNK_POSES, azimuths) along the tilts, each azimuth until its first stop:
    memory is independent of the step counts."""
    azimuths, tilts = settings.azimuths, settings.tilts
    first = np.full(len(azimuths), len(tilts))
    causes = np.full(len(azimuths), CAUSES.index("none"))
    least = np.full(len(azimuths), np.nan)
    going, start = np.arange(len(azimuths)), 0
    while len(going) and start < len(tilts):
        chunk = tilts[start:start + max(1, TILT_CHUNK_POSES // len(going))]
        evaluated = evaluate(robot, tilted_t6(robot, azimuths[going], chunk, settings.tilt_convention), posture,
                             settings, home)
        cause = evaluated["cause"].reshape(len(going), len(chunk))
        stopped = cause != CAUSES.index("none")
        stops = np.where(stopped.any(axis=1), stopped.argmax(axis=1), len(chunk))
        reached = np.arange(len(chunk)) < stops[:, None]
        index = np.where(reached, evaluated["direct_index_mm"].reshape(len(going), len(chunk)), np.nan)
        least[going] = np.fmin(least[going], np.fmin.reduce(index, axis=1))
        ended = stops < len(chunk)
        first[going[ended]] = start + stops[ended]
        causes[going[ended]] = cause[ended, stops[ended]]
        going, start = going[~ended], start + len(chunk)
    return first, causes, least


def sweeps(robot, posture, settings=Settings(), home=None):
    """{coordinate: [entries]} for each free coordinate: sweeps from home, angles over
    +-tilt_max in SWEEP_STEP_DEG steps, positions over +-the verification range."""
    start = np.array(robot.verification.home, dtype=float)
    result = {}
    for axis in sorted(tool_moving(robot, free_coordinates(robot)), key=lambda axis: (axis < 3, axis)):
        if axis >= 3:
            values = start[axis] + np.arange(-settings.tilt_max_deg, settings.tilt_max_deg + SWEEP_STEP_DEG / 2,
                                             SWEEP_STEP_DEG)
        else:
            values = start[axis] + np.linspace(-1.0, 1.0, SWEEP_STEPS) * max(robot.verification.range[axis], 1.0)
        poses = np.tile(start, (len(values), 1))
        poses[:, axis] = values
        evaluated = evaluate(robot, t6_from_matrix(matrix_from_pose(poses)), posture, settings, home)
        result[COORDINATES[axis]] = [_entry(robot, float(value), evaluated, i) for i, value in enumerate(values)]
    return result


def _entry(robot, value, evaluated, i):
    def number(key):
        return _finite_or_none(evaluated[key][i])

    scale = 1.0 / robot.joint_scale()
    return {"value": value, "warning": int(evaluated["warning"][i]), "cause": CAUSES[evaluated["cause"][i]],
            "direct_index_mm": number("direct_index_mm"), "min_inverse_index": number("min_inverse_index"),
            "min_rod_distance_mm": number("min_rod_distance_mm"),
            "min_crank_distance_mm": number("min_crank_distance_mm"), "load_fraction": number("load_fraction"),
            "min_stiffness_n_per_mm": number("min_stiffness_n_per_mm"),
            "joints": [float(v) for v in evaluated["joints"][i] * scale]}


def workspace_extent(robot, posture, axes, settings=Settings(), home=None):
    """(low, high, capped) per axis of ``axes`` (two position indices): the bounding box (mm)
    of the workspace at home orientation in their plane, found along SLICE_RAYS rays from
    home (a pose is inside while nothing limits it: cause 'none'); ``capped``: some ray was
    still inside at the search's end."""
    start = np.array(robot.verification.home, dtype=float)
    angles = np.linspace(0.0, 2 * np.pi, SLICE_RAYS, endpoint=False)
    directions = np.column_stack([np.cos(angles), np.sin(angles)])
    scale = max(max(robot.verification.range[axis] for axis in axes), 1.0)

    def inside(distances):
        poses = np.tile(start, (SLICE_RAYS, 1))
        for column, axis in enumerate(axes):
            poses[:, axis] += directions[:, column] * distances
        cause = evaluate(robot, t6_from_matrix(matrix_from_pose(poses)), posture, settings, home)["cause"]
        return cause == CAUSES.index("none")

    low, high = np.zeros(SLICE_RAYS), np.full(SLICE_RAYS, scale)
    searching = np.ones(SLICE_RAYS, dtype=bool)
    for _ in range(SLICE_DOUBLINGS):
        moved = searching & inside(high)
        low, high = np.where(moved, high, low), np.where(moved, 2 * high, high)
        searching = moved
    capped = bool(np.any(searching))
    for _ in range(30):
        middle = (low + high) / 2
        good = inside(middle)
        low, high = np.where(good, middle, low), np.where(good, high, middle)
    reach = np.where(searching, low, high)
    points = directions * reach[:, None]
    return [(float(start[axis] + points[:, column].min()), float(start[axis] + points[:, column].max()))
            for column, axis in enumerate(axes)], capped


def slices(robot, posture, settings=Settings(), home=None):
    """{'xy', 'xz'} for each plane of two free position coordinates: grids at home
    orientation over the workspace's extent in that plane plus a tenth (equal cell size on
    both axes), each {axes, first, second, causes, extent_mm, capped} and, where loads give
    them, the grids of LOAD_KEYS (null in an unreachable cell)."""
    start = np.array(robot.verification.home, dtype=float)
    free = set(free_coordinates(robot))
    result = {}
    for name, axes in (("xy", (0, 1)), ("xz", (0, 2))):
        if not set(axes) <= free:
            continue
        extent, capped = workspace_extent(robot, posture, axes, settings, home)
        margins = [0.1 * (high - low) + 1e-9 for low, high in extent]
        widest = max(high - low + 2 * margin for (low, high), margin in zip(extent, margins))
        cell = widest / (SLICE_CELLS - 1)
        spans = [np.arange(low - margin, high + margin + cell / 2, cell) for (low, high), margin in zip(extent, margins)]
        grid_first, grid_second = np.meshgrid(*spans, indexing="ij")
        poses = np.tile(start, (grid_first.size, 1))
        poses[:, axes[0]], poses[:, axes[1]] = grid_first.ravel(), grid_second.ravel()
        evaluated = evaluate(robot, t6_from_matrix(matrix_from_pose(poses)), posture, settings, home)
        result[name] = {"axes": [COORDINATES[axes[0]], COORDINATES[axes[1]]], "first": spans[0].tolist(),
                        "second": spans[1].tolist(), "causes": evaluated["cause"].reshape(grid_first.shape).tolist(),
                        "extent_mm": [list(pair) for pair in extent], "capped": capped}
        result[name].update({key: [[_finite_or_none(value) for value in row] for row in values.reshape(grid_first.shape)]
                             for key, values in ((key, evaluated[key]) for key in LOAD_KEYS)
                             if np.any(np.isfinite(values))})
    return result


def analyze(robot, posture=None, settings=Settings(), progress=None):
    """The analysis of ``posture`` (default: the robot's working posture) as JSON-ready data:
    {robot, posture, available, settings, tilt_limits, sweeps, slices, direct_index_min_mm,
    singular_at_home} (singular_at_home: null, or what makes home a singular pose; every tilt
    then stops at 0 degrees)."""
    posture = robot.working_posture if posture is None else posture
    step = progress or (lambda text: None)
    home = home_values(robot, posture, settings)
    step("tilt limits")
    limits = tilt_limits(robot, posture, settings, home)
    step("sweeps")
    swept = sweeps(robot, posture, settings, home)
    step("workspace slices")
    sliced = slices(robot, posture, settings, home)
    free = [COORDINATES[axis] for axis in free_coordinates(robot)]
    available = {
        "direct_index": "available" if robot.has_direct_index else
        f"not available: {robot.dof} limbs (the constraints that complete the platform are "
        f"{'not in the index' if robot.task else 'not modelled'}); a direct singularity is found from the "
        "closure Jacobian instead (direct singularity below)",
        "direct_singularity": ("available" if robot.direct_index_min is not None else
                               f"crossings only: the direct index below {CROSSING:g} of home's or det J's sign "
                               "differing from home's (the robot file sets no singularity: direct_index_min)")
        if robot.has_direct_index else
        f"no index, so no threshold: a pose is a direct singularity where the closure Jacobian over the free "
        f"coordinates ({', '.join(free)}) is singular (scaled determinant at most {SINGULAR ** 2:g}) or its "
        "determinant's sign differs from home's",
        "collision": "available" if robot.collision is not None else
        "not available: the robot file gives no collision radii (collision: leg_radius, rod_radius, crank_radius)",
        "tilt_limits": "available" if limits else
        f"not analysed: the platform's tilt is parasitic (task: {', '.join(free)})" if robot.task else
        f"not analysed: the platform cannot tilt (free: {', '.join(free)})",
        "loads": loads_available(robot),
        "slices": "available" if sliced else
        f"not analysed: fewer than two free position coordinates (free: {', '.join(free)})",
    }
    if robot.wrist is not None:
        available.update(wrist_available(robot, free, list(swept), home.wrist_pole, bool(limits)))
    described = {**asdict(settings), "tilt_convention": TILT_CONVENTIONS[settings.tilt_convention],
                 "collision": MODELS[settings.collision], "free_coordinates": free,
                 "azimuths": len(settings.azimuths) if limits else 0, "tilt_steps": len(settings.tilts),
                 "sweep_angle_step_deg": SWEEP_STEP_DEG, "sweep_position_steps": SWEEP_STEPS,
                 "slice_cells": SLICE_CELLS, "slice_rays": SLICE_RAYS,
                 "crossing_fraction": CROSSING, "crossing_sign_of_det_j": True,
                 "direct_index_at_home_mm": _finite_or_none(home.index_mm), "det_j_sign_at_home": home.det_sign,
                 "singular_fraction": SINGULAR}
    return {"robot": robot.name, "posture": posture, "available": available, "settings": described,
            "tilt_limits": limits, "sweeps": swept, "slices": sliced, "direct_index_min_mm": robot.direct_index_min,
            "singular_at_home": singular_at_home(robot, home)}


def singular_at_home(robot, home):
    """None, or one sentence saying why ``home`` (the posture's Home) is a singular pose."""
    if not home.singular:
        return None
    if robot.has_direct_index:
        return (f"home is a direct singularity: its direct index is {home.index_mm:.3g} mm, at most "
                f"{singular_index_mm(robot):.3g} mm ({SINGULAR:g} of the robot's size)")
    return (f"home is a direct singularity: the closure Jacobian over the free coordinates is singular there "
            f"(scaled determinant at most {SINGULAR ** 2:g})")


def _finite_or_none(value):
    """``value`` as a float, None where it is not finite (JSON's null)."""
    value = float(value)
    return value if np.isfinite(value) else None
