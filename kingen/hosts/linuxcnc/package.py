"""Packaging for LinuxCNC: the module's source and built module, a ``.hal`` snippet (loadrt
and the geometry's setp lines), an ``.ini`` snippet ([TRAJ] with the units, the home and the
path's top speed and acceleration; [KINS]; one [JOINT_n] per joint with the robot file's travel
limits, the joint at the verification home and its top speed and acceleration, the robot file's
or a stated default) and a setup sheet."""

import math
import shutil
from pathlib import Path

import numpy as np

from ...defaults import VERSION
from ...defaults import DEFAULT_TIMEOUT
from ...runtime.files import write_atomic, write_folder
from ...robot.placement import frames
from ...kinematics.home import workable_home
from ..render import template
from ..wrist import branch_words
from ...kinematics.routine import WARNINGS, warnings_to_exercise
from .build import build_module, header_folder, headers_found
from ..base import Written
from ...units import LENGTH_UNITS, robot_in_units
from .render import TEMPLATES, module_name, source_name, view_model
from .five_axis import coordinates, world_of_t6, wrist_joints
from ...conventions import t6_from_pose


def _number(value):
    return f"{value:.10g}"


def _exact(value):
    """A number as Python's shortest round-trip text: what LinuxCNC reads back is the module's double."""
    return repr(float(value))


DEFAULT_PATH_SPEED_MM = 100.0
"""[TRAJ] MAX_LINEAR_VELOCITY, the tool's top speed along its path: mm/s, written in the machine's
units. A stated start, not a machine's: the ``.ini`` and the sheet say so."""
DEFAULT_PATH_ACCELERATION_MM = 1000.0
"""[TRAJ] MAX_LINEAR_ACCELERATION: mm/s^2, written in the machine's units."""
DEFAULT_SPEED = {"LINEAR": 200.0, "ANGULAR": 180.0}
"""A joint's MAX_VELOCITY in the ``.ini`` where the robot file gives it no ``max_speed`` (a wrist's
joints never have one): mm/s (written in the machine's units) for a prismatic joint, degrees/s
for a revolute one; twice the path's, so that a leg moving faster than the tool (an inclined
rail) keeps up with the path's defaults."""
DEFAULT_ACCELERATION = {"LINEAR": 2000.0, "ANGULAR": 1800.0}
"""A joint's MAX_ACCELERATION where the robot file gives no ``max_acceleration``: mm/s^2 or
degrees/s^2, twice the path's."""


def _rates(machine, index, joint_type, units):
    """The ``.ini``'s MAX_VELOCITY and MAX_ACCELERATION of joint ``index`` of ``machine`` (the
    robot in the machine's ``units``): the robot file's ``max_speed`` and ``max_acceleration`` of
    a leg, else the defaults. {speed, acceleration: the numbers as text, with " (default)" in
    ``speed_shown`` and ``acceleration_shown`` for a default; defaulted: why a default stands, or ""}."""
    limb = machine.limbs[index] if index < machine.dof else None
    scale = 1.0 if joint_type == "ANGULAR" else 1.0 / LENGTH_UNITS[units]
    rates, missing = {}, []
    for key, field, defaults in (("speed", "max_speed", DEFAULT_SPEED),
                                 ("acceleration", "max_acceleration", DEFAULT_ACCELERATION)):
        given = getattr(limb, field) if limb is not None else None
        rates[key] = _number(given if given is not None else defaults[joint_type] * scale)
        rates[f"{key}_shown"] = rates[key] + (" (default)" if given is None else "")
        missing += [field] if given is None else []
    rates["defaulted"] = ("the robot file gives a wrist's joints no top speed or acceleration" if limb is None
                          else f"the robot file gives this joint no {' or '.join(missing)}" if missing else "")
    return rates


STATUS_WORDS = {"WARN_GOOD_SOLUTION": "good", "WARN_JOINT_LIMITS_EXCEEDED": "a joint beyond its travel",
                "WARN_UNREACHABLE": "unreachable", "WARN_SINGULAR_SOLUTION": "singular"}
"""The status pin's values in words; the sheet lists only those the robot's module can give."""


def joint_meanings(robot, units):
    """What each limb model's joint measures, once per model of ``robot`` in the order of its
    limbs: {model, unit ('degrees' or ``units``), words (the model's ``joint_words``)}."""
    meanings = {}
    for limb in robot.limbs:
        unit = "degrees" if limb.joint_type.wraps else units
        meanings.setdefault(limb.model, {"model": limb.model, "unit": unit, "words": type(limb).joint_words})
    return list(meanings.values())


def sheet_view(robot, units="mm", compiled=True):
    """What the snippets and the sheet show, in the machine's ``units``: the module view plus
    the joints' homes and limits, the frames placed by the limbs' joints, and only the
    statuses the robot's module can give (:func:`kingen.kinematics.routine.warnings_to_exercise`);
    ``compiled``: whether the package holds the built module (else the sheet says how to build it).
    KingenError when the working posture cannot be the machine's home (unreachable, a joint
    beyond its travel, singular: :func:`kingen.kinematics.home.workable_home`): the
    [JOINT_n] HOME values would lie outside their limits."""
    joints = workable_home(robot, robot.working_posture, "a LinuxCNC package").joints
    view = view_model(robot, units)
    home = np.asarray(robot.verification.home, dtype=float)
    machine = robot_in_units(robot, units)
    lower, upper = machine.travel_limits()
    ini = []
    for joint in view["joints"] + (wrist_joints(robot) if robot.wrist is not None else []):
        index, revolute = joint["index"], joint["revolute"]
        scale = 180.0 / math.pi if revolute else 1.0
        limited = bool(joint["limited"])
        joint_type = "ANGULAR" if revolute else "LINEAR"
        ini.append({**joint, **_rates(machine, index, joint_type, units), "type": joint_type,
                    "lower": _number(lower[index] * scale) if limited else "",
                    "upper": _number(upper[index] * scale) if limited else "",
                    "travel": f"[{_number(lower[index] * scale)}, {_number(upper[index] * scale)}]" if limited else "-",
                    "home": _exact(joints[index] * (scale if revolute else 1.0 / LENGTH_UNITS[units]))})
    parameters = [{**parameter, "value": _exact(parameter["value"])} for parameter in view["parameters"]]
    position = home[:3] / LENGTH_UNITS[units]
    world = (*position, *home[3:]) if robot.wrist is None else world_of_t6(robot, t6_from_pose(home[None]),
                                                                             LENGTH_UNITS[units])[0, :6]
    can_give = ["WARN_GOOD_SOLUTION", *warnings_to_exercise(robot)]
    statuses = sorted((WARNINGS[name], STATUS_WORDS[name]) for name in can_give)
    refused = [str(code) for code, _ in statuses if code in (WARNINGS["WARN_UNREACHABLE"], WARNINGS["WARN_SINGULAR_SOLUTION"])]
    if robot.wrist is not None:  # the five-axis module answers the wrist's own singularity
        refused[-1] += " (the legs' singularity; the wrist's own is answered)"
    return {**view, "ini_joints": ini, "frames": frames(robot, units),
            "statuses": ", ".join(f"{code} {words}" for code, words in statuses), "refused": " and ".join(refused), "parameters": parameters, "version": VERSION,
            "joint_count": robot.joint_count, "coordinates": " ".join(coordinates(robot)) if robot.wrist is not None else None,
            "joint_meanings": joint_meanings(robot, units), "compiled": compiled,
            "home_text": " ".join(_exact(value) for value in world), "description": robot.description,
            "units": units, "path_speed": _number(DEFAULT_PATH_SPEED_MM / LENGTH_UNITS[units]),
            "path_acceleration": _number(DEFAULT_PATH_ACCELERATION_MM / LENGTH_UNITS[units]),
            "wrist_branch": _wrist_branch(robot)}


def _wrist_branch(robot):
    """The wrist's branch the module answers (the working posture's last digit) and it in
    words (kingen.hosts.wrist.branch_words), or None without a wrist."""
    if robot.wrist is None:
        return None
    number = robot.working_posture % 2
    return {"number": number, "words": branch_words(robot)[number]}


def render_package(robot, units="mm", compiled=True):
    """The text files of the package as {file name: text}; ``compiled``: whether the package
    holds the built module beside them."""
    view = sheet_view(robot, units, compiled)
    module = module_name(robot)
    return {source_name(robot): template("kins.c.j2", TEMPLATES).render(**view), f"{module}.hal": template("module.hal.j2", TEMPLATES).render(**view),
            f"{module}.ini": template("module.ini.j2", TEMPLATES).render(**view),
            "SETUP.md": template("setup_sheet.md.j2", TEMPLATES).render(**view)}


def write_package(robot, out_dir, units="mm", timeout=DEFAULT_TIMEOUT):
    """Write the package folder whole or not at all, with the built module when LinuxCNC's
    headers are found (:func:`.build.linuxcnc_headers`); without them, the source, snippets and
    sheet only, and the returned paths' ``notices`` say so and how to build the module."""
    compiled = headers_found()
    files = render_package(robot, units, compiled)
    library = f"{module_name(robot)}.so"

    def fill(staging):
        if compiled:
            built = build_module(robot, staging / ".build", units, timeout=timeout)
            write_atomic(staging / library, built.library.read_bytes(), executable=True)
            shutil.rmtree(staging / ".build")
        for name, text in files.items():
            write_atomic(staging / name, text)

    write_folder(out_dir, fill, f"written by kingen for {robot.name} (linuxcnc)\n")
    if compiled:
        return Written(Path(out_dir) / name for name in (*files, library))
    notice = (f"{library} not built: LinuxCNC's headers are not in {header_folder()} (install Debian's "
              f"linuxcnc-uspace-dev or set KINGEN_LINUXCNC_INCLUDE); on the machine, build it with "
              f"'halcompile --install {source_name(robot)}' (SETUP.md)")
    return Written((Path(out_dir) / name for name in files), [notice])
