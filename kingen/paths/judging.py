"""What a batch of samples tells the findings: the places beyond each decision quantity's
boundary (the first and the worst of each move's piece), the joint speeds and accelerations
beyond their limits (the worst of each piece, with the feed override at which a speed fits),
each joint's peaks, the figures' trace, and every sample to the CSV sink."""

import numpy as np

from .power import fitting_feed

RATE_ROUNDING = 1e-9
"""A joint speed or acceleration above its limit by at most this fraction of it is rounding
(a joint that follows the path one to one, at the path's own limit), not a problem."""


def _by_piece(rows, pieces_of_rows):
    """(piece, its rows) for ``rows`` sorted by piece."""
    numbers, firsts = np.unique(pieces_of_rows, return_index=True)
    return zip(numbers, np.split(rows, firsts[1:]))


def _keys(batch):
    """Each sample's place in its batch as one increasing number: 2 piece + u."""
    return 2.0 * batch.piece + batch.u


def sample_numbers(findings, grid, batch):
    """Where the samples of ``batch`` stand along the program (n,), in regular samples on the
    findings' trace axis: ``grid``'s samples (the batch's owned regular samples, before they are
    recorded) are whole numbers, a refined sample between two of them a fraction."""
    keys = _keys(grid)
    if not len(keys):
        return np.full(len(batch.u), float(findings.samples))
    return findings.samples + np.interp(_keys(batch), keys, np.arange(len(keys), dtype=float))


def judge_margins(findings, evaluator, batch, pieces, lines, samples):
    """The first and the worst place of each piece beyond each decision quantity's boundary
    (``samples``: where the batch's samples stand along the program, sample_numbers)."""
    for column, quantity in enumerate(evaluator.quantities):
        margins = batch.margins[:, column]
        beyond = np.flatnonzero(margins <= 0.0)
        for number, rows in _by_piece(beyond, batch.piece[beyond]):
            for row in dict.fromkeys((rows[0], rows[np.argmin(margins[rows])])):
                findings.add(pieces[number].index, findings.place(
                    quantity.kind, quantity.joint, lines[number], batch.poses[row], batch.joints[row],
                    evaluator.value_of(quantity, batch, row), evaluator.limit_of(quantity), margins[row],
                    between=quantity.part, file=pieces[number].move.file, sample=samples[row],
                    warning=batch.warnings[row]))


def has_accelerations(move, timing):
    """Whether a move's joint accelerations are judged: it is timed (``timing``, timing.profile's)
    with a path acceleration, or by CSV times."""
    return timing is not None and (timing.acceleration is not None or move.duration is not None)


def judge_rates(findings, limits, grid, speeds, accelerations, pieces, lines):
    """Each piece's worst joint speed and acceleration beyond its limit (accelerations only
    where the piece's timing has them: a path acceleration, or CSV times)."""
    accelerated = np.array([has_accelerations(p.move, p.timing) for p in pieces])[grid.piece]
    for kind, rates, bounds, judged in (("joint speed", speeds, limits.speed, True),
                                        ("joint acceleration", accelerations, limits.acceleration, accelerated)):
        size = np.abs(rates)
        with np.errstate(invalid="ignore"):
            beyond = (size > bounds * (1.0 + RATE_ROUNDING)) & np.reshape(judged, (-1, 1))
        for joint in np.flatnonzero(np.any(beyond, axis=0)):
            rows = np.flatnonzero(beyond[:, joint])
            for number, piece_rows in _by_piece(rows, grid.piece[rows]):
                row = piece_rows[np.argmax(size[piece_rows, joint])]
                value, limit = size[row, joint], bounds[joint]
                findings.add(pieces[number].index, findings.place(
                    kind, joint, lines[number], grid.poses[row], grid.joints[row], value, limit, (limit - value) / limit,
                    float(limit / value) if kind == "joint speed" else None, file=pieces[number].move.file,
                    sample=findings.samples + row, warning=grid.warnings[row]))


def judge_power(findings, robot, grid, power, resting, pieces, lines):
    """Each piece's first and worst actuator power (W; kingen.paths.power.actuator_power's
    ``power`` and its part at rest ``resting``, (n, m)) beyond its limb's max_power, with the
    feed override at which it fits."""
    bounds = np.array([np.inf if limb.max_power is None else limb.max_power for limb in robot.limbs])
    size = np.abs(power)
    with np.errstate(invalid="ignore"):
        beyond = size > bounds * (1.0 + RATE_ROUNDING)
    for joint in np.flatnonzero(np.any(beyond, axis=0)):
        rows = np.flatnonzero(beyond[:, joint])
        for number, piece_rows in _by_piece(rows, grid.piece[rows]):
            for row in dict.fromkeys((piece_rows[0], piece_rows[np.argmax(size[piece_rows, joint])])):
                value, limit = size[row, joint], bounds[joint]
                findings.add(pieces[number].index, findings.place(
                    "actuator power", joint, lines[number], grid.poses[row], grid.joints[row], value, limit,
                    (limit - value) / limit, fitting_feed(power[row, joint], resting[row, joint], limit),
                    file=pieces[number].move.file))


def record(findings, batch, grid, speeds, accelerations, pieces, lines, sink):
    """Peaks, the trace, and every sample of ``batch`` to ``sink(lines, batch, rates)`` with the
    grid's rates where a sample is one of the grid's (NaN elsewhere)."""
    findings.update_peaks(batch.joints, lines[grid.piece], speeds, accelerations)
    findings.record_trace(lines[grid.piece], grid.poses, grid.joints, grid.warnings, speeds, accelerations,
                          grid.radicand, grid.direct_index)
    if sink is not None:
        keys, wanted = _keys(grid), _keys(batch)
        at = np.minimum(np.searchsorted(keys, wanted), len(keys) - 1)
        on_grid = keys[at] == wanted
        rates = np.full((len(batch.u), 2, speeds.shape[1]), np.nan)
        rates[on_grid, 0], rates[on_grid, 1] = speeds[at[on_grid]], accelerations[at[on_grid]]
        sink(lines[batch.piece], batch, rates)
