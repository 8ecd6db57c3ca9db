"""Run as a script by the Python that has LinuxCNC's ``gcode`` module (Debian's
/usr/bin/python3), never imported by kingen: LinuxCNC's own interpreter (the one AXIS's
preview runs) reads the program given as the first argument, after the start-up code given as
the second (as AXIS gives it the machine's position), and this canon prints, one line each,
every motion it is asked for (line 0: the start-up code's), in plain text that kingen.paths.interpreter reads:

    M <line> <kind> <units> <feed> x y z a b c [first second rotation plane]

kind T (traverse), F (straight feed) or A (arc); positions with the program's offsets and
rotation applied as AXIS applies them (rs274.interpret.Translated), in LinuxCNC's internal
units (inches, degrees); feed as the interpreter hands it (inches/min); units the program's
(1 inch, 2 mm, 3 cm) when the move was made. Before a block's moves, the path control mode they
are made in when it differs from the last printed (the interpreter's state after the block when
the gcode module hands it with the next block's first move, as a block's G61/G64 applies to its
own motion; else the state before the block: a G61/G64 on a moving line followed by a line
that does not move takes effect from the next moving line):

    B <mode> <p> <q>    mode 610 (G61), 611 (G61.1) or 640 (G64); G64's P and Q in mm

The end, after the last move:

    E <sequence> <message>  the interpreter refused the program: its last sequence number
    D                       the program was read to its end
"""

import ctypes
import os
import struct
import sys
import tempfile

import gcode
from rs274.interpret import Translated

TOOL = (0.0,) * 12 + (0,)
SETTINGS = 16
"""Where the interpreter's active settings (sequence number, feed, speed, G64 P, G64 Q: five
doubles) start in the gcode module's line-code object, after the object's header (64-bit CPython);
the module exposes the first three only, which tell whether the offset holds."""
UNITS_MM = {200: 25.4, 210: 1.0}
"""mm per program unit, by the interpreter's units word (G20, G21)."""


class Canon(Translated):
    """LinuxCNC's canonical calls printed; everything else (spindle, coolant, messages) ignored."""

    def __init__(self, parameter_file):
        self.parameter_file = parameter_file
        self.line, self.units, self.feed, self.plane = 0, 2, 0.0, 1
        self.block, self.mode, self.printed, self.after, self.tolerances = [], None, None, -1, (None, None)

    def __getattr__(self, name):
        return lambda *arguments: None

    def next_line(self, state):
        mode = self.mode_of(state)
        self.flush(mode if state.sequence_number and self.after == self.line else self.mode)
        self.line, self.units, self.mode = state.sequence_number, state.units, mode

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
        """Print the last block's moves after the path control mode they were made in."""
        if self.block and mode != self.printed:
            print("B", *map(repr, mode))
            self.printed = mode
        for line in self.block:
            print(*line)
        self.block = []

    def get_tool(self, tool):
        return (tool,) + TOOL

    def get_external_angular_units(self):
        return 1.0

    def get_external_length_units(self):
        return 1.0

    def get_axis_mask(self):
        return 0x3F

    def get_block_delete(self):
        return 0

    def set_feed_rate(self, feed):
        self.feed = feed

    def set_plane(self, plane):
        self.plane = plane

    def _print(self, kind, position, extra=""):
        self.block.append(("M", self.line, kind, self.units, repr(self.feed), *map(repr, position[:6]), extra))

    def straight_traverse_translated(self, *position):
        self._print("T", position)

    def straight_feed_translated(self, *position):
        self._print("F", position)

    def arc_feed(self, first, second, first_center, second_center, rotation, axis, a, b, c, u=0.0, v=0.0, w=0.0):
        order = {1: (0, 1, 2), 2: (1, 2, 0), 3: (2, 0, 1)}[self.plane]  # x, y, z of (first, second, normal)
        end, center = [0.0] * 3, [0.0] * 3
        for values, point in (((first, second, axis), end), ((first_center, second_center, axis), center)):
            for value, index in zip(values, order):
                point[index] = value
        end = self.rotate_and_translate(*end, a, b, c, u, v, w)
        center = self.rotate_and_translate(*center, a, b, c, u, v, w)
        self._print("A", end, f"{center[order[0]]!r} {center[order[1]]!r} {rotation} {self.plane}")


def main(program, start):
    with tempfile.TemporaryDirectory() as folder:
        parameters = os.path.join(folder, "kingen.var")
        open(parameters, "w").close()
        canon = Canon(parameters)
        result, sequence = gcode.parse(program, canon, "", start)
        canon.flush(canon.mode)
    if result > gcode.MIN_ERROR:
        print("E", sequence, " ".join(gcode.strerror(result).split()))
    else:
        print("D")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
