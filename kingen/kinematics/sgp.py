"""Every assembly mode of a six-limb robot, found exhaustively.

Given the joints, each limb's base-side point b_i and its passive link's length l_i are fixed
(a leg's base point and length, a carriage's position on its rail, a crank's tip), so the
platform is held by six fixed-length links between fixed base points and its own points a_i:
a Stewart-Gough platform. The general one has exactly 40 complex assembly modes (Raghavan
1993; Wampler 1996); special geometries (the symmetric hexagons machines are built with)
have fewer finite ones, the rest gone to infinity.

How all of them are found: a coefficient-parameter homotopy (Morgan and Sommese 1989). A
generic geometry drawn once from a fixed seed is solved by Martyushev's elimination template
(kingen/vendor/fksgp: all 40 solutions by standard linear algebra); its 40 solutions are then
tracked, by predictor-corrector continuation, along a complex path of geometries to the
robot's (the "gamma trick" keeps the path away from singular geometries with probability 1).
Every isolated solution of the robot's geometry is the end of one path; paths whose end
goes to infinity are counted as such. The real ends are polished by :mod:`kingen.kinematics.forward`'s
Newton on the robot's own closure equations.

Unknowns: the rotation's Cayley vector s (R = ((1 - s's) I + 2 s s' + 2 [s]x) / (1 + s's))
and the translation t, in a frame at the first base and platform points, scaled to the
geometry's size. Equations: |t|^2 = l_1^2, and for i = 2..6 the difference of limb i's and
limb 1's closure, multiplied by 1 + s's (polynomials of degree 3).
"""

import functools
from dataclasses import dataclass

import numpy as np

from ..conventions import rpy_from_rotation

COMPLEX_SOLUTIONS = 40
"""How many complex solutions the general Stewart-Gough platform has."""
SEED = 20261123
GENUINE = 1e-6
"""The template's normalised residual below which a start solution is accepted."""
REAL_PART = 1e-5
"""An end whose imaginary parts are below this (relative to its size) is polished as real."""
DIVERGED = 1e3
"""A path whose translation grows past this near the end (the geometry's size is 1, so a real
solution has |t| <= 1) is going to infinity. The Cayley vector is not judged: a half-turn is
a finite rotation at s = infinity."""
ENDGAME = 0.99
"""Paths are judged divergent only past this point of the path: earlier, a complex path may
pass near the parametrisation's own singularity (1 + s's = 0) and come back."""
MAX_ROUNDS = 4000


@dataclass(frozen=True)
class Solutions:
    """The ends of the 40 paths: ``candidates`` (k, 6) the real ones as poses (mm, radians,
    not yet polished), ``finite`` how many paths ended at a finite solution, ``infinite``
    how many went to infinity, ``failed`` how many the tracker lost (0 when exhaustive)."""

    candidates: np.ndarray
    finite: int
    infinite: int
    failed: int


def applies(robot, free):
    """Whether the homotopy solves this robot: six limbs, every pose coordinate free."""
    return robot.dof == 6 and bool(np.all(free))


def platform_of(robot, joints):
    """(base points b (6, 3), platform points a (6, 3), link lengths l (6,)) mm for joints
    (6,) (mm, radians): the Stewart-Gough platform these joints make."""
    base = np.array([limb.base_side_point(np.zeros(3), np.asarray(joint, dtype=float))
                     for limb, joint in zip(robot.limbs, joints)], dtype=float).reshape(6, 3)
    platform = np.array([limb.platform_point for limb in robot.limbs], dtype=float)
    lengths = np.array([float(limb.passive_length(np.asarray(joint, dtype=float)))
                        for limb, joint in zip(robot.limbs, joints)])
    return base, platform, lengths


def solve_all(robot, joints):
    """Solutions for the robot's joints (6,) (mm, radians): every path's end; deterministic."""
    return solve_platform(*platform_of(robot, joints))


def solve_platform(base, platform, lengths):
    """Solutions of the Stewart-Gough platform with base points ``base`` (6, 3), platform
    points ``platform`` (6, 3) and link lengths ``lengths`` (6,) (mm): poses with
    |R a_i + t - b_i| = l_i; deterministic."""
    turn_base, turn_platform = _frames()
    scale = max(np.max(np.linalg.norm(base - base[0], axis=1)), np.max(np.linalg.norm(platform - platform[0], axis=1)),
                np.max(lengths), 1e-300)
    target = ((platform - platform[0]) @ turn_platform / scale, (base - base[0]) @ turn_base / scale,
              (lengths / scale) ** 2)
    start, unknowns = _start_system()
    ends, status = _track(start, target, unknowns)
    finite = status == 1
    size = 1.0 + np.max(np.abs(ends), axis=1)
    real = finite & (np.max(np.abs(ends.imag), axis=1) <= REAL_PART * size)
    s, t = ends[real, :3].real, ends[real, 3:].real
    matrix, d = _cayley(s)
    rotations = turn_base @ (matrix / d[:, None, None]) @ turn_platform.T
    translations = base[0] + scale * t @ turn_base.T - rotations @ platform[0]
    poses = np.column_stack([translations, rpy_from_rotation(rotations)]) if len(s) else np.empty((0, 6))
    return Solutions(candidates=poses, finite=int(np.count_nonzero(finite)),
                     infinite=int(np.count_nonzero(status == 2)), failed=int(np.count_nonzero(status == 0)))


@functools.lru_cache(maxsize=1)
def _frames():
    """Two fixed rotations of the base and platform frames: no special direction of the
    robot's geometry meets one of the parametrisation's (Cayley's half-turns)."""
    rng = np.random.default_rng(SEED)
    turns = []
    for _ in range(2):
        turn = np.linalg.qr(rng.standard_normal((3, 3)))[0]
        turn[:, 0] *= np.sign(np.linalg.det(turn))
        turns.append(turn)
    return tuple(turns)


@functools.lru_cache(maxsize=1)
def _start_system():
    """(geometry (a, b, l^2), unknowns (40, 6) complex): a generic geometry from SEED and its
    40 solutions from the elimination template (imported here: it loads scipy, which a
    verify that never asks for every assembly mode does not need)."""
    from ..vendor.fksgp import solver66

    rng = np.random.default_rng(SEED)
    while True:
        platform = np.vstack([np.zeros(3), rng.uniform(-1.0, 1.0, (5, 3))])
        base = np.vstack([np.zeros(3), rng.uniform(-1.0, 1.0, (5, 3))])
        s, t = rng.standard_normal(3) * 0.5, rng.standard_normal(3)
        matrix, d = _cayley(s[None])
        rotation = matrix[0] / d[0]
        squared = np.sum((platform @ rotation.T + t - base) ** 2, axis=1)
        rt, error = solver66(base, platform, squared, 0, rng)
        if len(error) == COMPLEX_SOLUTIONS and np.all(np.asarray(error) <= GENUINE):
            break
    rotations = rt[:, :, :3]
    trace = np.trace(rotations, axis1=1, axis2=2)
    cayley = np.stack([rotations[:, 2, 1] - rotations[:, 1, 2], rotations[:, 0, 2] - rotations[:, 2, 0],
                       rotations[:, 1, 0] - rotations[:, 0, 1]], axis=1) / (1.0 + trace)[:, None]
    unknowns = np.column_stack([cayley, rt[:, :, 3]]).astype(complex)
    geometry = (platform.astype(complex), base.astype(complex), squared.astype(complex))
    unknowns, _ = _newton(unknowns, geometry, 5)
    return geometry, unknowns


def _cayley(s):
    """(M (n, 3, 3), d (n,)) with R = M / d for Cayley vectors s (n, 3) (complex allowed)."""
    squared = np.sum(s * s, axis=1)
    skew = np.zeros(s.shape[:1] + (3, 3), dtype=s.dtype)
    skew[:, 0, 1], skew[:, 0, 2], skew[:, 1, 2] = -s[:, 2], s[:, 1], -s[:, 0]
    skew[:, 1, 0], skew[:, 2, 0], skew[:, 2, 1] = s[:, 2], -s[:, 1], s[:, 0]
    matrix = (1.0 - squared)[:, None, None] * np.eye(3) + 2.0 * s[:, :, None] * s[:, None, :] + 2.0 * skew
    return matrix, 1.0 + squared


def _system(z, geometry):
    """F (n, 6) and dF/dz (n, 6, 6) at unknowns z (n, 6) for geometries (a, b, l^2), each
    (n, 6, 3), (n, 6, 3), (n, 6) or shared."""
    count = len(z)
    a = np.broadcast_to(geometry[0], (count, 6, 3))
    b = np.broadcast_to(geometry[1], (count, 6, 3))
    squared = np.broadcast_to(geometry[2], (count, 6))
    s, t = z[:, :3], z[:, 3:]
    matrix, d = _cayley(s)
    w = np.einsum("nij,nkj->nki", matrix, a)                       # M(s) a_i
    c = np.sum(a * a, -1) + np.sum(b * b, -1) - squared + squared[:, :1]
    bt = np.einsum("nki,ni->nk", b, t)
    relative = t[:, None, :] - b
    values = np.empty((len(z), 6), dtype=complex)
    values[:, 0] = np.sum(t * t, -1) - squared[:, 0]
    values[:, 1:] = (d[:, None] * (c - 2.0 * bt) + 2.0 * np.sum(relative * w, -1))[:, 1:]
    sa = np.einsum("ni,nki->nk", s, a)
    eye = np.eye(3)
    # dw/ds = -2 a s' + 2 (s'a) I + 2 s a' - 2 [a]x
    cross = np.zeros(a.shape + (3,), dtype=complex)
    cross[..., 0, 1], cross[..., 0, 2], cross[..., 1, 2] = -a[..., 2], a[..., 1], -a[..., 0]
    cross[..., 1, 0], cross[..., 2, 0], cross[..., 2, 1] = a[..., 2], -a[..., 1], a[..., 0]
    dw = (-2.0 * a[..., :, None] * s[:, None, None, :] + 2.0 * sa[..., None, None] * eye
          + 2.0 * s[:, None, :, None] * a[..., None, :] - 2.0 * cross)
    jacobian = np.empty((len(z), 6, 6), dtype=complex)
    jacobian[:, 0, :3] = 0.0
    jacobian[:, 0, 3:] = 2.0 * t
    ds = 2.0 * s[:, None, :] * (c - 2.0 * bt)[..., None] + 2.0 * np.einsum("nki,nkij->nkj", relative, dw)
    dt = -2.0 * d[:, None, None] * b + 2.0 * w
    jacobian[:, 1:, :3] = ds[:, 1:]
    jacobian[:, 1:, 3:] = dt[:, 1:]
    return values, jacobian


def _newton(z, geometry, iterations):
    """z after ``iterations`` Newton steps, and the last step's size (n,)."""
    step = np.zeros(len(z))
    for _ in range(iterations):
        values, jacobian = _system(z, geometry)
        delta = _solve(jacobian, values)
        z = z - delta
        step = np.linalg.norm(delta, axis=1)
    return z, step


def _solve(matrices, right):
    """Solutions x (n, 6) of matrices (n, 6, 6) x = right (n, 6); NaN rows where a matrix is
    singular or not finite."""
    with np.errstate(all="ignore"):
        try:
            return np.linalg.solve(matrices, right[..., None])[..., 0]
        except np.linalg.LinAlgError:
            result = np.full(right.shape, np.nan, dtype=complex)
            for row, (matrix, values) in enumerate(zip(matrices, right)):
                try:
                    result[row] = np.linalg.solve(matrix, values)
                except np.linalg.LinAlgError:
                    pass
            return result


def _track(start, target, unknowns):
    """Ends (40, 6) of the paths from ``start``'s solutions to ``target`` and their status:
    1 finite (also a singular end: a path that reaches the target geometry where Newton
    stalls, a multiple root), 2 gone to infinity, 0 lost."""
    gamma = np.exp(2j * np.pi * np.random.default_rng(SEED + 1).uniform())

    def geometry(tau):
        phi = gamma * tau / (1.0 + (gamma - 1.0) * tau)
        return tuple(s[None] + phi.reshape((-1,) + (1,) * np.ndim(s)) * (np.asarray(t) - s)[None]
                     for s, t in zip(start, target))

    def tangent(z, tau):
        step = 1e-6
        ahead, _ = _system(z, geometry(np.minimum(tau + step, 1.0)))
        behind, jacobian = _system(z, geometry(np.maximum(tau - step, 0.0)))
        rate = (ahead - behind) / (np.minimum(tau + step, 1.0) - np.maximum(tau - step, 0.0))[:, None]
        return -_solve(jacobian, rate)

    z = unknowns.copy()
    tau = np.zeros(len(z))
    h = np.full(len(z), 0.01)
    status = np.full(len(z), -1)
    for _ in range(MAX_ROUNDS):
        running = status == -1
        if not np.any(running):
            break
        index = np.nonzero(running)[0]
        zi, ti, hi = z[index], tau[index], np.minimum(h[index], 1.0 - tau[index])
        predicted = zi + hi[:, None] * tangent(zi, ti)
        corrected, last = _newton(predicted, geometry(ti + hi), 3)
        size = 1.0 + np.linalg.norm(corrected, axis=1)
        good = np.isfinite(last) & (last <= 1e-7 * size) & (np.linalg.norm(corrected - predicted, axis=1)
                                                             <= 0.1 * size)
        z[index[good]], tau[index[good]] = corrected[good], ti[good] + hi[good]
        h[index] = np.where(good, np.minimum(hi * 1.6, 0.05), hi * 0.5)
        status[index[good & (tau[index] >= 1.0)]] = 1
        status[index[(np.linalg.norm(z[index, 3:], axis=1) > DIVERGED) & (tau[index] > ENDGAME)]] = 2
        status[index[(~good) & (h[index] < 1e-12)]] = 0
    stalled = status != 1
    at_end = stalled & (tau >= 1.0 - 1e-5) & (np.linalg.norm(z[:, 3:], axis=1) < np.sqrt(DIVERGED))
    status[at_end] = 3  # a singular end (a multiple root): Newton converges slowly there
    status[stalled & ~at_end & (np.linalg.norm(z[:, 3:], axis=1) >= np.sqrt(DIVERGED)) & (tau > ENDGAME)] = 2
    ends = z.copy()
    finished = (status == 1) | (status == 3)
    if np.any(finished):
        ends[finished], _ = _newton(ends[finished], target, 3)
    status[status == 3] = 1
    status[status == -1] = 0
    return ends, status

