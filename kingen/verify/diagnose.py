"""Diagnoses: when a routine's joints disagree with the reference, name the likely defect.

Each hypothesis is tested against the evidence and stated with it: a constant
offset per joint (wrong reference length or zero), a sign flip, a scale (mm vs m,
degrees vs radians), swapped joints, postures in another order, T6 read untransposed.
Inputs are the plugin's and the reference's (n, dof, postures) arrays, mm or rad.
"""

import math

import numpy as np

from ..kinematics.routine import UNWRITTEN_WARNING, WARNINGS
from ..conventions import joint_errors, wrap_difference
from ..runtime.text import counted
from ..kinematics.reference import solve

UNREACHABLE_CODE = WARNINGS["WARN_UNREACHABLE"]
MATCH = 1e-6
"""Largest residual (mm or rad) at which a hypothesis counts as explaining the data."""
NAMED_SCALES = (
    (1e-3, "metres instead of mm"),
    (1e3, "micrometres instead of mm"),
    (1.0 / 25.4, "inches instead of mm"),
    (180.0 / math.pi, "degrees instead of radians"),
    (math.pi / 180.0, "radians read as degrees"),
)


def _errors(robot, a, b):
    """Angle-aware |a - b| (the rule verify uses), NaN counted as infinite."""
    return joint_errors(a, b, robot.revolute)


def diagnose(robot, t6, solutions, reference_joints, reference_warnings):
    """Hypotheses, one sentence each, explaining why ``solutions`` differ from the reference.

    Only poses where every posture is reachable (reference) and every value finite are
    used: joints of unreachable postures are free for a routine to choose."""
    reachable = np.all(reference_warnings != UNREACHABLE_CODE, axis=1)
    finite = np.all(np.isfinite(solutions), axis=(1, 2)) & reachable
    findings = []
    never = np.where(np.all(~np.isfinite(solutions), axis=(0, 1)))[0]
    if never.size:
        findings.append(f"the joints of postures {_ranges(never)} are never written (or are NaN) on any pose")
    if not np.any(finite):
        return findings
    t6, solutions, reference = t6[finite], solutions[finite], reference_joints[finite]

    untransposed = solve(robot, np.swapaxes(t6, 1, 2)).joints
    if _errors(robot, solutions, untransposed).max() <= MATCH:
        return findings + [
            "the routine reads T6 untransposed: it takes T6[i][3] as the position and T6[i][j] as "
            "R[i][j], but DELMIA passes rows n, o, a, p (its values match the reference fed the "
            f"transpose on all {len(t6)} poses)"
        ]

    permutation = _posture_permutation(robot, solutions, reference)
    if permutation is not None and permutation != list(range(robot.postures)):
        moved = ", ".join(f"{k}->{m}" for k, m in enumerate(permutation) if k != m)
        findings.append(
            f"postures are in another order: plugin posture -> reference posture {moved} "
            f"(permutation {permutation}; kingen numbers postures with the first two-branch limb "
            "most significant, branch 0 first)"
        )
        reference = reference[:, :, permutation]

    for joint in range(robot.dof):
        finding = _diagnose_joint(robot, joint, solutions, reference)
        if finding:
            findings.append(finding)
    return findings


def _posture_permutation(robot, solutions, reference):
    """plugin posture k -> the one reference posture it matches, or None where that fails."""
    if robot.postures == 1:
        return None
    permutation = []
    for k in range(robot.postures):
        matches = [m for m in range(robot.postures)
                   if _errors(robot, solutions[:, :, k:k + 1], reference[:, :, m:m + 1]).max() <= MATCH]
        if len(matches) != 1:
            return None
        permutation.append(matches[0])
    return permutation if sorted(permutation) == list(range(robot.postures)) else None


def _diagnose_joint(robot, joint, solutions, reference):
    revolute = bool(robot.revolute[joint])
    unit = robot.joint_types[joint].unit
    name = f"joint {joint} ({robot.joint_names[joint]})"
    mine, theirs = solutions[:, joint], reference[:, joint]
    difference = _wrapped(mine - theirs, revolute)
    if np.abs(difference).max() <= MATCH:
        return None

    for other in range(robot.dof):
        if other != joint and np.abs(_wrapped(mine - reference[:, other], revolute)).max() <= MATCH:
            return (f"{name} holds the values of reference joint {other} ({robot.joint_names[other]}): "
                    "joints swapped in the solutions array")

    offset = float(np.median(difference))
    if np.abs(difference - offset).max() <= MATCH:
        return (f"{name} is off by a constant {offset:+.6g} {unit} on every pose and posture: "
                f"{robot.limbs[joint].explain_offset(offset)}")

    if np.abs(_wrapped(mine + theirs, revolute)).max() <= MATCH:
        return f"{name} has its sign flipped: the routine returns minus the reference value"

    denominator = float(np.sum(theirs * theirs))
    if denominator > 0.0:
        scale = float(np.sum(mine * theirs)) / denominator
        if np.abs(mine - scale * theirs).max() <= MATCH * max(1.0, abs(scale)):
            label = next((text for value, text in NAMED_SCALES if math.isclose(scale, value, rel_tol=1e-6)), None)
            return f"{name} is scaled by {scale:.9g} ({label or 'a unit or gear-ratio error'})"

    worst = int(np.argmax(np.abs(difference).max(axis=1)))
    return (f"{name} disagrees by up to {np.abs(difference).max():.6g} {unit} (worst on pose {worst}); "
            "no constant offset, sign flip, scale, joint swap or posture order explains it")


def _wrapped(values, revolute):
    return wrap_difference(values) if revolute else values


def diagnose_warnings(plugin_warnings, reference_warnings, warning_names):
    """Sentences about warnings: never written, always 'good', or which codes differ how often."""
    findings = []
    unwritten = np.where(np.any(plugin_warnings == UNWRITTEN_WARNING, axis=0))[0]
    if unwritten.size:
        findings.append(f"the warnings of postures {_ranges(unwritten)} are never written on some poses")
    good = 0
    if np.all(plugin_warnings == good) and np.any(reference_warnings != good):
        counts = {warning_names[c]: int(np.count_nonzero(reference_warnings == c))
                  for c in np.unique(reference_warnings) if c != good}
        findings.append(f"the routine always answers WARN_GOOD_SOLUTION; the reference finds {counts}")
    else:
        pairs = {}
        for mine, theirs in zip(plugin_warnings.ravel(), reference_warnings.ravel()):
            if mine != theirs and mine != UNWRITTEN_WARNING:
                key = (warning_names.get(int(mine), str(mine)), warning_names.get(int(theirs), str(theirs)))
                pairs[key] = pairs.get(key, 0) + 1
        for (mine, theirs), count in sorted(pairs.items(), key=lambda item: -item[1])[:4]:
            findings.append(f"{counted(count, 'posture')} {'answers' if count == 1 else 'answer'} {mine} "
                            f"where the reference says {theirs}")
    return findings


def _ranges(indices):
    """[0, 1, 2, 5] -> '0-2, 5'."""
    parts, start = [], None
    indices = [int(i) for i in indices]
    for position, value in enumerate(indices):
        if start is None:
            start = value
        if position + 1 == len(indices) or indices[position + 1] != value + 1:
            parts.append(str(start) if start == value else f"{start}-{value}")
            start = None
    return ", ".join(parts)
