"""Where a move is at each point of its way: straight moves interpolated in world coordinates,
arcs as arcs (helices when the normal coordinate changes), the orientation interpolated as
the host does, and the samples that ``--chord`` asks for.

A move is traced by u in [0, 1]. Positions are in mm, angles in degrees. LinuxCNC moves its
A, B, C linearly with the path, like X, Y, Z (``--host linuxcnc``); ``--host delmia`` turns
the orientation about one fixed axis at a uniform rate (spherical linear interpolation).
"""

import math

import numpy as np

from ..conventions import matrix_from_pose, pose_from_t6, t6_from_matrix

TWO_PI = 2.0 * math.pi


def arc_frame(move):
    """(r0, r1, theta0, sweep) of an arc move in its plane: start and end radii (mm), the start
    angle and the signed swept angle (radians), as LinuxCNC sweeps it: ``rotation``'s sign the
    sense, |rotation| - 1 full turns more; a start equal to the end is a full turn."""
    first, second, _ = move.arc.axes
    center = np.array(move.arc.center)
    start = np.array([move.start[first], move.start[second]]) - center
    end = np.array([move.end[first], move.end[second]]) - center
    theta0, theta1 = math.atan2(start[1], start[0]), math.atan2(end[1], end[0])
    rotation = move.arc.rotation
    sweep = (theta1 - theta0) % TWO_PI if rotation > 0 else -((theta0 - theta1) % TWO_PI)
    if sweep == 0.0:
        sweep = math.copysign(TWO_PI, rotation)
    sweep += math.copysign(TWO_PI * (abs(rotation) - 1), rotation)
    return float(np.hypot(*start)), float(np.hypot(*end)), theta0, sweep


def lengths(move):
    """(xyz path length in mm, largest orientation change in degrees) of a move."""
    turn = float(np.max(np.abs(move.end[3:] - move.start[3:])))
    if move.arc is None:
        return float(np.linalg.norm(move.end[:3] - move.start[:3])), turn
    r0, r1, _, sweep = arc_frame(move)
    normal = move.arc.axes[2]
    return float(math.hypot(0.5 * (r0 + r1) * abs(sweep), move.end[normal] - move.start[normal])), turn


def sample_count(move, chord):
    """Intervals a move is cut into so that samples are at most ``chord`` mm and ``chord``
    degrees apart (at least 1)."""
    distance, turn = lengths(move)
    return max(1, math.ceil(max(distance, turn) / chord))


def positions(move, u):
    """(n, 3) the tool's x, y, z (mm) at path parameters ``u`` (n,)."""
    u = np.asarray(u, dtype=float)[:, None]
    if move.arc is None:
        return move.start[:3] + u * (move.end[:3] - move.start[:3])
    first, second, normal = move.arc.axes
    r0, r1, theta0, sweep = arc_frame(move)
    angle = theta0 + u[:, 0] * sweep
    radius = r0 + u[:, 0] * (r1 - r0)
    xyz = np.empty((len(u), 3))
    xyz[:, first] = move.arc.center[0] + radius * np.cos(angle)
    xyz[:, second] = move.arc.center[1] + radius * np.sin(angle)
    xyz[:, normal] = move.start[normal] + u[:, 0] * (move.end[normal] - move.start[normal])
    return xyz


def poses_and_t6(move, u, host):
    """(poses (n, 6) mm and degrees, T6 (n, 4, 4)) along ``move`` at parameters ``u``."""
    u = np.asarray(u, dtype=float)
    poses = np.empty((len(u), 6))
    poses[:, :3] = positions(move, u)
    if host == "delmia" and np.any(move.end[3:] != move.start[3:]):
        from scipy.spatial.transform import Rotation, Slerp  # here: scipy costs 0.35 s that only this needs

        ends = Rotation.from_matrix(matrix_from_pose(np.stack([move.start, move.end]))[:, :3, :3])
        matrices = np.zeros((len(u), 4, 4))
        matrices[:, :3, :3] = Slerp([0.0, 1.0], ends)(u).as_matrix()
        matrices[:, :3, 3] = poses[:, :3]
        matrices[:, 3, 3] = 1.0
        t6 = t6_from_matrix(matrices)
        poses[:, 3:] = pose_from_t6(t6)[:, 3:]
        return poses, t6
    poses[:, 3:] = move.start[3:] + u[:, None] * (move.end[3:] - move.start[3:])
    return poses, t6_from_matrix(matrix_from_pose(poses))
