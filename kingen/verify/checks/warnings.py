"""``warnings``: every posture's status equal to the reference's, except inside the tolerance
band around a threshold (:func:`kingen.verify.tally.warnings_in_band`)."""

import numpy as np

from ..diagnose import diagnose_warnings
from ...kinematics.routine import WARNING_NAMES, warnings_to_exercise
from ..boundaries import DIRECT_INDEX, RAYS, threshold_boundaries
from ..descent import Descent
from ..tally import WARNING_KINDS
from ...runtime.text import counted
from .base import STOPPED_CALLS, Check, VerifyCheck


class Warnings(VerifyCheck, name="warnings", needs="compared poses", item="warnings", uncompared=STOPPED_CALLS):
    def run(self, context):
        report, tally = context.report, context.tally
        _, _, warnings, _, reference_warnings = tally.first
        judged = int(tally.warning_counts.sum())
        counts = dict(zip(WARNING_KINDS, (int(count) for count in tally.warning_counts)))
        given = ", ".join(f"{count} {kind}" for kind, count in counts.items() if count)
        boundary = report.boundary_poses
        found = ", ".join(f"{kind} {count}" for kind, count in boundary.get("boundaries_found", {}).items())
        vocabulary = getattr(context.routine, "warning_vocabulary", None)
        missing = [kind for kind in warnings_to_exercise(context.robot, vocabulary) if not counts[kind]]
        detail = (f"{counted(report.warning_mismatches, 'mismatch', 'mismatches')}, {report.warnings_in_band} inside "
                  "the tolerance band, "
                  f"over {judged} postures of {report.samples} sampled poses and {boundary.get('poses', 0)} poses "
                  f"beside warnings' boundaries (boundaries found along {RAYS} rays"
                  f"{', or by a descent where they met none' if boundary.get('searched') else ''}: {found or 'none sought'}); the "
                  f"reference's warnings: {given or 'none'}")
        if vocabulary is not None:
            detail += f"; the routine tells only {', '.join(vocabulary)} (the reference's others read as good)"
        searched = boundary.get("searched", {})
        if missing:
            detail += (f"; not exercised: {', '.join(missing)} (the robot can give it, no compared pose did"
                       + "".join(f"; {kind}: {_searched(searched[kind])}" for kind in missing if kind in searched)
                       + "): widen the verification region or check the robot's limits")
        threshold = threshold_boundaries(context.robot, boundary.get("boundaries_found", {}))
        if threshold is not None:
            detail += "; " + _threshold_exercise(context.robot.direct_index_min, tally.direct_index_below, threshold,
                                                 searched.get(DIRECT_INDEX))
        check = Check("warnings", report.warning_mismatches == 0 and not missing, detail, judged=judged)
        if report.warning_mismatches:
            if tally.boundary_first is not None:
                warnings = np.concatenate([warnings, tally.boundary_first[2]])
                reference_warnings = np.concatenate([reference_warnings, tally.boundary_first[4]])
            check.diagnoses = diagnose_warnings(warnings, reference_warnings, WARNING_NAMES)
        return [check]


def _searched(descent):
    """A search's fields (kingen.verify.descent.Descent, as the report holds them) in words."""
    return Descent(**descent).summary()


def _threshold_exercise(threshold, below, boundaries, descent=None):
    """What exercised the direct index's threshold (``threshold`` mm): ``below`` compared
    postures at or under it, ``boundaries`` of it found along the rays or, where they missed
    it, by ``descent`` (its fields). Never reached, it is not exercised, with the region and
    method of the search that did not meet it: said, not failed (the warning itself is judged
    by its other causes' poses, or missing)."""
    where = "along the rays" if descent is None else f"by {_searched(descent)}"
    if not below and not boundaries:
        return (f"the direct-index threshold ({DIRECT_INDEX} {threshold:g} mm) not exercised: no compared "
                f"posture's index is at or below it, no ray from the verification home met it, and "
                f"{_searched(descent) if descent else 'no search ran'}")
    return (f"the direct-index threshold ({DIRECT_INDEX} {threshold:g} mm): {counted(below, 'compared posture')} at "
            f"or below it, {boundaries} of its boundaries found {where}")
