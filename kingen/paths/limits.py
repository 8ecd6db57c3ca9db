"""The limits a program is checked against: each joint's travel, top speed and top acceleration
from the robot file (``travel``, ``max_speed``, ``max_acceleration`` of each limb) or from a
LinuxCNC ``.ini`` (``[JOINT_n] MIN_LIMIT, MAX_LIMIT, MAX_VELOCITY, MAX_ACCELERATION``; a wrist's
joints after the legs', their speeds and accelerations from the ``.ini`` only), and
the path's own speed and acceleration caps from the ``.ini``'s ``[TRAJ]`` (what LinuxCNC's
planner moves the tool at). The ``.ini`` is read as LinuxCNC reads it (:mod:`.ini`); it also
names the tool table and parameter file the interpreter starts with (``[EMCIO] TOOL_TABLE``,
``[RS274NGC] PARAMETER_FILE``), and what LinuxCNC's trajectory planner (:mod:`.planner`) moves the tool
with: each axis's ``[AXIS_L] MAX_VELOCITY`` and ``MAX_ACCELERATION``, ``[TRAJ] ARC_BLEND_*``,
``[EMCMOT] SERVO_PERIOD`` and ``[DISPLAY] MAX_FEED_OVERRIDE``.

Internal units throughout: mm and radians for joints (per s, per s^2), mm/s and mm/s^2 for
the path. Where both give a limit, the tighter one holds.
"""

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import located
from .ini import load_ini

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
MACHINE_KEYS = (("EMCMOT", "SERVO_PERIOD"), ("DISPLAY", "MAX_FEED_OVERRIDE"))
"""The servo period and the largest feed override, which the planner's timing reads."""


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
    arc_blends: bool
    depth: int
    kink_ratio: float
    cycle: float
    feed_scale: float
    unit: float
    """mm per the .ini's [TRAJ] LINEAR_UNITS (ini_unit): what the interpreter reads lengths in."""

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


JOINT_KEYS = ("MIN_LIMIT", "MAX_LIMIT", "MAX_VELOCITY", "MAX_ACCELERATION")
TRAJ_KEYS = ("LINEAR_UNITS", "MAX_LINEAR_VELOCITY", "MAX_VELOCITY", "MAX_LINEAR_ACCELERATION", "MAX_ACCELERATION")
FILE_KEYS = (("EMCIO", "TOOL_TABLE"), ("RS274NGC", "PARAMETER_FILE"))
"""The files an ``.ini`` names that the interpreter starts with (relative to the ``.ini``'s folder)."""


SUBROUTINE_PATH = ("RS274NGC", "SUBROUTINE_PATH")
"""Where the interpreter looks for a subroutine called by name: folders separated by ``:``."""


def ini_keys(joint_count):
    """Every (section, key) check-path reads from an ``.ini`` for a robot of ``joint_count`` joints."""
    return ([(f"JOINT_{index}", key) for index in range(joint_count) for key in JOINT_KEYS]
            + [("TRAJ", key) for key in TRAJ_KEYS] + list(FILE_KEYS) + [SUBROUTINE_PATH]
            + [(f"AXIS_{axis}", key) for axis in AXES for key in ("MAX_VELOCITY", "MAX_ACCELERATION")]
            + [("TRAJ", key) for key in PLANNER_KEYS] + list(MACHINE_KEYS))


def ini_subroutine_path(ini):
    """The folders of the ``.ini``'s [RS274NGC] SUBROUTINE_PATH, relative ones taken from its
    folder, as absolute paths (a tuple; empty when it names none)."""
    text = ini.get(*SUBROUTINE_PATH) or ""
    return tuple(str((Path(ini.path).parent / name).resolve()) for name in text.split(":") if name.strip())


def _number(ini, section, key):
    """[section] key as a finite number (None when absent), above 0 for a speed, acceleration or
    planner setting (a key other than MIN_LIMIT, MAX_LIMIT and the switch ARC_BLEND_ENABLE);
    KingenError otherwise."""
    text = ini.get(section, key)
    if text is None:
        return None
    try:
        value = float(text.split()[0])
    except (ValueError, IndexError):
        value = float("nan")
    if not np.isfinite(value):
        raise located(ini.path, ini.line(section, key), f"[{section}] {key}", f"{text!r} is not a number")
    if value <= 0.0 and key not in ("MIN_LIMIT", "MAX_LIMIT", "ARC_BLEND_ENABLE"):
        raise located(ini.path, ini.line(section, key), f"[{section}] {key}", f"{text!r}: must be above 0")
    return value


def ini_unit(ini):
    """The ``.ini``'s [TRAJ] LINEAR_UNITS in mm (default mm); KingenError for another word."""
    unit_word = (ini.get("TRAJ", "LINEAR_UNITS") or "mm").split()[0].lower()
    if unit_word not in INI_UNITS:
        raise located(ini.path, ini.line("TRAJ", "LINEAR_UNITS"), "[TRAJ] LINEAR_UNITS",
                      f"{unit_word!r}: mm or inch expected")
    return INI_UNITS[unit_word]


def ini_files(ini):
    """{(section, key): path} of the tool table and parameter file the ``.ini`` names, relative
    names taken from its folder. A parameter file that is not there yet is left out (LinuxCNC
    starts without offsets and writes it); KingenError (file:line) for a tool table that is not
    a file."""
    found = {}
    for section, key in FILE_KEYS:
        name = ini.get(section, key)
        if name is None:
            continue
        path = Path(ini.path).parent / name
        if path.is_file():
            found[section, key] = path
        elif key == "TOOL_TABLE":
            raise located(ini.path, ini.line(section, key), f"[{section}] {key}", f"{name!r}: no such file")
    return found


def ini_limits(robot, path, ini=None):
    """The limits a LinuxCNC ``.ini`` gives ``robot``'s joints and path, in internal units: its
    [TRAJ] LINEAR_UNITS (mm or inch; default mm) for prismatic joints and the path, degrees for
    revolute joints. KingenError (file:line) when it lacks a [JOINT_n] of the robot's joints or
    a joint lacks MAX_VELOCITY or MAX_ACCELERATION. ``ini``: the file as read (load_ini), when
    the caller has read it already."""
    count = robot.joint_count
    ini = load_ini(path, ini_keys(count)) if ini is None else ini
    unit = ini_unit(ini)
    missing = [index for index in range(count) if not ini.has_section(f"JOINT_{index}")]
    if missing:
        raise located(path, ini.length, f"[JOINT_{missing[0]}]", f"missing (the file ends here): the robot has "
                                                                 f"{count} joints (JOINT_0 .. JOINT_{count - 1})")
    scale = np.where(robot.revolute, np.pi / 180.0, unit)
    values = {}
    for key in JOINT_KEYS:
        column = [_number(ini, f"JOINT_{index}", key) for index in range(count)]
        for index, value in enumerate(column):
            if value is None and key.startswith("MAX_") and key != "MAX_LIMIT":
                raise located(path, ini.line(f"JOINT_{index}"), f"[JOINT_{index}] {key}", "missing")
        default = -np.inf if key == "MIN_LIMIT" else np.inf
        values[key] = np.array([default if value is None else value for value in column]) * scale
    trajectory = {key: _number(ini, "TRAJ", key) for key in TRAJ_KEYS[1:]}
    path_speed = trajectory["MAX_LINEAR_VELOCITY"] or trajectory["MAX_VELOCITY"]
    path_acceleration = trajectory["MAX_LINEAR_ACCELERATION"] or trajectory["MAX_ACCELERATION"]
    return Limits(values["MIN_LIMIT"], values["MAX_LIMIT"], values["MAX_VELOCITY"], values["MAX_ACCELERATION"],
                  path_speed=path_speed * unit if path_speed else None,
                  path_acceleration=path_acceleration * unit if path_acceleration else None,
                  rapid_speed=path_speed * unit if path_speed else None,
                  sources=(f"{path} (read by {ini.reader} reader)",), machine=_machine(ini, unit))


def _machine(ini, unit):
    """The .ini's Machine: axis limits in mm (``unit``: mm per the .ini's linear unit) and degrees."""
    def number(section, key, default):
        value = _number(ini, section, key)
        return default if value is None else value

    rates = [np.array([number(f"AXIS_{axis}", key, np.inf) for axis in AXES]) * np.r_[[unit] * 3, [1.0] * 3]
             for key in ("MAX_VELOCITY", "MAX_ACCELERATION")]
    settings = {key: number("TRAJ", key, default) for key, default in PLANNER_KEYS.items()}
    period = number("EMCMOT", "SERVO_PERIOD", 1e6)
    return Machine(*rates, arc_blends=settings["ARC_BLEND_ENABLE"] != 0.0,
                   depth=int(settings["ARC_BLEND_OPTIMIZATION_DEPTH"]), kink_ratio=settings["ARC_BLEND_KINK_RATIO"],
                   cycle=period * 1e-9, feed_scale=number("DISPLAY", "MAX_FEED_OVERRIDE", 1.0), unit=unit)


def combined(first, second):
    """The tighter of two Limits, joint by joint; the path caps of whichever gives them."""
    def pick(name):
        return getattr(second, name) if getattr(second, name) is not None else getattr(first, name)

    return Limits(np.maximum(first.lower, second.lower), np.minimum(first.upper, second.upper),
                  np.minimum(first.speed, second.speed), np.minimum(first.acceleration, second.acceleration),
                  pick("path_speed"), pick("path_acceleration"), pick("rapid_speed"), first.sources + second.sources,
                  pick("machine"))


def limits_for(robot, ini=None, read=None):
    """The limits a program on ``robot`` is checked against: the robot file's, tightened by the
    ``.ini``'s when one is given (``read``: that file as load_ini read it, when it has been)."""
    limits = robot_limits(robot)
    return combined(limits, ini_limits(robot, ini, read)) if ini is not None else limits
