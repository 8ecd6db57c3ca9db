"""``values``: every joint of every posture the reference reaches, within the value bounds
(1e-9 mm and rad; a limb's singular band within its conditioning bound), with diagnoses of
what a failing routine got wrong (:mod:`kingen.verify.diagnose`)."""

from ..diagnose import diagnose
from ...runtime.text import counted
from .base import STOPPED_CALLS, Check, VerifyCheck

MIN_REACHABLE_POSES = 10
"""values fails unless at least this many sampled poses (or all of them, when fewer are
drawn) are reachable at some posture: a comparison of nothing proves nothing."""


class Values(VerifyCheck, name="values", needs="compared poses", item="values", uncompared=STOPPED_CALLS):
    def run(self, context):
        report, tally = context.report, context.tally
        t6, solutions, _, reference_joints, reference_warnings = tally.first
        compared = report.samples - tally.aborted
        required = min(MIN_REACHABLE_POSES, compared)
        reachable = tally.reachable_poses - tally.boundary_reachable  # drawn in the verification region
        if reachable < required:
            cause = ("no pose of the verification region is reachable" if not reachable else
                     f"only {reachable} of {compared} poses of the verification region are reachable")
            return [Check("values", False, f"{cause} at any posture: at least {required} needed to compare joints "
                                           "(move verification.home into the workspace, or narrow its range)",
                          judged=int(reachable))]
        values_ok = (report.max_abs_error_mm <= report.tolerance_mm and report.max_abs_error_rad <= report.tolerance_rad
                     and report.singular_out_of_bound == 0)
        aborted = f" ({tally.aborted} calls stopped at a write outside their buffers left out)" if tally.aborted else ""
        values = Check("values", values_ok,
                       f"max |error| {report.max_abs_error_mm:.3g} mm, {report.max_abs_error_rad:.3g} rad over "
                       f"{counted(report.samples - tally.aborted, 'pose')} x {counted(report.postures, 'posture')}"
                       f"{aborted}; "
                       f"{report.singular_entries} entries in a singular band, {report.singular_out_of_bound} beyond "
                       f"their bound (bounds {report.tolerance_mm:.3g} mm, {report.tolerance_rad:.3g} rad); "
                       f"{reachable} sampled poses reachable at some posture",
                       judged=int(tally.posture_counts[:3].sum()))
        if not values_ok:
            values.diagnoses = diagnose(context.robot, t6, solutions, reference_joints, reference_warnings)
        return [values]
