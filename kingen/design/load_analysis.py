"""What analyze judges of loads (docs/how-to/loads.md): a pose stops where holding the robot
file's payload at rest needs more than a limb's max_force or max_torque (cause
'actuator_load') or a passive joint stands beyond its joint_limits ('joint_angle'); every pose
judged also gets its largest actuator load as a fraction of its limit and, where every limb
gives its stiffness, the platform's smallest translational stiffness (N/mm: a force at the
platform origin in the weakest direction over the displacement it makes there)."""

from dataclasses import replace

import numpy as np

from ..kinematics.loads import SIDES, load_limited, loads_of, without_parts

LOAD_KEYS = ("load_fraction", "min_stiffness_n_per_mm")
"""What analyze records of loads per pose: the largest |load| / limit, and the least stiffness (N/mm)."""
UNIT_FORCES = np.eye(3)
"""The forces (N) at the platform origin whose displacements give its compliance's columns."""


def stiffness_given(robot):
    """Whether every limb gives its actuator's stiffness."""
    return all(limb.stiffness is not None for limb in robot.limbs)


def load_quantities(robot, t6, posture, solution):
    """Per pose of ``t6`` (n, 4, 4, what analysis.evaluate judges, with the reference's
    ``solution`` there) in ``posture``: {actuator_load,
    joint_angle: (n,) bool, beyond a limit; load_fraction: (n,) the largest |load| / limit over the
    limited actuators (NaN: none limited, or unreachable); min_stiffness_n_per_mm: (n,) (NaN without
    every limb's stiffness)}."""
    count = len(t6)
    held = loads_of(robot, t6, solution, posture)
    forces = np.abs(held.forces[:, 0, :robot.dof])
    limits = np.array([limb.actuator_limit or np.nan for limb in robot.limbs])
    with np.errstate(invalid="ignore"):
        fractions = forces / limits
    limited = np.isfinite(limits)
    fraction = np.max(fractions[:, limited], axis=1) if np.any(limited) else np.full(count, np.nan)
    bent = np.zeros(count, dtype=bool)
    for side, angles in zip(SIDES, (held.base_angles, held.platform_angles)):
        cones = np.array([limb.cone(side) if limb.cone(side) is not None else np.inf for limb in robot.limbs])
        bent |= np.any(np.degrees(angles[:, 0]) > cones, axis=1)
    return {"actuator_load": np.nan_to_num(fraction, nan=0.0) > 1.0, "joint_angle": bent, "load_fraction": fraction,
            "min_stiffness_n_per_mm": _least_stiffness(robot, t6, posture, solution)}


def _least_stiffness(robot, t6, posture, solution):
    """(n,) N/mm: 1 / the largest eigenvalue of the platform origin's translational compliance
    (NaN without every limb's stiffness, or where the posture holds no load)."""
    if not stiffness_given(robot):
        return np.full(len(t6), np.nan)
    unloaded = without_parts(replace(robot, payload=None))  # stiffness is the machine's, whatever it carries
    columns = [loads_of(unloaded, t6, solution, posture, np.r_[force, 0.0, 0.0, 0.0]).deflection[:, 0, :3]
               for force in UNIT_FORCES]
    compliance = np.stack(columns, axis=2)  # (n, 3, 3) mm per N
    symmetric = 0.5 * (compliance + np.swapaxes(compliance, 1, 2))
    finite = np.all(np.isfinite(symmetric), axis=(1, 2))
    least = np.full(len(t6), np.nan)
    least[finite] = 1.0 / np.linalg.eigvalsh(symmetric[finite])[:, -1]
    return least


def loads_available(robot):
    """analyze's 'available' entry for loads."""
    if load_limited(robot) or stiffness_given(robot):
        payload = f"the payload ({robot.payload.mass:g} kg) at rest" if robot.payload else "no payload (the file gives none)"
        return (f"available: {payload}; stops where an actuator's load passes its max_force or max_torque or a passive "
                "joint its joint_limits" + ("; smallest stiffness from every limb's stiffness" if stiffness_given(robot)
                                            else ""))
    return "not available: the robot file gives no limb max_force, max_torque, joint_limits or stiffness"
