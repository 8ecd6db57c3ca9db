"""``closure``: each limb's joint of each branch, put back into the limb's geometry, closes
the limb (:func:`kingen.verify.tally.closure_error`): catches a formula mistake that the
routine and the reference share."""

from ..report import not_exercised
from .base import Check, VerifyCheck

CLOSURE_TOLERANCE = 1e-9
"""Relative to the passive link's length."""


class Closure(VerifyCheck, name="closure", needs="compared poses", item="closure"):
    def run(self, context):
        tally = context.tally
        if not tally.closure_checked:
            return [not_exercised("closure", "no limb of a reachable posture was outside its singular band")]
        return [Check("closure", tally.closure_worst <= CLOSURE_TOLERANCE,
                      f"each limb's joint of each branch put back into the limb geometry: worst relative "
                      f"residual {tally.closure_worst:.3g} over {tally.closure_checked} joints "
                      f"(at most {CLOSURE_TOLERANCE:g} of the link length)", judged=tally.closure_checked)]
