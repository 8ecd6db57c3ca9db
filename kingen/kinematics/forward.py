"""Forward kinematics: every platform pose that given joints admit (the assembly modes).

The unknowns are the robot's free pose coordinates (all six for six limbs; a robot with
fewer limbs declares them, ``forward: {free: [x, y, z]}``), the others held at the pose
the search starts near. Each limb closes when its passive link has its length,
|C_i(pose) - P_i(q_i)| = l_i(q_i) (docs/explanation/conventions.md); the residuals' derivative with
respect to a platform twist is the limb's unit wrench, so Newton-Raphson needs no
finite differences. How every assembly mode is found, and said:

- six limbs, every coordinate free: exhaustively, as the Stewart-Gough platform the joints
  make (:mod:`kingen.kinematics.sgp`: all complex solutions, the real ones polished by Newton);
- a translating platform with three limbs: in closed form (three spheres: at most two poses);
- otherwise not exhaustively: Newton from seeded starts over a stated region (``search``
  times the verification region around home), which the output names. A machine with task
  coordinates (kingen.robot.constraints) is solved for them with every iterate on its manifold:
  x, y and yaw in closed form (kingen.kinematics.hybrid.parasitic), the derivative along the manifold.

An exhaustive method counts isolated solutions only: on a geometry with a continuum of them
(coincident joints, congruent planar platforms) its paths end elsewhere or nowhere. So its
answer is checked (check_exhaustive): Newton from ``near`` and home must find nothing it
missed, and the closure Jacobian must be regular at every pose found; else the answer says
"not exhaustive" and why, with every pose found.

Poses are (x, y, z) in mm and (roll, pitch, yaw) in radians here; the command line shows
degrees.
"""

from dataclasses import dataclass, replace

import numpy as np

from ..conventions import matrix_from_pose, pose_from_t6, t6_from_matrix
from ..runtime.text import counted
from .hybrid.parasitic import on_manifold, task_twists
from .reference import platform_points_in_base, solve
from .hybrid.wrist import tool_t6

COORDINATES = ("x", "y", "z", "roll", "pitch", "yaw")
ITERATIONS = 60
STARTS = 256
"""Deterministic starts drawn over SEARCH times the verification region (and the given ones)."""
SEARCH = 2.0
CONVERGED = 1e-13
"""Newton stops when no step exceeds this fraction of the robot's size (mm) or of a radian."""
SAME_POSE_MM = 1e-6
SAME_POSE_RAD = 1e-8
SINGULAR_RCOND = 1e-6
"""A pose's closure Jacobian (angle columns per robot size) is singular where its smallest
singular value is at most this fraction of its largest (rounding leaves about 1e-16)."""


@dataclass(frozen=True)
class AssemblyModes:
    """The poses the joints admit (``found``, nearest first), whether they are all of them
    (``exhaustive``) and how that is known (``method``, one line)."""

    found: list
    exhaustive: bool
    method: str


@dataclass(frozen=True)
class Assembly:
    """One pose the joints admit: ``pose`` (6,) mm and radians, ``residual_mm`` the largest
    |closure residual| there."""

    pose: np.ndarray
    residual_mm: float


def t6_of(poses):
    """T6 (n, 4, 4) of poses (n, 6) in mm and radians."""
    poses = np.asarray(poses, dtype=float)
    return t6_from_matrix(matrix_from_pose(np.concatenate([poses[:, :3], np.degrees(poses[:, 3:])], axis=1)))


def poses_of(t6):
    """Poses (n, 6) in mm and radians (forward kinematics' unknowns) of T6 (n, 4, 4): t6_of's inverse."""
    pose = pose_from_t6(t6)
    return np.concatenate([pose[:, :3], np.radians(pose[:, 3:])], axis=1)


def closure(robot, poses, joints):
    """Residuals (n, dof) mm of every limb at poses (n, 6) for joints (n, dof), and the unit
    wrenches (n, dof, 6) of the force lines there (the residuals' twist derivative)."""
    points = platform_points_in_base(t6_of(poses), [limb.platform_point for limb in robot.limbs])
    residuals = np.empty(points.shape[:2])
    for index, limb in enumerate(robot.limbs):
        residuals[:, index] = limb.closure_residual(points[:, index], joints[:, index])
    return residuals, unit_wrenches(robot, points, joints)


def unit_wrenches(robot, points, joints):
    """Unit wrenches [f; C x f] (n, dof, 6) of the limbs' force lines, at their platform
    points C (n, dof, 3, base frame, mm) for joints (n, dof): moments in mm."""
    wrenches = np.empty(points.shape[:2] + (6,))
    for index, limb in enumerate(robot.limbs):
        direction = limb.force_direction(points[:, index], joints[:, index])
        wrenches[:, index] = np.concatenate([direction, np.cross(points[:, index], direction)], axis=-1)
    return wrenches


def pose_jacobian(poses):
    """d(twist)/d(pose) (n, 6, 6): twist [v; omega] per unit rate of x, y, z, roll, pitch, yaw,
    with R = Rz(yaw) Ry(pitch) Rx(roll) and v the velocity of the platform point at the base
    origin (v = p_dot - omega x p)."""
    poses = np.asarray(poses, dtype=float)
    pitch, yaw = poses[:, 4], poses[:, 5]
    cy, sy, cp, sp = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch)
    axes = np.stack([np.stack([cy * cp, sy * cp, -sp], -1),          # roll: Rz Ry e_x
                     np.stack([-sy, cy, np.zeros_like(yaw)], -1),     # pitch: Rz e_y
                     np.broadcast_to([0.0, 0.0, 1.0], poses[:, :3].shape)], axis=1)  # yaw: e_z
    jacobian = np.zeros((len(poses), 6, 6))
    jacobian[:, :3, :3] = np.eye(3)
    jacobian[:, 3:, 3:] = np.swapaxes(axes, 1, 2)
    jacobian[:, :3, 3:] = -np.swapaxes(np.cross(axes, poses[:, None, :3]), 1, 2)
    return jacobian


def closure_derivative(robot, wrenches, poses, free):
    """d(residuals)/d(free coordinates) (n, dof, free count) at poses (n, 6) (mm, radians) from
    the limbs' unit wrenches there (n, dof, 6), the matrix forward kinematics' Newton solves
    with: for a machine with task coordinates along its manifold, per unit rate of each task
    coordinate in the robot's task order (kingen.kinematics.hybrid.parasitic.task_twists); otherwise
    over the pose coordinates ``free`` (6,) bool, R = Rz(yaw) Ry(pitch) Rx(roll). mm per mm, or
    mm per radian."""
    if robot.task:
        return wrenches @ task_twists(robot, t6_of(poses))
    return (wrenches @ pose_jacobian(poses))[:, :, free]


def scaled_closure_derivative(robot, wrenches, poses, free):
    """closure_derivative with each angle's column per mm of arc at the robot's size (divided by
    its size_mm): dimensionless, so that its singular values compare free of units."""
    names = robot.task or [name for name, chosen in zip(COORDINATES, free) if chosen]
    scale = np.array([1.0 if name in COORDINATES[:3] else 1.0 / robot.size_mm for name in names])
    return closure_derivative(robot, wrenches, poses, free) * scale


def newton(robot, starts, joints, free):
    """Newton-Raphson from every start (n, 6) towards the joints (n, dof): the converged
    poses (n, 6) and their largest residuals (n,). ``free`` (6,) bool: the coordinates solved
    for; the others keep the start's values."""
    poses = manifold_poses(robot, np.array(starts, dtype=float))
    with np.errstate(all="ignore"):
        for _ in range(ITERATIONS):
            residual, wrenches = closure(robot, poses, joints)
            matrix = closure_derivative(robot, wrenches, poses, free)
            step = _least_squares(matrix, -residual)
            step = np.where(np.isfinite(step), step, 0.0)
            step = _limited(step, robot.size_mm, free)
            poses[:, free] += step
            poses = manifold_poses(robot, poses)
            if np.all(np.abs(step) <= CONVERGED * np.array([robot.size_mm] * 3 + [1.0] * 3)[free]):
                break
        residual, _ = closure(robot, poses, joints)
    return poses, np.where(np.all(np.isfinite(residual), axis=1), np.max(np.abs(residual), axis=1), np.inf)


def manifold_poses(robot, poses):
    """Poses (n, 6) (mm, radians) of a machine with task coordinates with x, y and yaw its own
    for their z, roll and pitch (kingen.kinematics.hybrid.parasitic); other robots' as they are."""
    if not robot.task:
        return poses
    moved = on_manifold(robot, np.concatenate([poses[:, :3], np.degrees(poses[:, 3:])], axis=1))
    return np.concatenate([moved[:, :3], np.radians(moved[:, 3:])], axis=1)


def _least_squares(matrix, right):
    """Batched least squares through the normal equations with a tiny Tikhonov term."""
    normal = np.swapaxes(matrix, 1, 2) @ matrix
    normal += 1e-14 * np.trace(normal, axis1=1, axis2=2)[:, None, None] * np.eye(normal.shape[-1])
    return np.linalg.solve(normal, (np.swapaxes(matrix, 1, 2) @ right[..., None]))[..., 0]


def _limited(step, size_mm, free):
    """Newton steps no larger than a fifth of the robot's size and a fifth of a turn."""
    limits = np.array([size_mm / 5.0] * 3 + [np.pi * 0.4] * 3)[free]
    scale = np.max(np.abs(step) / limits, axis=1, keepdims=True)
    return step / np.maximum(scale, 1.0)


def free_mask(robot):
    """(6,) bool: the pose coordinates forward kinematics solves for (all six by default)."""
    free = robot.forward_free or COORDINATES
    return np.array([name in free for name in COORDINATES])


def starts(robot, near, search=SEARCH):
    """Deterministic starts: ``near`` first, the verification home, then seeded poses over
    ``search`` times the verification region around home (mm, radians; angles at most a half turn)."""
    home, half = search_region(robot, search)
    rng = np.random.default_rng(20261122)
    drawn = home + rng.uniform(-1.0, 1.0, (STARTS, 6)) * half
    return np.vstack([near, home, drawn])


def search_region(robot, search=SEARCH):
    """(centre (6,), half widths (6,)) of the multi-start search, mm and radians."""
    region = robot.verification
    home = np.concatenate([region.home[:3], np.radians(region.home[3:])])
    half = np.concatenate([region.range[:3], np.radians(region.range[3:])]) * search
    half[3:] = np.minimum(half[3:], np.pi)
    return home, half


def assemblies(robot, joints, near, search=SEARCH):
    """AssemblyModes for ``joints`` (joint_count,) (mm, rad); ``near`` (6,) (mm, rad) orders them
    and gives the values of coordinates that are not free; ``search`` widens a multi-start search.
    A robot with a wrist: the tool's poses (:func:`_tool_assemblies`)."""
    if robot.wrist is not None:
        return _tool_assemblies(robot, joints, near, search)
    from . import sgp  # here: it loads scipy (about 0.6 s), which nothing else verify runs needs

    joints = np.asarray(joints, dtype=float)
    near = np.asarray(near, dtype=float)
    free = free_mask(robot)
    exhaustive = True
    if robot.dof == 3 and list(free) == [True, True, True, False, False, False] and not robot.task:
        candidates = _translation_closed_form(robot, joints, near)
        method = "exhaustive: closed form (the platform point on three spheres: at most 2 poses)"
    elif sgp.applies(robot, free):
        solutions = sgp.solve_all(robot, joints)
        candidates = solutions.candidates
        exhaustive = solutions.failed == 0
        method = (f"{'exhaustive' if exhaustive else 'not exhaustive'}: {sgp.COMPLEX_SOLUTIONS} paths tracked from a "
                  f"generic Stewart-Gough platform to the one these joints make: "
                  f"{counted(solutions.finite, 'complex solution')}, {solutions.infinite} at infinity, "
                  f"{solutions.failed} lost")
    else:
        exhaustive, candidates, method = _multi_start(robot, joints, near, free, search)
    found = _polished(robot, candidates, joints, near, free)
    if not exhaustive and not sgp.applies(robot, free):
        found, method = _continuum(robot, joints, free, found, method)
    if exhaustive:
        exhaustive, found, method = check_exhaustive(robot, joints, near, free, found, method)
    if exhaustive:
        method = f"{method}: {len(found)} real"
    return AssemblyModes(found=found, exhaustive=exhaustive, method=method)


def check_exhaustive(robot, joints, near, free, found, method):
    """(exhaustive, found, method) for an exhaustive method's ``found`` poses and ``method``
    line: unchanged where Newton from ``near`` and the verification home reaches no pose
    missing from ``found`` and the closure Jacobian is regular at every pose; otherwise not
    exhaustive, the poses Newton reached added (nearest ``near`` first) and the line naming
    the continuum of solutions the method cannot see."""
    home, _ = search_region(robot)
    local = _polished(robot, np.vstack([near, np.where(free, home, near)]), joints, near, free)
    missed = [assembly for assembly in local if not any(_same(assembly.pose, other.pose) for other in found)]
    everything = sorted(found + missed, key=lambda assembly: np.linalg.norm(assembly.pose[:3] - near[:3]))
    singular = int(np.count_nonzero(_singular(robot, [assembly.pose for assembly in everything], joints, free)))
    if not missed and not singular:
        return True, found, method
    evidence = ([f"Newton from --near and home reaches {counted(len(missed), 'pose')} the method did not find"]
                if missed else [])
    if singular:
        evidence.append(f"the closure Jacobian is singular at {singular} of the {counted(len(everything), 'pose')}")
    kind = "the geometry has a continuum of solutions" if singular else "the method missed poses"
    return False, everything, (f"not exhaustive: {kind} ({'; '.join(evidence)}); "
                               f"{method.removeprefix('exhaustive: ')}: {len(found)} real isolated")


def _continuum(robot, joints, free, found, method):
    """(found, method) of a multi-start search: where the closure Jacobian is singular at every
    pose Newton reached, the joints admit a continuum of poses (coincident limbs, a platform
    free to move), not as many modes as starts: the nearest pose stands for it, and the line says so."""
    singular = _singular(robot, [assembly.pose for assembly in found], joints, free)
    if not len(found) or not np.all(singular):
        return found, method
    return found[:1], (f"not exhaustive: the geometry has a continuum of solutions (the closure Jacobian is singular at "
                       f"every one of the {counted(len(found), 'pose')} Newton reached; the nearest shown): "
                       f"{method.removeprefix('not exhaustive: ')}")


def _singular(robot, poses, joints, free):
    """(n,) bool: whether the closure Jacobian over the free coordinates is singular at each
    of the poses (n, 6) for ``joints`` (dof,) (SINGULAR_RCOND; angle columns in mm per robot
    size, so that the test is free of units)."""
    poses = np.asarray(poses, dtype=float).reshape(-1, 6)
    if not len(poses):
        return np.zeros(0, dtype=bool)
    _, wrenches = closure(robot, poses, np.tile(joints, (len(poses), 1)))
    values = np.linalg.svd(scaled_closure_derivative(robot, wrenches, poses, free), compute_uv=False)
    return values[:, -1] <= SINGULAR_RCOND * values[:, 0]


def _multi_start(robot, joints, near, free, search):
    begin = starts(robot, near, search)
    begin[:, ~free] = near[~free]
    candidates, _ = newton(robot, begin, np.tile(joints, (len(begin), 1)), free)
    home, half = search_region(robot, search)
    region = ", ".join(f"{name} {centre:g} +- {width:g}" for name, centre, width, is_free in zip(
        COORDINATES, np.concatenate([home[:3], np.degrees(home[3:])]),
        np.concatenate([half[:3], np.degrees(half[3:])]), free) if is_free)
    method = (f"not exhaustive: Newton from {counted(len(begin), 'start')} over {search:g} x the verification region "
              f"({region}; mm, deg); --search widens it")
    return False, candidates, method


def _polished(robot, candidates, joints, near, free):
    """Distinct converged poses among ``candidates`` after Newton, nearest ``near`` first."""
    candidates = np.asarray(candidates, dtype=float).reshape(-1, 6)
    if not len(candidates):
        return []
    polished, residuals = newton(robot, candidates, np.tile(joints, (len(candidates), 1)), free)
    tolerance = 1e-9 * robot.size_mm
    found = []
    for pose, residual in sorted(zip(polished, residuals), key=lambda item: np.linalg.norm(item[0][:3] - near[:3])):
        if residual <= tolerance and not any(_same(pose, other.pose) for other in found):
            found.append(Assembly(pose=pose, residual_mm=float(residual)))
    return found


def best_residual(robot, joints, near, search=SEARCH):
    """The smallest residual Newton reaches from the starts (mm): how close it came."""
    begin = starts(robot, near, search)
    free = free_mask(robot)
    begin[:, ~free] = np.asarray(near)[~free]
    _, residuals = newton(robot, begin, np.tile(np.asarray(joints, float), (len(begin), 1)), free)
    return float(np.min(residuals))


def _same(pose, other):
    rotation = matrix_from_pose(np.concatenate([pose[:3], np.degrees(pose[3:])]))[:3, :3]
    other_rotation = matrix_from_pose(np.concatenate([other[:3], np.degrees(other[3:])]))[:3, :3]
    return (np.max(np.abs(pose[:3] - other[:3])) <= SAME_POSE_MM
            and np.max(np.abs(rotation - other_rotation)) <= SAME_POSE_RAD)


def _translation_closed_form(robot, joints, near):
    """A translating platform (rotation held at ``near``'s) with three limbs: each limb puts
    its platform point on a sphere, so the position is on three spheres: 0, 1 or 2 poses."""
    rotation = matrix_from_pose(np.concatenate([[0.0, 0.0, 0.0], np.degrees(near[3:])]))[:3, :3]
    centres, radii = [], []
    for limb, joint in zip(robot.limbs, joints):
        base_side = limb.base_side_point(np.zeros((1, 3)), np.array([joint]))[0]
        centres.append(base_side - rotation @ np.asarray(limb.platform_point))
        radii.append(float(limb.passive_length(np.array([joint]))[0]))
    positions = _three_spheres(np.array(centres), np.array(radii))
    return [np.concatenate([position, near[3:]]) for position in positions]


def _three_spheres(centres, radii):
    """The points at distances ``radii`` from three ``centres``: trilateration."""
    ex = centres[1] - centres[0]
    d = np.linalg.norm(ex)
    if d == 0.0:
        return []
    ex = ex / d
    i = ex @ (centres[2] - centres[0])
    ey = centres[2] - centres[0] - i * ex
    if np.linalg.norm(ey) == 0.0:
        return []
    ey = ey / np.linalg.norm(ey)
    ez = np.cross(ex, ey)
    j = ey @ (centres[2] - centres[0])
    x = (radii[0] ** 2 - radii[1] ** 2 + d ** 2) / (2 * d)
    y = (radii[0] ** 2 - radii[2] ** 2 + i ** 2 + j ** 2) / (2 * j) - i * x / j
    squared = radii[0] ** 2 - x ** 2 - y ** 2
    if squared < -1e-9 * radii[0] ** 2:
        return []
    z = np.sqrt(max(squared, 0.0))
    base = centres[0] + x * ex + y * ey
    return [base + z * ez, base - z * ez] if z > 0 else [base]


def _tool_assemblies(robot, joints, near, search=SEARCH):
    """AssemblyModes of ``robot`` (with a wrist) for ``joints`` (joint_count,) (mm, rad): the
    parallel part's assembly modes (kingen.kinematics.forward.assemblies, searched near the
    platform's pose for the tool pose ``near`` (6,) (mm, rad), or its home where the reference
    has none), each carried to the tool by the wrist's forward: poses are the tool's (mm, rad),
    nearest ``near`` first, residuals the legs'."""
    joints, near = np.asarray(joints, dtype=float), np.asarray(near, dtype=float)
    solved = solve(robot, t6_of(near[None]))
    start = poses_of(solved.platform)[0]
    if not np.all(np.isfinite(start)):
        start = np.concatenate([robot.parallel.verification.home[:3], np.radians(robot.parallel.verification.home[3:])])
    modes = assemblies(robot.parallel, joints[:robot.dof], start, search)
    found = []
    for mode in modes.found:
        tool = tool_t6(robot, t6_of(mode.pose[None]), joints[None, robot.dof:])
        found.append(replace(mode, pose=poses_of(tool)[0]))
    found.sort(key=lambda mode: np.linalg.norm(mode.pose[:3] - near[:3]))
    return replace(modes, found=found, method=f"the parallel part, then the wrist's forward: {modes.method}")
