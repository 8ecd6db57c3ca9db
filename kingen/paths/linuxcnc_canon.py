"""Run as a script by the Python that has LinuxCNC's ``gcode`` module (Debian's
/usr/bin/python3), never imported by kingen: LinuxCNC's own interpreter (the one AXIS's
preview runs) reads the program, after the units code and the start-up code (as AXIS gives
them), and this canon writes every canonical motion it is asked for to the file descriptor
``MOVES`` (the interpreter's own output, ``(PRINT,...)`` comments among it, goes to stdout,
a channel apart), one line each, in plain text that kingen.paths.interpreter reads:

    F <number> <path>      a file the interpreter reads from (the program, a subroutine's)
    W <g5x> x y z a b c  <g92> x y z a b c  <rotation>   the work offsets the program starts with
    M <file> <line> <kind> <units> <feed> x y z a b c [first second rotation plane]

kind T (straight traverse), F (straight feed), A (arc), P (probe: to its programmed end),
R (rigid tap: down to its end and back); file 0 is the start-up code (not the program's);
positions with the program's work offsets, rotation and tool length offset applied (what
LinuxCNC's motion controller is asked for), in LinuxCNC's internal units (inches, degrees);
feed as the interpreter hands it (inches/min); units the program's (1 inch, 2 mm, 3 cm) when
the motion was made. Before a block's motions, the path control mode they are made in when it
differs from the last written (the interpreter's state after the block when the gcode module
hands it with the next block's first motion, as a block's G61/G64 applies to its own motion;
else the state before the block: a G61/G64 on a moving line followed by a line that does not
move takes effect from the next moving line):

    B <mode> <p> <q>    mode 610 (G61), 611 (G61.1) or 640 (G64); G64's P and Q in mm

The end, after the last motion:

    E <file> <line> <message>   the interpreter refused the program: where it stood
    D                           the program was read to its end

The tool table LinuxCNC's processes share (``$HOME/.tool.mmap``, under the private HOME kingen
gives this process) is created here and filled from the tool table file kingen gives (the
``.ini``'s, or every tool number 1 .. DEFAULT_TOOLS at no offset and no diameter).
"""

import ctypes
import os
import struct
import sys

import gcode
from rs274.interpret import Translated

DEFAULT_TOOLS = 999
"""Comment buffers the table is read with (kingen.paths.interpreter.DEFAULT_TOOLS tools without a table)."""
ENTRY = struct.Struct("ii12di")
"""CANON_TOOL_TABLE's leading fields: tool number, pocket, offsets x y z a b c u v w, diameter,
front angle, back angle, orientation (the comment after them is not read)."""
EMPTY = (-1,) + (0.0,) * 12 + (0,)
MM_UNITS = 210
"""The interpreter's units word for mm (G21): the gcode module's positions are then in mm."""
MM_PER_INCH = 25.4
SETTINGS = 16
"""Where the interpreter's active settings (sequence number, feed, speed, G64 P, G64 Q: five
doubles) start in the gcode module's line-code object, after the object's header (64-bit CPython);
the module exposes the first three only, which tell whether the offset holds."""
UNITS_MM = {200: 25.4, 210: 1.0}
"""mm per program unit, by the interpreter's units word (G20, G21)."""


class Tools:
    """The shared tool table (LinuxCNC's libtooldata): created, filled, read back by pocket."""

    def __init__(self, table):
        self.lib = ctypes.CDLL("libtooldata.so.0")
        self.status = ctypes.create_string_buffer(1 << 16)  # the creator's EMC_TOOL_STAT, never read here
        self.lib._Z17tool_mmap_creatorPK13EMC_TOOL_STATi(self.status, 0)
        self.lib._Z13tooldata_initb(0)
        self.lib._Z23tooldata_last_index_seti(0)
        self.lib._Z17tooldata_add_initi(1)
        self.comments = [ctypes.create_string_buffer(256) for _ in range(DEFAULT_TOOLS + 1)]
        pointers = (ctypes.c_char_p * len(self.comments))(*[ctypes.cast(b, ctypes.c_char_p) for b in self.comments])
        self.pointers = pointers
        for line in open(table, errors="replace").read().splitlines():
            self.lib._Z19tooldata_read_entryPKcPPc(line.encode()[:250], pointers)
        self.buffer = ctypes.create_string_buffer(4096)
        self.spindle = None

    def entry(self, pocket):
        """The tool table's entry at ``pocket`` as the gcode module's get_tool answers it."""
        if pocket == 0:
            if self.spindle is None:
                return EMPTY
            pocket = self.spindle
        if self.lib._Z12tooldata_getP16CANON_TOOL_TABLEi(self.buffer, pocket) != 0:
            return EMPTY
        values = ENTRY.unpack_from(self.buffer)
        return (values[0],) + values[2:]


def arc_end_cells():
    """The gcode module's own record of the machine's position (its static ``_pos_x`` ..
    ``_pos_w``, what GET_EXTERNAL_POSITION_X .. W answer when the interpreter synchronises, as
    after a tool change or a probe), found from those functions' code (``movsd disp(%rip),
    %xmm0; ret``), as ctypes doubles; None when the code is not that. The module updates them
    after straight motions only; the canon updates them after arcs, as LinuxCNC's motion
    controller would report the arc's end."""
    library = ctypes.CDLL(gcode.__file__)
    cells = []
    for axis in "XYZABCUVW":
        address = ctypes.cast(getattr(library, f"_Z23GET_EXTERNAL_POSITION_{axis}v"), ctypes.c_void_p).value
        code = ctypes.string_at(address, 9)
        if code[:4] != b"\xf2\x0f\x10\x05" or code[8] != 0xC3:
            return None
        cells.append(ctypes.c_double.from_address(address + 8 + int.from_bytes(code[4:8], "little", signed=True)))
    return cells


class Canon(Translated):
    """LinuxCNC's canonical motions written to ``moves``; messages, spindle, coolant ignored."""

    def __init__(self, parameter_file, moves, tools, length_units):
        self.parameter_file = parameter_file
        self.moves, self.tools, self.length_units = moves, tools, length_units
        self.units, self.feed, self.plane, self.sequence = 2, 0.0, 1, 0
        self.offset = (0.0,) * 6
        self.files, self.started = {"": 0}, False
        self.positions = arc_end_cells()
        self.block, self.mode, self.printed, self.after, self.tolerances = [], None, None, -1, (None, None)

    def __getattr__(self, name):
        if name.startswith("__"):
            raise AttributeError(name)
        return lambda *arguments: None

    def next_line(self, state):
        mode = self.mode_of(state)
        self.flush(mode if state.sequence_number and self.after == self.sequence else self.mode)
        self.sequence, self.units, self.mode = state.sequence_number, state.units, mode
        self.where()

    def mode_of(self, state):
        """(path mode, P mm, Q mm) the interpreter's ``state`` holds; notes in self.after the block
        it holds them after (the gcode module hands the state after the last block executed)."""
        sequence, feed, speed, p, q = struct.unpack("5d", ctypes.string_at(id(state) + SETTINGS, 40))
        if (feed, speed) != (state.feed_rate, state.speed):
            sequence, p, q = -1, 0.0, 0.0  # not the layout expected: G64 without tolerances
        self.after = int(sequence)
        if (p, q) != self.tolerances[:2]:
            scale = UNITS_MM.get(state.units, 1.0)
            self.tolerances = (p, q, p * scale, q * scale)
        return (state.path_mode, *self.tolerances[2:])

    def flush(self, mode):
        """Write the last block's motions after the path control mode they were made in."""
        if self.block and mode != self.printed:
            self.write("B", *map(repr, mode))
            self.printed = mode
        for fields in self.block:
            self.write(*fields)
        self.block = []

    def where(self):
        """(file number, line) of the block being executed (file 0: the start-up code)."""
        import interpreter  # LinuxCNC's embedded module, there once the interpreter runs

        this = interpreter.this
        name = this.filename or ""
        if name not in self.files:
            self.files[name] = len(self.files)
            self.write(f"F {self.files[name]} {os.path.abspath(name)}")
        if name and not self.started:
            self.started = True
            self.write("W", self.g5x_index if hasattr(self, "g5x_index") else 1,
                       *map(repr, (self.g5x_offset_x, self.g5x_offset_y, self.g5x_offset_z, self.g5x_offset_a,
                                   self.g5x_offset_b, self.g5x_offset_c)),
                       *map(repr, (self.g92_offset_x, self.g92_offset_y, self.g92_offset_z, self.g92_offset_a,
                                   self.g92_offset_b, self.g92_offset_c)), repr(self.rotation_xy))
        return self.files[name], this.sequence_number

    def write(self, *fields):
        self.moves.write(" ".join(map(str, fields)) + "\n")

    def get_tool(self, pocket):
        """The tool table's entry at ``pocket``; pocket 0 (the spindle) is the entry of the pocket
        the interpreter has in the spindle (after M6, and after M61, which makes no canon call)."""
        if pocket == 0:
            import interpreter

            current = interpreter.this.current_pocket
            self.tools.spindle = current if current > 0 else None
        return self.tools.entry(pocket)

    def tool_offset(self, *values):
        """The tool length offset (inches, degrees): x y z a b c of the nine values it is given."""
        self.offset = tuple(values[:6])

    def get_external_angular_units(self):
        return 1.0

    def get_external_length_units(self):
        return self.length_units

    def get_axis_mask(self):
        return 0x3F

    def get_block_delete(self):
        return 0

    def set_feed_rate(self, feed):
        self.feed = feed

    def set_plane(self, plane):
        self.plane = plane

    def _print(self, kind, position, extra=""):
        where = self.where()
        shifted = [value + offset for value, offset in zip(position[:6], self.offset)]
        self.block.append(("M", *where, kind, self.units, repr(self.feed), *map(repr, shifted), extra))

    def straight_traverse_translated(self, *position):
        self._print("T", position)

    def straight_feed_translated(self, *position):
        self._print("F", position)

    def straight_probe(self, *position):
        self._print("P", self.rotate_and_translate(*position))

    def rigid_tap(self, x, y, z, *scale):
        self._print("R", self.rotate_and_translate(x, y, z, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0))

    def arc_feed(self, first, second, first_center, second_center, rotation, axis, a, b, c, u=0.0, v=0.0, w=0.0):
        order = {1: (0, 1, 2), 2: (1, 2, 0), 3: (2, 0, 1)}[self.plane]  # x, y, z of (first, second, normal)
        end, center = [0.0] * 3, [0.0] * 3
        for values, point in (((first, second, axis), end), ((first_center, second_center, axis), center)):
            for value, index in zip(values, order):
                point[index] = value
        end = self.rotate_and_translate(*end, a, b, c, u, v, w)
        center = self.rotate_and_translate(*center, a, b, c, u, v, w)
        centre = [center[index] + self.offset[index] for index in order[:2]]
        self._print("A", end, f"{centre[0]!r} {centre[1]!r} {rotation} {self.plane}")
        if self.positions is not None:  # the arc's end in the program's units, before offsets
            scale = MM_PER_INCH if self.units == MM_UNITS else 1.0
            point = [0.0] * 3
            for value, index in zip((first, second, axis), order):
                point[index] = value * scale
            for cell, value in zip(self.positions, point + [a, b, c, u * scale, v * scale, w * scale]):
                cell.value = value


def main(program, unit_code, start_code, moves_fd, table, parameter_file, length_units):
    with os.fdopen(int(moves_fd), "w", buffering=1 << 16) as moves:
        canon = Canon(parameter_file, moves, Tools(table), float(length_units))
        result, _ = gcode.parse(program, canon, unit_code, start_code)
        canon.flush(canon.mode)
        if result > gcode.MIN_ERROR:
            file, line = canon.where()
            canon.write("E", file, line, " ".join(gcode.strerror(result).split()))
        else:
            canon.write("D")


if __name__ == "__main__":
    main(*sys.argv[1:])
