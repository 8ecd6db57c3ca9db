"""What kingen's own process recomputes of a report a child sent (:func:`kingen.verify.verify_library`).

The child that loads a routine runs its code, so a routine that takes the child over could
send a report of its own making. Besides the report, the child sends the routine's answers
on the first EVIDENCE_POSES poses of the sample; kingen's process draws those poses itself,
solves the reference there and compares, with the comparison verify uses. A report whose
``values`` check passed while those answers are off fails the ``report`` check, and so does
one that came without them: a forger then has to answer the poses right, which is what
``values`` asks of a routine."""

from typing import Optional, Tuple

from ..conventions import t6_from_pose
from ..kinematics.poses import PoseStream
from ..kinematics.routine import calls_decoder
from ..runtime.wire import WireError, typed
from .checks import Check
from .processes import compare_poses, set_chunk_job

EVIDENCE_POSES = 64
"""How many of the sample's first poses the child answers again for kingen's own process."""


def evidence_count(options):
    return min(EVIDENCE_POSES, options.samples)


def answers(robot, plugin, options):
    """In the child: the loaded routine ``plugin``'s Calls on the first evidence_count poses of
    ``options``' sample (mm, degrees), with the options' calibration fields, and its warning
    vocabulary (None: every warning)."""
    poses = PoseStream(robot, options.seed).draw(evidence_count(options))
    plugin.reset_host()
    calls = plugin.call(t6_from_pose(poses), options.link_lengths, options.link_offsets)
    vocabulary = getattr(plugin, "warning_vocabulary", None)
    return {"calls": calls, "vocabulary": None if vocabulary is None else list(vocabulary)}


def decoder(options):
    """The kingen.runtime.isolation decoder of what answers() sends, checked field by field."""
    calls = calls_decoder(evidence_count(options))

    def decode(value):
        if not isinstance(value, dict) or set(value) != {"calls", "vocabulary"}:
            raise WireError("answers that kingen cannot read (their fields)")
        vocabulary = typed(Optional[Tuple[str, ...]], value["vocabulary"])
        return calls(value["calls"]), vocabulary
    return decode


class _Answered:
    """The routine as its answers on the evidence poses stand for it (compare_poses's plugin)."""

    summarises_branches = False

    def __init__(self, routine, calls, vocabulary):
        self.routine, self._calls, self.warning_vocabulary = routine, calls, vocabulary

    def reset_host(self):
        pass

    def call(self, t6, link_lengths, link_offsets):
        return self._calls


def unconfirmed(robot, options, report, evidence):
    """The failed ``report`` check when ``report`` (from the child) says ``values`` passed but
    the routine's answers (``evidence``: decoder()'s (Calls, vocabulary), or None when none
    came) on the evidence poses, compared here with the reference (robot, options' fields),
    are beyond the value bounds; None when they agree or values did not pass."""
    if not any(check.name == "values" and check.passed for check in report.checks):
        return None
    count = evidence_count(options)
    if evidence is None:
        return Check("report", False, f"the host process said values passed but sent no answers on the first "
                                      f"{count} poses for kingen to compare itself: its report was not used")
    set_chunk_job(robot, robot.calibrated(options.link_lengths, options.link_offsets),
                  _Answered(report.routine, *evidence), options)
    counts = compare_poses(PoseStream(robot, options.seed).draw(count), captured=False).counts
    if counts["max_abs_error_mm"] <= report.tolerance_mm and counts["max_abs_error_rad"] <= report.tolerance_rad \
            and counts["singular_out_of_bound"] == 0:
        return None
    return Check("report", False, f"the host process said values passed, but the routine's answers on the first "
                                  f"{count} poses, compared with the reference in kingen's own process, are off by "
                                  f"up to {counts['max_abs_error_mm']:.3g} mm, {counts['max_abs_error_rad']:.3g} rad "
                                  "(beyond their bounds): its report was not used")

