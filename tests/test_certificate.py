"""The direct index's certificate (kingen.kinematics.certificate; docs/explanation/conventions.md, 'A certificate for
the direct index'): its det W against LAPACK's within the proven rounding allowance, its
bound never above the index, certification just below the bound and never just above it,
the rounding and translation conditions each shown to be what refuses a posture, and the
reference giving the same warnings with it as without it."""

from dataclasses import replace
from fractions import Fraction

import numpy as np
import pytest

from conftest import random_t6
from kingen.kinematics import certificate, reference
from kingen.kinematics.certificate import ROUNDING, certified_above, posture_determinants
from kingen.robot.model import load_robot
from kingen.kinematics.reference import solve
from kingen.kinematics.routine import WARNINGS
from kingen.kinematics.singularity import (PACKED, TRANSLATION_SINGULAR, direct_index, direct_index_side, limb_wrenches,
                                posture_values)

UNREACHABLE = WARNINGS["WARN_UNREACHABLE"]
UNIT_ROUNDOFF = Fraction(1, 2 ** 53)
G30 = 30 * UNIT_ROUNDOFF / (1 - 30 * UNIT_ROUNDOFF)
"""docs/explanation/conventions.md's rounding constant g30 = 30u / (1 - 30u), exactly."""


def lines_of(robot, count, seed):
    """(lines (dof, 2, 6, n) as the reference stores them, posture wrenches (n, postures, 6, 6),
    the reference's solution) at ``count`` seeded poses of the robot's region."""
    _, t6 = random_t6(robot, count, seed)
    expected = solve(robot, t6)
    wrenches, _ = limb_wrenches(robot, expected.points, expected.branch_joints, with_transmissions=False)
    return np.moveaxis(wrenches, 0, -1), posture_values(robot, wrenches), expected


def bound_of(lines, per_posture):
    """(n, postures) the certificate's lower bound |det W| / ((F / 3)^(3/2) T / 2), computed
    here from LAPACK's determinant, with F taken per pose as the certificate does."""
    force_third = (lines[:, :, :3] ** 2).sum(axis=2).max(axis=1).sum(axis=0) / 3.0
    moment_trace = (per_posture[..., 3:] ** 2).sum(axis=(2, 3))
    return np.abs(np.linalg.det(per_posture)) / (force_third[:, None] ** 1.5 * moment_trace / 2.0)


def unit_lines(rng, count, arm):
    """(count, 6, 6) random line sets: unit forces through points about ``arm`` mm from the origin."""
    forces = rng.normal(size=(count, 6, 3))
    forces /= np.linalg.norm(forces, axis=2, keepdims=True)
    points = rng.normal(size=(count, 6, 3)) * arm
    return np.concatenate([forces, np.cross(points, forces)], axis=2)


def as_lines(wrenches):
    """(6, 2, 6, n) one-branch lines (branch 1 a copy of branch 0) from W (n, 6, 6)."""
    per_limb = np.moveaxis(wrenches, 0, -1)  # (6, 6, n)
    return np.ascontiguousarray(np.stack([per_limb, per_limb], axis=1))


@pytest.mark.parametrize("name", ["ceart", "iwf", "hexapod"])
def test_its_determinant_is_lapacks_within_the_proven_rounding(name):
    robot = load_robot(name)
    lines, per_posture, expected = lines_of(robot, 300, seed=21)
    reachable = expected.warnings != UNREACHABLE
    mine, lapack = posture_determinants(robot, lines), np.linalg.det(per_posture)
    terms = np.prod(np.abs(per_posture).sum(axis=3), axis=2)  # prod_i |w_i|_1
    # LAPACK's own error is of the same order: twice the allowance covers both.
    assert np.all(np.abs(mine - lapack)[reachable] <= 2 * ROUNDING * terms[reachable])
    assert np.all(np.abs(lapack[reachable]) > 100 * ROUNDING * terms[reachable])  # the signs are judged


def test_the_bound_never_exceeds_the_index():
    """The proven inequality, on 3,000 random line sets from well conditioned to nearly
    singular (arms from 1 to 1e4 mm, one line pulled towards another)."""
    rng = np.random.default_rng(22)
    wrenches = np.concatenate([unit_lines(rng, 1000, arm) for arm in (1.0, 300.0, 1e4)])
    closeness = rng.uniform(0.0, 1.0, len(wrenches))[:, None]
    wrenches[:, 5] = closeness * wrenches[:, 0] + (1 - closeness) * wrenches[:, 5]
    exact = direct_index(np.einsum("nia,nib->nab", wrenches, wrenches))
    force_third = (wrenches[:, :, :3] ** 2).sum(axis=(1, 2)) / 3.0
    moment_trace = (wrenches[:, :, 3:] ** 2).sum(axis=(1, 2))
    bound = np.abs(np.linalg.det(wrenches)) / (force_third ** 1.5 * moment_trace / 2.0)
    assert np.all(bound <= exact * (1 + 1e-9) + 1e-12)
    assert np.median(exact / bound) < 10  # not vacuous


@pytest.mark.parametrize("posture", [0, 21, 63])
def test_it_certifies_below_its_bound_and_never_above(posture):
    """Against the bound from LAPACK's det: certified 1e-4 below it (the rounding allowance is
    about 1e-5 of |det W| here), never 1e-9 above it, and not 1e-7 below it (the allowance is
    there)."""
    robot = load_robot("ceart")
    lines, per_posture, expected = lines_of(robot, 200, seed=23)
    reachable = expected.warnings[:, posture] != UNREACHABLE
    bound = bound_of(lines, per_posture)[:, posture]
    assert np.all(certified_above(robot, lines, bound * (1 - 1e-4))[reachable, posture])
    assert not np.any(certified_above(robot, lines, bound * (1 - 1e-7))[:, posture])
    assert not np.any(certified_above(robot, lines, bound * (1 + 1e-9))[:, posture])


def test_it_certifies_exactly_where_the_proven_test_passes():
    """The test of docs/explanation/conventions.md with its constants, |det| > 2 g30 P + t (F / 3)^(3/2)
    T / 2 (1 + 1e-12), solved for t per posture from the certificate's own det: certified
    1e-9 below that t, not 1e-9 above it."""
    robot = load_robot("ceart")
    lines, per_posture, expected = lines_of(robot, 200, seed=28)
    reachable = expected.warnings != UNREACHABLE
    force_third = (lines[:, :, :3] ** 2).sum(axis=2).max(axis=1).sum(axis=0)[:, None] / 3.0
    terms = np.prod(np.abs(lines).sum(axis=2).max(axis=1), axis=0)[:, None]
    moment_trace = (per_posture[..., 3:] ** 2).sum(axis=(2, 3))
    passing = ((np.abs(posture_determinants(robot, lines)) - 2 * ROUNDING * terms)
               / (force_third ** 1.5 * moment_trace / 2.0 * (1 + certificate.MARGIN)))
    for posture in (0, 37):
        at = passing[:, posture]
        assert np.all(certified_above(robot, lines, at * (1 - 1e-9))[reachable[:, posture], posture])
        assert not np.any(certified_above(robot, lines, at * (1 + 1e-9))[:, posture])


def test_an_exactly_singular_posture_is_never_certified():
    """Two equal lines (det W = 0 exactly) with 1e5 mm arms: the computed det is rounding
    noise, not 0, and no bound however small is certified."""
    robot = load_robot("hexapod")
    wrenches = unit_lines(np.random.default_rng(24), 200, 1e5)
    wrenches[:, 3] = wrenches[:, 0]
    lines = as_lines(wrenches)
    assert np.count_nonzero(posture_determinants(robot, lines)) > 100
    assert not np.any(certified_above(robot, lines, 1e-300))


def test_it_never_certifies_what_the_reference_calls_translation_singular(monkeypatch):
    """Forces within 1e-7 of one plane through points 10 mm out: det M_vv is below the
    reference's translation-singular limit, so its index is 0 there, although |det W| clears
    both the rounding allowance and the bound for 1e-12 mm."""
    robot = load_robot("hexapod")
    rng = np.random.default_rng(25)
    forces = rng.normal(size=(50, 6, 3))
    forces[:, :, 2] = 1e-7 * rng.uniform(-1, 1, (50, 6))
    forces /= np.linalg.norm(forces, axis=2, keepdims=True)
    wrenches = np.concatenate([forces, np.cross(rng.normal(size=(50, 6, 3)) * 10.0, forces)], axis=2)
    gram = np.einsum("nia,nib->nab", wrenches, wrenches)
    entries = np.stack([gram[:, i, j] for i, j in PACKED])
    assert np.all(direct_index_side(entries, 1e-12) == 0.0)
    lines = as_lines(wrenches)
    assert not np.any(certified_above(robot, lines, 1e-12))
    monkeypatch.setattr(certificate, "TRANSLATION_MARGIN", 0.0)
    assert np.all(certified_above(robot, lines, 1e-12))


def triangular_lines(x, d):
    """Lines (6, 2, 6, 1) of W = [[I, X], [0, d I]], X all 0 but x in row 0, column 3: unit forces along
    the axes through the origin (the first with moment x) and three pure moments d. det W = d^3,
    P = (1 + x) d^3, F = 3, T = x^2 + 3 d^2, and every product and sum in the certificate's det W is exact."""
    wrenches = np.zeros((1, 6, 6))
    wrenches[0, :3, :3] = np.eye(3)
    wrenches[0, 0, 3] = x
    wrenches[0, 3:, 3:] = d * np.eye(3)
    return as_lines(wrenches)


def documented_test(x, d, bound):
    """docs/explanation/conventions.md's test for triangular_lines(x, d) in exact rational arithmetic (F / 3 = 1):
    |det| > 2 g30 P + t (F / 3)^(3/2) T / 2 (1 + 1e-12) and det^2 > 1e3 TRANSLATION_SINGULAR (F / 3)^3 (T / 3)^3."""
    x, d, bound = Fraction(x), Fraction(d), Fraction(bound)
    det, terms, moment_trace = d ** 3, (1 + x) * d ** 3, x * x + 3 * d * d
    return bool(det > 2 * G30 * terms + bound * moment_trace / 2 * (1 + Fraction(1, 10 ** 12))
                and det * det > 1000 * Fraction(TRANSLATION_SINGULAR) * (moment_trace / 3) ** 3)


SOLVED = (1 - 2 * G30) / (Fraction(3, 2) * (1 + Fraction(1, 10 ** 12)))
"""The bound at which W = I (det 1, P 1, F 3, T 3) meets the documented test's first inequality."""


@pytest.mark.parametrize("x, d, bound, certified", [
    (float((1 + 30 * UNIT_ROUNDOFF) / (2 * G30) - 1), 2.0 ** 47, 0.0, False),  # |det W| 30u below 2 g30 P
    (float(Fraction(99, 100) / (2 * G30) - 1), 2.0 ** 47, 0.0, True),  # 1 % above it
    (0.0, 1.0, float(SOLVED * (1 - Fraction(1, 10 ** 13))), True),  # W = I, 1e-13 below the solved bound
    (0.0, 1.0, float(SOLVED * (1 + Fraction(1, 10 ** 13))), False),  # 1e-13 above it
])
def test_it_certifies_exactly_where_the_documented_test_passes_in_exact_arithmetic(x, d, bound, certified):
    """Where det W and P are exact, the certificate is the documented test with g30 = 30u / (1 - 30u) and
    1 + 1e-12 themselves, not with a rounding allowance or a margin a few units of roundoff or 1e-12 off."""
    assert documented_test(x, d, bound) is certified
    assert certified_above(load_robot("hexapod"), triangular_lines(x, d), bound)[0, 0] == certified


@pytest.mark.parametrize("ratio", [1 - 1e-4, 1 + 5e-4])
def test_its_translation_condition_is_the_documented_one(ratio):
    """det W^2 > 1e3 TRANSLATION_SINGULAR (F / 3)^3 (T / 3)^3 decides, on six unit force lines (x, y, z
    through the origin; x, y, z with moments (0, 1, 0), (0, 0, 1), (1, q, 0)): det W = 1, F = 6, T = 3 + q^2,
    q set so that the left side is ``ratio`` times the right, measured with LAPACK's det."""
    q = np.sqrt(3 * ((TRANSLATION_SINGULAR * 8 * 1e3 * ratio) ** (-1 / 3) - 1))
    wrenches = np.zeros((1, 6, 6))
    wrenches[0, :3, :3] = wrenches[0, 3:, :3] = np.eye(3)
    wrenches[0, 3:, 3:] = [[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, q, 0.0]]
    force_third, moment_third = (wrenches[0, :, :3] ** 2).sum() / 3, (wrenches[0, :, 3:] ** 2).sum() / 3
    measured = np.linalg.det(wrenches[0]) ** 2 / (TRANSLATION_SINGULAR * force_third ** 3 * moment_third ** 3)
    assert measured / 1e3 == pytest.approx(ratio, rel=1e-6)
    assert certified_above(load_robot("hexapod"), as_lines(wrenches), 1e-12)[0, 0] == (measured > 1e3)


@pytest.mark.parametrize("threshold", [None, 450.0, 600.0])
def test_the_reference_warns_alike_with_and_without_it(monkeypatch, threshold):
    """CEART at its own threshold (every posture certified) and at thresholds among its
    indices (some certified, some below, some left to M): the same warnings and the same
    side of the threshold as with the certificate switched off."""
    robot = load_robot("ceart")
    if threshold is not None:
        robot = replace(robot, direct_index_min=threshold)
    _, t6 = random_t6(robot, 600, seed=26)
    calls = []
    monkeypatch.setattr(reference, "CERTIFY_SETTLED", 0.0)
    monkeypatch.setattr(reference, "certified_above", lambda *args: calls.append(1) or certified_above(*args))
    with_it = solve(robot, t6)
    assert len(calls) > 1
    monkeypatch.setattr(reference, "CERTIFY_SETTLED", 2.0)
    without = solve(robot, t6)
    limit = robot.direct_index_min
    np.testing.assert_array_equal(with_it.warnings, without.warnings)
    reachable = with_it.warnings != UNREACHABLE
    np.testing.assert_array_equal((with_it.direct_index <= limit)[reachable], (without.direct_index <= limit)[reachable])
    if threshold is not None:
        assert np.any(with_it.direct_index[reachable] <= limit) and np.any(with_it.direct_index[reachable] > limit)


@pytest.mark.parametrize("name, probed, kept", [("ceart", True, True), ("iwf", True, False), ("hexapod", False, False)])
def test_it_is_kept_only_where_its_probe_settles_most_postures(monkeypatch, name, probed, kept):
    """Tried on 32 poses of robots with more than one posture, kept where that settles half."""
    robot = load_robot(name)
    _, t6 = random_t6(robot, 1000, seed=27)
    poses = []
    monkeypatch.setattr(reference, "certified_above",
                        lambda robot, lines, bound: poses.append(lines.shape[-1]) or certified_above(robot, lines, bound))
    solve(robot, t6)
    assert poses == ([32, 968] if kept else [32] if probed else [])


@pytest.mark.parametrize("name, settles", [("ceart", True), ("iwf", False), ("rus_optimized", False),
                                           ("hexapod", False)])
def test_certificate_settles_says_what_solve_decides(monkeypatch, name, settles):
    """reference.certificate_settles answers as solve decides on the same poses: where it says
    True, solve builds no posture's M (what verify's chunks are sized by)."""
    robot = load_robot(name)
    _, t6 = random_t6(robot, 500, seed=28)
    assert reference.certificate_settles(robot, t6) == settles
    built = []
    original = reference.gram_partial_sums
    monkeypatch.setattr(reference, "gram_partial_sums", lambda *args: built.append(1) or original(*args))
    solve(robot, t6)
    assert bool(built) == (not settles and robot.direct_index_min is not None)


def test_verify_chunks_leave_out_the_matrices_the_certificate_spares():
    """CEART's chunks count joint entries only (the certificate settles it); IWF's also the
    packed matrices its direct index builds."""
    from kingen.verify.processes import CHUNK_ENTRIES, MAX_CHUNK_POSES, chunk_size

    ceart, iwf = load_robot("ceart"), load_robot("iwf")
    assert chunk_size(ceart) == min(MAX_CHUNK_POSES, CHUNK_ENTRIES // (ceart.dof * ceart.postures))
    assert chunk_size(iwf) < CHUNK_ENTRIES // (iwf.dof * iwf.postures)
