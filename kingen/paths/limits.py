"""The limits a program is checked against: each joint's travel, top speed and top acceleration
from the robot file (``travel``, ``max_speed``, ``max_acceleration`` of each limb) or from a
LinuxCNC ``.ini`` (``[JOINT_n] MIN_LIMIT, MAX_LIMIT, MAX_VELOCITY, MAX_ACCELERATION``; a wrist's
joints after the legs', their speeds and accelerations from the ``.ini`` only), and
the path's own speed and acceleration caps from the ``.ini``'s ``[TRAJ]``, and what LinuxCNC's
trajectory planner (:mod:`.planner`) moves the tool with: each axis's ``[AXIS_L] MAX_VELOCITY`` and
``MAX_ACCELERATION``, ``[TRAJ] ARC_BLEND_*``, ``[EMCMOT] SERVO_PERIOD`` and ``[DISPLAY]
MAX_FEED_OVERRIDE``.

Internal units throughout: mm and radians for joints (per s, per s^2), mm/s and mm/s^2 for
the path. Where both give a limit, the tighter one holds.
"""

import configparser
from dataclasses import dataclass

import numpy as np

from ..errors import located
from ..runtime.file_gate import read_limited

INI_BYTES = 1 << 20
INI_UNITS = {"mm": 1.0, "metric": 1.0, "millimeter": 1.0, "inch": 25.4, "in": 25.4, "imperial": 25.4}
"""[TRAJ] LINEAR_UNITS words LinuxCNC accepts, in mm."""


@dataclass(frozen=True)
class Limits:
    """(dof,) arrays lower, upper (mm or rad; -inf/+inf: none), speed (per s), acceleration
    (per s^2; inf: none); path_speed and path_acceleration (mm/s, mm/s^2, None: not given),
    rapid_speed (mm/s, None: rapids are not timed); sources: where they came from, in words;
    machine: the .ini's Machine (None: no .ini)."""

    lower: np.ndarray
    upper: np.ndarray
    speed: np.ndarray
    acceleration: np.ndarray
    path_speed: float = None
    path_acceleration: float = None
    rapid_speed: float = None
    sources: tuple = ()
    machine: object = None


AXES = "XYZABC"
PLANNER_KEYS = {"ARC_BLEND_ENABLE": 1.0, "ARC_BLEND_OPTIMIZATION_DEPTH": 50.0, "ARC_BLEND_KINK_RATIO": 0.1}
"""[TRAJ] settings of LinuxCNC's planner that kingen follows, with LinuxCNC's defaults."""


@dataclass(frozen=True)
class Machine:
    """What LinuxCNC's trajectory planner moves the tool with, from an .ini: axis_speed and
    axis_acceleration (6,) the [AXIS_X] .. [AXIS_C] MAX_VELOCITY and MAX_ACCELERATION (mm/s, mm/s^2
    for X Y Z; deg/s, deg/s^2 for A B C; inf where the axis has no section or key);
    arc_blends ([TRAJ] ARC_BLEND_ENABLE), depth (ARC_BLEND_OPTIMIZATION_DEPTH, segments looked
    ahead), kink_ratio (ARC_BLEND_KINK_RATIO), cycle (s: [EMCMOT] SERVO_PERIOD, the planner's
    period), feed_scale ([DISPLAY] MAX_FEED_OVERRIDE, the largest feed override the blends are
    planned for)."""

    axis_speed: np.ndarray
    axis_acceleration: np.ndarray
    arc_blends: bool = True
    depth: int = 50
    kink_ratio: float = 0.1
    cycle: float = 0.001
    feed_scale: float = 1.0

    @property
    def accelerated(self):
        """Whether the .ini gives an acceleration for every one of X, Y, Z (then the planner's
        timing applies)."""
        return bool(np.all(np.isfinite(self.axis_acceleration[:3])))


def robot_limits(robot):
    """The limits the robot file gives (internal units); a wrist's joints have travel only."""
    lower, upper = robot.travel_limits()
    scale = robot.joint_scale()
    wrist = [np.inf] * (robot.joint_count - robot.dof)
    rates = [np.array([getattr(limb, name) if getattr(limb, name) is not None else np.inf for limb in robot.limbs]
                      + wrist) * scale for name in ("max_speed", "max_acceleration")]
    return Limits(lower, upper, *rates, sources=("the robot file",))


def _ini(path):
    text = read_limited(path, INI_BYTES, "LinuxCNC .ini").decode("utf-8", "replace")
    parser = configparser.ConfigParser(strict=False, interpolation=None, comment_prefixes=("#", ";"),
                                       inline_comment_prefixes=None)
    parser.optionxform = str.upper
    try:
        parser.read_string(text, source=str(path))
    except configparser.Error as error:
        raise located(path, getattr(error, "lineno", None), "ini", " ".join(str(error.message).split())) from None
    return parser, text.splitlines()


def _line_of(lines, section):
    """The line of ``[section]`` in the file (1-based), or None."""
    return next((number for number, text in enumerate(lines, start=1) if text.strip() == f"[{section}]"), None)


def _number(parser, lines, path, section, key):
    """[section] key as a finite number (None when absent), above 0 for a speed, acceleration or
    planner setting (a key other than MIN_LIMIT, MAX_LIMIT and the switch ARC_BLEND_ENABLE);
    KingenError otherwise."""
    text = parser.get(section, key, fallback=None)
    if text is None:
        return None
    try:
        value = float(text.split()[0])
    except (ValueError, IndexError):
        value = float("nan")
    if not np.isfinite(value):
        raise located(path, _line_of(lines, section), f"[{section}] {key}", f"{text!r} is not a number")
    if value <= 0.0 and key not in ("MIN_LIMIT", "MAX_LIMIT", "ARC_BLEND_ENABLE"):
        raise located(path, _line_of(lines, section), f"[{section}] {key}", f"{text!r}: must be above 0")
    return value


def ini_limits(robot, path):
    """The limits a LinuxCNC ``.ini`` gives ``robot``'s joints and path, in internal units: its
    [TRAJ] LINEAR_UNITS (mm or inch; default mm) for prismatic joints and the path, degrees for
    revolute joints. KingenError (file:line) when it lacks a [JOINT_n] of the robot's joints or
    a joint lacks MAX_VELOCITY or MAX_ACCELERATION."""
    parser, lines = _ini(path)
    unit_word = parser.get("TRAJ", "LINEAR_UNITS", fallback="mm").split()[0].lower() if parser.has_section(
        "TRAJ") else "mm"
    if unit_word not in INI_UNITS:
        raise located(path, _line_of(lines, "TRAJ"), "[TRAJ] LINEAR_UNITS", f"{unit_word!r}: mm or inch expected")
    unit = INI_UNITS[unit_word]
    count = robot.joint_count
    missing = [index for index in range(count) if not parser.has_section(f"JOINT_{index}")]
    if missing:
        raise located(path, len(lines), f"[JOINT_{missing[0]}]", f"missing (the file ends here): the robot has "
                                                                 f"{count} joints (JOINT_0 .. JOINT_{count - 1})")
    scale = np.where(robot.revolute, np.pi / 180.0, unit)
    values = {}
    for key in ("MIN_LIMIT", "MAX_LIMIT", "MAX_VELOCITY", "MAX_ACCELERATION"):
        column = [_number(parser, lines, path, f"JOINT_{index}", key) for index in range(count)]
        for index, value in enumerate(column):
            if value is None and key.startswith("MAX_") and key != "MAX_LIMIT":
                raise located(path, _line_of(lines, f"JOINT_{index}"), f"[JOINT_{index}] {key}", "missing")
        default = -np.inf if key == "MIN_LIMIT" else np.inf
        values[key] = np.array([default if value is None else value for value in column]) * scale
    trajectory = {key: _number(parser, lines, path, "TRAJ", key) if parser.has_section("TRAJ") else None
                  for key in ("MAX_LINEAR_VELOCITY", "MAX_VELOCITY", "MAX_LINEAR_ACCELERATION", "MAX_ACCELERATION")}
    path_speed = trajectory["MAX_LINEAR_VELOCITY"] or trajectory["MAX_VELOCITY"]
    path_acceleration = trajectory["MAX_LINEAR_ACCELERATION"] or trajectory["MAX_ACCELERATION"]
    return Limits(values["MIN_LIMIT"], values["MAX_LIMIT"], values["MAX_VELOCITY"], values["MAX_ACCELERATION"],
                  path_speed=path_speed * unit if path_speed else None,
                  path_acceleration=path_acceleration * unit if path_acceleration else None,
                  rapid_speed=path_speed * unit if path_speed else None, sources=(str(path),),
                  machine=_machine(parser, lines, path, unit))


def _machine(parser, lines, path, unit):
    """The .ini's Machine: axis limits in mm (``unit``: mm per the .ini's linear unit) and degrees."""
    def number(section, key, default):
        value = _number(parser, lines, path, section, key) if parser.has_section(section) else None
        return default if value is None else value

    rates = [np.array([number(f"AXIS_{axis}", key, np.inf) for axis in AXES]) * np.r_[[unit] * 3, [1.0] * 3]
             for key in ("MAX_VELOCITY", "MAX_ACCELERATION")]
    settings = {key: number("TRAJ", key, default) for key, default in PLANNER_KEYS.items()}
    period = number("EMCMOT", "SERVO_PERIOD", 1e6)
    return Machine(*rates, arc_blends=settings["ARC_BLEND_ENABLE"] != 0.0,
                   depth=int(settings["ARC_BLEND_OPTIMIZATION_DEPTH"]), kink_ratio=settings["ARC_BLEND_KINK_RATIO"],
                   cycle=period * 1e-9, feed_scale=number("DISPLAY", "MAX_FEED_OVERRIDE", 1.0))


def combined(first, second):
    """The tighter of two Limits, joint by joint; the path caps of whichever gives them."""
    def pick(name):
        return getattr(second, name) if getattr(second, name) is not None else getattr(first, name)

    return Limits(np.maximum(first.lower, second.lower), np.minimum(first.upper, second.upper),
                  np.minimum(first.speed, second.speed), np.minimum(first.acceleration, second.acceleration),
                  pick("path_speed"), pick("path_acceleration"), pick("rapid_speed"), first.sources + second.sources,
                  pick("machine"))


def limits_for(robot, ini=None):
    """The limits a program on ``robot`` is checked against: the robot file's, tightened by the
    ``.ini``'s when one is given."""
    limits = robot_limits(robot)
    return combined(limits, ini_limits(robot, ini)) if ini is not None else limits
