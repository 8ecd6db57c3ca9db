"""The segments LinuxCNC's trajectory planner (``src/emc/tp`` and the task's canon, LinuxCNC 2.9)
makes of a G-code program's moves, and what it does where two meet.

A segment's top speed and acceleration are the canon's: the programmed feed, capped so that no
axis passes its ``[AXIS_L] MAX_VELOCITY`` (each axis's share of the move's direction), the path
acceleration the largest that keeps every axis within its ``MAX_ACCELERATION``, an arc's speed
capped by its normal acceleration (at most sqrt(3)/2 of its axes' acceleration, leaving half
of it for the tangent), and ``[TRAJ] MAX_LINEAR_VELOCITY`` over all.

Where two segments meet (:func:`join`): in exact stop (G61.1), between a rapid and a feed, at a
reversal and where the planner blends parabolically (G64 with a move that turns A B C, or
``ARC_BLEND_ENABLE = 0``) the first ends at rest, both accelerations halved where the blend is
parabolic (each timed rest to rest, the next one started while the first slows, the two
moving at once: :func:`overlap`). Moves whose
directions nearly agree (the change of direction within one period needs less than
``ARC_BLEND_KINK_RATIO`` of the axes' acceleration) run through at their top speed in G61 and
G64. At any other corner in exact path (G61) the first ends at rest and both lose that ratio of
their acceleration (LinuxCNC reserves it for a kink it then does not take); in G64 two straight
moves get LinuxCNC's blend arc (radius from G64's P tolerance, or a quarter of the shorter move
without one, and the normal acceleration) when it is faster than running through at the kink's
speed or a parabolic blend. Units: mm, s, degrees for A B C.
"""

import math
from dataclasses import dataclass, field

import numpy as np

from .sampling import arc_frame, lengths, positions

ACC_RATIO_TANGENTIAL = 0.5
"""The share of the acceleration an arc keeps for speeding up and slowing down (blendmath.h)."""
ACC_RATIO_NORMAL = math.sqrt(1.0 - ACC_RATIO_TANGENTIAL ** 2)
SHARP_CORNER = (math.pi * 2.0 / 180.0) ** 2
"""Two directions within 2 degrees of opposite: a reversal, taken with a stop (tp.c)."""
TOLERANCE_RATIO = 0.25
"""Without a G64 P, a blend may leave the corner by a quarter of the shorter move (tc.c)."""
BLEND_FRACTION = 0.5
"""A blend arc may take at most half of each move it joins (tc_types.h)."""
ANGLE_EPSILON = 1e-6


@dataclass
class Segment:
    """One segment of the planner's queue: ``length`` mm; ``reqvel`` the programmed speed and
    ``maxvel`` the axes' and the arc's cap (mm/s), ``limit`` [TRAJ] MAX_LINEAR_VELOCITY (inf: none);
    ``accel`` the path acceleration (mm/s^2) before the planner's reductions: ``ratio`` (an arc's
    tangential share), ``reduce_start`` and ``reduce_end`` (the kinks' where it starts and ends),
    ``halved`` (a parabolic blend's); ``start`` and ``finish`` its unit directions (3 floats) where
    it starts and ends; ``end`` the speed allowed where it ends (0: at rest); ``mode``
    and ``tolerance`` its path control mode (Move.path_mode's code) and G64's P (mm); ``corner`` the
    programmed end of its move (mm); ``circle`` a blend arc's centre, unit vectors to its start and
    along its start, radius (10,; None for a programmed move); ``overlap`` where it ends in a
    parabolic blend, the cosine between its direction and the next's (None: no such blend); ``parts`` the (move number, s0, s1, sigma0, sigma1) it
    follows: the move's path coordinate s0..s1 (mm) is the segment's sigma0..sigma1."""

    length: float
    reqvel: float
    maxvel: float
    accel: float
    start: tuple
    finish: tuple
    kind: str = "line"
    traverse: bool = False
    rotary: bool = False
    limit: float = math.inf
    ratio: float = 1.0
    reduce_start: float = 0.0
    reduce_end: float = 0.0
    halved: bool = False
    end: float = 0.0
    mode: str = "G64"
    tolerance: float = 0.0
    nominal: float = 0.0
    corner: np.ndarray = None
    circle: np.ndarray = None
    overlap: float = None
    parts: list = field(default_factory=list)

    @property
    def target(self):
        """Top speed at 100 % feed override (mm/s)."""
        return min(self.reqvel, self.maxvel, self.limit)

    def top(self, scale):
        """Top speed at feed override ``scale`` (what blends are planned for)."""
        return min(self.reqvel * scale, self.maxvel, self.limit)

    @property
    def tangential(self):
        """The acceleration along the path (mm/s^2) after the planner's reductions."""
        return self.accel * (1.0 - max(self.reduce_start, self.reduce_end)) * (0.5 if self.halved else 1.0) * self.ratio


def _axis_times(delta, caps):
    """The longest time any axis needs for its share ``delta`` (6,) at rates ``caps`` (6,)."""
    return max((share / cap for share, cap in zip(delta, caps) if share > 1e-9 and cap < math.inf), default=0.0)


def _unit(vector):
    size = math.sqrt(sum(value * value for value in vector))
    return tuple(value / size for value in vector)


def _direction(move, at):
    """The unit tangent (3 floats) of ``move``'s xyz path at u = ``at`` (0 or 1)."""
    if move.arc is None:
        step = move.end[:3] - move.start[:3]
    else:
        du = 1e-7 if at == 0 else -1e-7
        step = (positions(move, [at + du])[0] - positions(move, [at])[0]) * (1.0 if at == 0 else -1.0)
    return _unit(step.tolist())


def segment(number, move, speeds, accelerations, limit, cycle):
    """The Segment LinuxCNC makes of ``move`` (the program's ``number``-th) under axis ``speeds`` and
    ``accelerations`` (6,; mm and degrees per s, per s^2; inf: none) and [TRAJ] ``limit`` (mm/s),
    or None for a move without xyz motion or feed (timed otherwise)."""
    distance, _ = lengths(move)
    if distance == 0.0 or (move.kind != "rapid" and move.feed is None):
        return None
    delta = np.abs(move.end - move.start).tolist()
    chord = math.sqrt(sum(value * value for value in delta[:3]))
    t_speed, t_accel = _axis_times(delta, speeds), _axis_times(delta, accelerations)
    maxvel = chord / t_speed if t_speed > 0.0 else math.inf
    accel = chord / t_accel if t_accel > 0.0 else math.inf
    kind, ratio = "line", 1.0
    if move.arc is not None:
        kind = "arc"
        maxvel, accel, ratio = _arc_caps(move, speeds, accelerations, t_speed, t_accel, distance)
    reqvel = maxvel if move.kind == "rapid" else min(move.feed / 60.0, maxvel)
    maxvel = min(maxvel, distance / cycle)
    mode, tolerance, _ = move.path_mode if move.path_mode is not None else ("G61.1", 0.0, 0.0)
    return Segment(distance, reqvel, maxvel, accel, _direction(move, 0), _direction(move, 1), kind,
                   traverse=move.kind == "rapid", rotary=any(value > 0.0 for value in delta[3:]), limit=limit, ratio=ratio,
                   mode=mode, tolerance=tolerance, nominal=distance, corner=move.end[:3].copy(),
                   parts=[[number, 0.0, distance, 0.0, distance]])


def _arc_caps(move, speeds, accelerations, t_speed, t_accel, distance):
    """(maxvel, acceleration, tangential share) of an arc: the canon's caps from the plane's axes
    and the planner's split of the acceleration between the normal and the tangent."""
    first, second, normal = move.arc.axes
    r0, r1, _, sweep = arc_frame(move)
    spiral = (r1 - r0) / abs(sweep)
    radius = math.hypot(spiral, min(r0, r1))
    plane_speed = min(speeds[first], speeds[second])
    plane_accel = min(accelerations[first], accelerations[second])
    planar = min(math.sqrt(ACC_RATIO_NORMAL * plane_accel * radius), plane_speed)
    spiral_length = math.hypot(min(r0, r1) * abs(sweep), r1 - r0)
    maxvel = distance / max(t_speed, spiral_length / planar)
    accel = distance / max(t_accel, spiral_length / plane_accel)
    pitch = abs(move.end[normal] - move.start[normal]) / abs(sweep)
    effective = pitch ** 2 / radius + radius if radius > 0.0 else math.inf
    if maxvel ** 2 / effective > ACC_RATIO_NORMAL * accel:
        return math.sqrt(ACC_RATIO_NORMAL * accel * effective), accel, ACC_RATIO_TANGENTIAL
    return maxvel, accel, math.sqrt(1.0 - (maxvel ** 2 / effective / accel) ** 2)


def _inscribed(binormal, bounds):
    """The largest rate (of ``bounds``, 3 per axis) any direction in the plane normal to the unit
    ``binormal`` can have (blendmath's calculateInscribedDiameter)."""
    return min((bound / math.sqrt(max(1.0 - normal * normal, 1e-12)) for normal, bound in zip(binormal, bounds)
                if 0.0 < bound < math.inf), default=math.inf)


def _stop(previous):
    """End ``previous`` at rest (no blend arc)."""
    previous.end = 0.0
    return None


def join(previous, current, machine, bounds):
    """Join ``current`` to the ``previous`` Segment as the planner does (``machine``:
    limits.Machine; ``bounds`` (3 floats, 3 floats): the X Y Z speed and acceleration caps): sets
    previous.end and the reductions; the blend arc Segment between them when one is made (the
    two trimmed), else None."""
    if previous.mode == "G61.1" or previous.traverse != current.traverse:
        return _stop(previous)
    u1, u2 = previous.finish, current.start
    dot = min(max(sum(a * b for a, b in zip(u1, u2)), -1.0), 1.0)
    if previous.mode == "G64" and (previous.rotary or current.rotary or not machine.arc_blends):
        return _parabolic_blend(previous, current, dot)
    if previous.rotary or current.rotary or 2.0 + 2.0 * dot < SHARP_CORNER:
        return _stop(previous)
    top = min(previous.top(machine.feed_scale), current.top(machine.feed_scale))
    jump = top / machine.cycle + current.accel
    scale = max(jump * abs(b - a) / bound for a, b, bound in zip(u1, u2, bounds[1]))
    if "arc" in (previous.kind, current.kind):
        scale /= ACC_RATIO_TANGENTIAL
    if scale < machine.kink_ratio:
        previous.end = top
        previous.reduce_end, current.reduce_start = scale, scale
        return None
    if previous.mode == "G61":
        previous.reduce_end, current.reduce_start = machine.kink_ratio, machine.kink_ratio
        return _stop(previous)
    kink = top * machine.kink_ratio / scale
    parabolic = _parabolic(previous, current, dot, 0.5)[2] / 2.0
    arc = _blend_arc(previous, current, machine, bounds, dot) if previous.kind == current.kind == "line" else None
    best = max(parabolic, kink, arc.maxvel if arc is not None else 0.0)
    if arc is not None and arc.maxvel == best:
        return arc
    if kink == best:
        previous.end = kink
        previous.reduce_end, current.reduce_start = machine.kink_ratio, machine.kink_ratio
        return None
    return _parabolic_blend(previous, current, dot)


def _parabolic_blend(previous, current, dot):
    """A parabolic blend: both accelerations halved, ``previous`` ending at rest as its own
    profile, its ``overlap`` the cosine between the two directions (:func:`overlap` times the
    next move's start while the first slows down)."""
    previous.halved = current.halved = True
    previous.overlap = dot
    return _stop(previous)


def overlap(previous, current, last):
    """(the first's speed below which the next starts, the next's speed when the first ends at
    that speed) of the parabolic blend between two Segments as LinuxCNC runs it (``last``: the
    second is the program's last, whose length the planner never finalizes)."""
    return _parabolic(previous, current, previous.overlap, 1.0, 0.5 if last else 1.0)[:2]


def _parabolic(previous, current, dot, fraction, next_fraction=None):
    """(the first's, the second's, the net) speed of a parabolic blend (tp.c's
    tpComputeBlendVelocity: both accelerations halved; each move's triangle over ``fraction`` of
    it, the second's over ``next_fraction`` (default the same): 0.5 as the planner estimates a
    blend or for a move not finalized, 1 as it runs one)."""
    theta = math.acos(-dot) / 2.0
    speeds = []
    for segment_, share in ((previous, fraction), (current, fraction if next_fraction is None else next_fraction)):
        accel = segment_.accel * segment_.ratio * 0.5
        speeds.append((min(math.sqrt(accel * segment_.length * share), segment_.target), accel))
    t_reach = min(previous.length / speeds[0][0], current.length / speeds[1][0])
    t_blend = min(t_reach, max(speed / accel for speed, accel in speeds))
    blend = [min(speed, t_blend * accel) for speed, accel in speeds]
    tolerance = previous.tolerance
    if tolerance > 0.0 and math.cos(theta) > math.cos(math.pi / 2.0 - 1e-3):
        cap = 2.0 * math.sqrt(speeds[0][1] * tolerance / math.cos(theta))
        blend = [min(value, cap) for value in blend]
    return blend[0], blend[1], math.sin(theta) * sum(blend) / 2.0


def _blend_arc(previous, current, machine, bounds, dot):
    """The blend arc between two straight segments (blendmath.c's line-line blend), or None
    where the planner makes none; trims the two when it is made."""
    theta = math.acos(-dot) / 2.0
    if math.pi / 2.0 - theta < ANGLE_EPSILON or theta < ANGLE_EPSILON:
        return None
    phi = math.pi - 2.0 * theta
    tolerances = [segment_.tolerance if segment_.tolerance > 0.0 else segment_.nominal * TOLERANCE_RATIO
                  for segment_ in (previous, current)]
    tolerance = min(min(tolerances), previous.nominal * TOLERANCE_RATIO, current.nominal * TOLERANCE_RATIO)
    (x1, y1, z1), (x2, y2, z2) = previous.finish, current.start
    binormal = _unit((y1 * z2 - z1 * y2, z1 * x2 - x1 * z2, x1 * y2 - y1 * x2))
    a_max = _inscribed(binormal, bounds[1])
    a_normal = a_max * ACC_RATIO_NORMAL
    v_req = max(previous.top(1.0), current.top(1.0))
    v_goal = max(previous.top(machine.feed_scale), current.top(machine.feed_scale))
    phi_effective = min(phi, math.pi * 0.49)
    v1 = min(previous.maxvel, current.maxvel / math.cos(phi_effective))
    v2 = min(current.maxvel, previous.maxvel / math.cos(phi_effective))
    base = math.sqrt(sum((b * v2 - a * v1) ** 2 for a, b in zip(previous.finish, current.start)))
    altitude = v1 * v2 * math.sin(phi) / base if base > 0.0 else math.inf
    v_goal = min(v_goal, max(altitude, _inscribed(binormal, bounds[0])))
    d_tol = math.cos(theta) * tolerance / (1.0 - math.sin(theta))
    d_geom = min(min(previous.length, previous.nominal * BLEND_FRACTION), current.length * BLEND_FRACTION, d_tol)
    r_geom = math.tan(theta) * d_geom
    v_plan = min(math.sqrt(a_normal * r_geom), v_goal)
    a_parabolic = a_max * 0.5
    t_blend = min(math.sqrt(2.0 * a_parabolic * d_geom), v_plan) / a_parabolic
    radius = max(v_plan ** 2 / a_normal, min(t_blend * v_plan / phi, r_geom))
    if radius < 1e-12 or radius * phi < 1e-6:
        return None
    trim = radius / math.tan(theta)
    inward = np.array(_unit([b - a for a, b in zip(previous.finish, current.start)]))
    center = previous.corner + inward * radius / math.sin(theta)
    start = previous.corner - np.array(previous.finish) * trim
    arc = Segment(radius * phi, v_req, v_plan, a_max, previous.finish, current.start, "blend",
                  traverse=current.traverse, limit=current.limit, ratio=ACC_RATIO_TANGENTIAL, mode=current.mode,
                  tolerance=current.tolerance, nominal=radius * phi,
                  circle=np.concatenate([center, (start - center) / radius, previous.finish, [radius]]))
    _trim(previous, trim, arc, at_end=True)
    _trim(current, trim, arc, at_end=False)
    previous.end = arc.end = math.inf
    return arc


def _trim(segment_, trim, arc, at_end):
    """Shorten ``segment_`` by ``trim`` mm at its end (or start); that stretch of its move is
    followed by half the blend ``arc``."""
    half = arc.length / 2.0
    trim = min(trim, segment_.length)  # a blend may take all that is left of a move (rounding aside)
    if at_end:
        number, s0, s1, sigma0, sigma1 = segment_.parts[-1]
        segment_.parts[-1] = [number, s0, s1 - trim, sigma0, sigma1 - trim]
        arc.parts.insert(0, [number, s1 - trim, s1, 0.0, half])
    else:
        number, s0, s1, sigma0, sigma1 = segment_.parts[0]
        segment_.parts[0] = [number, s0 + trim, s1, sigma0, sigma1 - trim]
        arc.parts.append([number, s0, s0 + trim, half, arc.length])
    segment_.length -= trim
