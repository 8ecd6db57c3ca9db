"""Parasitic rotation of a Tricept-type machine, solved in closed form (docs/how-to/hybrid.md).

The passive tube (kingen.robot.passive_leg) runs from the universal joint's centre c to the
platform origin p, along the platform's t_p; the joint's second axis b_p (platform frame) stays
perpendicular to its first axis a (base frame). Given the task coordinates p of a T6 (mm):

    d = (p - c) / |p - c|,  b = (a x d) / |a x d|,  R = [d, b, d x b] [t_p, b_p, t_p x b_p]^T.

D = |a x d|^2 is the normalised radicand: near zero the tube lies along the first axis (the
universal joint's singularity, where the rotation about the tube is lost); it is never below
zero, and p = c gives no finite rotation (unreachable). The generated C does the same
operations in the same order (templates/routine_helpers.c.j2, ``parasitic_tube``).
"""

import numpy as np


def solve_tube(robot, t6):
    """(rotation (n, 3, 3), radicand (n,)): the machine's platform rotation R (base frame) for
    each T6's position (n, 4, 4, mm) and D (module docstring)."""
    leg = robot.passive_leg
    offset = np.asarray(t6, dtype=float)[:, 3, :3] - leg.base_point
    direction = offset / np.linalg.norm(offset, axis=-1, keepdims=True)
    across = np.cross(leg.first_axis, direction)
    radicand = np.sum(across * across, -1)
    second = across / np.sqrt(radicand)[:, None]
    machine = np.stack([direction, second, np.cross(direction, second)], axis=2)
    return machine @ leg.frame.T, radicand


def tube_residuals(robot, t6):
    """(n, 3) mm: the tube's constraint equations at the poses T6 (n, 4, 4), stated forward: the
    platform origin's offset from c across the tube, (p - c).(R b_p) and (p - c).(R (t_p x b_p)),
    and the universal joint's axes' cosine times the tube's length, a.(R b_p) |p - c|."""
    leg = robot.passive_leg
    t6 = np.asarray(t6, dtype=float)
    rotation, offset = np.swapaxes(t6[:, :3, :3], 1, 2), t6[:, 3, :3] - leg.base_point
    second = rotation @ leg.second_axis
    normal = rotation @ leg.frame[:, 2]
    return np.stack([np.sum(offset * second, -1), np.sum(offset * normal, -1),
                     (second @ leg.first_axis) * np.linalg.norm(offset, axis=-1)], axis=1)


def tube_wrenches(robot, t6):
    """(n, 3, 6) the tube's constraint wrenches [f, c x f] (or a couple [0, m]) at T6 (n, 4, 4)
    on the manifold: forces through c along R b_p and R (t_p x b_p) (they do no work on the
    joint's two rotations about c or the slide along the tube) and a couple along a x R b_p
    (none on the rotations about a and R b_p)."""
    leg = robot.passive_leg
    rotation = np.swapaxes(np.asarray(t6, dtype=float)[:, :3, :3], 1, 2)
    rows = []
    for force in (rotation @ leg.second_axis, rotation @ leg.frame[:, 2]):
        rows.append(np.concatenate([force, np.cross(leg.base_point, force)], axis=-1))
    couple = np.cross(leg.first_axis, rotation @ leg.second_axis)
    rows.append(np.concatenate([np.zeros_like(couple), couple], axis=-1))
    return np.stack(rows, axis=1)
