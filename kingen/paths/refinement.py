"""Samples added between the regular ones so that no boundary is crossed unseen.

Between two samples where a decision quantity g is within its limit at both ends (g > 0), g
can only dip to 0 if its slope there reaches min(g_a, g_b) / du. The slope is estimated by
the secant slopes of that interval and its two neighbours; where SAFETY times that estimate
over the interval reaches the smaller end value, the interval is split at its middle, and
again, until no interval is suspect, intervals are MIN_STEP short or the samples added reach
MAX_REFINED times the batch's own (a quantity that grazes its boundary along a whole move, such
as a wrist held on its singular pole, would otherwise double the samples MAX_ROUNDS times). Every interval whose
ends lie on two sides of a boundary is then bisected BISECTIONS times, so that the place
where the boundary is crossed is known to within 2^-BISECTIONS of the interval.
"""

import numpy as np

from .evaluation import Batch

SAFETY = 2.0
"""How many times the neighbouring secant slopes a quantity's slope is allowed to reach."""
MAX_ROUNDS = 40
MIN_STEP = 1e-12
"""Intervals (in the move's parameter u in [0, 1]) shorter than this are not split."""
BISECTIONS = 40
MAX_REFINED = 16
"""Refinement adds at most this many times a batch's own samples (bisection's are apart)."""


def _suspect(batch):
    """(n - 1,) bool: intervals between consecutive samples of one piece where some quantity,
    inside its limit at both ends, could dip across its boundary unseen."""
    margins, du = batch.margins, np.diff(batch.u)
    if margins.shape[1] == 0 or len(du) == 0:
        return np.zeros(len(du), dtype=bool)
    du = np.where(batch.piece[1:] == batch.piece[:-1], du, 0.0)  # no interval between two pieces
    first, second = margins[:-1], margins[1:]
    with np.errstate(invalid="ignore", divide="ignore"):
        slope = np.abs(second - first) / np.maximum(du, MIN_STEP)[:, None]
    slope = np.nan_to_num(slope, nan=np.inf, posinf=np.inf)
    slope[du == 0.0] = 0.0
    neighbours = np.maximum(slope, np.maximum(np.vstack([slope[:1], slope[:-1]]), np.vstack([slope[1:], slope[-1:]])))
    inside = (first > 0) & (second > 0)
    suspect = inside & (np.minimum(first, second) <= SAFETY * neighbours * du[:, None])
    return np.any(suspect, axis=1) & (du > MIN_STEP)


def _crossing(batch):
    """(n - 1,) bool: intervals of one piece whose two ends lie on two sides of some quantity's
    boundary."""
    inside = batch.margins > 0
    return np.any(inside[:-1] != inside[1:], axis=1) & (batch.piece[1:] == batch.piece[:-1])


def refined(batch, evaluate):
    """``batch`` (sorted by piece, then u) with the samples refinement and bisection add (sorted
    alike), and the count of added samples. ``evaluate(piece, u)`` gives the Batch of pieces
    ``piece`` at parameters ``u``."""
    added, allowed = 0, MAX_REFINED * len(batch.u)
    for _ in range(MAX_ROUNDS):
        suspect = np.flatnonzero(_suspect(batch))[:max(allowed - added, 0)]
        if len(suspect) == 0:
            break
        middles = 0.5 * (batch.u[suspect] + batch.u[suspect + 1])
        batch = Batch.joined(batch, evaluate(batch.piece[suspect], middles))
        added += len(middles)
    crossing = np.flatnonzero(_crossing(batch))
    if len(crossing) == 0:
        return batch, added
    low, high = batch.u[crossing].copy(), batch.u[crossing + 1].copy()
    low_inside, pieces = batch.margins[crossing] > 0, batch.piece[crossing]
    for _ in range(BISECTIONS):
        middle = 0.5 * (low + high)
        probe = evaluate(pieces, middle)
        same = np.all((probe.margins > 0) == low_inside, axis=1)
        low = np.where(same, middle, low)
        high = np.where(same, high, middle)
    sides = evaluate(np.concatenate([pieces, pieces]), np.concatenate([low, high]))
    return Batch.joined(batch, sides), added + len(low) + len(high)
