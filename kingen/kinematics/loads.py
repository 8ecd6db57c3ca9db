"""Loads at poses (kingen.kinematics.platform_loads: the method, docs/explanation/loads.md):
over any number of poses in blocks, a machine with a serial wrist through
kingen.kinematics.wrist_loads, and what verify and check-path judge of them."""

import numpy as np

from ..conventions import pose_from_t6
from .parasitic import solve_parasitic
from .platform_loads import Loads, Motion, external_wrench, machine_t6, payload_wrench, platform_loads
from .reference import solve
from .wrist_loads import wrist_loads

__all__ = ["Loads", "Motion", "held_problem", "held_text", "loads", "machine_pose", "machine_t6", "static_loads_of"]

BLOCK_POSTURES = 65536
"""Poses times postures computed at once: their (n, p, m, 6) arrays about 20 MB each."""


def loads(robot, t6, wrench=None, motion=None, postures=None):
    """:class:`Loads` of ``robot`` at T6 (n, 4, 4): the payload (robot.payload) under gravity and
    ``motion`` (a :class:`Motion`, or None: at rest) and an external wrench ``wrench`` (6,) [N, N m]
    at the platform origin, base frame; in ``postures`` (indices; None: every posture), which the
    result's posture axis then follows. A machine with a serial wrist: the pose, the payload,
    ``motion`` and ``wrench`` are the tool's (kingen.kinematics.wrist_loads)."""
    t6 = np.asarray(t6, dtype=float).reshape(-1, 4, 4)
    chosen = np.arange(robot.postures) if postures is None else np.asarray(postures, dtype=int)
    step = max(1, BLOCK_POSTURES // len(chosen))
    blocks = [_block_loads(robot, t6[start:start + step], wrench, motion, chosen) for start in range(0, len(t6), step)]
    if len(blocks) == 1:
        return blocks[0]
    return Loads(**{field: (None if blocks[0].__dict__[field] is None
                            else np.concatenate([block.__dict__[field] for block in blocks]))
                    for field in blocks[0].__dict__})


def _block_loads(robot, t6, wrench, motion, chosen, solution=None):
    """loads() over one block of poses (``solution``: the reference's there, when the caller has it)."""
    if robot.wrist is not None:
        return wrist_loads(robot, t6, wrench, motion, chosen)
    machine = solve_parasitic(robot, t6).t6 if robot.task else t6
    solution = solution if solution is not None else solve(robot, machine)
    external = external_wrench(machine, wrench) if wrench is not None else 0.0
    static = payload_wrench(robot, machine) + external
    applied = static if motion is None else payload_wrench(robot, machine, motion) + external
    return platform_loads(robot, machine, solution, chosen, static, applied)


def machine_pose(loads_result):
    """(n, 6) the machine's poses (mm, degrees) behind ``loads_result``."""
    return pose_from_t6(loads_result.machine)


def static_loads_of(robot, t6, solution):
    """Loads of ``robot`` in its posture 0 at rest (the payload under gravity) at T6 (n, 4, 4)
    the machine takes, from the reference's ``solution`` there: what check-path judges per sample."""
    return _block_loads(robot, np.asarray(t6, dtype=float), None, None, np.array([0]), solution)


def held_problem(robot, posture):
    """Why ``robot`` (no wrist) cannot hold its payload at the verification home in ``posture``,
    in words naming each limb, or None: every actuator's static load within its max_force or
    max_torque and every passive joint within its joint_limits."""
    if not any(limb.max_force or limb.max_torque or limb.joint_limits for limb in robot.limbs):
        return None
    result = loads(robot, machine_t6(robot, np.asarray(robot.verification.home, dtype=float)[None]))
    loaded, bent = [], []
    for index, limb in enumerate(robot.limbs):
        name = robot.joint_names[index]
        limit, unit = (limb.max_torque, "N m") if limb.joint_type.wraps else (limb.max_force, "N")
        force = result.forces[0, posture, index]
        if limit is not None and not abs(force) <= limit:
            loaded.append(f"{name} {force:.6g} {unit} (limit {limit:g})")
        for side, angles in (("base", result.base_angles), ("platform", result.platform_angles)):
            cone = getattr(limb.joint_limits, side) if limb.joint_limits is not None else None
            angle = np.degrees(angles[0, posture, index])
            if cone is not None and not angle <= cone:
                bent.append(f"{name}'s {side} joint {angle:.6g} deg (limit {cone:g})")
    held = f"the payload ({robot.payload.mass:g} kg)" if robot.payload is not None else "the unloaded platform"
    problems = ([f"holding {held} at the verification home needs more than the actuators give: {', '.join(loaded)}"]
                if loaded else []) + ([f"passive joints beyond their limits: {', '.join(bent)}"] if bent else [])
    return "; ".join(problems) or None


def held_text(robot):
    """What verify's machine check says it judged of loads, or '' where the file states no limit."""
    if not any(limb.max_force or limb.max_torque or limb.joint_limits for limb in robot.limbs):
        return ""
    held = f"holds its payload ({robot.payload.mass:g} kg)" if robot.payload is not None else "holds the unloaded platform"
    return f", {held} within every stated force, torque and joint-angle limit"
