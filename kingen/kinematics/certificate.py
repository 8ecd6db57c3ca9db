"""A cheap exact lower bound on the direct index, from det W: how the reference settles,
without forming M, the postures whose index lies far above the robot's threshold.

W is the posture's 6 x 6 matrix of unit line wrenches (a row per limb; kingen.kinematics.singularity).
With F = tr M_vv and T = tr M_ww (M = W^T W):

    direct index >= |det W| / ((F / 3)^(3/2) T / 2)

det W is computed by Laplace's expansion along limbs 0-2 against 3-5: per pose, the 20 minors
of each triple for each of its branch combinations, then one 20-term dot product per
posture. Its rounding is at most ROUNDING times P, the product of the rows' 1-norms, and a
posture is certified only where the bound, less twice that, still clears the threshold.
docs/explanation/conventions.md ('A certificate for the direct index') proves the bound and the rounding
allowance, and why a certified posture is never one the reference's own factorisation would
call translation-singular.
"""

import itertools

import numpy as np

from ..conventions import SIX
from .singularity import TRANSLATION_SINGULAR, branch_table

_TRIPLES = list(itertools.combinations(range(SIX), 3))
"""Column sets of a 3 x 3 minor (20): Laplace's expansion sums over these."""
_PAIRS = list(itertools.combinations(range(SIX), 2))
_PAIR_INDEX = {pair: k for k, pair in enumerate(_PAIRS)}
_FIRST, _SECOND = (np.array(side) for side in zip(*_PAIRS))
_TRIPLE_COLUMNS = np.array(_TRIPLES).T  # (3, 20): j < k < l
_TRIPLE_PAIRS = np.array([[_PAIR_INDEX[k, l], _PAIR_INDEX[j, l], _PAIR_INDEX[j, k]] for j, k, l in _TRIPLES]).T
_COMPLEMENT = np.array([_TRIPLES.index(tuple(sorted(set(range(SIX)) - set(triple)))) for triple in _TRIPLES])
_SIGN = np.array([-1.0 if sum(triple) % 2 == 0 else 1.0 for triple in _TRIPLES])
"""Laplace's sign for rows {1, 2, 3} and columns S+1 (1-based): (-1)^(6 + sum(S) + 3), -1 where sum(S) is even."""

_UNIT_ROUNDOFF = np.finfo(float).eps / 2
ROUNDING_STEPS = 30
"""Roundings on any term's path through det W's computation: 2 in a 2 x 2 minor, 3 more in a
3 x 3 minor, twice (one per triple), 1 for the product of two minors, 19 in a 20-term sum."""
ROUNDING = ROUNDING_STEPS * _UNIT_ROUNDOFF / (1 - ROUNDING_STEPS * _UNIT_ROUNDOFF)
"""gamma_30: |computed det W - det W| <= ROUNDING * sum of |terms| <= ROUNDING * prod_i |w_i|_1."""
FINITE_LIMIT = 1e300
"""A pose whose P (the product of row 1-norms) reaches this is not certified: below it no
intermediate of det W can overflow (every partial product is at most P, each 1-norm being
at least 1)."""
MARGIN = 1e-12
"""Relative allowance for the rounding of the bound's other quantities (each at most about
50 unit roundoffs, 5.6e-15): a posture is certified only when it clears the threshold by this."""
TRANSLATION_MARGIN = 1e3
"""A certified posture also has det M_vv above this many times the reference's own
translation-singular limit (TRANSLATION_SINGULAR (F / 3)^3), so that the reference's
factorisation, whose relative error there is below 1e-5, would not call it singular."""


BLOCK_POSES = 256
"""Poses certified at once, which bounds the temporaries (on CEART, with verify's memory
settings, blocks of 128 to 2,057 poses all cost 2.8 to 3.4 us a pose)."""


def certified_above(robot, lines, bound):
    """(m, postures) bool: True where the direct index provably exceeds ``bound`` (mm; a number,
    or one per pose), rounding included; False proves nothing. From the limbs' line wrenches
    ``lines`` (dof, 2, 6, m): branch 0 and 1 of each limb, components (force, moment about the
    base origin), poses last, as kingen.kinematics.singularity.limb_wrenches stores them. Robots with six
    force lines only."""
    count = lines.shape[-1]
    bound = np.broadcast_to(bound, (count,))
    settled = np.empty((count, robot.postures), dtype=bool)
    for begin in range(0, count, BLOCK_POSES):
        block = slice(begin, begin + BLOCK_POSES)
        # Rows of the chunk's lines, as they lie (a contiguous copy measured no faster).
        settled[block] = _per_posture(robot, _settled(lines[..., block], bound[block]))
    return settled


def _settled(lines, bound):
    """(8, 8, m) certified_above for each branch combination of limbs 0-2 and 3-5."""
    det = _combination_determinants(lines)
    squares = lines * lines
    # Per pose, over both branches of every limb: at least tr M_vv, tr M_ww and prod_i |w_i|_1 in every posture.
    force_third = squares[:, :, :3].sum(axis=2).max(axis=1).sum(axis=0) / 3.0  # (m,)
    terms = np.prod(np.abs(lines).sum(axis=2).max(axis=1), axis=0)
    moment = squares[:, :, 3:].sum(axis=2)  # (dof, 2, m)
    largest_moment_third = moment.max(axis=1).sum(axis=0) / 3.0
    moment_trace = _summed(moment[0:3])[:, None] + _summed(moment[3:6])[None, :]  # (8, 8, m): T per posture
    allowance = np.where(terms < FINITE_LIMIT, 2.0 * ROUNDING * terms, np.inf)
    slope = bound * force_third * np.sqrt(force_third) / 2.0 * (1.0 + MARGIN)
    cube = force_third * largest_moment_third
    translation = TRANSLATION_MARGIN * TRANSLATION_SINGULAR * cube * cube * cube
    return (np.abs(det) > allowance + slope * moment_trace) & (det * det > translation)


def posture_determinants(robot, lines):
    """(m, postures) det W of every posture, as certified_above computes it, from the limbs'
    line wrenches (dof, 2, 6, m)."""
    return _per_posture(robot, _combination_determinants(lines))


def _per_posture(robot, per_combination):
    """(m, postures) from values (8, 8, m) per branch combination of limbs 0-2 and of 3-5."""
    table = branch_table(robot)
    return per_combination[table[:, 0:3] @ (4, 2, 1), table[:, 3:6] @ (4, 2, 1)].T


def _combination_determinants(lines):
    """(8, 8, m) det W for each branch combination of limbs 0-2 (first) and 3-5 (second):
    Laplace's expansion, a batched 8 x 20 by 20 x 8 product per pose."""
    minors = [_triple_minors(lines[first:first + 3]) for first in (0, 3)]  # (8, 20, m) each
    first = minors[0].transpose(2, 0, 1)  # (m, 8, 20)
    other = (_SIGN[:, None] * minors[1][:, _COMPLEMENT]).transpose(2, 1, 0)  # (m, 20, 8)
    return np.matmul(first, other).transpose(1, 2, 0)


def _triple_minors(lines):
    """(8, 20, m) the 3 x 3 minors of three limbs' lines (3, 2, 6, m) over every column set,
    for each branch combination 4 b0 + 2 b1 + b2: by expansion along the first limb's row,
    from the 2 x 2 minors of the other two."""
    first, second, third = lines
    pairs = (second[:, None, _FIRST] * third[None, :, _SECOND]
             - second[:, None, _SECOND] * third[None, :, _FIRST])  # (2, 2, 15, m)
    j, k, l = (first[:, None, None, columns] for columns in _TRIPLE_COLUMNS)  # (2, 1, 1, 20, m)
    kl, jl, jk = (pairs[None, :, :, index] for index in _TRIPLE_PAIRS)  # (1, 2, 2, 20, m)
    return (j * kl - k * jl + l * jk).reshape(8, len(_TRIPLES), -1)


def _summed(per_line):
    """(8, m) the sum of three limbs' quantity (3, 2, m) for each branch combination 4 b0 + 2 b1 + b2."""
    first, second, third = per_line
    return (first[:, None, None] + second[None, :, None] + third[None, None, :]).reshape(8, -1)
