"""The static loads' part of every host's view-model (templates/loads.c.j2): the payload's
initializer, the rows of the pose coordinates a machine holds and its constraints' wrenches,
as C text. Pure, like kingen.hosts.render."""

from ..kinematics.forward import COORDINATES
from ..robot.constraints import constraint_table, family
from ..robot.limbs import c_double, c_vector
from ..robot.loads_schema import Payload
from .wrist import platform_constraints

ANGLE_RATE_ROWS = {"roll": "0.0, 0.0, 0.0, {r00}, {r10}, 0.0", "pitch": "0.0, 0.0, 0.0, -{r10}, {r00}, 0.0",
                   "yaw": "0.0, 0.0, 0.0, -{r20} * {r00}, -{r20} * {r10}, {r00} * {r00} + {r10} * {r10}"}
"""An angle's rate per twist [v; omega] at a pose of rotation R (r00 its entry R[0][0], and so
on), up to a positive factor (kingen.kinematics.hybrid.parasitic.task_rows): roll' = (c_yaw w_x + s_yaw
w_y) / c_pitch, pitch' = -s_yaw w_x + c_yaw w_y, yaw' = w_z + t_pitch (c_yaw w_x + s_yaw w_y),
times cos(pitch)^2, cos(pitch) and cos(pitch)^2."""


def held_row(name, element):
    """C initializer of pose coordinate ``name``'s rate per twist at a pose (up to a positive
    factor: only the held coordinates' span matters, the wrenches they carry lie in it), for x,
    y, z the platform origin's velocity component, v_k + omega . (p x e_k); ``element(row,
    column)`` the C text of the pose's homogeneous matrix entry (column 3 the position)."""
    if name not in "xyz":
        return ANGLE_RATE_ROWS[name].format(r00=element(0, 0), r10=element(1, 0), r20=element(2, 0))
    axis, position = "xyz".index(name), [element(row, 3) for row in range(3)]
    force, moment = ["0.0"] * 3, ["0.0"] * 3
    force[axis] = "1.0"
    moment[(axis + 1) % 3], moment[(axis + 2) % 3] = position[(axis + 2) % 3], "-" + position[(axis + 1) % 3]
    return ", ".join(force + moment)


def constraint_wrenches(robot):
    """The wrenches the constraints of ``robot``'s parallel part carry (one with task coordinates),
    as C text, in the robot's lengths: each an ``axis`` (unit) and a ``point``, ``turns`` 1 where
    the axis is in the platform frame (else the base's), ``moves`` 1 where the point is (else the
    base's), and a ``weight``; at the machine's pose (R, p) the wrench is [weight d; c x d] (base
    frame, moment about the base origin), d the axis and c the point in the base frame: a force
    along d through c (weight 1) or a couple c x d (weight 0). The same wrenches as
    kingen.kinematics.hybrid.parasitic.task_twists' constraint rows: a plane's force along its base
    axis through the limb's platform point, else kingen.hosts.wrist.platform_constraints."""
    parallel = robot.parallel
    if family(parallel) == "planes":
        table = constraint_table(parallel)
        rows = [(axis, point, 1.0, 0, 1) for axis, point in zip(table.axes, table.points)]
    else:
        rows = [(axis, base, weight, 1, 0) for axis, base, weight in platform_constraints(robot)]
    return [{"axis": c_vector(axis), "point": c_vector(point), "weight": c_double(weight), "turns": turns, "moves": moves}
            for axis, point, weight, turns, moves in rows]


def loads_view(robot, free, element, per_mm=1.0):
    """The static loads' part of a view: ``payload`` (mass kg, centre in the routine's lengths,
    ``per_mm`` of them to a mm, gravity m/s^2); for a machine without task coordinates the rows
    of the coordinates it holds (``free`` the mask of those it moves in; ``element`` as for
    :func:`held_row`), else its constraints' wrenches (:func:`constraint_wrenches`)."""
    payload = robot.payload
    centre = payload.centre if payload else (0.0, 0.0, 0.0)
    held = [] if robot.parallel.task else [name for index, name in enumerate(COORDINATES) if not free[index]]
    return {"payload": {"mass": c_double(payload.mass if payload else 0.0),
                        "centre": c_vector([value * per_mm for value in centre]),
                        "gravity": c_vector(robot.gravity)},
            "held": [held_row(name, element) for name in held], "held_names": " ".join(held),
            "constraint_wrenches": constraint_wrenches(robot) if robot.parallel.task else []}


def checked_payload(robot):
    """The payload the hosts' loads checks hold: the robot file's, or where it gives none a
    stand-in, 10 kg whose centre lies a tenth of the robot's size off the platform origin (so
    that every term is exercised)."""
    return robot.payload or Payload(mass=10.0, centre=(0.1 * robot.size_mm, -0.05 * robot.size_mm, 0.07 * robot.size_mm),
                                    inertia=((0.0,) * 3,) * 3)


def payload_words(robot):
    """Which payload :func:`checked_payload` holds, in words."""
    return "the robot file's payload" if robot.payload else "a stand-in payload (10 kg off the platform origin)"
