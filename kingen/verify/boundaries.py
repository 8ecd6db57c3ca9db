"""Poses on both sides of every warning's boundary, added to verify's sample so that each
warning a robot can give is exercised (a routine that never gives one fails ``warnings``),
and so is each threshold behind a warning that another cause also gives: the direct index's
(``direct_index_min``), whose boundary differs from the limbs' singular band that also gives
WARN_SINGULAR_SOLUTION, so a routine deciding the index wrongly near its threshold fails
even where the singular band's poses pass.

Uniform poses rarely land near a boundary: the limb singular band is 2e-5 wide in the
normalised radicand, a direct-index threshold or a travel limit may lie outside the
verification region. So rays are cast from the verification home, in directions drawn
from the region's half-widths, out to ``REACH`` times them; where the reference's warning of
a posture turns into the warning sought between two steps, the boundary is found by
bisection, and a pose just before and one just after it join the sample, each outside the
tolerance band in which routine and reference may disagree (mm, degrees; kingen.kinematics.poses).
"""

import math

import numpy as np

from ..conventions import t6_from_pose
from ..kinematics.hybrid.parasitic import on_manifold
from ..kinematics.reference import solve
from ..kinematics.routine import WARNINGS, warnings_to_exercise
from .descent import DIRECT_INDEX, descend
from .tally import warnings_in_band

RAYS = 64
STEPS = 32
REACH = 4.0
"""Rays reach this many times the region's half-widths from home (boundaries outside the
region are taken too: verify's report says how many poses came from here)."""
FAR = 4.0
"""Then, for a warning not met, translations up to this many times the robot's size."""
PER_WARNING = 16
"""Boundaries kept per warning: two poses each."""
PAST = {"WARN_JOINT_LIMITS_EXCEEDED": ("WARN_JOINT_LIMITS_EXCEEDED",), "WARN_UNREACHABLE": ("WARN_UNREACHABLE",),
        "WARN_SINGULAR_SOLUTION": ("WARN_SINGULAR_SOLUTION", "WARN_UNREACHABLE")}
"""The warnings on the far side of each warning's boundary: the limb singular band lies between
reachable and unreachable, so a ray that steps over it still brackets its edge."""
OFFSETS = (1e-7, 1e-6, 1e-5, 1e-4, 1e-3)
"""Distances from the boundary tried, as fractions of the ray's length, until both poses lie
outside the tolerance band."""
BISECTIONS = math.ceil(math.log2(10.0 / (STEPS * OFFSETS[0])))
"""Halvings of a grid step that leave its bracket at most a tenth of the smallest offset
wide (22): each pose then lies between 1 and 1.1 times its offset from the boundary."""
LEVELS_PER_SOLVE = 3
"""Halvings decided per reference solve, from the 7 midpoints they could visit on each ray:
22 halvings take 8 solves instead of 22, with the same brackets."""


def boundaries_to_seek(robot, vocabulary=None):
    """The boundaries verify seeks for ``robot``'s routine (of ``vocabulary``, when it has
    one): each warning it can give (routine.warnings_to_exercise), then DIRECT_INDEX when a
    direct-index threshold gives WARN_SINGULAR_SOLUTION besides a limb's singular band (alone,
    its boundary is that warning's)."""
    kinds = warnings_to_exercise(robot, vocabulary)
    if (robot.direct_index_min is not None and "WARN_SINGULAR_SOLUTION" in kinds
            and any(limb.has_radicand for limb in robot.limbs)):
        kinds.append(DIRECT_INDEX)
    return kinds


def threshold_boundaries(robot, found):
    """How many boundaries of the direct index's threshold ``found`` (boundary_poses's)
    holds, or None when none was sought (no threshold, or a routine without the warning)."""
    if DIRECT_INDEX in found:
        return found[DIRECT_INDEX]
    if robot.direct_index_min is not None and "WARN_SINGULAR_SOLUTION" in found:
        return found["WARN_SINGULAR_SOLUTION"]  # the threshold is that warning's only cause
    return None


def boundary_poses(robot, seed, link_lengths=None, link_offsets=None, vocabulary=None):
    """(poses (m, 6) in mm and degrees, {boundary: boundaries found}, {boundary: the
    kingen.verify.descent.Descent that sought it}) on both sides of each boundary of
    boundaries_to_seek, seeded; the same poses whatever the number of processes. Rays first
    span the verification region (``REACH`` times its half-widths); a boundary they do not meet
    is sought again along translations up to ``FAR`` times the robot's size (the direct index's
    threshold is not: far translations leave the workspace), then by a descent of its margin
    over reachable poses (kingen.verify.descent), bisected on the segment where a descent
    stepped past it."""
    region = robot.verification
    home, widths = np.asarray(region.home, dtype=float), np.asarray(region.range, dtype=float)
    generator = np.random.default_rng([seed, 0x626f756e64])  # apart from the sample's own stream
    kinds = boundaries_to_seek(robot, vocabulary)
    calibrated = robot.calibrated(link_lengths, link_offsets)
    far = np.zeros((RAYS, 6))
    far[:, :3] = generator.normal(size=(RAYS, 3))
    far[:, :3] *= FAR * robot.size_mm / np.linalg.norm(far[:, :3], axis=1, keepdims=True)
    stages = [generator.uniform(-1.0, 1.0, size=(RAYS, 6)) * widths * REACH, far]
    poses, found, searched = [], {kind: 0 for kind in kinds}, {}
    for stage, directions in enumerate(stages):
        missing = [kind for kind in kinds if not found[kind] and not (stage and kind == DIRECT_INDEX)]
        if not missing or not np.any(directions):
            continue
        for kind, count, sides in _boundaries(calibrated, np.broadcast_to(home, directions.shape), directions, missing):
            found[kind] = count
            poses.append(sides)
    for kind in [kind for kind in kinds if not found[kind]]:
        origins, directions, searched[kind] = descend(calibrated, kind, home, widths, REACH, generator)
        for _, count, sides in _boundaries(calibrated, origins, directions, [kind]):
            found[kind] = count
            poses.append(sides)
    return (np.concatenate(poses) if poses else np.zeros((0, 6))), found, searched


def _beyond(robot, kind, solution):
    """(n, postures) whether each posture of the reference's ``solution`` lies beyond the
    boundary ``kind``: it gives one of PAST's warnings, or for DIRECT_INDEX its direct index
    is at most the threshold (never where it has none: unreachable)."""
    if kind == DIRECT_INDEX:
        with np.errstate(invalid="ignore"):
            return solution.direct_index <= robot.direct_index_min
    return np.isin(solution.warnings, [WARNINGS[name] for name in PAST[kind]])


def _boundaries(robot, origins, directions, kinds):
    """(boundary, boundaries found, poses on both sides) for each of ``kinds`` that the rays
    origins + t directions (0 <= t <= 1; one origin and direction per ray) meet; ``robot`` calibrated as the routine is called.
    The brackets of every boundary are bisected together, one reference solve per step for
    all of them (each pose is solved on its own, so batching changes no pose)."""
    def warnings_at(fractions, rays):
        poses = origins[rays] + fractions[:, None] * directions[rays]
        if robot.task:  # a constrained machine's boundaries lie on its manifold
            poses = on_manifold(robot, poses)
        return solve(robot, t6_from_pose(poses)), poses

    rays_count = len(directions)
    if not rays_count:
        return
    steps = np.linspace(0.0, 1.0, STEPS + 1)
    grid, _ = warnings_at(np.tile(steps, rays_count), np.repeat(np.arange(rays_count), STEPS + 1))
    met, rays, lows, postures, bracket_kinds = [], [], [], [], []
    for kind in kinds:
        hits = _beyond(robot, kind, grid).reshape(rays_count, STEPS + 1, -1)  # (rays, steps, postures)
        count = 0
        for ray in range(rays_count):
            changes = np.argwhere(~hits[ray, :-1] & hits[ray, 1:])  # (step, posture) where it crosses
            if len(changes):
                rays.append(ray)
                lows.append(changes[0][0])
                postures.append(changes[0][1])
                bracket_kinds.append(kind)
                count += 1
            if count == PER_WARNING:
                break
        if count:
            met.append((kind, count))
    if not met:
        return
    rays, postures, bracket_kinds = np.array(rays), np.array(postures), np.array(bracket_kinds)
    low, high = steps[np.array(lows)], steps[np.array(lows) + 1]

    def inside(fractions):
        """(k, rays) whether each pose of ``fractions`` (k x rays,) lies beyond its ray's boundary."""
        repeats = len(fractions) // len(rays)
        solution, _ = warnings_at(fractions, np.tile(rays, repeats))
        kinds, columns = np.tile(bracket_kinds, repeats), np.tile(postures, repeats)
        beyond = np.zeros(len(fractions), dtype=bool)
        for kind, _ in met:
            mine = kinds == kind
            beyond[mine] = _beyond(robot, kind, solution)[mine, columns[mine]]
        return beyond.reshape(repeats, len(rays))

    for done in range(0, BISECTIONS, LEVELS_PER_SOLVE):
        low, high = _bisected(low, high, min(LEVELS_PER_SOLVE, BISECTIONS - done), inside)
    sides = _both_sides(robot, warnings_at, rays, low, high)
    first = 0
    for kind, count in met:
        yield kind, count, _chosen(sides, range(first, first + count), WARNINGS.get(kind), postures)
        first += count


def _bisected(low, high, levels, inside):
    """(low, high) after ``levels`` halvings of the brackets [low, high] (one per ray), each
    keeping the half whose upper end ``inside`` (fractions (k x rays,) -> (k, rays) bool)
    calls beyond the boundary: the brackets one halving at a time would give, bit for bit,
    from one call of ``inside`` on every midpoint those halvings could visit (2^levels - 1
    per ray, each computed as that halving computes it, 0.5 (low + high))."""
    span = 1 << levels
    points = {0: low, span: high}  # by position in the bracket, in units of span
    for level in range(levels):
        step = span >> (level + 1)
        for left in range(0, span, 2 * step):
            points[left + step] = 0.5 * (points[left] + points[left + 2 * step])
    table = np.stack([points[position] for position in range(span + 1)])  # (span + 1, rays)
    beyond = inside(table[1:span].ravel())  # (span - 1, rays)
    rays = np.arange(len(low))
    left, right = np.zeros(len(low), dtype=int), np.full(len(low), span)
    for _ in range(levels):
        middle = (left + right) // 2
        past = beyond[middle - 1, rays]
        right, left = np.where(past, middle, right), np.where(past, left, middle)
    return table[left, rays], table[right, rays]


def _both_sides(robot, warnings_at, rays, low, high):
    """For each offset of OFFSETS and side (before, after) of each bracketed boundary, then the
    bracket's own ends (offset 0, within a tenth of the smallest offset of the boundary): the
    poses there, which of them lie outside the tolerance band, and the reference's warnings
    there (count, postures). All in one reference solve (each pose is solved on its own, so
    batching changes no pose)."""
    cases = [(side, fractions) for offset in OFFSETS
             for side, fractions in (("before", np.clip(low - offset, 0.0, None)), ("after", high + offset))]
    cases += [("before", low), ("after", high)]
    solution, poses = warnings_at(np.concatenate([fractions for _, fractions in cases]), np.tile(rays, len(cases)))
    clear = ~np.any(warnings_in_band(robot, solution), axis=1)
    count = len(rays)
    return [(side, poses[k * count:(k + 1) * count], clear[k * count:(k + 1) * count],
             solution.warnings[k * count:(k + 1) * count]) for k, (side, _) in enumerate(cases)]


def _chosen(sides, brackets, code, postures):
    """A pose before and one after each of ``brackets`` (indices into the bisected rays), as
    near its boundary as the tolerance band allows. After a warning's boundary (its ``code``;
    None for the direct index's threshold), the pose nearest it that gives that warning in the
    bracket's posture (``postures``, by ray) where one does: a singular band narrower than the
    smallest offset is stepped over into unreachable poses, but the bracket's end lies in it."""
    chosen, fallback = {}, {}
    for side, poses, clear, warnings in sides:
        for index in brackets:
            if not clear[index]:
                continue
            fallback.setdefault((side, index), poses[index])
            if side == "before" or code is None or warnings[index, postures[index]] == code:
                chosen.setdefault((side, index), poses[index])
    for key, pose in fallback.items():
        chosen.setdefault(key, pose)
    return np.array(list(chosen.values())) if chosen else np.zeros((0, 6))
