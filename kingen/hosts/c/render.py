"""Rendering the C host's library: robot -> ``kingen_<name>.h`` and ``kingen_<name>.c``, from
this host's templates, the shared view-model (:func:`kingen.hosts.render.robot_view`), the
routine of all postures every host shares (``templates/postures_*.c.j2``) and the limb
models' partials in their three parts (the struct in the header, the rows in the default
geometry, the solver in the source). Pure."""

from pathlib import Path

from ...kinematics.forward import COORDINATES, free_mask
from ...kinematics.routine import SINGULAR_TOLERANCE
from ...kinematics.singularity import TRANSLATION_SINGULAR
from ...robot.limbs import c_double, c_vector
from ...robot.constraints import constraint_table, family
from ..render import newton_step, refuse, robot_view, template
from ..wrist import platform_constraints
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
        "closed_form": tuple(free) == (True, True, True, False, False, False) and robot.models == ("rail",)
        and robot.dof == 3,
        "limbs": robot.dof,
        "limb_count": "KINGEN_LIMBS" if robot.wrist is not None else "NUM_DOFS",
        "free_columns": [index for index, name in enumerate(COORDINATES) if free[index]],
        "free_names": " ".join(name for index, name in enumerate(COORDINATES) if free[index]),
        "fixed_names": " ".join(name for index, name in enumerate(COORDINATES) if not free[index]) or "none",
        "translation_singular": c_double(TRANSLATION_SINGULAR),
        "max_iterations": MAX_ITERATIONS,
        "tolerance": newton_step(robot),
        **loads_view(robot, free),
    }


ANGLE_RATE_ROWS = {"roll": "0.0, 0.0, 0.0, pose[0], pose[4], 0.0", "pitch": "0.0, 0.0, 0.0, -pose[4], pose[0], 0.0",
                   "yaw": "0.0, 0.0, 0.0, -pose[8] * pose[0], -pose[8] * pose[4], pose[0] * pose[0] + pose[4] * pose[4]"}
"""An angle's rate per twist [v; omega] at a row-major pose, up to a positive factor
(kingen.kinematics.parasitic.task_rows): roll' = (c_yaw w_x + s_yaw w_y) / c_pitch, pitch' = -s_yaw w_x +
c_yaw w_y, yaw' = w_z + t_pitch (c_yaw w_x + s_yaw w_y), times cos(pitch)^2, cos(pitch) and cos(pitch)^2."""


def held_row(name):
    """C initializer of a pose coordinate's rate per twist at a row-major pose (up to a positive
    factor: only the held coordinates' span matters, the wrenches they carry): for x, y, z the
    platform origin's velocity component, v_k + omega . (p x e_k)."""
    if name not in "xyz":
        return ANGLE_RATE_ROWS[name]
    axis, position = "xyz".index(name), ("pose[3]", "pose[7]", "pose[11]")
    force, moment = ["0.0"] * 3, ["0.0"] * 3
    force[axis] = "1.0"
    moment[(axis + 1) % 3], moment[(axis + 2) % 3] = position[(axis + 2) % 3], "-" + position[(axis + 1) % 3]
    return ", ".join(force + moment)


def constraint_wrenches(robot):
    """The wrenches the constraints of ``robot``'s parallel part carry (one with task coordinates),
    as C text: each an ``axis`` (unit) and a ``point`` (mm), ``turns`` 1 where the axis is in the
    platform frame (else the base's), ``moves`` 1 where the point is (else the base's), and a
    ``weight``; at the machine's pose (R, p) the wrench is [weight d; c x d] (base frame, moment
    about the base origin), d the axis and c the point in the base frame: a force along d
    through c (weight 1) or a couple c x d (weight 0). The same wrenches as
    kingen.kinematics.parasitic.task_twists' constraint rows: a plane's force along its base
    axis through the limb's platform point, a platform revolute axis's force through its leg's
    base point (kingen.hosts.wrist.constraint_rows), the tube's two forces and its couple."""
    parallel = robot.parallel
    if family(parallel) == "planes":
        table = constraint_table(parallel)
        rows = [(axis, point, 1.0, 0, 1) for axis, point in zip(table.axes, table.points)]
    else:
        rows = [(axis, base, weight, 1, 0) for axis, base, weight in platform_constraints(robot)]
    return [{"axis": c_vector(axis), "point": c_vector(point), "weight": c_double(weight), "turns": turns, "moves": moves}
            for axis, point, weight, turns, moves in rows]


def loads_view(robot, free):
    """The static loads' part of the view: the payload's initializer (mass kg, centre mm, gravity
    m/s^2); for a machine without task coordinates the held coordinates' rows, else its
    constraints' wrenches (:func:`constraint_wrenches`)."""
    payload = robot.payload
    held = [] if robot.parallel.task else [name for index, name in enumerate(COORDINATES) if not free[index]]
    return {"payload": {"mass": c_double(payload.mass if payload else 0.0),
                        "centre": c_vector(payload.centre if payload else (0.0, 0.0, 0.0)),
                        "gravity": c_vector(robot.gravity)},
            "held": [held_row(name) for name in held], "held_names": " ".join(held),
            "constraint_wrenches": constraint_wrenches(robot) if robot.parallel.task else []}


def render(robot):
    """{header name: text, source name: text}."""
    view = view_model(robot)
    header, source = file_names(robot)
    return {header: template("header.c.j2", TEMPLATES).render(**view),
            source: template("source.c.j2", TEMPLATES).render(**view)}
