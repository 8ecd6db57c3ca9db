"""Rendering a LinuxCNC kinematics module: robot -> ``<name>kins.c``, from this host's
template, the shared view-model (:func:`kingen.hosts.render.robot_view`) and the limb models'
partials (with their force lines and transmissions, for the forward Jacobian). Pure."""

import hashlib
import math
from dataclasses import replace
from pathlib import Path

from ...robot.limbs import c_double
from ...robot.placement import branch_words
from ..loads import loads_view
from ..render import (refuse, build_info, closed_form_model, gram_lines, newton_stops, robot_view,
                      schur_test_lines, template)
from . import LinuxcncHost
from .five_axis import wrist_view
from ...kinematics.routine import SINGULAR_TOLERANCE
from ...units import LENGTH_UNITS, robot_in_units

TEMPLATES = Path(__file__).resolve().parent / "templates"
HOST = LinuxcncHost()
"""The host the shared view-model asks for the module's names (kingen.hosts.render.robot_view)."""
STOCK_MODULES = frozenset({
    "5axiskins", "corexykins", "genhexkins", "genserkins", "lineardeltakins", "maxkins", "pentakins", "pumakins",
    "rosekins", "rotarydeltakins", "rotatekins", "scarakins", "scorbot-kins", "tripodkins", "trivkins", "userkins",
    "xyzab_tdr_kins", "xyzac-trt-kins", "xyzbc-trt-kins", "switchkins", "kins",
})
"""LinuxCNC's own kinematics modules (Debian's linuxcnc-uspace 2.9): a generated module may
not take their names."""
HAL_NAME_LEN = 47
"""The longest component, pin or parameter name LinuxCNC's HAL accepts (hal.h's HAL_NAME_LEN)."""
SHORTEST_PREFIX = 9
"""The shortest HAL component name :func:`hal_prefix` cuts to: 4 of the module's name's
characters, a '-' and 4 hex digits."""
SETTINGS = ("max-iterations", "tolerance", "max-step", "max-step-angle", "status", "iterations")
"""The module's own pins and parameters, besides the geometry."""
LOAD_SETTINGS = ("payload.mass", *(f"payload.centre.{axis}" for axis in "xyz"), *(f"gravity.{axis}" for axis in "xyz"))
"""The parameters of the payload whose static loads the pins load.N give."""
MAX_ITERATIONS = 20
MAX_STEP = 25.0
MAX_STEP_ANGLE = 10.0
"""mm and degrees per angle: how far the forward may move from the pose passed in (the last
servo cycle's) before it fails instead of jumping to another assembly mode."""
TRANSLATION = ("x", "y", "z")


def full_name(robot):
    """The module's name before any cut: <name>kins."""
    return f"{robot.name}kins"


def module_name(robot):
    """The HAL module's name, its file's (<module>.so, ``loadrt <module>``) and its HAL
    component's, which starts every pin's and parameter's name: the same, since LinuxCNC unloads
    a module by its component's name (``halcmd unloadrt``, ``unload all`` at shutdown);
    :func:`hal_prefix`."""
    return hal_prefix(robot)


def source_name(robot):
    return f"{module_name(robot)}.c"


def translating(robot):
    """Whether the platform only translates (forward.free is x, y, z, no task coordinates: an
    Exechon-type machine's rotation follows its position): A B C pass through."""
    return not robot.task and (tuple(robot.forward_free) == TRANSLATION or set(robot.forward_free) == set(TRANSLATION))


WORLD_AXES = ("X", "Y", "Z", "A", "B", "C")
"""LinuxCNC's world coordinates, in pose order (A B C: roll, pitch, yaw)."""


def free_indices(robot):
    """The pose coordinates (0 x .. 5 yaw) the forward solves for: x y z for a translating
    platform, a constrained machine's task coordinates (its parasitic ones follow), else all six."""
    names = ("x", "y", "z", "roll", "pitch", "yaw")
    free = robot.task or (TRANSLATION if translating(robot) else names)
    return [names.index(name) for name in names if name in free]


def robot_problem(robot):
    """Why this host cannot drive ``robot``, or None."""
    if full_name(robot) in STOCK_MODULES:
        return f"name: the module name '{full_name(robot)}' is LinuxCNC's own module's"
    if robot.dof != 6 and not translating(robot) and not robot.task and robot.wrist is None:
        return (f"forward: LinuxCNC drives six-limb robots and translating platforms (forward: {{free: [x, y, z]}}); "
                f"{robot.name} has {robot.dof} limbs and free coordinates {list(robot.forward_free)}")
    longest = f"{_cut(full_name(robot), SHORTEST_PREFIX)}.{max(hal_suffixes(robot), key=len)}"
    if len(longest) > HAL_NAME_LEN:
        return (f"name: the HAL name '{longest}' has {len(longest)} characters with the HAL component cut to its "
                f"shortest; LinuxCNC takes at most {HAL_NAME_LEN}: shorten the limbs' names")
    if robot.postures > 1 and not robot.working_posture_given:
        return (f"working_posture: LinuxCNC's inverse kinematics has one answer: name the posture the machine "
                f"is built in (working_posture: 0 to {robot.postures - 1})")
    return None


def check_robot(robot):
    refuse(robot, robot_problem(robot))


def hal_suffixes(robot):
    """What follows ``<component>.`` in the names of the module's pins and parameters."""
    parallel = robot.parallel
    return (*SETTINGS, *LOAD_SETTINGS, *(f"load.{index}" for index in range(robot.joint_count)),
            *(parameter["name"] for parameter in _parameters(parallel)))


def hal_prefix(robot):
    """The module's HAL component name, which starts every name of its pins and parameters: <name>kins
    (:func:`full_name`) where every such name then fits LinuxCNC's HAL_NAME_LEN, else its first
    characters, a '-' and the first 4 hex digits of its sha256, as long as the longest name
    allows (at least SHORTEST_PREFIX characters: robot_problem refuses a robot whose limbs'
    names leave less)."""
    module = full_name(robot)
    room = HAL_NAME_LEN - 1 - max(len(suffix) for suffix in hal_suffixes(robot))
    return module if len(module) <= room else _cut(module, room)


def _cut(module, length):
    """``module`` cut to ``length`` characters, the last five a '-' and 4 hex digits of its sha256."""
    return f"{module[:length - 5]}-{hashlib.sha256(module.encode()).hexdigest()[:4]}"


def _parameters(robot):
    """HAL parameters of the geometry, one per number of a length field: {name
    '<joint>.<field>[.x|.y|.z]', member (in kingen_hal), value (the robot's, in its units)}."""
    parameters, rows = [], {}
    for joint, limb in enumerate(robot.limbs):
        number = rows[limb.model] = rows.get(limb.model, -1) + 1  # the limb's row in its model's table
        for field in limb.length_fields:
            member = f"{limb.model}s[{number}].{field}"
            base = f"{robot.joint_names[joint]}.{field.replace('_', '-')}"
            value = getattr(limb, field)
            if isinstance(value, (list, tuple)):
                parameters += [{"name": f"{base}.{axis}", "member": f"{member}[{index}]", "value": value[index]}
                               for index, axis in enumerate("xyz")]
            else:
                parameters.append({"name": base, "member": member, "value": value})
    return parameters


def view_model(robot, units="mm"):
    """What the module's source shows, in the machine's ``units``; ``branch_words`` names the
    working posture's branches in the limb models' words (true at the verification home). With
    a wrist: its parallel part's at the working posture's (carrying the robot's payload, on the
    tool), and the wrist (:mod:`.five_axis`)."""
    check_robot(robot)
    if robot.wrist is not None:
        parallel = replace(robot.parallel, working_posture_given=True, payload=robot.payload, gravity=robot.gravity)
        return {**view_model(parallel, units), "wrist": wrist_view(robot, units),
                "build_info": build_info(robot, module_name(robot), 1, (("host", "linuxcnc"),
                                                                        ("posture", robot.working_posture)))}
    labels = branch_words(robot)
    tolerance, stall = newton_stops(robot, LENGTH_UNITS[units])
    robot = robot_in_units(robot, units)
    view = robot_view(robot, HOST)
    branches = robot.posture_branches(robot.working_posture)
    lower, upper = robot.travel_limits()
    joints = []
    for index, limb in enumerate(robot.limbs):
        revolute = limb.joint_type.wraps
        limited = limb.travel is not None
        joints.append({
            "index": index, "name": robot.joint_names[index], "model": limb.model,
            "unit": "degrees" if revolute else units, "branch": branches[index], "revolute": int(revolute),
            "limited": int(limited), "lower": c_double(lower[index] if limited else 0.0),
            "upper": c_double(upper[index] if limited else 0.0),
            "travel_text": f"[{limb.travel[0]:.10g}, {limb.travel[1]:.10g}] {'degrees' if revolute else units}"
            if limited else "",
        })
    two_branch = [(index, limb) for index, limb in enumerate(robot.limbs) if limb.branches == 2]
    words = ", ".join(f"{robot.joint_names[index]} {labels[index][branches[index]]}" for index, limb in two_branch)
    free = free_indices(robot)
    return {
        **view,
        "module": module_name(robot),
        "full_name": full_name(robot),
        "build_info": build_info(robot, module_name(robot), 1, (("host", "linuxcnc"),
                                                                ("posture", robot.working_posture))),
        "unit_name": units,
        "translating": translating(robot),
        "free_count": len(free),
        "free_indices": free,
        "parasitic_indices": [index for index in range(6) if index not in free],
        "task_words": ", ".join(WORLD_AXES[index] for index in free),
        "closed_form": closed_form_model(robot) if translating(robot) else None,
        "working_posture": robot.working_posture,
        "branch_words": words,
        "joints": joints,
        "wrist": None,
        "direct_index": True,
        "jacobian": True,
        "schur_lines": schur_test_lines("m[{k}]"),
        "gram_lines": gram_lines(accumulate=True),
        "direct_index_min": c_double(robot.direct_index_min) if robot.direct_index_min is not None else None,
        "singular_tolerance": c_double(SINGULAR_TOLERANCE),
        "parameters": _parameters(robot),
        "max_iterations": MAX_ITERATIONS,
        "tolerance": tolerance,
        "stall": stall,
        "max_step": c_double(MAX_STEP / LENGTH_UNITS[units]),
        "max_step_angle": c_double(MAX_STEP_ANGLE),
        "degree": c_double(math.pi / 180.0),
        "metres_per_unit": c_double(LENGTH_UNITS[units] / 1000.0),
        **loads_view(robot, [index in free for index in range(6)], lambda row, column: f"T6[{column}][{row}]",
                     1.0 / LENGTH_UNITS[units]),
    }


def render(robot, units="mm"):
    """The module's source as {file name: text}, in the machine's ``units``."""
    return {source_name(robot): template("kins.c.j2", TEMPLATES).render(**view_model(robot, units))}


def harness_source():
    """The HAL stand-in's C source (a fixed file)."""
    return (TEMPLATES / "kingen_hal.c").read_text()
