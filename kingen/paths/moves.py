"""A program's moves: what every program reader (:mod:`.program`, :mod:`.interpreter`) gives
and every later stage reads. Poses are x, y, z in mm and roll, pitch, yaw (LinuxCNC's A, B,
C) in degrees, in the robot's base frame."""

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Arc:
    """A circular (or helical) move in one plane: ``axes`` the indices (first, second, normal)
    of x, y, z in that plane (LinuxCNC's first and second axis, the plane's normal), ``center``
    the centre's (first, second) coordinates in mm, ``rotation`` LinuxCNC's: its sign the
    sense (positive counter-clockwise seen from the normal's tip), |rotation| - 1 extra full turns."""

    axes: tuple
    center: tuple
    rotation: int


@dataclass(frozen=True)
class Move:
    """One programmed motion from ``start`` to ``end`` (6 floats each, mm and degrees).

    line: the G-code line (1-based) or CSV row's line in the file; kind: "feed", "rapid",
    "arc", "probe" (to its programmed end), "tap" (a rigid tap's way down or back) (G-code) or
    "row" (CSV). feed: mm/min along the xyz path (deg/min for a move that
    only turns), None when the program gives none (a rapid, a CSV without feed). duration: s
    (a CSV with ``t``), else None. start_line: the CSV row ``start`` was read from (None for G-code).
    file: the file ``line`` is in when it is not the program's own (a G-code subroutine's), else None.
    path_mode: the path control mode the move was made in, (code, P, Q): code "G61" (exact path),
    "G61.1" (exact stop) or "G64" (blending), P and Q G64's tolerances in mm (0: none given); None
    for a CSV row."""

    line: int
    kind: str
    start: np.ndarray
    end: np.ndarray
    feed: float = None
    duration: float = None
    arc: Arc = None
    start_line: int = None
    file: str = None
    path_mode: tuple = None
