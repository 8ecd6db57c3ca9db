"""Units, frames and pose conventions shared by every kingen module.

- Lengths in mm. Prismatic joints in mm, revolute joints in radians in (-pi, pi].
- YAML files and command-line poses give angles in degrees.
- A pose ``x y z roll pitch yaw`` (mm, degrees) is the platform frame in the base
  frame with R = Rz(yaw) . Ry(pitch) . Rx(roll) (fixed axes X, then Y, then Z).
- H is the usual homogeneous matrix (columns n, o, a, p). A routine is called with
  T6 = transpose(H): rows n, o, a, p, column 3 = (0, 0, 0, 1).
- Posture k: each two-branch limb gives one binary digit, the first such limb
  most significant, branch 0 before branch 1.

All functions are vectorised over leading axes. docs/explanation/conventions.md states all of this
with the limb models' equations.
"""

import math
from dataclasses import dataclass

import numpy as np

SIX = 6
"""A platform's degrees of freedom: the force lines a robot needs for the direct index, one each."""


@dataclass(frozen=True)
class JointType:
    """A kind of joint and every unit that follows from it, defined once; a host names the
    kind by ``name``."""

    name: str
    unit: str
    """Unit of joint values in the plugin, the reference and reports: 'mm' or 'rad'."""
    yaml_unit: str
    """Unit in robot files and on the command line: 'mm' or 'deg'."""
    yaml_scale: float
    """Factor from the YAML unit to the internal one."""
    wraps: bool
    """Values are angles, compared modulo 2 pi (pi equals -pi)."""
    c_units: str
    """How generated C comments name the unit."""


PRISMATIC = JointType("prismatic", "mm", "mm", 1.0, False, "mm")
REVOLUTE = JointType("revolute", "rad", "deg", math.pi / 180.0, True, "radians")


def rotation_from_rpy(roll, pitch, yaw):
    """Rotation matrices R = Rz(yaw) Ry(pitch) Rx(roll); angles in radians, shape (..., 3, 3)."""
    roll, pitch, yaw = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (roll, pitch, yaw)))
    cr, sr = np.cos(roll), np.sin(roll)
    cp, sp = np.cos(pitch), np.sin(pitch)
    cy, sy = np.cos(yaw), np.sin(yaw)
    rotation = np.empty(roll.shape + (3, 3))
    rotation[..., 0, 0] = cy * cp
    rotation[..., 0, 1] = cy * sp * sr - sy * cr
    rotation[..., 0, 2] = cy * sp * cr + sy * sr
    rotation[..., 1, 0] = sy * cp
    rotation[..., 1, 1] = sy * sp * sr + cy * cr
    rotation[..., 1, 2] = sy * sp * cr - cy * sr
    rotation[..., 2, 0] = -sp
    rotation[..., 2, 1] = cp * sr
    rotation[..., 2, 2] = cp * cr
    return rotation


def matrix_from_pose(pose):
    """Homogeneous matrices H (..., 4, 4) from poses (..., 6): x y z in mm, roll pitch yaw in degrees."""
    pose = np.asarray(pose, dtype=float)
    angles = np.radians(pose[..., 3:6])
    matrix = np.zeros(pose.shape[:-1] + (4, 4))
    matrix[..., :3, :3] = rotation_from_rpy(angles[..., 0], angles[..., 1], angles[..., 2])
    matrix[..., :3, 3] = pose[..., :3]
    matrix[..., 3, 3] = 1.0
    return matrix


def t6_from_matrix(matrix):
    """The transposed T6 (rows n, o, a, p) from homogeneous matrices H."""
    return np.swapaxes(np.asarray(matrix, dtype=float), -1, -2).copy()


def matrix_from_t6(t6):
    """Homogeneous matrices H from the transposed T6."""
    return t6_from_matrix(t6)


def t6_from_pose(pose):
    """T6 (..., 4, 4) for poses (..., 6) in mm and degrees."""
    return t6_from_matrix(matrix_from_pose(pose))


def pose_from_t6(t6):
    """Poses (..., 6) x y z in mm and roll pitch yaw in degrees from T6 (..., 4, 4);
    pitch in [-90, 90] degrees (the inverse of t6_from_pose away from pitch = +/-90)."""
    t6 = np.asarray(t6, dtype=float)
    angles = rpy_from_rotation(np.swapaxes(t6[..., :3, :3], -1, -2))
    return np.concatenate([t6[..., 3, :3], np.degrees(angles)], axis=-1)


def rpy_from_rotation(rotation):
    """(roll, pitch, yaw) (..., 3) in radians of rotation matrices (..., 3, 3) with
    R = Rz(yaw) Ry(pitch) Rx(roll); pitch in [-pi/2, pi/2]."""
    roll = np.arctan2(rotation[..., 2, 1], rotation[..., 2, 2])
    pitch = np.arcsin(np.clip(-rotation[..., 2, 0], -1.0, 1.0))
    yaw = np.arctan2(rotation[..., 1, 0], rotation[..., 0, 0])
    return np.stack([roll, pitch, yaw], -1)


def wrap_angle(angle):
    """Angles in radians mapped to (-pi, pi], as the generated C does it: an angle already
    there is returned unchanged, one within one turn of it moved by one 2 pi step, any
    other reduced by floored modulo."""
    angle = np.asarray(angle, dtype=float)

    def inside(value):
        return (value > -np.pi) & (value <= np.pi)

    stepped = np.where(angle > np.pi, angle - 2.0 * np.pi, angle + 2.0 * np.pi)
    with np.errstate(invalid="ignore"):
        wrapped = np.mod(angle + np.pi, 2.0 * np.pi) - np.pi
    wrapped = np.where(wrapped == -np.pi, np.pi, wrapped)
    return np.where(inside(angle), angle, np.where(inside(stepped), stepped, wrapped))


def angle_difference(a, b):
    """Signed difference a - b in radians, wrapped to (-pi, pi] (so pi and -pi agree)."""
    return wrap_angle(np.asarray(a, dtype=float) - np.asarray(b, dtype=float))


def branch_of_posture(posture, bit):
    """Branch (0 or 1) a two-branch limb with binary digit ``bit`` takes in posture ``posture``."""
    return (np.asarray(posture) >> bit) & 1


def wrap_difference(difference):
    """Signed angle differences (radians) with whole turns removed, in [-pi, pi]."""
    return difference - (2.0 * np.pi) * np.rint(difference / (2.0 * np.pi))


def joint_errors(solutions, joints, revolute):
    """|solutions - joints| per entry for arrays (n, dof, postures), mm or rad.

    ``revolute`` (dof,) marks joints compared modulo 2 pi (so pi equals -pi).
    A non-finite entry of ``solutions`` (unwritten, NaN) is an infinite error.
    """
    difference = np.array(solutions, dtype=float) - joints
    difference[:, revolute] = wrap_difference(difference[:, revolute])
    np.abs(difference, out=difference)
    difference[~np.isfinite(difference)] = np.inf
    return difference
