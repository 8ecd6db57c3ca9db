"""Constraining limbs and the task coordinates of a lower-mobility machine (docs/how-to/hybrid.md).

A limb whose base-side joint is a revolute joint with its axis a fixed in the base (a rail's
P-R-S, a leg's R-P-S: ``revolute_axis``) keeps its platform point C in the plane
a.(C - c) = 0 (``LimbModel.constraint_plane``). Three such planes leave the platform three
degrees of freedom: the robot file's ``task`` coordinates (z, roll, pitch); the other three,
x, y and yaw, follow from them (parasitic motion) and are solved in closed form
(kingen.kinematics.hybrid.parasitic). A leg whose platform-side joint is a revolute joint with its
axis e fixed in the platform (S-P-R, U-P-R: ``platform_revolute_axis``) stays normal to it:
(R e).(b - p) = e.n. Two legs sharing one such axis and a third with another (the Exechon's)
leave the platform x, y, z of its origin as task coordinates; roll, pitch and yaw follow, in
closed form (kingen.kinematics.hybrid.parasitic_axes). A passive leg (the Tricept's tube,
kingen.robot.passive_leg) fixes the rotation from x, y, z too. This module validates the
declaration and writes the constant tables the solution uses, for the reference and the C alike.
"""

from dataclasses import dataclass

import numpy as np

from .passive_leg import check_tube

TASK = ("z", "roll", "pitch")
PARASITIC = ("x", "y", "yaw")
"""The task coordinates kingen solves the parasitic ones of in closed form, and those: the
family of revolute axes fixed in the base ("planes")."""
POSITION = ("x", "y", "z")
ORIENTATION = ("roll", "pitch", "yaw")
"""The task coordinates of the family of revolute axes fixed in the platform ("axes", the
Exechon's), and its parasitic ones."""
PARALLEL = 1e-9
"""Two platform revolute axes are one pair's when their unit vectors differ by less than this."""
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


@dataclass(frozen=True)
class AxesTable:
    """The platform revolute axes' constraints (R e).(b - p) = e.n of an Exechon-type machine:
    a pair of limbs i, j with one axis e_a, a third k with e_b (platform frame, unit).
    ``pair`` (i, j, k); ``base`` b_i, ``third_base`` b_k (base frame, mm); ``difference``
    d = b_i - b_j; ``pair_rhs`` (e_a.(n_i - n_j), e_a.n_i); ``third_rhs`` e_b.n_k (mm);
    ``cosine`` e_a.e_b; ``frame`` (3, 3) columns e_a, e_b's part normal to e_a, their cross
    product (platform frame)."""

    pair: tuple
    base: np.ndarray
    third_base: np.ndarray
    difference: np.ndarray
    pair_rhs: tuple
    third_rhs: float
    cosine: float
    frame: np.ndarray


def family(robot):
    """'planes' (revolute axes fixed in the base, task z, roll, pitch), 'axes' (fixed in the
    platform, task x, y, z), 'tube' (a passive leg, task x, y, z) or None: no task coordinates."""
    if not robot.task:
        return None
    if robot.passive_leg is not None:
        return "tube"
    return "axes" if set(robot.task) == set(POSITION) else "planes"


def platform_axes(limbs):
    """[(limb index, (axis, base point, platform point))] of the limbs with a platform revolute axis."""
    return [(index, found) for index, limb in enumerate(limbs) if (found := limb.platform_constraint()) is not None]


def _pairing(axes):
    """(i, j, k) positions in ``axes`` (three unit vectors): i, j share their axis, k's differs; or None."""
    for i, j, k in ((0, 1, 2), (0, 2, 1), (1, 2, 0)):
        if np.linalg.norm(axes[i] - axes[j]) < PARALLEL and np.linalg.norm(np.cross(axes[i], axes[k])) > PARALLEL:
            return i, j, k
    return None


def axes_table(robot):
    """The AxesTable of a machine of the 'axes' family (checked by check_coordinates)."""
    found = platform_axes(robot.limbs)
    i, j, k = _pairing([axis for _, (axis, _, _) in found])
    (e_a, b_i, n_i), (_, b_j, n_j), (e_b, b_k, n_k) = found[i][1], found[j][1], found[k][1]
    normal = e_b - np.dot(e_a, e_b) * e_a
    normal = normal / np.linalg.norm(normal)
    return AxesTable(pair=(found[i][0], found[j][0], found[k][0]), base=b_i, third_base=b_k,
                     difference=b_i - b_j, pair_rhs=(float(np.dot(e_a, n_i - n_j)), float(np.dot(e_a, n_i))),
                     third_rhs=float(np.dot(e_b, n_k)), cosine=float(np.dot(e_a, e_b)),
                     frame=np.stack([e_a, normal, np.cross(e_a, normal)], axis=1))


def _check_axes(robot, locate):
    """Raise a located error unless the 'axes' family's machine is one kingen solves: three
    limbs, each with a platform revolute axis and none fixed in the base, two sharing one axis
    from distinct base points, the third's axis another."""
    limbs = robot.limbs
    found = platform_axes(limbs)
    if constrained_limbs(limbs):
        raise locate.error(["limbs", constrained_limbs(limbs)[0][0], "revolute_axis"],
                           f"task: [{', '.join(POSITION)}] takes revolute axes fixed in the platform "
                           f"(platform_revolute_axis), not in the base")
    if len(limbs) != len(POSITION) or len(found) != len(limbs):
        raise locate.error(["limbs"], f"a machine with task coordinates {', '.join(POSITION)} has {len(POSITION)} "
                                      f"limbs, each with a platform_revolute_axis; this one has {len(limbs)} limbs, "
                                      f"{len(found)} with one")
    pairing = _pairing([axis for _, (axis, _, _) in found])
    if pairing is None or np.linalg.norm(found[pairing[0]][1][1] - found[pairing[1]][1][1]) < PARALLEL:
        raise locate.error(["limbs", found[0][0], "platform_revolute_axis"],
                           "kingen solves two limbs sharing one platform revolute axis from distinct base points "
                           "and a third with another axis (the Exechon's legs): these axes are not such")


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
    if robot.passive_leg is not None:
        return check_tube(robot, locate)
    if task and set(task) == set(POSITION) and len(task) == len(POSITION):
        return _check_axes(robot, locate)
    if platform_axes(limbs):
        raise locate.error(["limbs", platform_axes(limbs)[0][0], "platform_revolute_axis"],
                           f"a platform revolute axis constrains the platform: declare the task coordinates "
                           f"(task: [{', '.join(POSITION)}])")
    if not task:
        if planes:
            raise locate.error(["limbs", planes[0][0], "revolute_axis"],
                               f"a revolute axis constrains the platform: declare the task coordinates "
                               f"(task: [{', '.join(TASK)}])")
        return
    if set(task) != set(TASK) or len(task) != len(TASK):
        raise locate.error(["task"], f"kingen solves the parasitic {', '.join(PARASITIC)} from the task coordinates "
                                     f"{', '.join(TASK)} (revolute_axis), or {', '.join(ORIENTATION)} from "
                                     f"{', '.join(POSITION)} (platform_revolute_axis): give task: [{', '.join(TASK)}] "
                                     f"or [{', '.join(POSITION)}]")
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
