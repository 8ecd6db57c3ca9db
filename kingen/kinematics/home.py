"""The machine at its verification home, from the numpy reference: whether a posture reaches
home within its joints' travel, the direct index there, and the robot's extent across. What
verify's ``machine`` check judges and what a host refuses to package: one rule for both.

Joints and travel are named in the robot file's units (its length unit, or degrees)."""

from dataclasses import dataclass
from itertools import combinations

import numpy as np

from ..conventions import rpy_from_rotation, t6_from_pose
from ..errors import located
from ..units import LENGTH_UNITS
from .forward import closure_derivative, free_mask, unit_wrenches
from .hybrid.parasitic import off_manifold_words
from .reference import solve
from .routine import WARNINGS

SINGULAR = 1e-6
"""A reachable pose is singular, whatever home's values, where its direct index is at most
this fraction of the robot's size (robots with a direct index), or, for the others, where
the closure Jacobian over the free coordinates, its columns and then its rows scaled to unit
length, has a determinant of at most SINGULAR ** 2 in magnitude. At an exact singularity
rounding leaves about 1e-8 and 1e-15 of them; the thresholds lie far above."""
SMALLEST_MM, LARGEST_MM = 10.0, 1e5
"""A robot less than SMALLEST_MM or more than LARGEST_MM across (mm) was likely drawn in
other units than its file says."""


def closure_square(robot, t6, points, joints):
    """d(closure residuals)/d(free coordinates) (n, dof, free count) at T6 (n, 4, 4) with the
    limbs' platform points ``points`` (n, dof, 3, base frame, mm) and ``joints`` (n, dof): over
    the platform twist for six free coordinates (free of any angle convention), along the
    manifold (per unit rate of each task coordinate) for a machine with task coordinates, over
    the free pose coordinates (mm, radians) otherwise."""
    wrenches = unit_wrenches(robot, points, joints)
    free = free_mask(robot)
    if np.all(free):
        return wrenches
    poses = np.concatenate([t6[:, 3, :3], rpy_from_rotation(np.swapaxes(t6[:, :3, :3], 1, 2))], axis=1)
    return closure_derivative(robot, wrenches, poses, free)


def equilibrated_det(square):
    """det of square matrices (n, k, k) with their columns and then their rows scaled to unit
    length (at most 1 in magnitude, Hadamard; free of the coordinates' units); 0 for a zero
    column or row."""
    with np.errstate(divide="ignore", invalid="ignore"):
        scaled = square / np.linalg.norm(square, axis=1, keepdims=True)
        scaled = scaled / np.linalg.norm(scaled, axis=2, keepdims=True)
        return np.nan_to_num(np.linalg.det(np.nan_to_num(scaled)))


def singular_index_mm(robot):
    """The direct index (mm) at or below which a pose of ``robot`` is singular (SINGULAR)."""
    return SINGULAR * robot.size_mm


@dataclass(frozen=True)
class HomePosture:
    """One posture at the verification home: its joints (dof,) in mm or rad, whether every
    limb reaches home, the limbs (indices) whose joint lies outside its travel, and the
    direct index (mm; NaN where unreachable or not defined); for a robot without a direct index,
    ``determinant``, the closure Jacobian's equilibrated determinant (NaN where not defined)."""

    posture: int
    joints: np.ndarray
    reachable: bool
    beyond: tuple
    direct_index: float
    determinant: float = np.nan


def _solved_at_home(robot, indices=False):
    """The reference's Solution for ``robot``'s verification home (one pose)."""
    return solve(robot, t6_from_pose(np.asarray([robot.verification.home], dtype=float)), indices=indices)


def home_postures(robot):
    """Every posture of ``robot`` at its verification home (HomePosture, in posture order)."""
    solution = _solved_at_home(robot, indices=True)
    lower, upper = robot.travel_limits()
    postures = []
    t6 = t6_from_pose(np.asarray([robot.verification.home], dtype=float))
    square = robot.wrist is None and not robot.has_direct_index and robot.dof == np.count_nonzero(free_mask(robot))
    for posture in range(robot.postures):
        joints = solution.joints[0, :, posture]
        index = np.nan if solution.direct_index is None else float(solution.direct_index[0, posture])
        determinant = (float(equilibrated_det(closure_square(robot, t6, solution.points, joints[None]))[0])
                       if square else np.nan)
        postures.append(HomePosture(determinant=determinant,
            posture=posture, joints=joints,
            reachable=bool(solution.warnings[0, posture] != WARNINGS["WARN_UNREACHABLE"]),
            beyond=tuple(int(i) for i in np.flatnonzero((joints < lower) | (joints > upper))), direct_index=index))
    return postures


def judged_posture(robot):
    """The posture verify judges the machine by: the working posture when the robot file gives
    one; else the first that can be the machine's home (home_problem), or the working posture
    when none can."""
    postures = home_postures(robot)
    if not robot.working_posture_given:
        working = [posture for posture in postures if home_problem(robot, posture) is None]
        if working:
            return working[0]
    return postures[robot.working_posture]


def _in_file_units(robot, index, value):
    """A joint value (mm or degrees) of limb ``index`` in the robot file's units, with the unit."""
    if robot.limbs[index].joint_type.wraps:
        return value, "degrees"
    return value / LENGTH_UNITS[robot.length_unit], robot.length_unit


def joint_words(robot, home, limbs=None):
    """'leg1 451.95 mm (travel 300 to 400)' for each limb of ``limbs`` (every limb when None) at
    the HomePosture ``home``, in the robot file's units."""
    words = []
    for index in (range(robot.dof) if limbs is None else limbs):
        limb = robot.limbs[index]
        value, unit = _in_file_units(robot, index, home.joints[index] / limb.joint_type.yaml_scale)
        if limb.travel is None:
            travel = "no travel limits"
        else:
            low, high = (_in_file_units(robot, index, bound)[0] for bound in limb.travel)
            travel = f"travel {low:.6g} to {high:.6g}"
        words.append(f"{robot.joint_names[index]} {value:.6g} {unit} ({travel})")
    return ", ".join(words)


def home_problem(robot, home):
    """Why the HomePosture ``home`` cannot be the machine's home, or None when it can: home
    unreachable (off the manifold of a machine with task coordinates: by how much, where), or
    beyond the travel of some limbs (each named with its joint at home and its travel), or
    singular there: for robots with a direct index, the index at most singular_index_mm (an
    architecturally singular design); for the others, the closure Jacobian's equilibrated
    determinant at most SINGULAR ** 2 (coincident limbs, a platform free to move)."""
    if not home.reachable:
        off = off_manifold_words(robot, robot.verification.home)
        if off is not None:
            return (f"the verification home is off the machine's manifold {off[0]}: the machine's pose for its "
                    f"{', '.join(robot.task)} there is {off[1]}; its joints there in posture {home.posture}: "
                    f"{joint_words(robot, home)}")
        return f"the verification home is unreachable in posture {home.posture}: {joint_words(robot, home)}"
    if home.beyond:
        return (f"the verification home lies beyond travel in posture {home.posture}: "
                f"{joint_words(robot, home, home.beyond)}")
    if home.direct_index <= singular_index_mm(robot):
        return (f"the direct index at the verification home is {home.direct_index:.3g} mm in posture {home.posture}, "
                f"at most {singular_index_mm(robot):.3g} mm: the design is singular there (the platform can move "
                "with every joint held)")
    if abs(home.determinant) <= SINGULAR ** 2:
        return (f"the closure Jacobian at the verification home is singular in posture {home.posture} (its scaled "
                f"determinant is {home.determinant:.3g}, at most {SINGULAR ** 2:g}): the platform can move with every "
                "joint held, or two limbs are one")
    return None


def workable_home(robot, posture, what):
    """The HomePosture of ``posture`` of ``robot``; KingenError (the robot file's
    ``verification.home``, one line) when it cannot be the machine's home (home_problem):
    ``what`` (e.g. 'a LinuxCNC package') would hold joints at home the machine cannot take."""
    home = home_postures(robot)[posture]
    problem = home_problem(robot, home)
    if problem is not None:
        raise located(robot.path, robot.line_of("verification", "home"), "verification.home",
                      f"{problem}: {what} cannot be written for it")
    return home


def extent_mm(robot):
    """The largest distance (mm) between two of the limbs' base-side and platform points with
    the platform at the verification home, posture 0: how large the robot is across."""
    solution = _solved_at_home(robot)
    joints = solution.joints[0, :, 0]
    points = [solution.points[0, index] for index in range(robot.dof)]
    points += [limb.base_side_point(solution.points[:1, index], joints[index:index + 1])[0]
               for index, limb in enumerate(robot.limbs)]
    return max((float(np.linalg.norm(a - b)) for a, b in combinations(points, 2)), default=0.0)


def size_problem(robot):
    """Why ``robot`` cannot be verified or packaged as its file is read, or None: a file that
    states no ``units:`` read in mm, for a machine less than SMALLEST_MM across (its lengths are
    likely metres): its size and the ``units:`` line to add."""
    if robot.length_unit_given:
        return None
    across = extent_mm(robot)
    if across >= SMALLEST_MM:
        return None
    return (f"the machine is {across:.3g} mm across its base and platform points at home, less than "
            f"{SMALLEST_MM:g} mm: the file states no units, so its lengths were read in mm; add the line "
            f"'units: m' if they are metres ('units: inch' for inches, 'units: mm' if the machine is this small)")


def check_size(robot, what):
    """KingenError (the robot file's ``name`` line, one line) when size_problem finds one:
    ``what`` (e.g. 'a package') is not written for a machine whose units are in doubt."""
    problem = size_problem(robot)
    if problem is not None:
        raise located(robot.path, robot.line_of("name"), "units", f"{problem}: {what} is not written for it")


def scale_notice(robot):
    """A notice when ``robot`` is less than SMALLEST_MM or more than LARGEST_MM across, naming
    the unit its file was read in (the file states it: size_problem judges those that do not);
    else None."""
    across = extent_mm(robot)
    if SMALLEST_MM <= across <= LARGEST_MM or not robot.length_unit_given and across < SMALLEST_MM:
        return None
    unit = robot.length_unit
    size = f"{across:.3g} mm" if unit == "mm" else f"{across / LENGTH_UNITS[unit]:.3g} {unit} ({across:.3g} mm)"
    read = ("mm (units: mm)" if unit == "mm"
            else f"{unit} (units: {unit})")
    bound = "less than 10 mm" if across < SMALLEST_MM else "more than 100 m"
    return (f"the robot is {size} across its base and platform points at home, {bound}: its lengths were read in "
            f"{read}; check the file's units")
