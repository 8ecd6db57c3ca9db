"""Constraining limbs and the task coordinates of a lower-mobility machine (docs/how-to/hybrid.md).

A limb whose base-side joint is a revolute joint with its axis a fixed in the base (a rail's
P-R-S, a leg's R-P-S: ``revolute_axis``) keeps its platform point C in the plane
a.(C - c) = 0 (``LimbModel.constraint_plane``). Three such planes leave the platform three
degrees of freedom: the robot file's ``task`` coordinates (z, roll, pitch); the other three,
x, y and yaw, follow from them (parasitic motion) and are solved in closed form
(kingen.kinematics.parasitic). This module validates the declaration and writes the
constant tables the solution uses, for the reference and the C alike.
"""

from dataclasses import dataclass

import numpy as np

TASK = ("z", "roll", "pitch")
PARASITIC = ("x", "y", "yaw")
"""The task coordinates kingen solves the parasitic ones of in closed form, and those."""
DETERMINED = 1e-6
"""The x and y rows of the planes fix x and y when |w| (below), relative to the product of their norms, exceeds this."""


@dataclass(frozen=True)
class ConstraintTable:
    """The planes a_i.(C_i - c_i) = 0 (k = 3 rows): ``axes`` a_i (3, 3) unit, base frame;
    ``points`` the constrained limbs' platform points n_i (3, 3), platform frame, mm; ``offsets``
    d_i = a_i.c_i (3,), mm; ``null`` w (3,), with w.N = 0 for N the (3, 2) matrix of the axes'
    x and y components; ``pseudo_inverse`` (N^T N)^-1 N^T (2, 3)."""

    axes: np.ndarray
    points: np.ndarray
    offsets: np.ndarray
    null: np.ndarray
    pseudo_inverse: np.ndarray


def constrained_limbs(limbs):
    """[(limb index, (axis, point))] of the limbs that constrain the platform, in joint order."""
    return [(index, plane) for index, limb in enumerate(limbs) if (plane := limb.constraint_plane()) is not None]


def constraint_table(robot):
    """The ConstraintTable of a robot with task coordinates."""
    planes = constrained_limbs(robot.limbs)
    axes = np.array([axis for _, (axis, _) in planes])
    offsets = np.array([float(np.dot(axis, point)) for _, (axis, point) in planes])
    points = np.array([robot.limbs[index].platform_point for index, _ in planes], dtype=float)
    matrix = axes[:, :2]
    return ConstraintTable(axes=axes, points=points, offsets=offsets, null=np.cross(matrix[:, 0], matrix[:, 1]),
                           pseudo_inverse=np.linalg.solve(matrix.T @ matrix, matrix.T))


def check_coordinates(robot, locate):
    """Raise a located error unless the robot's forward coordinates are one per limb (the task's,
    when it has task coordinates) and its constraining limbs and task coordinates make a machine
    kingen solves: three limbs, each constraining the platform, task z, roll and pitch, and
    planes whose x and y components fix x and y."""
    free, task, limbs = robot.forward_free, robot.task, robot.limbs
    if free and (len(set(free)) != len(free) or len(free) != robot.dof or task and set(free) != set(task)):
        raise locate.error(["forward", "free"], f"give {robot.dof} distinct pose coordinates, one per limb (the task's)")
    planes = constrained_limbs(limbs)
    if not task:
        if planes:
            raise locate.error(["limbs", planes[0][0], "revolute_axis"],
                               f"a revolute axis constrains the platform: declare the task coordinates "
                               f"(task: [{', '.join(TASK)}])")
        return
    if set(task) != set(TASK) or len(task) != len(TASK):
        raise locate.error(["task"], f"kingen solves the parasitic {', '.join(PARASITIC)} from the task coordinates "
                                     f"{', '.join(TASK)}: give task: [{', '.join(TASK)}]")
    if len(limbs) != len(TASK) or len(planes) != len(limbs):
        raise locate.error(["limbs"], f"a machine with task coordinates has {len(TASK)} limbs, each with a "
                                      f"revolute_axis; this one has {len(limbs)} limbs, {len(planes)} with one")
    matrix = np.array([axis[:2] for _, (axis, _) in planes])
    null = np.cross(matrix[:, 0], matrix[:, 1])
    scale = np.linalg.norm(matrix[:, 0]) * np.linalg.norm(matrix[:, 1])
    if not np.linalg.norm(null) > DETERMINED * scale:
        raise locate.error(["limbs", planes[0][0], "revolute_axis"],
                           "the revolute axes do not fix the platform's x and y (their x and y components "
                           "are parallel or zero): the constraints leave the platform free to slide")
