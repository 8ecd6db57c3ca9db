"""The generated direct-index test (render.schur_test_lines), compiled alone and judged against
LAPACK: it must say "above the threshold" exactly when the smallest eigenvalue of the Schur
complement of M's force block exceeds t^2, on both sides of the threshold."""

import cffi
import numpy as np
import pytest

from kingen.runtime.compiler import compile_c
from kingen.hosts.render import schur_test_lines
from kingen.kinematics.singularity import PACKED

DECLARATION = "double margin_of(const double m[21], double threshold);"


@pytest.fixture(scope="module")
def margin_of(tmp_path_factory):
    """The generated lines as a C function margin_of(M packed, threshold mm)."""
    folder = tmp_path_factory.mktemp("schur")
    body = "\n    ".join(schur_test_lines("m[{k}]"))
    source = folder / "schur.c"
    source.write_text(f"#define KINGEN_DIRECT_MIN threshold\n"
                      f"double margin_of(const double m[21], double threshold)\n{{\n    {body}\n    return margin;\n}}\n")
    library = folder / "libschur.so"
    compile_c([source], library, ["-std=c89", "-pedantic", "-Wall", "-Werror", "-O2", "-shared", "-fPIC"])
    ffi = cffi.FFI()
    ffi.cdef(DECLARATION)
    handle = ffi.dlopen(str(library))
    return lambda gram, threshold: handle.margin_of(ffi.from_buffer("double[]", _packed(gram)), threshold)


def _packed(gram):
    return np.ascontiguousarray([gram[i, j] for i, j in PACKED], dtype=float)


def _random_gram(rng, size_mm):
    """M = sum of w w^T over six random unit wrenches w = [f; C x f], C within size_mm."""
    forces = rng.normal(size=(6, 3))
    forces /= np.linalg.norm(forces, axis=1, keepdims=True)
    points = rng.uniform(-size_mm, size_mm, size=(6, 3))
    wrenches = np.hstack([forces, np.cross(points, forces)])
    return wrenches.T @ wrenches


def _index(gram):
    """The direct index (mm) by LAPACK: sqrt of the least eigenvalue of M's Schur complement."""
    schur = gram[3:, 3:] - gram[3:, :3] @ np.linalg.solve(gram[:3, :3], gram[:3, 3:])
    return np.sqrt(np.linalg.eigvalsh(schur)[0])


def test_the_test_takes_the_side_of_the_threshold_lapack_takes(margin_of):
    """200 random six-line matrices (platforms up to 700 mm), each with the threshold 1e-7
    (relative) below and above its index: above, then not above."""
    rng = np.random.default_rng(24)
    for _ in range(200):
        gram = _random_gram(rng, 700.0)
        index = _index(gram)
        assert margin_of(gram, index * (1.0 - 1e-7)) > 0.0
        assert not margin_of(gram, index * (1.0 + 1e-7)) > 0.0


def test_a_singular_force_block_is_singular_whatever_the_threshold(margin_of):
    """Six forces in one plane: M_vv is singular (a pure-translation singularity), so no
    threshold is passed, not even 0."""
    rng = np.random.default_rng(7)
    forces = np.hstack([rng.normal(size=(6, 2)), np.zeros((6, 1))])
    forces /= np.linalg.norm(forces, axis=1, keepdims=True)
    points = rng.uniform(-500.0, 500.0, size=(6, 3))
    wrenches = np.hstack([forces, np.cross(points, forces)])
    gram = wrenches.T @ wrenches
    assert not margin_of(gram, 0.0) > 0.0
    assert not margin_of(gram, 29.3) > 0.0


@pytest.mark.parametrize("entry", [0, 5, 9, 13, 20])
def test_a_nan_anywhere_in_m_is_not_above(margin_of, entry):
    """A NaN entry (force block, coupling or moment block) never passes as 'above'."""
    gram = _random_gram(np.random.default_rng(3), 300.0)
    i, j = PACKED[entry]
    gram[i, j] = gram[j, i] = np.nan
    assert not margin_of(gram, 1e-3) > 0.0
