"""A G-code program's moves timed as LinuxCNC's trajectory planner moves them (LinuxCNC 2.9's
``src/emc/tp``), at 100 % feed override: each move's speed at every point of its path.

The moves become the planner's segments and blends (:mod:`.blends`). Along a chain of segments
that do not stop between them, the planner looks ahead: each segment ends no faster than the
rest of the chain lets the tool stop by its end (``[TRAJ] ARC_BLEND_OPTIMIZATION_DEPTH``
segments ahead, the chain's end taken as a stop beyond them), no faster than the junction allows
(the two segments' top speeds, a kink's speed; 0 at a stop), and the tool speeds up from where
the last segment left it. Within a segment the speed is the trapezoid (or triangle) of its
tangential acceleration between its start and end speeds, capped by its top speed.

A move's path coordinate s (mm, along its programmed xyz path) maps onto the segments that
follow it: where a blend arc cuts the corner, the stretch of the move it replaces is followed on
the arc (:meth:`Plan.blended`: the places checked there are the arc's), s mapped linearly onto
the arc's half, and timed at the arc's speed (:meth:`Plan.rates`).

What stays approximate: a parabolic blend (a move that turns A B C, ``ARC_BLEND_ENABLE = 0``,
or where it is faster than a blend arc) times each move rest to rest at half acceleration and
adds, where the next move has started (:meth:`Plan.overlap`), the joints' speeds along the next
move at its start, not along the path the overlap cuts; a corner between an arc and a move not tangent to it gets the tangent
or parabolic treatment, not LinuxCNC's line-arc blend arc; G64's Q merges straight moves
(:func:`merged`) but does not turn arcs within Q of their chord into lines; the planner's velocity ramp for segments shorter than a few
periods and its consumption of a very short move by a blend arc are not modelled; a lower feed
ahead is slowed for in time (LinuxCNC may enter it faster and slow down inside).
"""

import math
from dataclasses import dataclass, replace

import numpy as np

from .blends import join, overlap, segment
from .timing import profile


@dataclass(frozen=True)
class Plan:
    """One move's speed along its path as the planner moves it: ``length`` its xyz path (mm),
    ``speed`` and ``acceleration`` the largest top speed (mm/s) and tangential acceleration
    (mm/s^2) of the segments it follows; ``parts`` (k, 19) rows s0, s1 (the move's stretch, mm),
    sigma0, sigma1 (the segment's, mm), the segment's length, top speed, tangential acceleration,
    start and end speeds, and for a blend arc its circle (centre, unit vectors to its start and
    along its start, radius; NaN for the programmed path); where the move ends in a parabolic
    blend, ``tail`` (its speed below which the next move starts, the next's speed when this one
    ends from that speed, this move's and the next's tangential acceleration, the next's top
    speed; mm/s, mm/s^2) and ``following`` the next Move."""

    length: float
    speed: float
    acceleration: float
    parts: np.ndarray
    tail: tuple = None
    following: object = None

    def overlap(self, s):
        """(n,) the next move's speed (mm/s) while the tool passes path coordinates ``s`` (n,; mm)
        of this move's end in a parabolic blend (0 elsewhere): the next move starts when this one,
        slowing down, passes below the blend's speed (below its own peak for a move that never
        reaches it) and speeds up while this one slows to its end, its speed the blend's share of
        this one's loss, at most what its acceleration allows (tp.c's tpUpdateBlend)."""
        if self.tail is None:
            return np.zeros(len(s))
        blend, reached, own, accel, top = self.tail
        _, _, _, _, length, cap, tangential, first, last = self.parts[-1, :9]
        start = min(blend, cap, math.sqrt((first ** 2 + last ** 2) / 2.0 + tangential * length))
        rate, change = self.rates(s)
        slowing = (change < 0.0) & (rate < start) & (np.asarray(s) > self.parts[-1, 0])
        lost = start - rate
        return np.where(slowing, np.minimum(np.minimum(lost * reached / blend, accel * lost / own), top), 0.0)

    def _rows(self, s):
        """Each of path coordinates ``s`` (n,): the row of the part it lies on."""
        return np.minimum(np.searchsorted(self.parts[:, 1], s, side="left"), len(self.parts) - 1)

    @property
    def arcs(self):
        """Whether a blend arc follows part of the move."""
        return bool(np.any(np.isfinite(self.parts[:, 18])))

    def blended(self, s):
        """(mask (n,), xyz (m, 3) mm): which of path coordinates ``s`` (n,; mm) lie where a blend arc
        replaces the programmed path, and the arc's points there."""
        s = np.asarray(s, dtype=float)
        return _arc_points(self.parts[self._rows(s)], s)

    def rates(self, s):
        """(ds/dt mm/s, d2s/dt2 mm/s^2) (n,) at path coordinates ``s`` (n,; mm): the tool's speed and
        tangential acceleration divided by d sigma/ds (1 on the programmed path; on a blend, the
        arc's half over the stretch of the move it replaces)."""
        s = np.asarray(s, dtype=float)
        return _path_rates(self.parts[self._rows(s)], s)


def _sigma(rows, s):
    """The place on each part's segment (mm) of path coordinates ``s`` (n,) on parts ``rows`` (n, 19)."""
    s0, s1, sigma0, sigma1, length = rows[:, :5].T
    span = np.where(s1 > s0, s1 - s0, 1.0)
    return np.minimum(np.maximum(sigma0 + (s - s0) * (sigma1 - sigma0) / span, 0.0), length)


def _path_rates(rows, s):
    """Plan.rates of path coordinates ``s`` (n,) on parts ``rows`` (n, 19)."""
    sigma = _sigma(rows, s)
    s0, s1, sigma0, sigma1, length, top, accel, start, end = rows[:, :9].T
    scale = np.where(s1 > s0, (sigma1 - sigma0) / np.where(s1 > s0, s1 - s0, 1.0), 1.0)
    rising = np.sqrt(start ** 2 + 2.0 * accel * sigma)
    falling = np.sqrt(end ** 2 + 2.0 * accel * (length - sigma))
    rate = np.minimum(top, np.minimum(rising, falling))
    change = np.where(rising < np.minimum(top, falling), accel, np.where(falling < np.minimum(top, rising), -accel, 0.0))
    return rate / scale, change / scale


def _arc_points(rows, s):
    """Plan.blended of path coordinates ``s`` (n,) on parts ``rows`` (n, 19)."""
    on = np.isfinite(rows[:, 18])
    circle = rows[on, 9:]
    angle = _sigma(rows[on], s[on]) / circle[:, 9]
    xyz = circle[:, :3] + circle[:, 9:10] * (np.cos(angle)[:, None] * circle[:, 3:6]
                                             + np.sin(angle)[:, None] * circle[:, 6:9])
    return on, xyz


class Stack:
    """Many Plans' parts stacked, to look up many moves' samples at once: ``which`` (n,) the
    plan of each sample (index into the plans given), ``s`` (n,) its path coordinate (mm)."""

    def __init__(self, plans):
        counts = [len(plan.parts) for plan in plans]
        self.parts = np.concatenate([plan.parts for plan in plans]) if plans else np.zeros((0, 19))
        self.offsets = np.concatenate([[0], np.cumsum(counts)]).astype(int)
        self.scale = np.array([1.0 / (plan.length * (1.0 + 1e-12)) for plan in plans])
        owner = np.repeat(np.arange(len(plans)), counts)
        self.keys = owner + self.parts[:, 1] * self.scale[owner]

    def rows(self, which, s):
        """(n,) the stacked row of the part each sample lies on."""
        row = np.searchsorted(self.keys, which + s * self.scale[which], side="left")
        return np.minimum(np.maximum(row, self.offsets[which]), self.offsets[which + 1] - 1)

    def rates(self, which, s):
        """(ds/dt, d2s/dt2, the part's index within its plan) (n,) of the samples (Plan.rates)."""
        row = self.rows(which, s)
        return (*_path_rates(self.parts[row], s), row - self.offsets[which])

    def blended(self, which, s):
        """Plan.blended of the samples."""
        return _arc_points(self.parts[self.rows(which, s)], s)


def _speeds(chain, start, depth, last):
    """(start speeds, end speeds) (n,) of a chain of Segments (``start``: the first's start speed,
    mm/s), each ending at rest after ``depth`` segments of look-ahead; ``last``: the chain ends the
    program, its last segment never finalized (the planner lets the one before it end no faster
    than the last's triangle, as if the last could be cut to half)."""
    count = len(chain)
    top = np.array([segment.target for segment in chain])
    accel = np.array([segment.tangential for segment in chain])
    length = np.array([segment.length for segment in chain])
    junction = np.array([min(segment.end, top[index], top[index + 1]) if index + 1 < count and segment.end > 0.0
                         else 0.0 for index, segment in enumerate(chain)])
    reach = 2.0 * accel * length
    if last:
        reach[-1] /= 2.0
    finals, first = np.zeros(count), np.arange(count)
    for ahead in range(depth, 0, -1):  # every segment's window at once, from its far end back
        index = first + ahead
        within = index < count
        index = np.minimum(index, count - 1)
        finals = np.where(within, np.minimum(junction[index - 1], np.sqrt(finals ** 2 + reach[index])), finals)
    starts, ends = np.empty(count), np.empty(count)
    speed = start
    for index in range(count):
        starts[index] = speed
        speed = min(finals[index], math.sqrt(speed ** 2 + 2.0 * accel[index] * length[index]))
        ends[index] = speed
    return starts, ends


class _Queue:
    """The planner's queue between stops: Segments joined as they come, planned and handed out
    move by move when the chain stops (or grows past twice the look-ahead)."""

    def __init__(self, limits):
        machine = limits.machine
        self.machine = machine
        speeds = machine.axis_speed.copy()
        accelerations = machine.axis_acceleration.copy()
        if limits.path_acceleration is not None:
            accelerations[:3] = np.where(np.isfinite(accelerations[:3]), accelerations[:3], limits.path_acceleration)
        self.speeds, self.accelerations = speeds, accelerations
        self.bounds = (speeds[:3].tolist(), accelerations[:3].tolist())
        self.limit = limits.path_speed if limits.path_speed is not None else math.inf
        self.chain, self.moves, self.start = [], {}, 0.0

    def add(self, number, move):
        """Queue ``move`` (the program's ``number``-th); False when the planner does not time it."""
        new = segment(number, move, self.speeds, self.accelerations, self.limit, self.machine.cycle)
        if new is None:
            return False
        if self.chain:
            arc = join(self.chain[-1], new, self.machine, self.bounds)
            if arc is not None:
                self.chain.append(arc)
        self.chain.append(new)
        self.moves[number] = move
        return True

    def ready(self):
        """Whether the queued chain ends at rest (its last junction made; one segment more after
        a parabolic blend, whose overlap depends on whether the next is the program's last) or
        has grown long."""
        return self._cut() is not None or len(self.chain) > 4 * self.machine.depth + 2

    def _cut(self):
        """The number of queued segments before a stop that may be planned now, or None."""
        chain = self.chain
        if len(chain) > 1 and chain[-2].end == 0.0 and chain[-2].overlap is None:
            return len(chain) - 1
        if len(chain) > 2 and chain[-3].end == 0.0 and chain[-3].overlap is not None:
            return len(chain) - 2
        return None

    def plans(self, final=False):
        """(move, Plan) of the moves whose segments are all planned: every queued move when
        ``final``; else those before the stop that ends the chain, or those more than the
        look-ahead before its end (the rest stay queued, the tool's speed where they start kept)."""
        chain = self.chain
        if not chain:
            return []
        cut = len(chain) if final else self._cut() or len(chain) - self.machine.depth - 1
        if final and chain[-1].mode == "G64":
            chain[-1].halved = True  # its end still a parabolic blend: nothing follows to blend with
        starts, ends = _speeds(chain, self.start, self.machine.depth, final)
        parts, last = {}, {}
        for index, piece in enumerate(chain):
            row = [piece.length, piece.target, piece.tangential, starts[index], ends[index],
                   *(piece.circle if piece.circle is not None else [np.nan] * 10)]
            for number, s0, s1, sigma0, sigma1 in piece.parts:
                parts.setdefault(number, []).append([s0, s1, sigma0, sigma1, *row])
                last[number] = index
        done = {number for number, index in last.items() if index < cut}
        tails = {piece.parts[-1][0]: (*overlap(piece, chain[index + 1], final and index + 2 == len(chain)),
                                      piece.tangential, chain[index + 1].tangential, chain[index + 1].target,
                                      chain[index + 1].parts[0][0])
                 for index, piece in enumerate(chain[:-1]) if piece.overlap is not None}
        kept = [index for index, piece in enumerate(chain) if any(part[0] not in done for part in piece.parts)]
        self.chain, self.start = chain[kept[0]:] if kept else [], starts[kept[0]] if kept else 0.0
        if kept:
            self.chain[0].parts = [part for part in self.chain[0].parts if part[0] not in done]
        result, moves = [], dict(self.moves)
        for number in sorted(done):
            rows = np.array(sorted(parts[number]))
            tail = tails.get(number)
            result.append((self.moves.pop(number), Plan(
                float(rows[-1, 1]), float(np.max(rows[:, 5])), float(np.max(rows[:, 6])), rows,
                None if tail is None else tail[:5], None if tail is None else moves.get(tail[5]))))
        return result


CHAIN = 100
"""The most points LinuxCNC's canon merges into one line before it starts another (emccanon.cc)."""


def merged(moves):
    """``moves`` as LinuxCNC's canon hands them to the planner: in G64 with Q (its naive CAM
    detector), a run of straight feeds at one feed and path mode, without A B C motion, whose
    programmed points all lie within Q (mm) of the line from the run's start to its last point
    becomes that one line, named by its last move's line; any other move passes unchanged."""
    chain = []
    for move in moves:
        if chain and not _linkable(chain, move):
            yield _joined(chain)
            chain = []
        mode = move.path_mode
        if (move.kind == "feed" and move.arc is None and mode is not None and mode[0] == "G64" and mode[2] > 0.0
                and np.array_equal(move.start[3:], move.end[3:])):
            chain.append(move)
        else:
            yield from ([_joined(chain)] if chain else [])
            chain = []
            yield move
    if chain:
        yield _joined(chain)


def _linkable(chain, move):
    """Whether ``move`` extends the run ``chain`` (the canon's ``linkable``)."""
    first = chain[0]
    if (move.kind != "feed" or move.arc is not None or move.feed != first.feed or move.path_mode != first.path_mode
            or len(chain) > CHAIN or not np.array_equal(move.start[3:], move.end[3:])):
        return False
    start, step = first.start[:3], move.end[:3] - first.start[:3]
    size = float(np.dot(step, step))
    if size == 0.0:
        return False
    points = np.array([link.end[:3] for link in chain])
    along = np.clip((points - start) @ step / size, 0.0, 1.0)
    return bool(np.all(np.linalg.norm(start + along[:, None] * step - points, axis=1) <= move.path_mode[2]))


def _joined(chain):
    """The one line a run of moves becomes (itself for a run of one)."""
    return chain[0] if len(chain) == 1 else replace(chain[-1], start=chain[0].start)


def planned(moves, limits):
    """(move, timing) of each of ``moves`` (G-code moves, in order) under ``limits``
    (limits.Limits), G64's Q runs merged into one move each (:func:`merged`): a Plan for the moves
    LinuxCNC's planner times (an .ini's X Y Z accelerations, or a [TRAJ] acceleration), else
    timing.profile's (a move that only turns; no .ini)."""
    moves = merged(moves)
    if limits.machine is None or not (limits.machine.accelerated or limits.path_acceleration is not None):
        for move in moves:
            yield move, profile(move, limits)
        return
    queue = _Queue(limits)
    for number, move in enumerate(moves):
        if not queue.add(number, move):
            yield from queue.plans(final=True)
            yield move, profile(move, limits)
        elif queue.ready():
            yield from queue.plans()
    yield from queue.plans(final=True)
