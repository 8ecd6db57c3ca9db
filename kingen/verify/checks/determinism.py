"""``determinism``: calling again with the same T6 gives the same output, bit for bit (a
routine that keeps state between calls fails)."""

import numpy as np

from .base import Check, VerifyCheck

DETERMINISM_POSES = 1000


class Determinism(VerifyCheck, name="determinism", needs="compared poses", item="interface"):
    def run(self, context):
        t6, solutions, warnings, _, _ = context.tally.first
        again = context.call(t6[:DETERMINISM_POSES])
        same = (np.array_equal(again.solutions, solutions[:DETERMINISM_POSES], equal_nan=True)
                and np.array_equal(again.warnings, warnings[:DETERMINISM_POSES]))
        return [Check("determinism", same, "the same T6 gives the same output" if same
                      else "calling again with the same T6 gives different output (state kept between calls?)")]
