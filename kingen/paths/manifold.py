"""A machine with task coordinates followed along its manifold (docs/how-to/check-path.md).

Such a machine is commanded by its task coordinates only (robot.task: z, roll, pitch or x, y,
z), exactly the words its LinuxCNC module reads (the coordinates its forward solves for:
kingen.kinematics.forward.free_mask);
the other coordinates are parasitic: the machine takes them
(kingen.kinematics.hybrid.parasitic.solve_parasitic). Every sample a check solves is first put on
the manifold here: its task coordinates kept, its parasitic ones the machine's, so each
sample is a pose the machine takes.

A CSV of poses gives six coordinates per row; each row is compared with the machine's pose
for its task coordinates (deviations in mm and degrees; a row whose task coordinates no pose
has is not compared: its samples are unreachable). A row off the manifold (beyond the
routine's manifold_tolerance_mm / MANIFOLD_TOLERANCE_RAD, where the routine would warn) is a problem, kind
``off manifold``, unless the check reads the task coordinates only (``--task-only``): then
it is a notice. Either way the path checked is the machine's, through the rows' task
coordinates. A G-code program's parasitic words are not read.
"""

import itertools
import math

import numpy as np

from ..conventions import angle_difference, pose_from_t6, t6_from_pose
from ..hosts.linuxcnc.render import WORLD_AXES
from ..kinematics.forward import free_mask
from ..kinematics.hybrid.parasitic import MANIFOLD_TOLERANCE_RAD, manifold_tolerance_mm, solve_parasitic
from ..units import number_text
from .moves import Move
from .program import POSE_COLUMNS

OFF_MANIFOLD = "off manifold"
"""The kind of problem a CSV row off the machine's manifold is."""

ROWS_AT_ONCE = 1000
"""How many CSV moves Manifold.moves solves in one machine_poses call."""


def machine_poses(robot, poses):
    """(poses (n, 6) mm and degrees, T6 (n, 4, 4) mm) of the machine at the task coordinates of
    ``poses`` (n, 6): the parasitic coordinates its constraints give (where no pose has these
    task coordinates, the closest approach: the reference then calls it unreachable); the
    pose off the manifold check (``off`` (n,) bool) as the routine decides it."""
    with np.errstate(all="ignore"):
        machine = solve_parasitic(robot, t6_from_pose(np.asarray(poses, dtype=float)))
        return pose_from_t6(machine.t6), machine.t6, machine.off


class Manifold:
    """What a check of a machine with task coordinates keeps: the parasitic coordinates' range
    over every reachable sample, and (for a CSV) the rows' deviations from the machine's poses."""

    def __init__(self, robot, task_only, csv):
        self.robot, self.task_only, self.csv = robot, task_only, csv
        self.task = np.flatnonzero(free_mask(robot))
        self.parasitic = [index for index in range(6) if index not in self.task]
        self.low = np.full(6, np.inf)
        self.high = np.full(6, -np.inf)
        self.rows = self.rows_off = 0
        self.deviation = np.zeros(6)
        self.first_off = None
        """(line, deviations (6,) mm and degrees, 0 for the task coordinates) of the first row off."""

    def samples(self, poses):
        """(poses, T6) of the machine at the task coordinates of sampled ``poses`` (n, 6)."""
        machine, t6, _ = machine_poses(self.robot, poses)
        return machine, t6

    def observe(self, poses, reachable):
        """Keep the parasitic coordinates' range over the machine's ``poses`` (n, 6) where
        ``reachable`` (n,) (elsewhere no pose has the task coordinates: the closest approach
        is no motion of the machine's)."""
        kept = poses[reachable & np.all(np.isfinite(poses), axis=1)]
        if len(kept):
            self.low = np.minimum(self.low, kept.min(axis=0))
            self.high = np.maximum(self.high, kept.max(axis=0))

    def _row(self, line, pose, machine, off, deviation):
        """(the machine's pose for a CSV row's ``pose`` at ``line``, its deviations (6,) where it
        is off the manifold, else None), given ``machine`` (6,) and ``off`` from machine_poses
        and ``deviation`` (6,) from deviations, 0 at the task coordinates; the deviations are
        recorded. A row whose task coordinates no pose has is kept as written (its samples are
        judged unreachable)."""
        if not np.all(np.isfinite(machine)):
            return pose, None
        self.rows += 1
        self.deviation = np.maximum(self.deviation, deviation)
        if off:
            self.rows_off += 1
            if self.first_off is None:
                self.first_off = (line, deviation)
        return machine, deviation if off else None

    def moves(self, moves, findings):
        """A CSV's ``moves`` between the machine's poses at its rows' task coordinates; a row off
        the manifold is added to ``findings`` as a problem unless the check reads task
        coordinates only. The rows are solved ROWS_AT_ONCE moves at a time (one machine_poses
        call each); each move's rows are judged just before it is yielded."""
        moves, start, index = iter(moves), None, 0
        while chunk := list(itertools.islice(moves, ROWS_AT_ONCE)):
            asked = np.array(([chunk[0].start] if start is None else []) + [move.end for move in chunk])
            machine, _, off = machine_poses(self.robot, asked)
            deviation = deviations(asked, machine)
            deviation[:, self.task] = 0.0
            solved = iter(zip(asked, machine, off, deviation))
            for move in chunk:
                if start is None:
                    start, deviation = self._row(move.start_line, *next(solved))
                    self._judge(findings, index, move.start_line, move.start, deviation)
                end, deviation = self._row(move.line, *next(solved))
                self._judge(findings, index, move.line, move.end, deviation)
                yield Move(move.line, move.kind, start, end, feed=move.feed, duration=move.duration, arc=move.arc,
                           start_line=move.start_line)
                start, index = end, index + 1

    def _judge(self, findings, index, line, asked, deviation):
        """A row off the manifold (``deviation``: its deviations, else None) as a problem of
        move ``index``, named by its coordinate farthest beyond its tolerance."""
        if deviation is None or self.task_only:
            return
        coordinate = max(self.parasitic, key=lambda at: deviation[at] / tolerance(self.robot, at))
        limit = tolerance(self.robot, coordinate)
        findings.add(index, findings.place(OFF_MANIFOLD, None, line, asked, np.full(self.robot.dof, np.nan), deviation[coordinate], limit,
                                           limit - deviation[coordinate], between=POSE_COLUMNS[coordinate]))

    def verdict(self):
        """The manifold check's verdict: 'passed', 'failed' or 'not exercised: why'."""
        if not self.csv:
            return f"not exercised: G-code commands the task coordinates only ({self.not_read()} not read: parasitic)"
        if self.task_only:
            return "not exercised: --task-only reads the rows' task coordinates only"
        if self.rows == 0:
            return "not exercised: the program has no move"
        return "failed" if self.rows_off else "passed"

    def not_read(self):
        """The LinuxCNC words the machine does not read, e.g. 'X, Y, C'."""
        return ", ".join(WORLD_AXES[index] for index in self.parasitic)

    def summary(self):
        """Plain data for the report: what is read, the parasitic range over the reachable samples, the
        CSV rows' deviations (mm and degrees)."""
        ranges = {POSE_COLUMNS[index]: [float(self.low[index]), float(self.high[index])] if self.low[index] <= self.high[index]
                  else None for index in self.parasitic}
        first = None if self.first_off is None else {
            "line": self.first_off[0], "deviation": {POSE_COLUMNS[index]: float(self.first_off[1][index])
                                                      for index in self.parasitic}}
        return ranges, {
            "task": [POSE_COLUMNS[index] for index in self.task],
            "read": ", ".join(WORLD_AXES[index] for index in self.task), "not_read": self.not_read(),
            "task_only": self.task_only, "rows": self.rows, "rows_off": self.rows_off,
            "max_deviation": {POSE_COLUMNS[index]: float(self.deviation[index]) for index in self.parasitic}
            if self.csv else None, "first_off": first,
            "tolerance": {"mm": manifold_tolerance_mm(self.robot), "deg": math.degrees(MANIFOLD_TOLERANCE_RAD)}}

    def lines(self):
        """The report's lines about the manifold (display text)."""
        ranges, data = self.summary()
        units = {name: "mm" if name in POSE_COLUMNS[:3] else "deg" for name in POSE_COLUMNS}
        shown = ", ".join(f"{name} {number_text(values[0])} .. {number_text(values[1])} {units[name]}" if values else f"{name} -"
                          for name, values in ranges.items())
        said = [f"task coordinates {data['read']} read; {data['not_read']} not read: parasitic (over the path's reachable samples: {shown})"]
        if self.csv and self.rows:
            worst = ", ".join(f"{name} {number_text(value)} {units[name]}" for name, value in data["max_deviation"].items())
            said.append(f"rows against the machine's poses: {self.rows_off} of {self.rows} off the manifold "
                        f"(largest deviations: {worst})")
            if self.first_off is not None:
                line, deviation = self.first_off
                off = ", ".join(f"{POSE_COLUMNS[at]} {number_text(deviation[at])} {units[POSE_COLUMNS[at]]}" for at in self.parasitic)
                said.append(f"first row off the manifold: line {line} ({off})"
                            + ("; read as its task coordinates (--task-only)" if self.task_only else ""))
        return said


def deviations(asked, machine):
    """(n, 6) |asked - machine| per pose coordinate of poses (n, 6) (mm, and degrees with whole
    turns removed); NaN where either is not finite."""
    with np.errstate(invalid="ignore"):
        deviation = np.abs(asked - machine)
        deviation[:, 3:] = np.degrees(np.abs(angle_difference(np.radians(asked[:, 3:]), np.radians(machine[:, 3:]))))
    return deviation


def tolerance(robot, index):
    """How far pose coordinate ``index`` may be from ``robot``'s (mm or degrees) before the
    routine calls the pose off the manifold."""
    return manifold_tolerance_mm(robot) if index < 3 else math.degrees(MANIFOLD_TOLERANCE_RAD)
