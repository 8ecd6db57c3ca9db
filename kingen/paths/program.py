"""A program as a stream of moves: what ``check-path`` reads from a CSV of poses (a G-code file
goes through LinuxCNC's interpreter, :mod:`.interpreter`), and the text of a program's lines.

Every pose is x, y, z in mm and roll, pitch, yaw (LinuxCNC's A, B, C) in degrees, in the
robot's base frame. Moves are produced one at a time, so a program of any length is read
in constant memory.
"""

import math
from pathlib import Path

import numpy as np

from ..defaults import MAX_MM
from ..errors import located
from ..robot.schema import MAX_DEGREES
from ..runtime.file_gate import csv_rows, refuse_special_file
from .moves import Move

GCODE_SUFFIXES = (".ngc", ".nc", ".gcode")
POSE_COLUMNS = ("x", "y", "z", "roll", "pitch", "yaw")
TIMING_COLUMNS = ("t", "feed")
MAX_SECONDS = 1e9
"""A CSV's ``t`` within +/- this many seconds (about 32 years)."""
FEED_RANGE = (1e-6, 1e9)
"""A CSV's ``feed`` within these mm/min: a move of the geometry range's length then lasts a
finite time."""
RANGES = {**{name: (-MAX_MM, MAX_MM) for name in POSE_COLUMNS[:3]},
          **{name: (-MAX_DEGREES, MAX_DEGREES) for name in POSE_COLUMNS[3:]},
          "t": (-MAX_SECONDS, MAX_SECONDS), "feed": FEED_RANGE}
"""What each CSV column may hold (mm, degrees, s, mm/min), both ends included: the geometry
range a robot file's poses have, so every length, turn and time computed from a row is finite."""
UNITS = {"x": "mm", "y": "mm", "z": "mm", "roll": "degrees", "pitch": "degrees", "yaw": "degrees", "t": "s",
         "feed": "mm/min"}


def is_gcode(path):
    """Whether ``path`` names a G-code program (by its suffix), else a CSV of poses."""
    return Path(path).suffix.lower() in GCODE_SUFFIXES


def _number(text, path, line, column):
    try:
        value = float(text)
    except ValueError:
        raise located(path, line, column, f"{text.strip()!r} is not a number") from None
    if not math.isfinite(value):
        raise located(path, line, column, f"{text.strip()!r} is not a finite number")
    low, high = RANGES[column]
    if column == "feed" and value <= 0.0:
        raise located(path, line, column, f"{value:g} mm/min: a feed must be above 0")
    if not low <= value <= high:
        raise located(path, line, column, f"{value:g} {UNITS[column]} is not within {low:g} to {high:g}")
    return value


def _header(row):
    """The columns a header row names, or None when ``row`` is data (its first cell a number)."""
    names = [cell.strip().lower() for cell in row]
    try:
        float(names[0])
        return None
    except ValueError:
        return names


def _columns(names, path, line):
    """Column indices of the pose and of t or feed (None) for a header's ``names``."""
    missing = [name for name in POSE_COLUMNS if name not in names]
    if missing:
        raise located(path, line, "header", f"no column {', '.join(missing)} (columns: x, y, z, roll, pitch, yaw, "
                                         f"optionally t or feed)")
    unknown = [name for name in names if name not in POSE_COLUMNS + TIMING_COLUMNS]
    if unknown:
        raise located(path, line, "header", f"unknown column {unknown[0]!r}")
    if all(name in names for name in TIMING_COLUMNS):
        raise located(path, line, "header", "give t or feed, not both")
    timing = next((name for name in TIMING_COLUMNS if name in names), None)
    return [names.index(name) for name in POSE_COLUMNS], timing, (names.index(timing) if timing else None)


def csv_moves(path):
    """The moves of a CSV of poses: the first row is where the program starts, each further
    row a straight move to its pose. Columns x, y, z, roll, pitch, yaw (mm, degrees), in that
    order without a header, or named by a header row with optionally ``t`` (s, increasing:
    the row is reached at that time) or ``feed`` (mm/min, positive). KingenError (file:line)
    on a missing or non-numeric value, a value outside its column's RANGES, a time that does
    not increase."""
    refuse_special_file(path)
    with open(path, newline="", encoding="utf-8", errors="replace") as stream:
        pose_at, timing, timing_at = list(range(6)), None, None
        previous, previous_time, previous_line, first = None, None, None, True
        for line, row in csv_rows(path, stream):
            if not row or all(not cell.strip() for cell in row) or row[0].lstrip().startswith("#"):
                continue
            if first:
                first, names = False, _header(row)
                if names is not None:
                    pose_at, timing, timing_at = _columns(names, path, line)
                    continue
            width = max(pose_at + ([timing_at] if timing else []))
            if len(row) <= width:
                raise located(path, line, "row", f"{len(row)} values, {width + 1} expected")
            pose = np.array([_number(row[index], path, line, name) for index, name in zip(pose_at, POSE_COLUMNS)])
            value = _number(row[timing_at], path, line, timing) if timing else None
            if previous is not None:
                if timing == "t" and value <= previous_time:
                    raise located(path, line, "t", f"{value:g} s does not come after the previous row's "
                                                   f"{previous_time:g} s")
                if np.array_equal(pose, previous):  # no motion (a dwell when timed)
                    previous, previous_time = pose, value
                    continue
                yield Move(line, "row", previous, pose, feed=value if timing == "feed" else None,
                           duration=value - previous_time if timing == "t" else None, start_line=previous_line)
            previous, previous_time, previous_line = pose, value, line
        if previous is None:
            raise located(path, None, None, "no poses in the program")


def source_lines(path, numbers):
    """{line number: its text, stripped} for the wanted line ``numbers`` of the file at ``path``,
    read in one pass."""
    wanted, found = set(numbers), {}
    if not wanted:
        return found
    with open(path, encoding="utf-8", errors="replace") as stream:
        for number, text in enumerate(stream, start=1):
            if number in wanted:
                found[number] = text.strip()
                if len(found) == len(wanted):
                    break
    return found
