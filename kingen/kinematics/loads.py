"""Loads at poses (kingen.kinematics.platform_loads: the method, docs/explanation/loads.md):
over any number of poses in blocks, a machine with a serial wrist through
kingen.kinematics.hybrid.wrist_loads, and what verify and check-path judge of them."""

from dataclasses import replace

import numpy as np

from ..conventions import pose_from_t6
from .hybrid.wrist_loads import wrist_loads
from .platform_loads import Loads, Motion, applied_wrenches, machine_t6, platform_loads
from .reference import solve

__all__ = ["Loads", "Motion", "beyond_limits", "held_problem", "held_text", "load_limited", "load_unit", "loads",
           "loads_of", "machine_pose", "machine_solution", "machine_t6", "without_parts"]
SIDES = ("base", "platform")
"""A limb's passive joints, as joint_limits names them."""

BLOCK_POSTURES = 65536
"""Poses times postures computed at once: their (n, p, m, 6) arrays about 20 MB each."""
MANIFOLD_MATCH = 1e-12
"""A T6 is the pose the machine takes when no entry differs from it by more than this fraction
of the machine's size (rotation entries and mm alike)."""


def loads(robot, t6, wrench=None, motion=None, postures=None):
    """:class:`Loads` of ``robot`` at T6 (n, 4, 4): the payload (robot.payload) under gravity and
    ``motion`` (a :class:`Motion`, or None: at rest) and an external wrench ``wrench`` (6,) [N, N m]
    at the platform origin, base frame; in ``postures`` (indices; None: every posture), which the
    result's posture axis then follows. A machine with a serial wrist: the pose, the payload,
    ``motion`` and ``wrench`` are the tool's (kingen.kinematics.hybrid.wrist_loads)."""
    t6 = np.asarray(t6, dtype=float).reshape(-1, 4, 4)
    chosen = np.arange(robot.postures) if postures is None else np.asarray(postures, dtype=int)
    step = max(1, BLOCK_POSTURES // len(chosen))
    blocks = [_block_loads(robot, t6[start:start + step], wrench, motion, chosen) for start in range(0, len(t6), step)]
    if len(blocks) == 1:
        return blocks[0]
    given = not robot.task and robot.wrist is None  # the machine takes each T6 as asked: its loads' machine, no copy
    return Loads(**{field: (t6 if field == "machine" and given else None if blocks[0].__dict__[field] is None
                            else np.concatenate([block.__dict__[field] for block in blocks]))
                    for field in blocks[0].__dict__})


def _block_loads(robot, t6, wrench, motion, chosen, solution=None):
    """loads() over one block of poses (``solution``: the reference's at ``t6``, the poses the
    machine takes, when the caller has it; without it a machine with task coordinates answers at
    the pose it takes for each T6's task coordinates, whatever the T6's rotation)."""
    if robot.wrist is not None:
        return wrist_loads(robot, t6, wrench, motion, chosen)
    if solution is None:
        t6, solution = machine_solution(robot, t6)
    return platform_loads(robot, t6, solution, chosen, *applied_wrenches(robot, t6, wrench, motion), motion)


def machine_solution(robot, t6):
    """(T6 (n, 4, 4) the machine takes, the reference's Solution there) for T6 ``t6``: a machine
    with task coordinates takes, for a T6 off its manifold, the pose for the T6's task coordinates
    (whatever its rotation); (``t6``, None) for a robot with a wrist, whose loads solve the wrist
    and its parallel part themselves (kingen.kinematics.hybrid.wrist_loads)."""
    if robot.wrist is not None:
        return t6, None
    solution = solve(robot, t6)
    if robot.task and np.max(np.abs(solution.machine - t6), initial=0.0) > MANIFOLD_MATCH * max(robot.size_mm, 1.0):
        t6 = solution.machine  # a T6 off the manifold: the pose the machine takes for its task coordinates
        solution = solve(robot, t6)
    return t6, solution


def machine_pose(loads_result):
    """(n, 6) the machine's poses (mm, degrees) behind ``loads_result``."""
    return pose_from_t6(loads_result.machine)


def loads_of(robot, t6, solution, posture=0, wrench=None, motion=None):
    """Loads of ``robot`` in ``posture`` (the payload under gravity, moving with ``motion`` or at
    rest, and ``wrench`` at the platform origin) at T6 (n, 4, 4) the machine takes, from the
    reference's ``solution`` there (:func:`machine_solution`; no solve again): what check-path and
    analyze judge per sample."""
    return _block_loads(robot, np.asarray(t6, dtype=float), wrench, motion, np.array([posture]), solution)


def without_parts(robot):
    """``robot`` with its limbs' moving parts left out (massless limbs): what the C library's
    static loads hold, the payload alone."""
    return replace(robot, limbs=tuple(limb.model_copy(update={"parts": None}) for limb in robot.limbs))


def load_limited(robot):
    """Whether the robot file limits an actuator's load or a passive joint's angle."""
    return any(limb.actuator_limit or limb.joint_limits for limb in robot.limbs)


def beyond_limits(robot, result, index=0, posture=0):
    """What of ``result`` (Loads) at pose ``index`` in its ``posture`` column leaves a limit the
    robot file states: (loaded, bent), lists of (limb index, load N or N m, limit) and of (limb
    index, side, angle deg, limit deg). A load that is not a number (a singular posture) is beyond."""
    loaded, bent = [], []
    for number, limb in enumerate(robot.limbs):
        force = result.forces[index, posture, number]
        if limb.actuator_limit is not None and not abs(force) <= limb.actuator_limit:
            loaded.append((number, force, limb.actuator_limit))
        for side, angles in zip(SIDES, (result.base_angles, result.platform_angles)):
            angle = np.degrees(angles[index, posture, number])
            if limb.cone(side) is not None and not angle <= limb.cone(side):
                bent.append((number, side, angle, limb.cone(side)))
    return loaded, bent


def load_unit(limb):
    """'N m' for a revolute actuator's load, 'N' for a prismatic one's."""
    return "N m" if limb.joint_type.wraps else "N"


def held_problem(robot, posture):
    """Why ``robot`` (no wrist) cannot hold its payload at the verification home in ``posture``,
    in words naming each limb, or None: every actuator's static load within its max_force or
    max_torque and every passive joint within its joint_limits."""
    if not load_limited(robot):
        return None
    result = loads(robot, machine_t6(robot, np.asarray(robot.verification.home, dtype=float)[None]), postures=[posture])
    loaded, bent = beyond_limits(robot, result)
    names = robot.joint_names
    loaded = [f"{names[n]} {force:.6g} {load_unit(robot.limbs[n])} (limit {limit:g})" for n, force, limit in loaded]
    bent = [f"{names[n]}'s {side} joint {angle:.6g} deg (limit {cone:g})" for n, side, angle, cone in bent]
    held = f"the payload ({robot.payload.mass:g} kg)" if robot.payload is not None else "the unloaded platform"
    problems = ([f"holding {held} at the verification home needs more than the actuators give: {', '.join(loaded)}"]
                if loaded else []) + ([f"passive joints beyond their limits: {', '.join(bent)}"] if bent else [])
    return "; ".join(problems) or None


def held_text(robot):
    """What verify's machine check says it judged of loads, or '' where the file states no limit."""
    if not load_limited(robot):
        return ""
    held = f"holds its payload ({robot.payload.mass:g} kg)" if robot.payload is not None else "holds the unloaded platform"
    return f", {held} within every stated force, torque and joint-angle limit"
