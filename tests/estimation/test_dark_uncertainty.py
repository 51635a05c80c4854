"""The Paule–Mandel floor (Eq. (PM.1) of imucalib.estimation.dark_uncertainty)."""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.errors import InvalidInputError
from imucalib.estimation.dark_uncertainty import paule_mandel_floor


def _weighted_mean_chi2(x: np.ndarray, sigma: np.ndarray):
    def chi2_of(s: float) -> tuple[float, int]:
        w = 1.0 / (sigma**2 + s**2)
        mean = np.sum(w * x) / np.sum(w)
        return float(np.sum(w * (x - mean) ** 2)), x.size - 1
    return chi2_of


def test_equal_sigma_gives_the_closed_form():
    rng = np.random.default_rng(4)
    x = rng.normal(0.0, 3.0, 12)
    sigma = np.full(12, 1.0)
    expected = np.sqrt(np.var(x, ddof=1) - 1.0)  # s² = S² − σ²
    assert paule_mandel_floor(_weighted_mean_chi2(x, sigma), scale=1.0) == pytest.approx(
        expected, rel=1e-6)


def test_unequal_sigma_makes_chi2_its_expectation():
    rng = np.random.default_rng(5)
    sigma = rng.uniform(0.5, 2.0, 15)
    x = rng.normal(0.0, sigma) + rng.normal(0.0, 2.5, 15)
    chi2_of = _weighted_mean_chi2(x, sigma)
    s = paule_mandel_floor(chi2_of, scale=float(np.median(sigma)))
    chi2, dof = chi2_of(s)
    assert s > 0 and chi2 == pytest.approx(dof, rel=1e-4)  # s to rtol 1e-4


def test_no_excess_scatter_gives_zero():
    x = np.array([0.1, -0.1, 0.05, -0.05])
    assert paule_mandel_floor(_weighted_mean_chi2(x, np.ones(4)), scale=1.0) == 0.0
    assert paule_mandel_floor(lambda s: (5.0, 0), scale=1.0) == 0.0  # nothing to judge by


def test_bad_scale_and_residuals_that_are_not_noise_are_refused():
    with pytest.raises(InvalidInputError, match="scale"):
        paule_mandel_floor(lambda s: (1.0, 1), scale=0.0)
    with pytest.raises(InvalidInputError, match="not noise"):
        paule_mandel_floor(lambda s: (10.0, 1), scale=1.0)  # χ² that no floor lowers
