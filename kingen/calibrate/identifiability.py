"""What the measurements can tell apart: the identifiable parameters from the rank of the
identification Jacobian, the combinations that cannot be identified (named in words), the
observability indices and the standard deviations a plan predicts (a fit's: kingen.calibrate.noise).

The Jacobian's columns are in mm-equivalents (kingen.calibrate.parameters), its rows the
residuals' (mm-equivalents). Columns are taken in the parameters' order, the measuring frame
and the target first: a column that adds less than RANK_TOLERANCE of its own length to the
span of those taken before it cannot be told apart from them and is kept at its nominal
value (Gram-Schmidt with the parameters' priority, as QR with column pivoting does with the
columns' norms).
"""

import numpy as np

RANK_TOLERANCE = 1e-5
"""A column whose part outside the span of those taken is below this fraction of its length,
or of the largest column's, is not identifiable."""
NAMED = 6
"""At most this many partners are named in a combination's words."""


def priority(parameters):
    """The order columns are taken in: the measuring frame and the target, then the limbs'."""
    first = [i for i, group in enumerate(parameters.groups) if group in ("frame", "target")]
    return first + [i for i in range(len(parameters)) if i not in first]


def identifiable(jacobian, order):
    """(columns,) bool: the columns of ``jacobian`` (m, p) that add to the span of those taken
    before them in ``order`` (indices)."""
    norms = np.linalg.norm(jacobian, axis=0)
    floor = RANK_TOLERANCE * max(float(np.max(norms, initial=0.0)), np.finfo(float).tiny)
    basis = np.zeros((jacobian.shape[0], 0))
    chosen = np.zeros(jacobian.shape[1], dtype=bool)
    for column in order:
        vector = jacobian[:, column]
        for _ in range(2):  # twice: Gram-Schmidt's second pass keeps the basis orthonormal
            vector = vector - basis @ (basis.T @ vector)
        length = np.linalg.norm(vector)
        if length > max(RANK_TOLERANCE * norms[column], floor):
            basis = np.column_stack([basis, vector / length])
            chosen[column] = True
    return chosen


def combinations(jacobian, names, chosen, selected):
    """Words for each selected parameter that is not identifiable: the identified parameters
    its column moves together with (the largest shares first), or that it does not change
    the measurements at all."""
    words = []
    norms = np.linalg.norm(jacobian, axis=0)
    floor = RANK_TOLERANCE * max(float(np.max(norms, initial=0.0)), np.finfo(float).tiny)
    taken = np.flatnonzero(chosen)
    for column in np.flatnonzero(selected & ~chosen):
        if norms[column] <= floor:
            words.append(f"{names[column]} does not change these measurements: it cannot be identified from them "
                         "(kept at its nominal value)")
            continue
        shares, *_ = np.linalg.lstsq(jacobian[:, taken], jacobian[:, column], rcond=None)
        weight = np.abs(shares) * norms[taken]
        order = np.argsort(-weight)
        partners = [names[taken[i]] for i in order[:NAMED] if weight[i] > 0.05 * norms[column]]
        more = int(np.count_nonzero(weight > 0.05 * norms[column])) - len(partners)
        listed = ", ".join(partners) + (f" and {more} more" if more > 0 else "")
        words.append(f"{names[column]} moves together with {listed or 'the identified parameters'}: "
                     "it cannot be told apart from them (kept at its nominal value)")
    return words


def indices(jacobian):
    """The observability indices of the identified columns of the Jacobian (m, r): condition
    number (largest over smallest singular value), smallest singular value, noise
    amplification index (smallest squared over largest, Nahvi and Hollerbach)."""
    values = np.linalg.svd(jacobian, compute_uv=False)
    if not len(values) or values[-1] <= 0.0:
        return {"condition_number": float("inf"), "min_singular_value": 0.0, "noise_amplification": 0.0}
    return {"condition_number": float(values[0] / values[-1]), "min_singular_value": float(values[-1]),
            "noise_amplification": float(values[-1] ** 2 / values[0])}


def predicted_deviations(jacobian, row_sigma):
    """Standard deviations (r,) (mm-equivalents) the identified parameters would have from
    rows of the Jacobian (m, r) whose residuals have standard deviations ``row_sigma`` (m,)."""
    weighted = jacobian / row_sigma[:, None]
    return np.sqrt(np.diag(np.linalg.pinv(weighted.T @ weighted)))
