"""``closure``: each limb's joint of each branch, put back into the limb's geometry, closes
the limb (:func:`kingen.verify.tally.closure_error`): catches a formula mistake that the
routine and the reference share."""

from ..report import not_exercised
from .base import Check, VerifyCheck

CLOSURE_TOLERANCE = 1e-9
"""Relative to the passive link's length."""
CONSTRAINT_TOLERANCE_MM = 1e-9
"""A machine with task coordinates: the largest constraint residual at its pose (mm)."""
WRIST_TOLERANCE = 1e-9
"""A machine with a wrist: how far (mm, and as unit vectors) the wrist's forward from the
routine's wrist joints may miss the asked tool tip and tool axis (three joints: every tool axis)."""


class Closure(VerifyCheck, name="closure", needs="compared poses", item="closure"):
    def run(self, context):
        tally = context.tally
        constraints = constraint_checks(context.robot, tally) + wrist_checks(context.robot, tally)
        if not tally.closure_checked:
            return [not_exercised("closure", "no limb of a reachable posture was outside its singular band"),
                    *constraints]
        return [Check("closure", tally.closure_worst <= CLOSURE_TOLERANCE,
                      f"each limb's joint of each branch put back into the limb geometry: worst relative "
                      f"residual {tally.closure_worst:.3g} over {tally.closure_checked} joints "
                      f"(at most {CLOSURE_TOLERANCE:g} of the link length)", judged=tally.closure_checked),
                *constraints]


def constraint_checks(robot, tally):
    """[] for a robot without task coordinates (of its parallel part); else the check that its
    constraint equations close at the machine's pose the reference solves every pose at (those
    that have one; with a wrist, the platform's pose for the tool pose)."""
    if not robot.parallel.task:
        return []
    if not tally.constraint_checked:
        return [not_exercised("constraints", "no sampled pose's task coordinates had a machine pose")]
    return [Check("constraints", tally.constraint_worst <= CONSTRAINT_TOLERANCE_MM,
                  f"each constraint equation at the machine's pose for the task coordinates: worst residual "
                  f"{tally.constraint_worst:.3g} mm over {tally.constraint_checked} poses (at most "
                  f"{CONSTRAINT_TOLERANCE_MM:g} mm)", judged=tally.constraint_checked)]


def wrist_checks(robot, tally):
    """[] for a robot without a wrist; else ``wrist``: the wrist's forward from the routine's
    wrist joints, on the platform's pose, gives the asked tool tip and tool axis back (with three
    wrist joints the whole tool frame)."""
    if robot.wrist is None:
        return []
    read, free = (("tool frame (its three axes)", "the whole pose is read") if robot.wrist.whole_pose
                  else ("tool axis", "the turn about the tool axis is free"))
    if not tally.wrist_checked:
        return [not_exercised("wrist", "no posture the reference reaches lay outside the wrist's singular bands")]
    return [Check("wrist", tally.wrist_worst <= WRIST_TOLERANCE,
                  f"the wrist's forward from the routine's wrist joints at the platform's pose: the asked tool tip "
                  f"and {read} missed by at most {tally.wrist_worst:.3g} (mm; unit vector) over "
                  f"{tally.wrist_checked} (pose, posture) pairs (at most {WRIST_TOLERANCE:g}; {free})",
                  judged=tally.wrist_checked)]
