"""G-code programs read by LinuxCNC's own interpreter: its Python ``gcode`` module (what AXIS's
preview runs), in a child process of the Python that has it, through the canon of
:mod:`.linuxcnc_canon`, whose plain-text lines become :class:`~.moves.Move` s here.

Units, work offsets (G54..G59.3, G92, G10 L2 rotation), tool length offsets, arcs, probing,
rigid tapping, canned and lathe cycles, cutter compensation, subroutines and parameters are
the interpreter's; kingen parses no G-code. The child runs in a clean environment with a
private HOME (where LinuxCNC's shared tool table is created) and TMPDIR, in the program's
folder (subroutines beside it are found); its own output (``(PRINT,...)`` comments) goes to a
file apart from the motions, which come through a pipe line by line, so memory does not grow
with the program. When the program is read to its end, ``rs274 -g``, the same interpreter
standalone, reads it again with the same tool table and parameters: an error it raises that
the ``gcode`` module passes over (a feed move without a feed) is bad input too.
"""

import math
import os
import shutil
import signal
import subprocess
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..defaults import INTERPRETER_SECONDS
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
DEFAULT_TOOLS = 999
"""Without a tool table, tools 1 .. DEFAULT_TOOLS exist, with no offsets and no diameter."""
PATH_MODES = {610: "G61", 611: "G61.1", 640: "G64"}
"""The interpreter's path control modes (an unset one, before the first block, is LinuxCNC's G64)."""
PLANE_AXES = {1: (0, 1, 2), 2: (1, 2, 0), 3: (2, 0, 1)}
"""LinuxCNC's plane (G17 XY, G19 YZ, G18 XZ): the x, y, z indices of its first and second
axis and of its normal."""
KINDS = {"T": "rapid", "F": "feed", "A": "arc", "P": "probe", "R": "tap"}
"""The canon's motion letters and the Move kinds they become."""
RS274_MOTIONS = (b"STRAIGHT_TRAVERSE(", b"STRAIGHT_FEED(", b"STRAIGHT_PROBE(", b"ARC_FEED(", b"RIGID_TAP(",
                 b"NURBS_FEED(")
"""The canonical calls ``rs274`` prints for a motion (a spline, G5 .. G5.2, is one NURBS_FEED;
the gcode module cuts it into straight feeds)."""
CLEAN_PATH = "/usr/local/bin:/usr/bin:/bin"


@dataclass(frozen=True)
class Setup:
    """What the interpreter starts with: the tool table file (None: tools 1 .. DEFAULT_TOOLS
    at no offset), the parameter file whose work offsets it starts with (None: all zero),
    ``offset`` (x y z mm, a b c degrees; None: the parameter file's) the work offset of the
    coordinate system it starts in, the machine's length unit in mm (the ``.ini``'s
    LINEAR_UNITS, which the tool table is written in), the CPU seconds it may take, the
    folders it looks for a subroutine called by name in besides the program's (the ``.ini``'s
    SUBROUTINE_PATH, absolute)."""

    tool_table: object = None
    parameter_file: object = None
    offset: tuple = None
    machine_unit: float = 1.0
    seconds: float = INTERPRETER_SECONDS
    subroutine_path: tuple = ()


@dataclass
class Reading:
    """What reading a program showed besides its moves: ``motions`` the canonical motions the
    ``gcode`` module emitted (a rigid tap one; a spline as its straight pieces), ``zero_length``
    those of them that go nowhere, ``rs274_motions`` the canonical motions ``rs274 -g`` printed
    for the same program (a spline one; None: rs274 not run),
    ``files`` {number: path} the files it read, ``work_offset`` the work offsets it started
    with ({"system": "G54".., "g5x": [x y z a b c], "g92": [...], "rotation": deg}, mm and
    degrees), ``offset_from`` where that offset came from (in words), ``line`` the last (file,
    line) reached."""

    motions: int = 0
    zero_length: int = 0
    rs274_motions: int = None
    files: dict = field(default_factory=dict)
    work_offset: dict = None
    offset_from: str = "none given: the machine's origin"
    line: tuple = (None, 1)


def linuxcnc_python():
    """The Python with LinuxCNC's modules (``KINGEN_LINUXCNC_PYTHON``, else LINUXCNC_PYTHON), or None."""
    python = os.environ.get("KINGEN_LINUXCNC_PYTHON", LINUXCNC_PYTHON)
    return python if os.access(python, os.X_OK) else None


def interpreter_python():
    """The Python to run the interpreter with; KingenError when it is missing."""
    python = linuxcnc_python()
    if python is None:
        raise KingenError(f"{os.environ.get('KINGEN_LINUXCNC_PYTHON', LINUXCNC_PYTHON)}: not found: reading G-code "
                          "needs LinuxCNC's interpreter (Debian's linuxcnc-uspace; KINGEN_LINUXCNC_PYTHON names its Python)")
    return python


def start_code(start, unit=1.0):
    """The start-up code that puts the interpreter at pose ``start`` (mm, degrees) in absolute
    distances, as AXIS tells it the machine's position, in ``unit`` (mm: 25.4 for inches, in
    which a program without G20 or G21 is then read):
    G21 (or G20) G90 G53 G0 X.. C.."""
    inch = unit == MM_PER_INCH
    values = [value / MM_PER_INCH if inch and index < 3 else value for index, value in enumerate(start)]
    words = " ".join(f"{axis}{value:.15f}" for axis, value in zip("XYZABC", values))
    return f"G{20 if inch else 21} G90 G53 G0 {words}"


def unit_code(offset):
    """The code run before the start-up code: mm, and ``offset`` (mm, degrees) as the work
    offset of the coordinate system the program starts in (G10 L2 P0), when given."""
    if offset is None:
        return "G21"
    return "G21 G10 L2 P0 " + " ".join(f"{axis}{value:.9f}" for axis, value in zip("XYZABC", offset))


def _private(folder, setup):
    """Prepare the interpreter's private folder: its HOME, TMPDIR, tool table and parameter
    file copies, and an ``.ini`` of its own holding only the subroutine path (so no other
    ``.ini``'s Python or remaps apply); (environment, tool table path, parameter file path)."""
    home, scratch = folder / "home", folder / "tmp"
    home.mkdir()
    scratch.mkdir()
    table = folder / "tool.tbl"
    if setup.tool_table is not None:
        shutil.copyfile(setup.tool_table, table)
    else:
        table.write_text("".join(f"T{number} P{number}\n" for number in range(1, DEFAULT_TOOLS + 1)))
    parameters = folder / "kingen.var"
    if setup.parameter_file is not None:
        shutil.copyfile(setup.parameter_file, parameters)
    else:
        parameters.write_text("")
    environment = {"PATH": CLEAN_PATH, "HOME": str(home), "TMPDIR": str(scratch), "LANG": "C.UTF-8"}
    if setup.subroutine_path:
        ini = folder / "kingen.ini"
        ini.write_text(f"[RS274NGC]\nSUBROUTINE_PATH = {':'.join(setup.subroutine_path)}\n")
        environment["INI_FILE_NAME"] = str(ini)
    return environment, table, parameters


def _limit_cpu(child, seconds):
    """Bound the CPU time of the started ``child`` (SIGXCPU past ``seconds``, SIGKILL a second
    later); nothing when it has already ended."""
    import resource

    limit = max(1, math.ceil(seconds))
    try:
        resource.prlimit(child.pid, resource.RLIMIT_CPU, (limit, limit + 1))
    except (ProcessLookupError, PermissionError):
        pass


def gcode_moves(path, start=(0.0,) * 6, setup=Setup(), reading=None):
    """The moves of the G-code program at ``path`` as LinuxCNC's interpreter makes them
    (mm, degrees; feeds in mm/min, or deg/min for moves that only turn), the machine standing
    at pose ``start`` (mm, degrees) when the program begins, with ``setup``; a program that
    sets no units (G20, G21) is read in the machine's (``setup.machine_unit``: inches on an
    inch machine, else mm). A straight motion of length 0 is counted in
    ``reading`` (a Reading, filled as the program is read) and not yielded; a rigid tap is two
    moves, down and back. KingenError ``path:line: G-code: <the interpreter's message>`` where
    it refuses the program or runs out of time."""
    reading = Reading() if reading is None else reading
    position = np.asarray(start, dtype=float)
    for kind, file, line, units, feed, end, arc, mode in canonical_motions(path, start, setup, reading):
        end = _snapped(position, end)
        moves = _moves(kind, file, line, units, feed, position, end, arc, mode)
        reading.motions += 1
        reading.zero_length += not moves
        yield from moves
        position = end


def canonical_motions(path, start=(0.0,) * 6, setup=Setup(), reading=None):
    """Every canonical motion LinuxCNC's interpreter emits for the program at ``path`` (see
    gcode_moves), as (kind letter, file (None: the program), line, units word, feed in
    inches/min, end (6,) mm and degrees with every offset applied, arc (center (2,) mm, rotation,
    plane) or None), in order; the start-up code's motion is not among them."""
    refuse_special_file(path)
    if not Path(path).is_file():
        raise KingenError(f"{path}: no such file")
    reading = Reading() if reading is None else reading
    program, python = os.path.abspath(path), interpreter_python()
    with tempfile.TemporaryDirectory(prefix="kingen-interpreter-") as scratch:
        folder = Path(scratch)
        environment, table, parameters = _private(folder, setup)
        read_end, write_end = os.pipe()
        with open(read_end, encoding="utf-8", errors="replace") as lines, open(folder / "messages", "wb") as messages:
            try:
                child = subprocess.Popen(
                    [python, "-I", str(CANON), program, unit_code(setup.offset), start_code(start, setup.machine_unit),
                     str(write_end), str(table), str(parameters), repr(1.0 / setup.machine_unit)],
                    stdout=messages, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, pass_fds=(write_end,),
                    env=environment, cwd=os.path.dirname(program), preexec_fn=dying_with_this_process())
            finally:
                os.close(write_end)
            _limit_cpu(child, setup.seconds)
            try:
                finished = yield from _read(lines, path, reading)
            finally:
                if child.poll() is None:
                    child.kill()
                child.wait()
        said = " ".join((folder / "messages").read_bytes().decode("utf-8", "replace").split()[-40:])
        if not finished:
            _stopped(path, child.returncode, said, reading, setup)
        _rs274_errors(path, program, folder, environment, table, parameters, setup, reading)


def _read(lines, path, reading):
    """Yield the motions of the canon's ``lines``; True when the program was read to its end."""
    files, started, mode = {0: None}, False, ("G64", 0.0, 0.0)
    for text in lines:
        fields = text.split()
        if not fields:
            continue
        if fields[0] == "F":
            number, name = int(fields[1]), text.split(None, 2)[2].strip()
            files[number] = None if os.path.abspath(name) == os.path.abspath(path) or number == 1 else name
            reading.files[number] = name
        elif fields[0] == "B":
            mode = (PATH_MODES.get(int(fields[1]), "G64"), float(fields[2]), float(fields[3]))
        elif fields[0] == "W":
            reading.work_offset = _work_offset(fields)
        elif fields[0] == "D":
            return True
        elif fields[0] == "E":
            file, line = files.get(int(fields[1])), int(fields[2])
            message = " ".join(fields[3:])
            raise located(file or path, refused_line(file or path, line) if file is None else max(line, 1),
                          "G-code", message)
        elif fields[0] == "M" and not started:  # the start-up code's motion
            started = True
        elif fields[0] == "M":
            file, line = files.get(int(fields[1])), int(fields[2])
            reading.line = (file, line)
            yield _motion(fields, file, line, mode)
    return False


def _work_offset(fields):
    """The W record as plain data (mm, degrees)."""
    values = [float(value) for value in fields[2:9]] + [float(value) for value in fields[9:15]]
    scale = np.array([MM_PER_INCH] * 3 + [1.0] * 3)
    system = int(float(fields[1]))
    names = ["G54", "G55", "G56", "G57", "G58", "G59", "G59.1", "G59.2", "G59.3"]
    return {"system": names[system - 1] if 1 <= system <= 9 else str(system),
            "g5x": (np.array(values[0:6]) * scale).tolist(), "g92": (np.array(values[6:12]) * scale).tolist(),
            "rotation": float(fields[15]) if len(fields) > 15 else 0.0}


def _stopped(path, code, said, reading, setup):
    """The KingenError for an interpreter child that ended without a verdict: out of CPU time
    (the line reached), LinuxCNC missing, or anything else (its last words)."""
    file, line = reading.line
    if code in (-signal.SIGXCPU, -signal.SIGKILL):
        raise located(file or path, line, "G-code", f"LinuxCNC's interpreter ran out of its {setup.seconds:g} s of "
                                                    f"CPU time (--interpreter-seconds) here: an endless loop?")
    if "No module named 'gcode'" in said or "No module named 'rs274'" in said:
        raise KingenError(f"{path}: reading G-code needs LinuxCNC's interpreter, and {interpreter_python()} has no "
                          f"'gcode' module (Debian's linuxcnc-uspace; KINGEN_LINUXCNC_PYTHON names its Python)")
    raise KingenError(f"{path}: LinuxCNC's interpreter stopped without finishing the program: {said or 'no message'}")


def _rs274_errors(path, program, folder, environment, table, parameters, setup, reading):
    """Read the program again with ``rs274 -g`` (the tool table, in inches as rs274 reads one,
    and a fresh copy of the parameters), counting the motions it prints into ``reading``:
    KingenError at the refused line when it raises an error."""
    if not os.access(RS274, os.X_OK):
        return
    variables = folder / "rs274.var"
    shutil.copyfile(setup.parameter_file, variables) if setup.parameter_file is not None else variables.write_text("")
    with open(folder / "rs274.err", "w+b") as errors:
        ini = ["-i", environment["INI_FILE_NAME"]] if "INI_FILE_NAME" in environment else []
        inches = folder / "rs274.tbl"
        inches.write_text(_in_inches(table.read_text(errors="replace"), setup.machine_unit))
        child = subprocess.Popen([RS274, "-g", "-t", str(inches), "-v", str(variables), *ini, program],
                                 stdout=subprocess.PIPE, stderr=errors, stdin=subprocess.DEVNULL, env=environment,
                                 cwd=os.path.dirname(program), preexec_fn=dying_with_this_process())
        _limit_cpu(child, setup.seconds)
        with child.stdout:
            reading.rs274_motions = sum(1 for text in child.stdout if any(name in text for name in RS274_MOTIONS))
        code = child.wait()
        errors.seek(0)
        said = [text.strip() for text in errors.read().decode("utf-8", "replace").splitlines()
                if text.strip() and text.strip() != "executing"]
    if code == 0:
        return
    if code < 0:
        file, line = reading.line
        raise located(file or path, line, "G-code", f"rs274 ran out of its {setup.seconds:g} s of CPU time "
                                                    f"(--interpreter-seconds)")
    if len(said) < 2:
        return
    message, block = said[-2], _squeezed(said[-1])
    matches = [number for number, text in _numbered(path) if _squeezed(text) == block]
    raise located(path, matches[0] if matches else reading.line[1], "G-code", message)


def _in_inches(table, machine_unit):
    """A tool table's text with its lengths (offsets X Y Z U V W, diameter D) in inches from the
    machine's unit (``machine_unit`` mm), as ``rs274`` reads a tool table; comments kept."""
    if machine_unit == MM_PER_INCH:
        return table
    scale = machine_unit / MM_PER_INCH
    lines = []
    for line in table.splitlines():
        words, _, comment = line.partition(";")
        words = [_scaled(word, scale) if word[:1].upper() in "XYZUVWD" else word for word in words.split()]
        lines.append(" ".join(words) + (f" ;{comment}" if comment else ""))
    return "\n".join(lines) + "\n"


def _scaled(word, scale):
    """A tool table word ``X1.5`` times ``scale`` (the word itself when its value is no number)."""
    try:
        return f"{word[0]}{float(word[1:]) * scale!r}"
    except ValueError:
        return word


def _numbered(path):
    with open(path, encoding="utf-8", errors="replace") as stream:
        yield from enumerate(stream, start=1)


def refused_line(path, sequence):
    """The line the interpreter refused, from its sequence number when it stopped: that
    line's (refused while executing the block) or one past it (refused while reading it).
    The block's text tells the two apart where only one of them can hold the refused words;
    else the earlier."""
    candidates = [number for number in (sequence - 1, sequence) if number >= 1] or [1]
    texts = source_lines(path, candidates)
    written = [number for number in candidates if _squeezed(texts.get(number, "")) not in (None, "%")]
    return written[-1] if len(written) == 1 else candidates[-1] if sequence >= 1 else 1


def _squeezed(text):
    return "".join(text.split()).lower() or None


def _motion(fields, file, line, mode):
    """A canon line ``M file line kind units feed x y z a b c [...]`` made in path control mode
    ``mode`` as (kind, file, line, units, feed, end (mm, degrees), arc, mode)."""
    kind, units = fields[3], int(fields[4])
    numbers = [float(value) for value in fields[5:12]]
    end = np.array(numbers[1:7])
    end[:3] *= MM_PER_INCH
    arc = None
    if kind == "A":
        arc = (np.array([float(fields[12]), float(fields[13])]) * MM_PER_INCH, int(fields[14]), int(fields[15]))
    return kind, file, line, units, numbers[0], end, arc, mode


ROUNDING_MM = 1e-9
"""A motion's x, y, z within this fraction of the position's size (at least 1 mm) of where it
starts are where it starts: the round trip through the interpreter's inches, not a move (a move
that only turns stays one, timed on its turn)."""


def _snapped(start, end):
    """``end`` (6,) with its x, y, z replaced by ``start``'s where they differ by rounding alone (ROUNDING_MM)."""
    if np.all(np.abs(end[:3] - start[:3]) <= ROUNDING_MM * max(1.0, float(np.max(np.abs(start[:3]))))):
        return np.concatenate([start[:3], end[3:]])
    return end


def _moves(kind, file, line, units, feed, start, end, arc, mode):
    """The Moves a canonical motion from ``start`` makes in path control mode ``mode``
    (Move.path_mode): none for a straight one of length 0, two for a rigid tap (down to
    ``end``'s x y z and back; the orientation stays)."""
    if kind == "R":
        bottom = np.concatenate([end[:3], start[3:]])
        if np.array_equal(bottom, start):
            return []
        rate = feed * MM_PER_INCH if math.isfinite(feed) else None
        return [Move(line, "tap", start, bottom, feed=rate, file=file, path_mode=mode),
                Move(line, "tap", bottom, start.copy(), feed=rate, file=file, path_mode=mode)]
    if np.array_equal(end, start) and arc is None:
        return []
    turning_only = np.array_equal(end[:3], start[:3])
    rate = feed * (MM_PER_INCH if not turning_only or units != INCH_PROGRAM else 1.0)
    rate = rate if math.isfinite(rate) else None
    if kind == "T":
        return [Move(line, "rapid", start, end, file=file, path_mode=mode)]
    shape = None if arc is None else Arc(PLANE_AXES[arc[2]], tuple(arc[0]), arc[1])
    return [Move(line, KINDS[kind], start, end, feed=rate, arc=shape, file=file, path_mode=mode)]
