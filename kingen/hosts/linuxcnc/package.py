"""Packaging for LinuxCNC: the module's source and built module, a ``.hal`` snippet (loadrt
and the geometry's setp lines), an ``.ini`` snippet ([KINS], one [JOINT_n] per limb with the
robot file's travel limits and the joints at the verification home) and a setup sheet."""

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
        ini.append({**joint, "type": "ANGULAR" if revolute else "LINEAR",
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
