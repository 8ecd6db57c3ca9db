"""G-code programs read by LinuxCNC's own interpreter: its Python ``gcode`` module (what AXIS's
preview runs), in a child process of the Python that has it, through the canon of
:mod:`.linuxcnc_canon`, whose plain-text lines become :class:`~.program.Move` s here.

Units, offsets (G54..G59.3, G92, G10 L2 rotation), arcs, subroutines and parameters are the
interpreter's; kingen parses no G-code. The child's output is read line by line as it comes,
so memory does not grow with the program.
"""

import math
import os
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from ..errors import KingenError, located
from ..runtime.file_gate import refuse_special_file
from ..runtime.household import dying_with_this_process
from .moves import Arc, Move
from .program import source_lines

MM_PER_INCH = 25.4
INCH_PROGRAM = 200
"""The interpreter's units word for a program in inches (G20); G21 (mm) is 210."""
LINUXCNC_PYTHON = "/usr/bin/python3"
"""The Python that has LinuxCNC's ``gcode`` module (Debian's linuxcnc-uspace installs it for
the system's Python); ``KINGEN_LINUXCNC_PYTHON`` names another."""
CANON = Path(__file__).with_name("linuxcnc_canon.py")
RS274 = "/usr/bin/rs274"
RS274_SECONDS = 60.0
PLANE_AXES = {1: (0, 1, 2), 2: (1, 2, 0), 3: (2, 0, 1)}
"""LinuxCNC's plane (G17 XY, G19 YZ, G18 XZ): the x, y, z indices of its first and second
axis and of its normal."""


def interpreter_python():
    """The Python to run the interpreter with; KingenError when it is missing."""
    python = os.environ.get("KINGEN_LINUXCNC_PYTHON", LINUXCNC_PYTHON)
    if not os.access(python, os.X_OK):
        raise KingenError(f"{python}: not found: reading G-code needs LinuxCNC's interpreter "
                          f"(Debian's linuxcnc-uspace; KINGEN_LINUXCNC_PYTHON names its Python)")
    return python


def start_code(start):
    """The start-up code that puts the interpreter at pose ``start`` (mm, degrees) in mm and
    absolute distances, as AXIS tells it the machine's position: G21 G90 G53 G0 X.. C.."""
    return "G21 G90 G53 G0 " + " ".join(f"{axis}{value:.9f}" for axis, value in zip("XYZABC", start))


def gcode_moves(path, start=(0.0,) * 6):
    """The moves of the G-code program at ``path`` as LinuxCNC's interpreter makes them
    (mm, degrees; feeds in mm/min, or deg/min for moves that only turn), the machine standing
    at pose ``start`` (mm, degrees) when the program begins; a program that sets no units
    (G20, G21) is read in mm. KingenError ``path:line: G-code: <the interpreter's message>``
    where it refuses the program."""
    refuse_special_file(path)
    if not Path(path).is_file():
        raise KingenError(f"{path}: no such file")
    with tempfile.TemporaryFile() as errors:
        child = subprocess.Popen([interpreter_python(), "-I", str(CANON), os.path.abspath(path),
                                  start_code(start)], stdout=subprocess.PIPE,
                                 stderr=errors, stdin=subprocess.DEVNULL, text=True, errors="replace",
                                 preexec_fn=dying_with_this_process())
        try:
            yield from _moves(child.stdout, path, errors, np.asarray(start, dtype=float))
        finally:
            child.stdout.close()
            if child.poll() is None:
                child.kill()
            child.wait()


def _moves(lines, path, errors, position):
    for text in lines:
        fields = text.split()
        if not fields:
            continue
        if fields[0] == "D":
            return
        if fields[0] == "E":
            raise located(path, refused_line(path, int(fields[1])), "G-code", " ".join(fields[2:]))
        move = _move(fields, position)
        if move is not None and move.line > 0:
            yield move
        if move is not None:
            position = move.end
    errors.seek(0)
    said = " ".join(errors.read().decode("utf-8", "replace").split()[-40:])
    if "No module named 'gcode'" in said or "No module named 'rs274'" in said:
        raise KingenError(f"{path}: reading G-code needs LinuxCNC's interpreter, and {interpreter_python()} has no "
                          f"'gcode' module (Debian's linuxcnc-uspace; KINGEN_LINUXCNC_PYTHON names its Python)")
    raise KingenError(f"{path}: LinuxCNC's interpreter stopped without finishing the program: {said or 'no message'}")


def refused_line(path, sequence):
    """The line the interpreter refused, from its last sequence number: that line's (refused
    while executing the block) or one past it (refused while reading it). ``rs274``, the same
    interpreter standalone, prints the refused block's text after its message, which tells
    the two apart; without it, the line before."""
    candidates = [number for number in (sequence - 1, sequence) if number >= 1] or [1]
    try:
        printed = subprocess.run([RS274, "-g", os.path.abspath(path)], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                 text=True, errors="replace", timeout=RS274_SECONDS, stdin=subprocess.DEVNULL).stdout
    except (OSError, subprocess.TimeoutExpired):
        return candidates[0]
    said = {_squeezed(text) for text in printed.splitlines()}
    texts = source_lines(path, candidates)
    return next((number for number in candidates if _squeezed(texts.get(number, "")) in said), candidates[0])


def _squeezed(text):
    return "".join(text.split()).lower() or None


def _move(fields, start):
    """The Move a canon line ``M line kind units feed x y z a b c [...]`` stands for, from
    ``start``; None for a move of length 0."""
    line, kind, units = int(fields[1]), fields[2], int(fields[3])
    numbers = [float(value) for value in fields[4:11]]
    end = np.array(numbers[1:7])
    end[:3] *= MM_PER_INCH
    if np.array_equal(end, start):
        return None
    turning_only = np.array_equal(end[:3], start[:3])
    feed = numbers[0] * (MM_PER_INCH if not turning_only or units != INCH_PROGRAM else 1.0)
    if kind == "T":
        return Move(line, "rapid", start, end)
    arc = None
    if kind == "A":
        first, second = float(fields[11]) * MM_PER_INCH, float(fields[12]) * MM_PER_INCH
        arc = Arc(PLANE_AXES[int(fields[14])], (first, second), int(fields[13]))
    return Move(line, "arc" if arc else "feed", start, end, feed=feed if math.isfinite(feed) else None, arc=arc)
