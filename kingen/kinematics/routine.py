"""The routine contract every host shares: what a compiled inverse-kinematics routine answers
for a batch of poses, in kingen's units, and how close it must come to the reference.

A host (:mod:`kingen.hosts`) loads a routine and calls it on T6 matrices (mm); whatever its
own interface, it hands verify a :class:`Calls`: every posture's joints (mm for prismatic,
radians for revolute joints) and a status per posture in the codes of ``WARNINGS``
(docs/explanation/conventions.md). A host whose routines report other codes maps them to these.
"""

import re
from dataclasses import dataclass

import numpy as np

from ..errors import KingenError
from ..runtime.wire import WireError

WARNINGS = {
    "WARN_GOOD_SOLUTION": 0,
    "WARN_JOINT_LIMITS_EXCEEDED": 1,
    "WARN_UNREACHABLE": 2,
    "WARN_SINGULAR_SOLUTION": 5,
}
"""A posture's status: reachable and regular, a joint beyond its travel, no real solution,
within a singularity's band (a limb's, or the platform's direct index)."""
WARNING_NAMES = {value: name for name, value in WARNINGS.items()}


def answer_frame(t, pose, joints, warning, **more):
    """A routine's answer at one pose as plain JSON data (a frame of kingen.view's scene):
    ``{t, pose, joints, warning, **more}``: ``pose`` (6) mm and degrees and ``joints`` (the
    routine's units: mm, radians; None where not finite) rounded to 1e-9, ``warning`` its WARN_*
    name."""
    return {"t": float(t), "pose": [round(float(value), 9) + 0.0 for value in pose],
            "joints": [round(float(value), 9) + 0.0 if np.isfinite(value) else None for value in joints],
            "warning": WARNING_NAMES.get(int(warning), f"warning {int(warning)}"), **more}


SINGULAR_TOLERANCE = 0.00001
"""Band |D| <= 1e-5 around a limb singularity (D: a limb's normalised radicand): the
routine answers WARN_SINGULAR_SOLUTION there, WARN_UNREACHABLE below -1e-5."""


def warning_codes(outside, singular, unreachable):
    """(int32 array, the flags' broadcast shape) each posture's WARN_* code from its boolean flags:
    a joint beyond its travel (``outside``), within a singular band (``singular``), no real
    solution (``unreachable``); each later one wins (unreachable over singular over limits)."""
    warnings = np.full(np.broadcast_shapes(np.shape(outside), np.shape(singular), np.shape(unreachable)),
                       WARNINGS["WARN_GOOD_SOLUTION"], dtype=np.int32)
    for flags, code in ((outside, "WARN_JOINT_LIMITS_EXCEEDED"), (singular, "WARN_SINGULAR_SOLUTION"),
                        (unreachable, "WARN_UNREACHABLE")):
        np.copyto(warnings, WARNINGS[code], where=flags)
    return warnings


def warnings_to_exercise(robot, vocabulary=None):
    """The warnings ``robot``'s routine can give besides WARN_GOOD_SOLUTION (within the
    routine's ``vocabulary`` of warnings, when it has one): verify exercises each of them,
    and the setup sheets list only these."""
    kinds = []
    wrist = robot.wrist is not None
    if (any(limb.travel is not None and (not limb.joint_type.wraps or limb.travel[1] - limb.travel[0] < 360.0)
            for limb in robot.limbs)  # a revolute travel of a full turn or more is never exceeded
            or wrist and np.any((robot.wrist.lower > -np.pi) | (robot.wrist.upper < np.pi))):  # angles in (-pi, pi]
        kinds.append("WARN_JOINT_LIMITS_EXCEEDED")
    if (any(limb.has_radicand for limb in robot.limbs) or (robot.task and robot.parasitic_given)  # off the manifold
            or wrist and _wrist_misses_axes(robot.wrist)):
        kinds.append("WARN_UNREACHABLE")
    if any(limb.has_radicand for limb in robot.limbs) or robot.direct_index_min is not None or wrist:
        kinds.append("WARN_SINGULAR_SOLUTION")  # a wrist: where its axes align
    return [kind for kind in kinds if vocabulary is None or kind in vocabulary]


def _wrist_misses_axes(wrist):
    """Whether some axes lie beyond the reach of ``wrist``'s first two joints (its
    WARN_UNREACHABLE: the tool axis of a two-axis wrist, the third axis of a three-axis one):
    over every target axis w_p the wrist's radicand D (kingen.kinematics.hybrid.wrist) is least at
    a1.w_p = +/-1, -(|a1.a2| + |a2.z0|)^2 / (1 - (a1.a2)^2), and only below -SINGULAR_TOLERANCE is
    an axis unreachable (axes a calibration tilted by a few hundredths of a degree reach every axis)."""
    first, second, start = wrist.axes[0], wrist.axes[1], wrist.axes[2] if wrist.whole_pose else wrist.tool[:3, 2]
    cosine, along = abs(first @ second), abs(second @ start)
    return (cosine + along) ** 2 / (1.0 - cosine * cosine) > SINGULAR_TOLERANCE


UNWRITTEN_WARNING = -1
"""Sentinel put in every warning slot before a call: left there, it was never written."""
UNWRITTEN_JOINT = float("nan")
"""Sentinel put in every solutions entry before a call."""
VALUE_TOLERANCE_MM = 1e-9
VALUE_TOLERANCE_RAD = 1e-9
"""How close a routine's joints must be to the reference's (prismatic, revolute)."""
WARNING_BAND = 1e-9
"""Half-width of the band around a warning threshold (radicand +/- SINGULAR_TOLERANCE:
relative; travel limits: mm or rad) inside which routine and reference may disagree."""

INPUTS_MODIFIED = 16
"""The fault bit of a call that changed its inputs. Every other fault bit a host reports
means the call was stopped at a faulting write: its outputs are partial."""
C_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,254}")


@dataclass(frozen=True)
class Calls:
    """Routine results for n poses: returned (n,), solutions (n, dof, postures), warnings (n, postures).

    faults (n,): per call the host's fault bits (writes outside the output buffers, modified
    inputs: :data:`INPUTS_MODIFIED`); 0 for a clean call.
    """

    returned: np.ndarray
    solutions: np.ndarray
    warnings: np.ndarray
    faults: np.ndarray
    branch_values: np.ndarray = None
    """(n, dof, 2) each limb's value in its branch 0 and 1 as the routine wrote it (at
    kingen.kinematics.singularity.representative_postures), when the host summarised the calls by
    branch (then ``solutions`` is read-only, so that the summary stays theirs); else None."""
    repeats: np.ndarray = None
    """(n,) with ``branch_values``: whether every posture's value of every limb equals (==, so
    never for NaN) its value in the branch it takes (kingen.kinematics.singularity.branch_table)."""

    @property
    def guard_violations(self):
        return int(np.count_nonzero(self.faults & ~INPUTS_MODIFIED))

    @property
    def inputs_modified(self):
        return bool(np.any(self.faults & INPUTS_MODIFIED))


CALLS_ARRAYS = {"returned": ("iu", 1), "solutions": ("f", 3), "warnings": ("iu", 2), "faults": ("iu", 1),
                "branch_values": ("f", 3), "repeats": ("iub", 1)}
"""Calls' arrays as they travel from a child: numpy dtype kinds and dimensions."""


def calls_decoder(poses):
    """A kingen.runtime.isolation decoder of the Calls a child sends for ``poses`` poses: each array of
    its numeric kind, ``poses`` long and consistent with the others in joints and postures,
    the branch summary (n, dof, 2) and (n,) both or neither; WireError naming what is not."""
    def decode(value):
        if not isinstance(value, dict) or set(value) != set(CALLS_ARRAYS):
            raise WireError("Calls that kingen cannot read (their fields)")
        summary = value["branch_values"] is not None
        for name, (kinds, dimensions) in CALLS_ARRAYS.items():
            array = value[name]
            if array is None and name in ("branch_values", "repeats") and not summary:
                continue
            if not (isinstance(array, np.ndarray) and array.dtype.kind in kinds and array.ndim == dimensions
                    and len(array) == poses):
                raise WireError(f"Calls that kingen cannot read ({name}: not {poses} poses' numbers)")
        _, dof, postures = value["solutions"].shape
        if value["warnings"].shape[1] != postures or summary and value["branch_values"].shape[1:] != (dof, 2):
            raise WireError("Calls that kingen cannot read (their joint or posture counts disagree)")
        return Calls(**value)
    return decode


def check_routine_name(routine):
    """``routine`` if it is a C identifier; else KingenError (it would be looked up as a symbol)."""
    if not isinstance(routine, str) or not C_IDENTIFIER.fullmatch(routine):
        raise KingenError(f"routine name {routine!r} is not a C identifier")
    return routine
