"""The wrench on the platform that is equivalent, by virtual work, to the forces on the limbs'
moving parts (docs/explanation/loads.md, 'The limbs' parts').

Each part is a point mass (a limb's ``parts``: kingen.robot.loads_schema.LimbParts). With C the
limb's platform point, B(q) its passive link's base side, u = C - B, L = |u| and f = u / L
(base frame, mm):

- the passive link's part sits at x = C - d f (d from the platform joint);
- the actuator's part at x = B + d f where it turns with the link about B (a leg's cylinder),
  else it moves as the base side times a gain g (x' = g B'; a crank's point d from its pivot,
  g = d / r; a carriage, g = 1).

A force F (N) on a part does the power F . x' = [X; C x X] . t + s q', the platform's twist t
(kingen.kinematics.platform_loads) and the joint's rate q' = (f . C') / (f . B' + l'). So it acts
as the wrench [X; C x X] + s [f; C x f] / (f . B' + l') (N; N mm about the base origin). With
P = I - f f^T:

    link part:             X = F - (d / L) P F,   s = (d / L) (P F) . B'
    turning with the link: X = (d / L) P F,       s = F . B' - (d / L) (P F) . B'
    moving with B:         X = 0,                 s = g F . B'

F is the part's weight m g and, for a moving platform, minus m times its acceleration
(d'Alembert), from the platform's motion by differentiating the closure |C - B(q)| = l(q) twice.
"""

import numpy as np

from .singularity import branch_table, branch_values

MM_PER_M = 1000.0


def with_parts(robot, machine, solution, chosen, static, applied, motion):
    """(static, applied) wrenches (n, p, 6) [N; N mm about the base origin] on the platform at the
    T6 ``machine`` (n, 4, 4), in postures ``chosen`` (p,): the payload's ``static`` and ``applied``
    (n, 6) plus the limbs' parts' weight, and with ``motion`` (kingen.kinematics.platform_loads.
    Motion, or None) their d'Alembert forces too. Without parts: the inputs as (n, 1, 6)."""
    static, applied = static[:, None, :], applied[:, None, :]
    limbs = [(index, limb) for index, limb in enumerate(robot.limbs[:robot.dof]) if limb.parts is not None]
    if not limbs:
        return static, applied
    table = branch_table(robot)[chosen, :robot.dof]
    joints = branch_values(robot, solution.joints[:, :robot.dof])  # (n, dof, 2)
    gravity = np.asarray(robot.gravity, dtype=float)
    rest, moving = np.zeros((len(machine), len(chosen), 6)), np.zeros((len(machine), len(chosen), 6))
    for index, limb in limbs:
        for branch in sorted(set(table[:, index].tolist())):
            columns = table[:, index] == branch
            point, joint = solution.points[:, index], joints[:, index, branch]
            geometry = _geometry(limb, point, joint)
            rest[:, columns] += _part_wrench(limb, geometry, point, gravity, None)[:, None]
            moving[:, columns] += _part_wrench(limb, geometry, point, gravity,
                                               _accelerations(limb, geometry, point, machine, motion))[:, None]
    return static + rest, applied + moving


def _dot(a, b):
    return np.einsum("ni,ni->n", a, b)


def _geometry(limb, point, joint):
    """The limb's link at platform points (n, 3) and joints (n,): a dict of f (n, 3), L (n,),
    B' and B'' (n, 3), the transmission f . B' + l' (n,) and the joint (n,)."""
    line = point - limb.base_side_point(point, joint)
    length = np.linalg.norm(line, axis=-1)
    direction = line / length[:, None]
    rate = np.broadcast_to(limb.base_side_velocity(joint), direction.shape)
    return {"f": direction, "L": length, "B1": rate,
            "B2": np.broadcast_to(limb.base_side_acceleration(joint), direction.shape),
            "transmission": _dot(direction, rate) + limb.link_length_rate}


def _accelerations(limb, geometry, point, machine, motion):
    """{'link': (n, 3), 'actuator': (n, 3)} the parts' accelerations (mm/s^2, base frame) as the
    platform moves with ``motion``, or None at rest."""
    if motion is None:
        return None
    f, length, rate, curve = geometry["f"], geometry["L"][:, None], geometry["B1"], geometry["B2"]
    velocity = np.broadcast_to(np.asarray(motion.velocity, dtype=float), (len(point), 6))
    acceleration = np.broadcast_to(np.asarray(motion.acceleration, dtype=float), (len(point), 6))
    omega, alpha, arm = velocity[:, 3:], acceleration[:, 3:], point - machine[:, 3, :3]
    point_rate = velocity[:, :3] + np.cross(omega, arm)
    point_acceleration = acceleration[:, :3] + np.cross(alpha, arm) + np.cross(omega, np.cross(omega, arm))
    joint_rate = _dot(f, point_rate) / geometry["transmission"]
    stretch = point_rate - rate * joint_rate[:, None]  # u'
    turn = (stretch - f * _dot(f, stretch)[:, None]) / length  # f'
    joint_acceleration = (_dot(turn, stretch) + _dot(f, point_acceleration)
                          - _dot(f, curve) * joint_rate ** 2) / geometry["transmission"]
    base_acceleration = rate * joint_acceleration[:, None] + curve * joint_rate[:, None] ** 2  # B''
    second = point_acceleration - base_acceleration  # u''
    turn_rate = ((second - f * _dot(f, second)[:, None] - f * _dot(turn, stretch)[:, None]) / length
                 - 2.0 * turn * _dot(f, stretch)[:, None] / length)  # f''
    accelerations = {}
    if limb.parts.link is not None:
        accelerations["link"] = point_acceleration - limb.parts.link.centre * turn_rate
    if limb.parts.actuator is not None:
        gain = limb.actuator_part_gain(limb.parts.actuator.centre)
        accelerations["actuator"] = (base_acceleration + limb.parts.actuator.centre * turn_rate if gain is None
                                     else gain * base_acceleration)
    return accelerations


def _part_wrench(limb, geometry, point, gravity, accelerations):
    """(n, 6) [N; N mm about the base origin]: the wrench on the platform equivalent to the limb's
    parts' weight, less mass times ``accelerations`` (mm/s^2; None: at rest) (module docstring)."""
    f, length, rate = geometry["f"], geometry["L"][:, None], geometry["B1"]
    across = np.zeros_like(f)  # X
    along = np.zeros(len(f))  # s
    for name, part in (("link", limb.parts.link), ("actuator", limb.parts.actuator)):
        if part is None:
            continue
        force = part.mass * (gravity - (np.zeros_like(f) if accelerations is None else accelerations[name] / MM_PER_M))
        normal = force - f * _dot(f, force)[:, None]  # P F
        share = part.centre / length
        gain = limb.actuator_part_gain(part.centre) if name == "actuator" else None
        if name == "link":
            across += force - share * normal
            along += share[:, 0] * _dot(normal, rate)
        elif gain is None:
            across += share * normal
            along += _dot(force, rate) - share[:, 0] * _dot(normal, rate)
        else:
            along += gain * _dot(force, rate)
    line = np.concatenate([f, np.cross(point, f)], axis=1) / geometry["transmission"][:, None]
    return np.concatenate([across, np.cross(point, across)], axis=1) + along[:, None] * line
