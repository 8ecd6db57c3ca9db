"""The check of a whole program: its moves read one at a time, each sampled in chunks of at
most CHUNK regular samples (at most ``chord`` mm and degrees apart), refined and bisected
between them (:mod:`.refinement`), solved in batches by the numpy reference, judged, and
forgotten: memory does not grow with the program.

Joint speeds and accelerations are judged at the regular samples (finite differences along
the path, :mod:`.timing`); the boundaries of travel, reach, the singular bands, the direct
index and the assembly mode at every sample, refined ones included.
"""

import time
from dataclasses import dataclass

import numpy as np

from .evaluation import Evaluator
from .findings import Findings
from .limits import limits_for
from .interpreter import gcode_moves
from .program import csv_moves, is_gcode, source_lines
from .refinement import refined
from .sampling import lengths, poses_and_t6, sample_count
from .timing import joint_rates, profile

CHUNK = 20000
"""Regular samples solved at once."""
DEFAULT_CHORD = 0.1
"""mm and degrees between regular samples."""
RATE_ROUNDING = 1e-9
"""A joint speed or acceleration above its limit by at most this fraction of it is rounding
(a joint that follows the path one to one, at the path's own limit), not a problem."""


@dataclass(frozen=True)
class Settings:
    """What a check is run with: the host whose interpolation is followed ('linuxcnc' or
    'delmia'), the posture (None: the robot's working posture), the chord (mm and degrees),
    the LinuxCNC .ini (None: the robot file's limits only)."""

    host: str = "linuxcnc"
    posture: int = None
    chord: float = DEFAULT_CHORD
    ini: object = None


@dataclass
class Outcome:
    """A finished check: the robot, program, settings, limits, the evaluator (its checks), the
    findings, the source text of every line named, the seconds it took."""

    robot: object
    program: str
    settings: Settings
    posture: int
    limits: object
    evaluator: object
    findings: Findings
    sources: dict
    seconds: float


class _Checker:
    def __init__(self, robot, settings, sink, progress):
        self.robot, self.settings, self.sink, self.progress = robot, settings, sink, progress
        self.posture = robot.working_posture if settings.posture is None else settings.posture
        self.limits = limits_for(robot, settings.ini)
        self.evaluator = Evaluator(robot, self.posture, self.limits)
        scale = np.where(robot.revolute, 180.0 / np.pi, 1.0)
        self.findings = Findings(robot.joint_names, scale)

    def evaluate(self, move, u):
        poses, t6 = poses_and_t6(move, u, self.settings.host)
        return self.evaluator.evaluate(u, poses, t6)

    def move(self, index, move):
        """Sample, refine, solve and judge one move."""
        count = sample_count(move, self.settings.chord)
        timing = profile(move, self.limits)
        self.findings.moves += 1
        self.findings.timed_moves += timing is not None
        distance, turn = lengths(move)
        length = timing.length if timing is not None else (distance or turn)
        self.evaluator.assembly_sign = None
        for begin in range(0, count, CHUNK):
            end = min(count, begin + CHUNK)
            low, high = max(0, begin - 1), min(count, end + 1)
            grid = self.evaluate(move, np.arange(low, high + 1) / count)
            if timing is not None:
                speeds, accelerations = joint_rates(grid.joints, grid.u * length, self.robot.revolute, timing)
            else:
                speeds = accelerations = np.full_like(grid.joints, np.nan)
            batch, _ = refined(grid.take(np.arange(begin - low, end - low + 1)), lambda u: self.evaluate(move, u))
            keep = (batch.u < end / count) | (end == count)
            if index > 0 and begin == 0:
                keep &= batch.u > 0.0
            batch = batch.take(np.flatnonzero(keep))
            own = np.arange(begin - low + (index > 0 and begin == 0), end - low + (end == count))
            self._judge(index, move, batch)
            self._judge_rates(index, move, grid.take(own), speeds[own], accelerations[own], timing)
            self._record(move, batch, grid.take(own), speeds[own], accelerations[own], timing is not None)

    def _judge(self, index, move, batch):
        for column, quantity in enumerate(self.evaluator.quantities):
            margins = batch.margins[:, column]
            beyond = np.flatnonzero(margins <= 0.0)
            if len(beyond) == 0:
                continue
            for row in dict.fromkeys((beyond[0], beyond[np.argmin(margins[beyond])])):
                value = self.evaluator.value_of(quantity, batch, row)
                self.findings.add(index, self.findings.place(
                    quantity.kind, quantity.joint, move.line, batch.poses[row], batch.joints[row], value,
                    self.evaluator.limit_of(quantity), margins[row]))

    def _judge_rates(self, index, move, grid, speeds, accelerations, timing):
        if timing is None or len(grid.u) == 0:
            return
        judged = [("joint speed", speeds, self.limits.speed)]
        if timing.acceleration is not None or move.duration is not None:
            judged.append(("joint acceleration", accelerations, self.limits.acceleration))
        for kind, rates, limits in judged:
            for joint in np.flatnonzero(np.isfinite(limits)):
                size = np.abs(rates[:, joint])
                row = int(np.argmax(size))
                if size[row] <= limits[joint] * (1.0 + RATE_ROUNDING):
                    continue
                override = float(limits[joint] / size[row]) if kind == "joint speed" else None
                self.findings.add(index, self.findings.place(
                    kind, joint, move.line, grid.poses[row], grid.joints[row], size[row], limits[joint],
                    (limits[joint] - size[row]) / limits[joint], override))

    def _record(self, move, batch, grid, speeds, accelerations, timed):
        self.findings.update_peaks(move.line, batch.joints, *((speeds, accelerations) if timed else ()))
        self.findings.record_trace(move.line, grid.joints, speeds, accelerations, grid.radicand, grid.direct_index)
        if self.sink is not None:
            at = np.searchsorted(grid.u, batch.u)
            on_grid = (at < len(grid.u)) & (grid.u[np.minimum(at, len(grid.u) - 1)] == batch.u)
            rates = np.full((len(batch.u), 2, self.robot.dof), np.nan)
            rates[on_grid, 0], rates[on_grid, 1] = speeds[at[on_grid]], accelerations[at[on_grid]]
            self.sink(move, batch, rates)
        if self.progress is not None:
            self.progress(self.findings)


def program_moves(path, start):
    """The moves of the program at ``path``: a G-code file through LinuxCNC's interpreter, the
    machine at pose ``start`` (mm, degrees) when it begins; any other file as a CSV of poses
    (which starts at its first row)."""
    return gcode_moves(path, start) if is_gcode(path) else csv_moves(path)


def check_program(robot, program, settings=Settings(), sink=None, progress=None):
    """Check ``program`` (a G-code file or a CSV of poses, :mod:`.program`) on ``robot`` with
    ``settings``: the Outcome. ``sink(move, batch, rates)`` receives every sample as it is
    judged (rates (n, 2, dof): speeds and accelerations, NaN off the regular samples);
    ``progress(findings)`` is called after each chunk. KingenError on bad input."""
    started = time.perf_counter()
    checker = _Checker(robot, settings, sink, progress)
    for index, move in enumerate(program_moves(program, robot.verification.home)):
        checker.move(index, move)
    findings = checker.findings
    named = {place.line for place in list(findings.problems.values()) + list(findings.first.values())
             + list(findings.worst.values())}
    return Outcome(robot, str(program), settings, checker.posture, checker.limits, checker.evaluator, findings,
                   source_lines(program, named), time.perf_counter() - started)
