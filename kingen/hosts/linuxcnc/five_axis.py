"""LinuxCNC's world for a machine with a wrist (docs/how-to/linuxcnc.md, 'Five-axis
machines'). A three-axis wrist makes a six-axis machine: X Y Z A B C the tool pose as the hexapod
modules read it (the tip, roll, pitch, yaw in degrees, R = Rz(C) Ry(B) Rx(A)). A two-axis wrist: X Y Z the tool tip (base frame, the machine's units) and A, C the tool axis,
w = Rz(C) Rx(A) w0 (degrees), w0 the tool axis (base frame) at the verification home with the
wrist at 0. The turn about the tool axis is free: B is not read, and the forward gives B = 0.
An axis has two (A, C) pairs, (A, C) and (2 phi - A, C + 180) for w0 = (0, 0, -1) (phi = 180):
the forward takes the pair nearest the pose it starts from; along the base z axis C is free and
keeps its value. Pure numpy, the same formulas as the module's C (templates/five_axis.c.j2)."""

import numpy as np

from ...conventions import pose_from_t6, t6_from_pose
from ...robot.limbs import c_double, c_vector
from ...units import LENGTH_UNITS
from ..wrist import wrist_joint_rows, wrist_table

COORDINATES = "XYZAC"
"""LinuxCNC's [TRAJ] COORDINATES of a five-axis module."""
SIX_COORDINATES = "XYZABC"
"""LinuxCNC's [TRAJ] COORDINATES of a six-axis module (a three-axis wrist)."""


def coordinates(robot):
    """The [TRAJ] COORDINATES of ``robot``'s module (it has a wrist)."""
    return SIX_COORDINATES if robot.wrist.whole_pose else COORDINATES


def home_axis(robot):
    """(3,) w0: the tool axis (base frame, unit) at the verification home with the wrist at 0,
    its components within 1e-12 of 0 (a degree's sine and cosine rounding) made exactly 0."""
    axis = t6_from_pose(np.asarray([robot.verification.home], dtype=float))[0, 2, :3]
    axis = np.where(np.abs(axis) < 1e-12, 0.0, axis)
    return axis / np.linalg.norm(axis)


def axis_of_world(w0, a, c):
    """(n, 3) the tool axis w = Rz(C) Rx(A) w0 for A, C (n,) degrees."""
    a, c = np.radians(np.asarray(a, dtype=float)), np.radians(np.asarray(c, dtype=float))
    u = np.stack([np.full(a.shape, w0[0]), np.cos(a) * w0[1] - np.sin(a) * w0[2],
                  np.sin(a) * w0[1] + np.cos(a) * w0[2]], -1)
    return np.stack([np.cos(c) * u[:, 0] - np.sin(c) * u[:, 1], np.sin(c) * u[:, 0] + np.cos(c) * u[:, 1], u[:, 2]], -1)


def world_of_axis(w0, w, seed_a, seed_c):
    """(A, C) (n,) degrees of the tool axes ``w`` (n, 3): of the two pairs the one nearest
    (``seed_a``, ``seed_c``) (n,), C on the turn nearest ``seed_c``, C = ``seed_c`` along the base z axis."""
    w = np.asarray(w, dtype=float)
    seed_a, seed_c = np.broadcast_to(seed_a, len(w)).astype(float), np.broadcast_to(seed_c, len(w)).astype(float)
    phi, half = np.arctan2(w0[1], w0[2]), np.arccos(np.clip(w[:, 2] / np.hypot(w0[1], w0[2]), -1.0, 1.0))
    pairs = []
    for sign in (1.0, -1.0):
        angle = np.arctan2(np.sin(phi + sign * half), np.cos(phi + sign * half))
        u = np.stack([np.full(len(w), w0[0]), np.cos(angle) * w0[1] - np.sin(angle) * w0[2]], -1)
        free = (np.sum(u * u, -1) <= 1e-24) | (np.sum(w[:, :2] ** 2, -1) <= 1e-24)
        c = np.degrees(np.arctan2(u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0], u[:, 0] * w[:, 0] + u[:, 1] * w[:, 1]))
        c = np.where(free, seed_c, c + 360.0 * np.floor((seed_c - c) / 360.0 + 0.5))
        a = np.degrees(angle)
        pairs.append((a, c, np.abs(a - seed_a) + np.abs(c - seed_c)))
    first = pairs[0][2] <= pairs[1][2]
    return np.where(first, pairs[0][0], pairs[1][0]), np.where(first, pairs[0][1], pairs[1][1])


def world_of_t6(robot, t6, scale=1.0):
    """EmcPose numbers (n, 9) of tool T6 (n, 4, 4) (mm): X Y Z the tool tip / ``scale``; A and C
    the tool axis's pair nearest A = C = 0, B 0 (a two-axis wrist) or A B C the tool's roll,
    pitch, yaw in degrees (a three-axis wrist); U V W 0."""
    t6 = np.asarray(t6, dtype=float).reshape(-1, 4, 4)
    world = np.zeros((len(t6), 9))
    world[:, :3] = t6[:, 3, :3] / scale
    if robot.wrist.whole_pose:
        world[:, 3:6] = pose_from_t6(t6)[:, 3:]
    else:
        world[:, 3], world[:, 5] = world_of_axis(home_axis(robot), t6[:, 2, :3], 0.0, 0.0)
    return world


def wrist_view(robot, units="mm"):
    """What templates/five_axis.c.j2 shows of ``robot``'s wrist at its working posture, lengths
    in the machine's ``units`` ('mm' or 'inch', as X Y Z and the legs'): the wrist's
    table, its branch and travel (radians), and what follows from w0 alone (its length normal
    to the base x axis and angle about it, as :func:`world_of_axis` computes them), and the
    platform's verification home (a six-axis forward's second start)."""
    wrist, mm_per_unit = robot.wrist, LENGTH_UNITS[units]
    w0 = home_axis(robot)
    return {**wrist_table(robot, mm_per_unit), "names": ", ".join(wrist.names), "count": len(wrist.names),
            "branch": robot.working_posture % 2,
            "home_axis": c_vector(w0), "home_radius": c_double(np.hypot(w0[1], w0[2])),
            "home_phi": c_double(np.arctan2(w0[1], w0[2])),
            "home_centre": c_vector(np.asarray(robot.parallel.verification.home[:3]) / mm_per_unit),
            "lower": c_vector(np.clip(wrist.lower, -1e300, 1e300)),
            "upper": c_vector(np.clip(wrist.upper, -1e300, 1e300))}


def wrist_joints(robot):
    """The wrist's joints as the module view's joints (kingen.hosts.linuxcnc.render.view_model):
    index after the legs', degrees, travel from the robot file."""
    return [{**row, "unit": "degrees", "revolute": 1} for row in wrist_joint_rows(robot)]
