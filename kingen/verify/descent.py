"""The search for a warning's boundary that rays from the verification home miss
(kingen.verify.boundaries): a random descent of the warning's margin over reachable poses.

Each warning's decision rests on one quantity per posture, its margin here: positive on the
good side, at most 0 beyond the boundary (the direct index less the robot's threshold, mm;
the least distance of a joint to its travel limits as a fraction of the travel; the least
limb radicand less the singular band's half-width; the least radicand plus it). A wide
sample of seeds (the region rays span, and a wider one) gives the postures whose margin is
lowest; from each, a chain of seeded random steps keeps a step only where the margin falls
and the posture stays reachable outside the limbs' singular band (so that the warning's
decision there is the margin's alone). Where a chain steps past its boundary, the pose before
and the pose after are the ends of a segment on which kingen.verify.boundaries bisects to the
boundary. Where none does, the search says how low the margin came, from what and in how
many steps: the region where the boundary provably was not found.
"""

from dataclasses import dataclass

import numpy as np

from ..conventions import t6_from_pose
from ..kinematics.reference import limb_solution, solve
from ..kinematics.routine import SINGULAR_TOLERANCE
from ..kinematics.singularity import posture_direct_index

SEEDS = 256
"""Poses drawn to start from: half in the rays' region, half in the wider one (WIDE_TILT_DEG)."""
CHAINS = 16
"""Descents run side by side, from the seeds' lowest margins (a posture each, distinct where
the seeds allow)."""
STARTS = 64
"""Seeds' postures a stalled chain may start again from, lowest margin first."""
STALL = 6
"""Steps without a lower margin after which a chain starts again from the next seed."""
CANDIDATES = 4
"""Random steps tried per chain and descent step; the best that lowers the margin is kept."""
DESCENT_STEPS = 400
"""Descent steps at most: on CEART the direct index's 29.3 mm is met within 16 to 266 steps for
96 of the seeds 0 to 99."""
WIDE_TILT_DEG = 45.0
"""The wider seeds' rotations (each angle within +- this many degrees of home's) and translations
(within half the robot's size of home's)."""
FIRST_STEP = 0.05
"""A step's spread at first, as a fraction of the wider region's half-widths; it grows by
GROW after a kept step and shrinks by SHRINK after none, within STEP_RANGE."""
GROW, SHRINK, STEP_RANGE = 1.5, 0.6, (1e-4, 0.3)
DIRECT_INDEX = "direct_index_min"
"""The boundary sought where the reference's direct index falls to the robot's threshold."""


@dataclass(frozen=True)
class Descent:
    """What a search did: for ``kind``, ``chains`` descents (restarts included) over ``steps``
    steps from ``seeds`` poses (``region``, words) reached ``lowest`` (the least margin, in ``unit``);
    ``crossed`` chains stepped past the boundary."""

    kind: str
    seeds: int
    chains: int
    steps: int
    lowest: float
    unit: str
    region: str
    crossed: int

    def summary(self):
        """One phrase for verify's report: what was searched and how low it came."""
        reached = "met it" if self.crossed else f"came no lower than {self.lowest:.4g} {self.unit} above it"
        return (f"a descent of its margin ({self.chains} chains, {CHAINS} at a time, over {self.steps} steps from "
                f"{self.seeds} seeds in {self.region}) {reached}")


def _margins(robot, kind, solution, postures=None):
    """``kind``'s margin (see the module docstring) of posture ``postures`` (n,) of each pose of
    the reference's ``solution``, or of every posture (n, postures) when None (the solution
    then solved with ``indices`` for the direct index); +inf where the pose is not a valid
    place to be (unreachable, or in a limb's singular band where that decides the warning)."""
    count = len(solution.finite)
    least = np.min(solution.radicands, axis=1)  # +inf for robots of legs only
    if kind == "WARN_SINGULAR_SOLUTION" and not any(limb.has_radicand for limb in robot.limbs) and robot.wrist is None:
        kind = DIRECT_INDEX  # the threshold is that warning's only cause (a wrist's radicands are its own)
    if kind == "WARN_UNREACHABLE":
        margin = (least + SINGULAR_TOLERANCE)[:, None]
    elif kind == "WARN_SINGULAR_SOLUTION":
        margin = np.where(least >= -SINGULAR_TOLERANCE, least - SINGULAR_TOLERANCE, np.inf)[:, None]
    else:
        if kind == DIRECT_INDEX:
            index = (solution.direct_index if postures is None else
                     posture_direct_index(robot, solution.points, solution.branch_joints, postures)[:, None])
            margin = index - robot.direct_index_min
        else:
            lower, upper = (limit[:, None] for limit in robot.travel_limits())
            joints = solution.joints if postures is None else solution.joints[np.arange(count), :, postures][..., None]
            with np.errstate(invalid="ignore"):
                room = np.minimum(joints - lower, upper - joints) / np.where(np.isfinite(upper - lower), upper - lower, 1.0)
            margin = np.min(np.where(np.isnan(room), np.inf, room), axis=1)  # (n, postures or 1)
        margin = np.where((least > SINGULAR_TOLERANCE)[:, None], margin, np.inf)
    margin = np.where(solution.finite[:, None] & ~np.isnan(margin), margin, np.inf)
    return np.broadcast_to(margin, (count, robot.postures)) if postures is None else margin[:, 0]


def _wide_half_widths(robot):
    """(6,) the wider region's half-widths about home: half the robot's size (mm) for x, y, z,
    WIDE_TILT_DEG for each angle; also the scale of a descent's steps."""
    return np.r_[[0.5 * robot.size_mm] * 3, [WIDE_TILT_DEG] * 3]


def _seeds(robot, kind, home, widths, reach, generator):
    """(poses (m, 6), postures (m,), margins (m,), region words): the seeds' valid postures on
    the boundary's good side, lowest margin first, a posture's first appearance before any
    repeat (so that the first chains try distinct postures); at most STARTS of them."""
    wide = _wide_half_widths(robot)
    half = SEEDS // 2
    seeds = home + np.concatenate([generator.uniform(-1.0, 1.0, size=(half, 6)) * widths * reach,
                                   generator.uniform(-1.0, 1.0, size=(SEEDS - half, 6)) * wide])
    every = _margins(robot, kind, solve(robot, t6_from_pose(seeds), indices=kind == DIRECT_INDEX))  # (seeds, postures)
    order = [divmod(int(flat), robot.postures) for flat in np.argsort(every, axis=None, kind="stable")
             if 0.0 < every.flat[flat] < np.inf][:STARTS]
    seen = set()
    firsts = [pair for pair in order if pair[1] not in seen and not seen.add(pair[1])]
    ranked = firsts + [pair for pair in order if pair not in firsts]
    rows = np.array([seed for seed, _ in ranked], dtype=int)
    postures = np.array([posture for _, posture in ranked], dtype=int)
    region = (f"home +- {reach:g} x the verification range, and home +- {0.5 * robot.size_mm:.4g} mm and "
              f"+- {WIDE_TILT_DEG:g} degrees")
    return seeds[rows], postures, every[rows, postures], region


def descend(robot, kind, home, widths, reach, generator):
    """(origins (m, 6), directions (m, 6), Descent): segments origin + t direction (0 <= t <= 1,
    poses in mm and degrees) each crossing ``kind``'s boundary from its good side, for
    ``robot`` calibrated as the routine is called; none when the search did not meet it.
    A chain that has not lowered its margin for STALL steps starts again from the next seed."""
    starts, start_postures, start_margins, region = _seeds(robot, kind, home, widths, reach, generator)
    unit = "mm" if kind == DIRECT_INDEX else "of the travel" if kind == "WARN_JOINT_LIMITS_EXCEEDED" else "in D"
    chains = min(CHAINS, len(starts))
    lowest = float(np.min(start_margins)) if len(starts) else np.inf
    if not chains:
        return np.zeros((0, 6)), np.zeros((0, 6)), Descent(kind, SEEDS, 0, 0, lowest, unit, region, 0)
    poses, postures, margin = starts[:chains].copy(), start_postures[:chains].copy(), start_margins[:chains].copy()
    following = chains
    scale = _wide_half_widths(robot)
    spread, stalled = np.full(chains, FIRST_STEP), np.zeros(chains, dtype=int)
    for step in range(1, DESCENT_STEPS + 1):
        candidates = poses[:, None, :] + generator.normal(size=(chains, CANDIDATES, 6)) * (spread[:, None, None] * scale)
        solution = limb_solution(robot, t6_from_pose(candidates.reshape(-1, 6)))
        values = _margins(robot, kind, solution, np.repeat(postures, CANDIDATES)).reshape(chains, CANDIDATES)
        best = np.argmin(values, axis=1)
        value, chosen = values[np.arange(chains), best], candidates[np.arange(chains), best]
        lower = value < margin
        crossed = lower & (value <= 0.0)
        if np.any(crossed):
            return poses[crossed], chosen[crossed] - poses[crossed], Descent(
                kind, SEEDS, following, step, float(np.min(value)), unit, region, int(np.sum(crossed)))
        poses[lower], margin[lower] = chosen[lower], value[lower]
        lowest = min(lowest, float(np.min(margin)))
        spread = np.clip(np.where(lower, spread * GROW, spread * SHRINK), *STEP_RANGE)
        stalled = np.where(lower, 0, stalled + 1)
        for chain in np.flatnonzero(stalled >= STALL)[:len(starts) - following]:
            poses[chain], postures[chain], margin[chain] = starts[following], start_postures[following], \
                start_margins[following]
            spread[chain], stalled[chain], following = FIRST_STEP, 0, following + 1
    return np.zeros((0, 6)), np.zeros((0, 6)), Descent(kind, SEEDS, following, DESCENT_STEPS, lowest, unit, region, 0)
