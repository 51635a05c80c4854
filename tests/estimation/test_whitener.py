"""The whitening of a full covariance: LAPACK's triangular solve, as scipy's wrapper makes it."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

from imucalib.estimation._common import make_whitener


@pytest.mark.parametrize("m", [1, 2, 3, 9, 41])
@pytest.mark.parametrize("fortran", [False, True])
def test_whiten_equals_solve_triangular_bit_for_bit(m, fortran):
    rng = np.random.default_rng(m)
    a = rng.normal(size=(m, m))
    cov = a @ a.T + m * np.eye(m)
    white, known = make_whitener(m, covariance=cov)
    assert known and white.chol is not None
    if fortran:
        object.__setattr__(white, "chol", np.asfortranarray(white.chol))
    for b in (rng.normal(size=m), rng.normal(size=(m, 4))):
        np.testing.assert_array_equal(
            white.whiten(b), scipy.linalg.solve_triangular(white.chol, b, lower=True))
        np.testing.assert_array_equal(
            white.whiten_transpose(b),
            scipy.linalg.solve_triangular(white.chol, b, lower=True, trans="T"))
        np.testing.assert_allclose(white.colour(white.whiten(b)), b, rtol=1e-12, atol=1e-12)
