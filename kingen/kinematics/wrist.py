"""The inverse kinematics of a parallel part with a two-axis wrist, from the tool pose, in
closed form (kingen.robot.wrist says which wrists; docs/how-to/hybrid.md).

The tool pose is read as a five-axis machine reads it: the tool tip q and the tool's z axis w
(the T6's third row); the turn about the tool axis is free. With the tool tip on the tool's z
axis at ``reach`` from the wrist centre, the wrist centre is p = q - reach w; the parallel
part's closed form (kingen.kinematics.parasitic) gives its rotation R for p, and the reference
its legs' joints. The wrist must then turn the tool's zero-joint axis z0 onto w_p = R^T w
(platform frame): Rot(a1, t1) Rot(a2, t2) z0 = w_p. The intermediate c = Rot(a2, t2) z0 has
a2.c = a2.z0, a1.c = a1.w_p and |c| = 1: c = alpha a1 + beta a2 + g (a1 x a2), with
g = +/- sqrt(D) / |a1 x a2|, D = 1 - |alpha a1 + beta a2|^2 the wrist's normalised radicand;
branch 0 takes g >= 0, branch 1 g < 0 (an A/C head's flip). t2 turns z0 onto c about a2, t1
turns c onto w_p about a1 (each an atan2 of the vectors' parts normal to the axis).

Warnings, per posture (the parallel part's posture times 2 plus the wrist's branch), the worst
of the parallel part's (kingen.kinematics.reference) and the wrist's: D below -1e-5 (no wrist
angle reaches w) is unreachable; |D| within 1e-5 (the branches meet), or 1 - (a1.w_p)^2 within
1e-5 (the tool axis along the first axis: t1 is lost, the wrist's singularity) is singular;
a wrist joint outside its travel is beyond the joint limits. A T6 the parallel part cannot
answer (non-finite, or no rotation for its wrist centre) is unreachable in every posture; a
non-finite one has wrist joints 0, as the reference gives its legs. ``turn`` says how far (rad) the
asked tool frame is turned about the tool axis from the machine's: the answer ignores it.
"""

from dataclasses import dataclass

import numpy as np

from .parasitic import solve_parasitic
from .reference import solve
from .routine import SINGULAR_TOLERANCE, WARNINGS

RANK = np.zeros(max(WARNINGS.values()) + 1, dtype=int)
RANK[[WARNINGS["WARN_JOINT_LIMITS_EXCEEDED"], WARNINGS["WARN_SINGULAR_SOLUTION"], WARNINGS["WARN_UNREACHABLE"]]] = 1, 2, 3
"""Per WARN_* code, its rank: which warning wins when the parallel part and the wrist give two."""


@dataclass(frozen=True)
class ToolSolution:
    """Over n tool T6: ``joints`` (n, legs + wrist joints, postures) the legs' (mm) then the
    wrist's (rad, (-pi, pi]); ``warnings`` (n, postures) WARN_* codes; ``platform_t6`` (n, 4, 4)
    the parallel part's pose; ``tool_t6`` (n, postures, 4, 4) the machine's tool pose in each
    posture; ``turn`` (n, postures) the asked tool frame's turn about the tool axis from the
    machine's (rad); ``radicand`` (n,) the wrist's D."""

    joints: np.ndarray
    warnings: np.ndarray
    platform_t6: np.ndarray
    tool_t6: np.ndarray
    turn: np.ndarray
    radicand: np.ndarray


def rotation_about(axis, angle):
    """Rotation matrices (n, 3, 3) by ``angle`` (n,) rad about the unit ``axis`` (3,) (Rodrigues)."""
    cross = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    angle = np.asarray(angle, dtype=float)[:, None, None]
    return np.eye(3) + np.sin(angle) * cross + (1.0 - np.cos(angle)) * (cross @ cross)


def angle_about(axis, start, end):
    """(n,) the angle (rad, (-pi, pi]) about the unit ``axis`` (3,) or (n, 3) from ``start`` to
    ``end`` (n, 3 each), measured between their parts normal to the axis."""
    start = start - np.sum(start * axis, -1)[:, None] * axis
    end = end - np.sum(end * axis, -1)[:, None] * axis
    return np.arctan2(np.sum(np.cross(start, end) * axis, -1), np.sum(start * end, -1))


def _wrist_branches(wrist, target):
    """(angles (n, 2 branches, 2 joints) rad, radicand (n,), aligned (n,) 1 - (a1.w_p)^2) for the
    tool axis ``target`` w_p (n, 3), platform frame; see the module docstring."""
    first, second = wrist.axes
    start = wrist.tool[:3, 2]
    cosine = first @ second
    normal = np.cross(first, second)
    onto_first, onto_second = target @ first, np.full(len(target), start @ second)
    alpha = (onto_first - cosine * onto_second) / (1.0 - cosine * cosine)
    beta = (onto_second - cosine * onto_first) / (1.0 - cosine * cosine)
    particular = np.outer(alpha, first) + np.outer(beta, second)
    radicand = 1.0 - np.sum(particular * particular, -1)
    step = np.sqrt(np.where(radicand > 0.0, radicand, 0.0)) / np.linalg.norm(normal)
    angles = []
    for sign in (1.0, -1.0):
        middle = particular + np.outer(sign * step, normal)
        angles.append(np.stack([angle_about(first, middle, target),
                                angle_about(second, np.broadcast_to(start, middle.shape), middle)], -1))
    return np.stack(angles, 1), radicand, 1.0 - onto_first * onto_first


def _wrist_warnings(wrist, angles, radicand, aligned):
    """(n, 2) the wrist's own WARN_* code per branch (module docstring)."""
    beyond = np.any((angles < wrist.lower) | (angles > wrist.upper), axis=2)
    codes = np.where(beyond, WARNINGS["WARN_JOINT_LIMITS_EXCEEDED"], WARNINGS["WARN_GOOD_SOLUTION"])
    singular = (np.abs(radicand) <= SINGULAR_TOLERANCE) | (aligned <= SINGULAR_TOLERANCE)
    codes = np.where(singular[:, None], WARNINGS["WARN_SINGULAR_SOLUTION"], codes)
    return np.where(~(radicand >= -SINGULAR_TOLERANCE)[:, None], WARNINGS["WARN_UNREACHABLE"], codes)


def worst(first, second):
    """Elementwise the warning of higher RANK of two WARN_* code arrays."""
    return np.where(RANK[second] > RANK[first], second, first)


def solve_tool(hybrid, t6):
    """Every posture of ``hybrid`` (kingen.robot.hybrid.HybridRobot) for tool T6 arrays
    (n, 4, 4, base frame, mm): see the module docstring."""
    robot, wrist = hybrid.robot, hybrid.wrist
    t6 = np.asarray(t6, dtype=float).reshape(-1, 4, 4)
    axis, tip = t6[:, 2, :3], t6[:, 3, :3]
    platform = np.tile(np.eye(4), (len(t6), 1, 1))
    platform[:, 3, :3] = tip - wrist.reach * axis
    with np.errstate(all="ignore"):
        machine = solve_parasitic(robot, platform).t6
        legs = solve(robot, machine)
        rotation = np.swapaxes(machine[:, :3, :3], 1, 2)
        angles, radicand, aligned = _wrist_branches(wrist, np.einsum("nji,nj->ni", rotation, axis))
    angles = np.where(legs.finite[:, None, None] & np.isfinite(angles), angles, 0.0)
    postures = robot.postures * 2
    joints = np.concatenate([np.repeat(legs.joints, 2, axis=2),
                             np.tile(np.swapaxes(angles, 1, 2), (1, 1, robot.postures))], axis=1)
    warnings = worst(np.repeat(legs.warnings, 2, axis=1),
                     np.tile(_wrist_warnings(wrist, angles, radicand, aligned), (1, robot.postures)))
    tool = np.zeros((len(t6), postures, 4, 4))
    for posture in range(postures):
        turned = (rotation @ rotation_about(wrist.axes[0], joints[:, robot.dof, posture])
                  @ rotation_about(wrist.axes[1], joints[:, robot.dof + 1, posture]))
        tool[:, posture, :3, :3] = np.swapaxes(turned @ wrist.tool[:3, :3], 1, 2)
        tool[:, posture, 3, :3] = machine[:, 3, :3] + turned @ wrist.tool[:3, 3]
        tool[:, posture, 3, 3] = 1.0
    turn = np.stack([angle_about(tool[:, posture, 2, :3], tool[:, posture, 0, :3], t6[:, 0, :3])
                     for posture in range(postures)], 1)
    return ToolSolution(joints=joints, warnings=warnings, platform_t6=machine, tool_t6=tool, turn=turn,
                        radicand=radicand)
