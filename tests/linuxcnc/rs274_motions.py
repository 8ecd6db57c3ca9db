"""The canonical motions of ``rs274 -g`` (LinuxCNC's standalone interpreter), parsed from its
printed canonical calls on their own, for tests to compare kingen's reading of a program with:
each motion's name and its end point in world coordinates (mm, degrees), the work offsets,
the XY rotation and the tool length offset applied as LinuxCNC's AXIS applies them
(rs274.interpret.Translated: G92, then the rotation, then G5x; the tool length offset added).
A NURBS feed (G5.1, G5.2) is printed without its points: its end is None."""

import math
import re
import subprocess

CALL = re.compile(r"^\s*\d+\s+N\S*\s+([A-Z_0-9]+)\((.*)\)\s*$")
UNITS = {"CANON_UNITS_MM": 1.0, "CANON_UNITS_INCHES": 25.4, "CANON_UNITS_CM": 10.0}
PLANES = {"CANON_PLANE_XY": (0, 1, 2), "CANON_PLANE_YZ": (1, 2, 0), "CANON_PLANE_XZ": (2, 0, 1)}
MOTIONS = ("STRAIGHT_TRAVERSE", "STRAIGHT_FEED", "STRAIGHT_PROBE", "ARC_FEED", "RIGID_TAP", "NURBS_FEED")


def _numbers(text):
    return [float(value) for value in re.findall(r"[-+]?\d+\.?\d*(?:[eE][-+]?\d+)?", text)]


def rs274_motions(program, table, variables, home, cwd):
    """[(name, end (6,) mm and degrees, or None)] of every canonical motion ``rs274 -g`` prints
    for ``program`` with tool table ``table`` and parameter file ``variables``; ``home`` its HOME.
    Raises AssertionError when rs274 reports an error."""
    done = subprocess.run(["rs274", "-g", "-t", str(table), "-v", str(variables), str(program)], cwd=cwd,
                          capture_output=True, text=True, timeout=120, env={"HOME": str(home), "PATH": "/usr/bin:/bin"})
    assert done.returncode == 0, done.stderr
    scale, plane, g5x, g92, rotation, tool = 1.0, PLANES["CANON_PLANE_XY"], [0.0] * 6, [0.0] * 6, 0.0, [0.0] * 6
    position, found = [0.0] * 6, []
    for text in done.stdout.splitlines():
        call = CALL.match(text)
        if call is None:
            continue
        name, arguments = call.groups()
        if name == "USE_LENGTH_UNITS":
            scale = UNITS[arguments.strip()]
        elif name == "SELECT_PLANE":
            plane = PLANES[arguments.strip()]
        elif name == "SET_XY_ROTATION":
            rotation = _numbers(arguments)[0]
        elif name in ("SET_G5X_OFFSET", "SET_G92_OFFSET", "USE_TOOL_LENGTH_OFFSET"):
            values = _numbers(arguments)[1:7] if name == "SET_G5X_OFFSET" else _numbers(arguments)[:6]
            values = [value * (scale if index < 3 else 1.0) for index, value in enumerate(values)]
            g5x, g92, tool = ((values, g92, tool) if name == "SET_G5X_OFFSET" else
                              (g5x, values, tool) if name == "SET_G92_OFFSET" else (g5x, g92, values))
        elif name in MOTIONS:
            values = _numbers(arguments)
            if name == "NURBS_FEED":
                found.append((name, None))
                continue
            if name == "ARC_FEED":
                point = [0.0] * 3
                for value, index in zip((values[0], values[1], values[5]), plane):
                    point[index] = value
                values = point + values[6:9]
            elif name == "RIGID_TAP":
                values = values[:3] + position[3:]
            position = [value * (scale if index < 3 else 1.0) for index, value in enumerate(values[:6])]
            found.append((name, _world(position, g5x, g92, rotation, tool)))
    return found


def _world(position, g5x, g92, rotation, tool):
    shifted = [value + offset for value, offset in zip(position, g92)]
    cosine, sine = math.cos(math.radians(rotation)), math.sin(math.radians(rotation))
    x, y = shifted[0] * cosine - shifted[1] * sine, shifted[0] * sine + shifted[1] * cosine
    shifted[0], shifted[1] = x, y
    return [value + offset + length for value, offset, length in zip(shifted, g5x, tool)]
