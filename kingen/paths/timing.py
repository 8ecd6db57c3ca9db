"""How fast a move goes along its path, and what that asks of the joints.

Each move is timed on its own, starting and ending at rest, with a trapezoidal speed profile:
the path accelerates at the ``.ini``'s [TRAJ] acceleration to the programmed feed (capped by
[TRAJ] MAX_LINEAR_VELOCITY), cruises, and decelerates to a stop at the move's end (a triangle
when the move is too short to reach the feed), as LinuxCNC's planner times exact-stop moves
(G61). Blending of consecutive moves (G64) is not modelled: a blended corner keeps some speed
and turns the path's velocity instead, which this timing does not see.

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

    def at(self, s):
        """(ds/dt, d2s/dt2) at path coordinates ``s`` (n,)."""
        if self.acceleration is None:
            return np.full(len(s), self.speed), np.zeros(len(s))
        a = self.acceleration
        rising = np.sqrt(2.0 * a * np.clip(s, 0.0, None))
        falling = np.sqrt(2.0 * a * np.clip(self.length - s, 0.0, None))
        speed = np.minimum(self.speed, np.minimum(rising, falling))
        acceleration = np.where(rising < np.minimum(self.speed, falling), a,
                                np.where(falling < np.minimum(self.speed, rising), -a, 0.0))
        return speed, acceleration


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


def joint_rates(joints, s, revolute, move_profile):
    """(speeds, accelerations) (n, dof) of the joints (n, dof; mm or rad) sampled at path
    coordinates ``s`` (n,), by finite differences along the path (revolute joints unwrapped)
    and the chain rule: dq/dt = q' ds/dt, d2q/dt2 = q'' (ds/dt)^2 + q' d2s/dt2 (zeros for a
    single sample)."""
    joints = np.where(revolute, np.unwrap(joints, axis=0), joints) if np.any(revolute) else joints
    if len(s) < 2:
        return np.zeros_like(joints), np.zeros_like(joints)
    first = np.gradient(joints, s, axis=0)
    second = np.gradient(first, s, axis=0) if len(s) > 2 else np.zeros_like(first)
    speed, acceleration = move_profile.at(s)
    return first * speed[:, None], second * (speed ** 2)[:, None] + first * acceleration[:, None]
