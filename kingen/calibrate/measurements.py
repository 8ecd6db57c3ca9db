"""Reading a measurement file: a CSV with a header row, the joints as the controller reads them
(``q1`` .. ``qN``, the robot file's units: mm or inches, degrees) and what the device measured, in its
own frame: ``x, y, z, roll, pitch, yaw`` (the robot file's length unit, degrees; ``--measure pose``) or ``x, y, z``
(``--measure position``). Columns may come in any order; blank lines and lines starting with
``#`` are skipped. Every problem is one KingenError naming file, line and column.
"""

import csv
import io
import math
from dataclasses import dataclass

import numpy as np

from ..defaults import MAX_MM
from ..errors import located
from ..robot.schema import MAX_DEGREES
from ..runtime.file_gate import csv_rows, read_limited
from ..units import LENGTH_UNITS
from .parameters import POSE_NAMES

MAX_BYTES = 64 * 1024 * 1024
MAX_MEASUREMENTS = 10_000
"""Measurement rows a file may hold at most (``calibrate plan --poses`` chooses at most as
many): what calibration holds grows with the rows (its Jacobian and the fit's copies of it,
some 16 kB a row: about 300 MB in all at this bound)."""
MEASURED = {"pose": POSE_NAMES, "position": POSE_NAMES[:3]}
"""The measured columns of each kind of measurement."""


@dataclass(frozen=True)
class Measurements:
    """Measurements read from ``path``: ``joints`` (n, joint_count: the legs', then a wrist's) in
    kingen's internal units (mm, radians), ``measured`` (n, 6) mm and degrees or (n, 3) mm (converted from the robot file's unit), ``lines`` (n,) each row's
    1-based line in the file, ``columns`` the header as written (for errors)."""

    path: str
    measure: str
    joints: np.ndarray
    measured: np.ndarray
    lines: tuple
    columns: tuple

    def where(self, row, column):
        """'FILE:LINE: column' of measurement ``row`` (0-based), for errors."""
        return f"{self.path}:{self.lines[row]}: {column}"


def joint_columns(robot):
    """q1 .. qN for ``robot``."""
    return tuple(f"q{i + 1}" for i in range(robot.joint_count))


def read_measurements(path, robot, measure):
    """The Measurements in the CSV at ``path`` for ``robot`` (a Robot) and ``measure``: at most
    MAX_BYTES read, at most MAX_MEASUREMENTS rows (refused at the first beyond), every value
    finite and within its column's bounds (_bounds); KingenError at file, line and column."""
    data = read_limited(path, MAX_BYTES, "a measurement file")
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        raise located(path, None, None, f"not UTF-8 text (byte {error.start})") from None
    del data  # the text alone from here on: at most 64 MB, read line by line
    rows = ((number, row) for number, row in csv_rows(path, _lines(text))
            if row and not row[0].lstrip().startswith("#"))
    header_line, header = next(rows, (None, None))
    if header is None:
        raise located(path, 1, "header", "no header row (expected " + ", ".join(_expected(robot, measure)) + ")")
    header = tuple(name.strip() for name in header)
    order = _columns(path, header_line, header, robot, measure)
    bounds = _bounds(header, robot, measure)
    values, lines = [], []
    for number, row in rows:
        if len(values) == MAX_MEASUREMENTS:
            raise located(path, number, None, f"more than {MAX_MEASUREMENTS:,} measurements, which a measurement "
                                              "file holds at most")
        if len(row) != len(header):
            raise located(path, number, None, f"{len(row)} values; the header has {len(header)} columns")
        values.append([_number(path, number, name, cell, bound) for name, cell, bound in zip(header, row, bounds)])
        lines.append(number)
    if not values:
        raise located(path, header_line + 1, None, "no measurements after the header")
    values = np.array(values)
    joints = values[:, order[:robot.joint_count]] * _joint_scale(robot)
    measured = values[:, order[robot.joint_count:]]
    measured[:, :3] *= LENGTH_UNITS[robot.length_unit]
    return Measurements(str(path), measure, joints, measured, tuple(lines), header)


def _lines(text):
    """The lines of ``text`` (each with its newline), one at a time: no copy of the whole (a
    StringIO of 64 MB of text holds four bytes a character)."""
    start = 0
    while start < len(text):
        end = text.find("\n", start) + 1 or len(text)
        yield text[start:end]
        start = end


def _bounds(header, robot, measure):
    """Per column of ``header``: (the largest magnitude it may hold, its unit), in the robot
    file's units: lengths (prismatic joints, x, y, z) within the geometry range of +/-MAX_MM mm,
    angles (revolute joints, roll, pitch, yaw) within +/-MAX_DEGREES degrees."""
    unit = robot.length_unit
    length, angle = (MAX_MM / LENGTH_UNITS[unit], unit), (MAX_DEGREES, "degrees")
    kinds = {**{name: angle if revolute else length for name, revolute in zip(joint_columns(robot), robot.revolute)},
             **{name: length if name in POSE_NAMES[:3] else angle for name in MEASURED[measure]}}
    return [kinds[name] for name in header]


def _joint_scale(robot):
    """Per joint: internal units (mm, radians) per unit of the robot file (mm or inches, degrees)."""
    return robot.joint_scale() * np.where(robot.revolute, 1.0, LENGTH_UNITS[robot.length_unit])


def _expected(robot, measure):
    return joint_columns(robot) + MEASURED[measure]


def _columns(path, line, header, robot, measure):
    """The index in ``header`` of each expected column, in expected order."""
    expected = _expected(robot, measure)
    for name in header:
        if header.count(name) > 1:
            raise located(path, line, name, "this column is given twice")
    missing = [name for name in expected if name not in header]
    if missing:
        hint = (" (a position measurement has x, y, z only: --measure position)" if measure == "pose"
                and set(missing) <= set(POSE_NAMES[3:]) else "")
        raise located(path, line, missing[0], f"missing column (expected {', '.join(expected)}){hint}")
    extra = [name for name in header if name not in expected]
    if extra:
        hint = (" (a pose measurement: --measure pose)" if measure == "position" and extra[0] in POSE_NAMES else "")
        raise located(path, line, extra[0], f"unexpected column (expected {', '.join(expected)}){hint}")
    return [header.index(name) for name in expected]


def _number(path, line, column, cell, bound):
    """The number in ``cell``, within +/-``bound[0]`` (its unit ``bound[1]``): else KingenError at
    file, line and column."""
    try:
        value = float(cell.strip())
    except ValueError:
        raise located(path, line, column, f"'{cell.strip()[:40]}' is not a number") from None
    if not math.isfinite(value):
        raise located(path, line, column, f"{cell.strip()[:40]} is not a finite number")
    if abs(value) > bound[0]:
        raise located(path, line, column, f"{value:g} {bound[1]} is not within +/-{bound[0]:g} {bound[1]}")
    return value


def write_measurements(robot, measure, joints, measured):
    """CSV text of ``joints`` (n, joint_count; internal units) and ``measured`` (n, 6 or 3; mm,
    degrees) in the layout and units read_measurements reads (the robot file's)."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(_expected(robot, measure))
    shown = np.asarray(joints) / _joint_scale(robot)
    measured = np.array(measured, dtype=float)
    measured[:, :3] /= LENGTH_UNITS[robot.length_unit]
    for row_joints, row_measured in zip(shown, measured):
        writer.writerow([f"{value:.12g}" for value in (*row_joints, *row_measured)])
    return buffer.getvalue()
