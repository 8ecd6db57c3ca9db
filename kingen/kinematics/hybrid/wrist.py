"""The inverse kinematics of a parallel part with a two- or three-axis wrist, from the tool
pose, in closed form (kingen.robot.wrist says which wrists; docs/how-to/hybrid.md).

The tool pose is read as a five-axis machine reads it: the tool tip q and the tool's z axis w
(the T6's third row); the turn about the tool axis is free. With the tool tip on the tool's z
axis at ``reach`` from the wrist centre, the wrist centre is p = q - reach w; the parallel
part's closed form (kingen.kinematics.hybrid.parasitic) gives its rotation R for p, and the reference
its legs' joints. The wrist must then turn the tool's zero-joint axis z0 onto w_p = R^T w
(platform frame): Rot(a1, t1) Rot(a2, t2) z0 = w_p. The intermediate c = Rot(a2, t2) z0 has
a2.c = a2.z0, a1.c = a1.w_p and |c| = 1: c = alpha a1 + beta a2 + g (a1 x a2), with
g = +/- sqrt(D) / |a1 x a2|, D = 1 - |alpha a1 + beta a2|^2 the wrist's normalised radicand;
branch 0 takes g >= 0, branch 1 g < 0 (an A/C head's flip). t2 turns z0 onto c about a2, t1
turns c onto w_p about a1 (each an atan2 of the vectors' parts normal to the axis). These are
the geometric angles; each joint reads its angle less its zero offset (Wrist.zero), wrapped to
(-pi, pi], and its travel limits apply to that reading.

The answer is the reference's kingen.kinematics.reference.Solution over the whole machine's
joints (the legs', then the wrist's) and postures (the parallel part's posture times 2 plus the
wrist's branch). Its radicands are the legs', then for the first wrist joint 1 - (a1.w_p)^2 and
for the second D, so that the reference's rules give the wrist's warnings: D below -1e-5 (no
wrist angle reaches w) is unreachable; |D| within 1e-5 (the branches meet), or 1 - (a1.w_p)^2
within 1e-5 (the tool axis along the first axis: t1 is lost, the wrist's singularity) is
singular; a wrist joint outside its travel is beyond the joint limits. Each posture's warning is
the worst of the parallel part's and the wrist's. A T6 the parallel part cannot answer
(non-finite, or no rotation for its wrist centre) is unreachable in every posture; a non-finite
one has wrist joints 0, as the reference gives its legs. :func:`tool_turn` says how far (rad)
the asked tool frame is turned about the tool axis from the machine's: the answer ignores it.

A three-axis (spherical) wrist reads the tool pose whole: with R the asked tool rotation and t
the tool tip's offset from the wrist centre in the tool frame (kingen.robot.wrist.Wrist.tip),
the wrist centre is p = q - R t; the parallel part gives its rotation Rp for p, and the wrist
must give Rot(a1, t1) Rot(a2, t2) Rot(a3, t3) = M := Rp^T R R0^T (R0 the tool rotation at zero).
Its first two joints solve Rot(a1, t1) Rot(a2, t2) a3 = M a3 exactly as above (z0 := a3, w_p :=
M a3: the same two branches, radicand D and measure 1 - (a1.w_p)^2); t3 is the angle about a3
from a vector u normal to a3 to Rot(a2, t2)^T Rot(a1, t1)^T M u. Its radicands are the two
above, then the third joint's 1 - (a1.w_p)^2 again (t3 is lost with t1: the gimbal lock); no
turn is free.
"""

import numpy as np

from ...conventions import wrap_angle
from .parasitic import solve_parasitic
from ..routine import SINGULAR_TOLERANCE, WARNINGS, warning_codes


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


def _wrist_branches(first, second, start, target):
    """(angles (n, 2 branches, 2 joints) rad, radicand (n,), aligned (n,) 1 - (a1.w_p)^2) turning
    the unit ``start`` z0 (3,) onto ``target`` w_p (n, 3) by Rot(``first``, t1) Rot(``second``,
    t2), platform frame; see the module docstring."""
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


def solve_tool(robot, t6, solve_parallel, solution_type):
    """Every posture of ``robot`` (a Robot with a wrist) for tool T6 arrays (n, 4, 4, base frame,
    mm): ``solve_parallel`` (robot, T6) is the reference's solver of the parallel part,
    ``solution_type`` its Solution, which this returns (module docstring) with ``platform`` the
    parallel part's pose for each T6."""
    parallel, wrist, dof = robot.parallel, robot.wrist, robot.dof
    t6 = np.asarray(t6, dtype=float).reshape(-1, 4, 4)
    axis, tip = t6[:, 2, :3], t6[:, 3, :3]
    platform = np.tile(np.eye(4), (len(t6), 1, 1))
    if wrist.whole_pose:
        platform[:, 3, :3] = tip - np.swapaxes(t6[:, :3, :3], 1, 2) @ wrist.tip
    else:
        platform[:, 3, :3] = tip - wrist.reach * axis
    machine = solve_parasitic(parallel, platform).t6
    legs = solve_parallel(parallel, machine)
    rotation = np.swapaxes(machine[:, :3, :3], 1, 2)
    if wrist.whole_pose:
        angles, radicand, aligned = _spherical_branches(wrist, rotation, np.swapaxes(t6[:, :3, :3], 1, 2))
    else:
        angles, radicand, aligned = _wrist_branches(wrist.axes[0], wrist.axes[1], wrist.tool[:3, 2],
                                                    np.einsum("nji,nj->ni", rotation, axis))
    angles = wrap_angle(angles - wrist.zero)  # the joints' readings (kingen.robot.wrist.WristJoint.zero_offset)
    angles = np.where(legs.finite[:, None, None] & np.isfinite(angles), angles, 0.0)
    if wrist.branch is not None:  # a one-posture view: its branch's joints in both columns
        angles = angles[:, [wrist.branch, wrist.branch]]
    branch_joints = np.concatenate([legs.branch_joints, np.swapaxes(angles, 1, 2)], axis=1)
    wrist_radicands = [aligned, radicand, aligned][:len(wrist.names)]
    radicands = np.concatenate([legs.radicands, np.stack(wrist_radicands, axis=1)], axis=1)
    lower, upper = robot.travel_limits()
    kept = (0, 1) if wrist.branch is None else (wrist.branch,)
    beyond = np.any((angles < lower[dof:]) | (angles > upper[dof:]), axis=2)[:, :len(kept)]
    beyond = np.tile(beyond, (1, parallel.postures))
    wrist_singular = np.any(np.abs(radicands[:, dof:]) <= SINGULAR_TOLERANCE, axis=1)[:, None]
    wrist_unreachable = ~(radicand >= -SINGULAR_TOLERANCE)[:, None]
    legs_codes = np.repeat(legs.warnings, len(kept), axis=1)
    warnings = warning_codes((legs_codes == WARNINGS["WARN_JOINT_LIMITS_EXCEEDED"]) | beyond,
                             (legs_codes == WARNINGS["WARN_SINGULAR_SOLUTION"]) | wrist_singular,
                             (legs_codes == WARNINGS["WARN_UNREACHABLE"]) | wrist_unreachable)
    branches = tuple(tuple(limbs) + (branch,) * len(wrist.names) for limbs in legs.posture_branches for branch in kept)
    return solution_type(branch_joints=branch_joints, warnings=warnings, radicands=radicands, finite=legs.finite,
                         posture_branches=branches, constraint=legs.constraint, points=legs.points, platform=machine,
                         parallel=legs)


def _spherical_branches(wrist, platform_rotation, tool_rotation):
    """(angles (n, 2 branches, 3 joints) rad, radicand (n,), aligned (n,)) of a three-axis
    ``wrist`` for the platform's and the asked tool's rotations (n, 3, 3, column form, base
    frame); see the module docstring."""
    first, second, third = wrist.axes
    wanted = np.swapaxes(platform_rotation, 1, 2) @ tool_rotation @ wrist.tool[:3, :3].T  # M
    angles, radicand, aligned = _wrist_branches(first, second, third, wanted @ third)
    normal = np.cross(third, np.eye(3)[np.argmin(np.abs(third))])
    normal = np.broadcast_to(normal / np.linalg.norm(normal), (len(wanted), 3))
    with_third = []
    for branch in range(2):
        undone = (np.swapaxes(rotation_about(second, angles[:, branch, 1]), 1, 2)
                  @ np.swapaxes(rotation_about(first, angles[:, branch, 0]), 1, 2) @ wanted)
        last = angle_about(third, normal, np.einsum("nij,nj->ni", undone, normal))
        with_third.append(np.concatenate([angles[:, branch], last[:, None]], axis=1))
    return np.stack(with_third, 1), radicand, aligned


def tool_t6(robot, platform, wrist_joints):
    """(n, 4, 4) the tool's T6 (base frame, mm) of ``robot`` (with a wrist) for its platform's
    T6 ``platform`` (n, 4, 4) and the wrist's joints' readings (n, 2 or 3) rad (each joint turns
    by its reading plus its ``zero``): the forward of the wrist."""
    turned = np.swapaxes(platform[:, :3, :3], 1, 2)
    for index, joint_axis in enumerate(robot.wrist.axes):
        turned = turned @ rotation_about(joint_axis, wrist_joints[:, index] + robot.wrist.zero[index])
    tool = np.zeros((len(platform), 4, 4))
    tool[:, :3, :3] = np.swapaxes(turned @ robot.wrist.tool[:3, :3], 1, 2)
    tool[:, 3, :3] = platform[:, 3, :3] + turned @ robot.wrist.tool[:3, 3]
    tool[:, 3, 3] = 1.0
    return tool


def orientation_rows(wrist):
    """The T6 rows of the tool's orientation ``wrist`` answers: the tool axis (row 2) for two
    joints (the turn about it free), all three (the whole rotation) for three."""
    return (0, 1, 2) if wrist.whole_pose else (2,)


def tool_miss(wrist, reached, asked):
    """((n,) tool tip distance mm, (n,) orientation miss) of the tool T6 ``reached`` from
    ``asked`` (n, 4, 4 each): the miss the largest distance of the :func:`orientation_rows`
    (unit vectors) between them."""
    tip = np.linalg.norm(reached[:, 3, :3] - asked[:, 3, :3], axis=1)
    rows = list(orientation_rows(wrist))
    return tip, np.max(np.linalg.norm(reached[:, rows, :3] - asked[:, rows, :3], axis=2), axis=1)


def tool_turn(asked, reached):
    """(n,) how far (rad, (-pi, pi]) the asked tool T6 ``asked`` (n, 4, 4) is turned about the
    tool axis from the machine's ``reached`` (n, 4, 4): the part of the pose a five-axis reading
    leaves free."""
    return angle_about(reached[:, 2, :3], reached[:, 0, :3], asked[:, 0, :3])
