"""Parasitic rotation of an Exechon-type machine, solved in closed form (docs/how-to/hybrid.md).

Each leg with a revolute joint at its platform point n, axis e fixed in the platform, keeps
(R e).(b - p) = e.n (kingen.robot.constraints, ``AxesTable``). Given the task coordinates p
(the platform frame's origin, mm) of a T6:

- v = R e_a (the pair's axis) is the unit vector with v.d = e_a.(n_i - n_j) and
  v.(b_i - p) = e_a.n_i: v = v0 + t m, with v0 in the span of d and g = b_i - p (their Gram
  system), m = d x g and t = +/- sqrt((1 - |v0|^2) / |m|^2), the sign whose v is nearer the
  verification home's;
- u = R e_b (the third's axis) is the unit vector with u.v = e_a.e_b and u.(b_k - p) = e_b.n_k,
  the same way with v and h = b_k - p;
- R maps the platform frame (e_a, e_b's part normal to e_a, their cross product) to
  (v, u's part normal to v, their cross product).

D = min(1 - |v0|^2, 1 - |u0|^2) is the normalised radicand: below zero no rotation has these
task coordinates (unreachable), near zero two branches meet (a constraint singularity). The
generated C does the same operations in the same order (templates/routine_helpers.c.j2,
``parasitic_axes``). The constraint's wrench is a force along R e through b (``axes_wrenches``).
"""

import numpy as np

from ...conventions import t6_from_pose
from ...robot.constraints import axes_table


def home_axes(robot, table):
    """(v, u) (3,) each: the pair's and the third's axes, base frame, at the verification home."""
    rotation = t6_from_pose(np.asarray([robot.verification.home], dtype=float))[0, :3, :3].T
    return rotation @ table.frame[:, 0], rotation @ (table.frame[:, 0] * table.cosine
                                                      + table.frame[:, 1] * np.sqrt(1.0 - table.cosine ** 2))


def _unit_on_two_planes(first, first_rhs, second, second_rhs, home):
    """(x (n, 3), radicand (n,)): the unit x with x.first = first_rhs, x.second = second_rhs,
    on the side of their common normal ``home`` is on; radicand 1 - |x0|^2 (below 0: none, and
    x is x0 / |x0|, the unit vector nearest the planes' line, so that the rotation built from it
    is one)."""
    ff, fs, ss = (np.sum(first * first, -1), np.sum(first * second, -1), np.sum(second * second, -1))
    determinant = ff * ss - fs * fs
    alpha = (first_rhs * ss - second_rhs * fs) / determinant
    beta = (second_rhs * ff - first_rhs * fs) / determinant
    particular = alpha[..., None] * first + beta[..., None] * second
    radicand = 1.0 - np.sum(particular * particular, -1)
    normal = np.cross(first, second)
    step = np.sqrt(np.where(radicand > 0.0, radicand, 0.0) / determinant)
    step = np.where(np.sum(normal * home, -1) >= 0.0, step, -step)
    particular = particular / np.sqrt(np.where(radicand < 0.0, 1.0 - radicand, 1.0))[..., None]
    return particular + step[..., None] * normal, radicand


def solve_axes(robot, t6):
    """(rotation (n, 3, 3), radicand (n,)): the machine's platform rotation for each T6's
    position (n, 4, 4, mm) and D (module docstring)."""
    table = axes_table(robot)
    position = np.asarray(t6, dtype=float)[:, 3, :3]
    home_v, home_u = home_axes(robot, table)
    count = len(position)
    v, first = _unit_on_two_planes(np.broadcast_to(table.difference, (count, 3)),
                                   np.full(count, table.pair_rhs[0]), table.base - position,
                                   np.full(count, table.pair_rhs[1]), home_v)
    u, second = _unit_on_two_planes(v, np.full(count, table.cosine), table.third_base - position,
                                    np.full(count, table.third_rhs), home_u)
    normal = u - np.sum(u * v, -1)[:, None] * v
    normal = normal / np.linalg.norm(normal, axis=-1, keepdims=True)
    machine = np.stack([v, normal, np.cross(v, normal)], axis=2)
    return machine @ table.frame.T, np.minimum(first, second)


def axes_wrenches(robot, t6):
    """(n, 3, 6) each constraint's row [a, b x a] at T6 (n, 4, 4): a = R e through the base point
    b (base frame), a force along the platform axis; the constraint's rate per unit twist
    [v; omega] (v: the velocity of the point at the base origin) is -(row . twist)."""
    rotation = np.asarray(t6, dtype=float)[:, :3, :3].transpose(0, 2, 1)
    rows = []
    for limb in robot.limbs:
        axis, base, _ = limb.platform_constraint()
        direction = rotation @ axis
        rows.append(np.concatenate([direction, np.cross(base, direction)], axis=-1))
    return np.stack(rows, axis=1)
