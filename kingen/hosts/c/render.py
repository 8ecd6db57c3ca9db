"""Rendering the C host's library: robot -> ``kingen_<name>.h`` and ``kingen_<name>.c``, from
this host's templates, the shared view-model (:func:`kingen.hosts.render.robot_view`), the
routine of all postures every host shares (``templates/postures_*.c.j2``) and the limb
models' partials in their three parts (the struct in the header, the rows in the default
geometry, the solver in the source). Pure."""

from pathlib import Path

from ...kinematics.forward import COORDINATES, free_mask
from ...kinematics.routine import SINGULAR_TOLERANCE
from ...kinematics.singularity import TRANSLATION_SINGULAR
from ...robot.limbs import c_double
from ..loads import loads_view
from ..render import closed_form_model, newton_stops, refuse, robot_view, template
from . import CHost

TEMPLATES = Path(__file__).resolve().parent / "templates"
HOST = CHost()
"""The host the shared view-model asks for the library's names."""
MAX_ITERATIONS = 20
"""Newton's steps at most in the forward kinematics."""


def prefix(robot):
    """Every public name of the library starts with this: kingen_<name>."""
    return f"kingen_{robot.name}"


def file_names(robot):
    """(header, source) file names."""
    return f"{prefix(robot)}.h", f"{prefix(robot)}.c"


def robot_problem(robot):
    """Why this host cannot build ``robot`` (one whose forward it cannot solve), or None."""
    if not robot.has_forward:  # a robot file's free coordinates are one per limb (robot.constraints)
        return (f"forward: the C library's forward solves for as many pose coordinates as the robot has limbs; "
                f"{robot.name} has {robot.dof} limbs and free coordinates all six")
    return None


def has_machine_pose(robot):
    """Whether ``robot``'s library exports <prefix>_machine_pose: a machine with task coordinates
    and no wrist (a wrist machine's pose is the tool's)."""
    return bool(robot.task) and robot.wrist is None


def check_robot(robot):
    refuse(robot, robot_problem(robot))


def view_model(robot):
    """What the header and source substitute: the shared view with the force lines and
    transmissions every limb computes (the Jacobian and the forward need them), the limbs'
    rows read from the geometry passed in, and the forward's settings."""
    check_robot(robot)
    view = robot_view(robot, HOST)
    parallel = robot.parallel  # a wrist's forward solves its parallel part's task coordinates, then the wrist
    free = free_mask(parallel)
    joints = [{**joint, "unit": "radians" if joint_type.wraps else "mm"}
              for joint, joint_type in zip(view["joints"], robot.joint_types)]
    digits = ", ".join(f"{joint['name']} {joint['bit']}" for joint in joints if joint["bit"] >= 0)
    tolerance, stall = newton_stops(robot)
    return {
        **view,
        "joints": joints,
        "prefix": prefix(robot),
        "direct_index": True,
        "jacobian": True,
        "limb_tables": "geometry->",
        "calibration_arguments": "0, 0",
        "entry_check": None,
        "singular_tolerance": c_double(SINGULAR_TOLERANCE),
        "digits": digits or "none (one posture)",
        "revolute": [int(joint_type.wraps) for joint_type in robot.joint_types],
        "free_count": int(free.sum()),
        "free_angles": bool(free[3:].any() or parallel.task),
        "task_words": ", ".join(parallel.task),
        "parasitic_words": ", ".join(name for name in COORDINATES if name not in parallel.task),
        "parasitic_indices": [index for index, name in enumerate(COORDINATES) if name not in parallel.task],
        "closed_form": closed_form_model(robot) if tuple(free) == (True, True, True, False, False, False) else None,
        "limbs": robot.dof,
        "limb_count": "KINGEN_LIMBS" if robot.wrist is not None else "NUM_DOFS",
        "free_columns": [index for index, name in enumerate(COORDINATES) if free[index]],
        "free_names": " ".join(name for index, name in enumerate(COORDINATES) if free[index]),
        "fixed_names": " ".join(name for index, name in enumerate(COORDINATES) if not free[index]) or "none",
        "translation_singular": c_double(TRANSLATION_SINGULAR),
        "max_iterations": MAX_ITERATIONS,
        "tolerance": tolerance,
        "stall": stall,
        "machine_pose": has_machine_pose(robot),
        **loads_view(robot, free, lambda row, column: f"pose[{4 * row + column}]"),
    }


def render(robot):
    """{header name: text, source name: text}."""
    view = view_model(robot)
    header, source = file_names(robot)
    return {header: template("header.c.j2", TEMPLATES).render(**view),
            source: template("source.c.j2", TEMPLATES).render(**view)}
