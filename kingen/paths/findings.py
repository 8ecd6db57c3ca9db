"""What a program's samples showed, kept in memory that does not grow with the program: each
move's worst place per problem (up to MAX_PROBLEMS of them, the rest counted), the first and
the worst place of each kind of problem, each joint's peaks, and a thinned trace for the
report's figures and its view.

Joint values are reported in the robot file's joint units: mm for prismatic joints, degrees
for revolute ones (speeds per s, accelerations per s^2).
"""

from dataclasses import dataclass, field

import numpy as np

MAX_PROBLEMS = 1000
TRACE_POINTS = 4000
"""The figures' samples at most: the trace keeps every k-th sample, k doubling as it fills."""
UNSCALED = ("unreachable", "limb singular", "joint angle", "actuator load", "actuator power")
"""Kinds whose values are not the joint's (radicands; degrees, N, N m or W already in display units)."""


@dataclass
class Place:
    """One offending place: the check ``kind``, the joint's name (None: the platform's), the
    program line, the pose (mm, degrees), the joints (mm or degrees), the offending ``value``
    and its ``limit`` (the quantity's units), the ``margin`` (below 0: beyond the limit; the
    smaller, the worse), for a joint speed or an actuator power the feed override at which it would fit, for a
    collision the links whose clearance it is ('rods' or 'cranks'), the file ``line`` is in
    when it is not the program's own (a G-code subroutine's; None: the program's), where it
    stands along the program (``sample``: in regular samples, on the trace's axis, fractional
    between two of them; None: not known) and the routine's WARN_* code there (None: not known)."""

    kind: str
    joint: str
    line: int
    pose: list
    joints: list
    value: float
    limit: float
    margin: float
    override: float = None
    between: str = None
    file: str = None
    sample: float = None
    warning: int = None

    def key(self):
        return self.kind, self.joint or self.between


@dataclass
class Peak:
    """One joint's extremes over the program: travel used (lowest, highest), largest speed and
    acceleration with the lines they were reached on."""

    low: float = np.inf
    high: float = -np.inf
    speed: float = 0.0
    speed_line: int = None
    acceleration: float = 0.0
    acceleration_line: int = None


@dataclass
class Findings:
    """The running record of a check (see the module docstring)."""

    joint_names: tuple
    display_scale: np.ndarray
    """Per joint: internal units to display units (1 for mm, 180/pi for rad)."""
    problems: dict = field(default_factory=dict)
    dropped: int = 0
    first: dict = field(default_factory=dict)
    worst: dict = field(default_factory=dict)
    peaks: list = None
    samples: int = 0
    moves: int = 0
    timed_moves: int = 0
    accelerated_moves: int = 0
    """Moves whose joint accelerations are judged (judging.has_accelerations)."""
    trace: dict = field(default_factory=lambda: {"sample": [], "line": [], "poses": [], "joints": [], "warnings": [],
                                                  "speeds": [], "accelerations": [], "radicand": [],
                                                  "direct_index": []})
    trace_stride: int = 1

    def __post_init__(self):
        self.peaks = [Peak() for _ in self.joint_names]

    def place(self, kind, joint, line, pose, joints, value, limit, margin, override=None, between=None, file=None,
              sample=None, warning=None):
        """A Place from internal units (joints in mm or rad) for joint index ``joint`` or None,
        on ``line`` of ``file`` (None: the program), at ``sample`` along the program with the
        routine's ``warning`` there (each None: not known)."""
        scale = self.display_scale
        shown = float(scale[joint]) if joint is not None and kind not in UNSCALED else 1.0
        return Place(kind, None if joint is None else self.joint_names[joint], int(line),
                     [float(v) for v in pose], [float(v) for v in np.asarray(joints) * scale],
                     float(value) * shown, float(limit) * shown, float(margin), override, between, file,
                     None if sample is None else float(sample), None if warning is None else int(warning))

    def add(self, move_index, place):
        """Record ``place`` as its move's problem of its kind (the worst kept) and in the first
        and worst places of its kind."""
        key = (move_index,) + place.key()
        kept = self.problems.get(key)
        if kept is None:
            if len(self.problems) >= MAX_PROBLEMS:
                self.dropped += 1
            else:
                self.problems[key] = place
        elif place.margin < kept.margin:
            self.problems[key] = place
        self.first.setdefault(place.key(), place)
        if place.key() not in self.worst or place.margin < self.worst[place.key()].margin:
            self.worst[place.key()] = place

    def update_peaks(self, joints, lines, speeds, accelerations):
        """Each joint's travel used from ``joints`` (m, dof; internal units) and its largest
        |speed| and |acceleration| (n, dof; NaN where not timed) at samples on program ``lines`` (n,)."""
        scale = self.display_scale
        if len(joints):
            low, high = np.min(joints, axis=0) * scale, np.max(joints, axis=0) * scale
        for index, peak in enumerate(self.peaks):
            if len(joints):
                peak.low, peak.high = min(peak.low, low[index]), max(peak.high, high[index])
            for rates, name in ((speeds, "speed"), (accelerations, "acceleration")):
                size = np.abs(rates[:, index])
                if not np.any(np.isfinite(size)):
                    continue
                row = int(np.nanargmax(size))
                if size[row] * scale[index] > getattr(peak, name):
                    setattr(peak, name, float(size[row] * scale[index]))
                    setattr(peak, f"{name}_line", int(lines[row]))

    def record_trace(self, lines, poses, joints, warnings, speeds, accelerations, radicand, direct_index):
        """Every trace_stride-th sample of a batch (on program ``lines`` (n,); poses (n, 6) mm and
        degrees, the machine's; the routine's WARN_* codes (n,)) for the figures and the report's
        view (display units); when the trace is full it keeps every other point and the stride doubles."""
        count = len(joints)
        take = (self.samples + np.arange(count)) % self.trace_stride == 0
        scale = self.display_scale
        columns = {"sample": self.samples + np.flatnonzero(take), "line": np.asarray(lines)[take],
                   "poses": np.asarray(poses)[take], "joints": joints[take] * scale,
                   "warnings": np.asarray(warnings)[take], "speeds": np.abs(speeds[take]) * scale,
                   "accelerations": np.abs(accelerations[take]) * scale, "radicand": radicand[take],
                   "direct_index": direct_index[take]}
        for name, values in columns.items():
            self.trace[name].append(np.asarray(values))
        self.samples += count
        if sum(len(part) for part in self.trace["sample"]) > TRACE_POINTS:
            for name in self.trace:
                joined = np.concatenate(self.trace[name])
                self.trace[name] = [joined[::2]]
            self.trace_stride *= 2

    def trace_arrays(self):
        """The trace as one array per series."""
        return {name: np.concatenate(parts) if parts else np.empty(0) for name, parts in self.trace.items()}

    def sorted_problems(self):
        """The kept problems by line, then kind."""
        return sorted(self.problems.values(),
                      key=lambda place: (place.file is not None, place.file or "", place.line, place.kind,
                                         place.joint or ""))
