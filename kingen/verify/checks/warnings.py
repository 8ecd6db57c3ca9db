"""``warnings``: every posture's status equal to the reference's, except inside the tolerance
band around a threshold (:func:`kingen.verify.tally.warnings_in_band`)."""

from ...diagnose import diagnose_warnings
from ...routine import WARNING_NAMES
from ..tally import WARNING_KINDS
from .base import STOPPED_CALLS, Check, VerifyCheck


class Warnings(VerifyCheck):
    name = "warnings"
    needs = "compared poses"
    item = "warnings"
    uncompared = STOPPED_CALLS

    def run(self, context):
        report, tally = context.report, context.tally
        _, _, warnings, _, reference_warnings = tally.first
        judged = int(tally.warning_counts.sum())
        given = ", ".join(f"{int(count)} {kind}" for kind, count in zip(WARNING_KINDS, tally.warning_counts) if count)
        check = Check("warnings", report.warning_mismatches == 0,
                      f"{report.warning_mismatches} mismatches, {report.warnings_in_band} inside the tolerance band, "
                      f"over {judged} postures (the reference's: {given or 'none'})", judged=judged)
        if not check.passed:
            check.diagnoses = diagnose_warnings(warnings, reference_warnings, WARNING_NAMES)
        return [check]
