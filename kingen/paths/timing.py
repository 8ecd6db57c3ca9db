"""How fast a move goes along its path when it is timed on its own, and what the path's speed
asks of the joints.

A move timed on its own starts and ends at rest, with a trapezoidal speed profile: the path
accelerates at the ``.ini``'s [TRAJ] acceleration to the programmed feed (capped by [TRAJ]
MAX_LINEAR_VELOCITY), cruises, and decelerates to a stop at the move's end (a triangle when the
move is too short to reach the feed). G-code moves that LinuxCNC's planner times are timed by
:mod:`.planner` instead (blends, look-ahead, axis limits); this is what is left: a CSV's rows, a
move that only turns, a program checked without an ``.ini``.

The path coordinate s is the xyz length (mm), or the largest orientation change (degrees) of
a move that only turns. A CSV row with ``t`` is traversed at the uniform speed that reaches
it on time; a move without a feed or time (a rapid without an ``.ini``, a CSV without
``feed`` or ``t``) is not timed.
"""

from dataclasses import dataclass

import numpy as np

from .sampling import lengths


@dataclass(frozen=True)
class Profile:
    """A move's path length (mm or degrees), top speed (per s) and path acceleration (per s^2;
    None: the move is taken at ``speed`` throughout and no acceleration is judged)."""

    length: float
    speed: float
    acceleration: float = None

    def rates(self, s):
        """(ds/dt, d2s/dt2) (n,) at path coordinates ``s`` (n,) of this move (see path_rates)."""
        s = np.asarray(s, dtype=float)
        return path_rates(s, self.length, self.speed, np.nan if self.acceleration is None else self.acceleration)


def path_rates(s, length, speed, acceleration):
    """(ds/dt, d2s/dt2) at path coordinates ``s`` of moves of ``length``, top ``speed`` and path
    ``acceleration`` (arrays alike; NaN acceleration: none, the move taken at ``speed``)."""
    timed = np.isfinite(acceleration)
    a = np.where(timed, acceleration, 1.0)
    rising = np.where(timed, np.sqrt(2.0 * a * np.clip(s, 0.0, None)), np.inf)
    falling = np.where(timed, np.sqrt(2.0 * a * np.clip(length - s, 0.0, None)), np.inf)
    rate = np.minimum(speed, np.minimum(rising, falling))
    change = np.where(rising < np.minimum(speed, falling), a, np.where(falling < np.minimum(speed, rising), -a, 0.0))
    return rate, np.where(timed, change, 0.0)


def profile(move, limits):
    """The move's Profile under ``limits`` (kingen.paths.limits.Limits) at the programmed feed
    (100% override), or None when the move is not timed."""
    distance, turn = lengths(move)
    turning_only = distance == 0.0
    length = turn if turning_only else distance
    if length == 0.0:
        return None
    if move.duration is not None:
        return Profile(length, length / move.duration)
    if move.kind == "rapid":
        speed = limits.rapid_speed if not turning_only else None
    elif move.feed is not None:
        speed = move.feed / 60.0
        if limits.path_speed is not None and not turning_only:
            speed = min(speed, limits.path_speed)
    else:
        speed = None
    if speed is None:
        return None
    return Profile(length, speed, None if turning_only else limits.path_acceleration)


def _along(values, s, same):
    """d values / ds (n, dof) by finite differences within runs of equally spaced samples
    (``same`` (n - 1,): whether samples i and i + 1 are of one run), of second order: central
    inside a run, one-sided over three samples at its ends (over two in a run of two), 0 for a
    run of one sample."""
    with np.errstate(invalid="ignore", divide="ignore"):
        forward = np.diff(values, axis=0) / np.diff(s)[:, None]
    forward[~same] = np.nan
    gap = np.full((1, values.shape[1]), np.nan)
    ahead, behind = np.vstack([forward, gap]), np.vstack([gap, forward])
    ahead2, behind2 = np.vstack([ahead[1:], gap]), np.vstack([gap, behind[:-1]])
    start = np.where(np.isnan(ahead2), ahead, 1.5 * ahead - 0.5 * ahead2)
    end = np.where(np.isnan(behind2), behind, 1.5 * behind - 0.5 * behind2)
    return np.where(np.isnan(behind), np.nan_to_num(start), np.where(np.isnan(ahead), end, 0.5 * (ahead + behind)))


def joint_rates(joints, s, run, revolute, rate, change):
    """(speeds, accelerations) (n, dof) of the joints (n, dof; mm or rad) sampled at path
    coordinates ``s`` (n,), equally spaced within each run of samples of one move (``run``
    (n,): which), revolute joints unwrapped: by finite differences along the path and the
    chain rule, dq/dt = q' ds/dt, d2q/dt2 = q'' (ds/dt)^2 + q' d2s/dt2, with the path's speed
    ``rate`` = ds/dt and its change ``change`` = d2s/dt2 at each sample (n,; a timing's rates)."""
    joints = np.where(revolute, np.unwrap(joints, axis=0), joints) if np.any(revolute) else joints
    same = run[1:] == run[:-1]
    first = _along(joints, s, same)
    second = _along(first, s, same)
    return first * rate[:, None], second * (rate ** 2)[:, None] + first * change[:, None]
