"""Rate-transfer fits on synthetic whole-revolution means of the twin's gyro model."""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.errors import InsufficientExcitationError, InvalidInputError
from imucalib.procedures.rate_transfer.fit import fit_line, fit_rate_transfer

RATES = np.deg2rad(np.array([r * s for r in (5, 12.5, 18, 27, 36, 45, 60) for s in (1, -1)]))


def means(x: np.ndarray, *, m: float, asym: float, k2: float, b: float = 1e-4) -> np.ndarray:
    """y = b + h((1 + m)·x), h(u) = u + K2·u² + (asym/2)·|u| (the twin's gyro model)."""
    u = (1.0 + m) * x
    return b + u + k2 * u * u + 0.5 * asym * np.abs(u)


def test_noiseless_means_give_the_truth_exactly() -> None:
    y = means(RATES, m=3e-4, asym=2e-3, k2=5e-3)
    t = fit_rate_transfer(RATES, y, np.full(RATES.size, 1e-6))
    assert t.params[1] - 1.0 == pytest.approx(3e-4, abs=1e-12)
    assert t.asymmetry[0] == pytest.approx(2e-3, rel=1e-9)      # (RT-9): asymmetry = a
    assert t.params[3] / t.params[1] ** 2 == pytest.approx(5e-3, rel=1e-9)  # E2 = K2 (1+M)²
    assert t.params[0] == pytest.approx(1e-4, abs=1e-12)
    k_plus, k_minus = t.slopes
    assert k_plus == pytest.approx(1.0003 * 1.001) and k_minus == pytest.approx(1.0003 * 0.999)


def test_nonlinearity_is_the_largest_deviation_in_ppm_of_full_scale() -> None:
    x = np.deg2rad(np.array([-60.0, -30.0, 0.0, 30.0, 60.0]))
    y = 2.0 * x
    y[3] += 1e-5  # one mean off the line
    line = fit_line(x, y, np.ones(5))
    full = abs(line.scale_factor) * np.deg2rad(60.0)
    assert line.nonlinearity_ppm == pytest.approx(np.max(np.abs(line.residuals_rps)) / full * 1e6)
    assert 0.5 * 1e-5 / full * 1e6 < line.nonlinearity_ppm < 1e-5 / full * 1e6


def test_injected_asymmetry_and_quadratic_recovered_within_4_sigma() -> None:
    rng = np.random.default_rng(1)
    se = np.full(RATES.size, 2e-5)
    for _ in range(20):
        y = means(RATES, m=-2e-4, asym=1e-3, k2=2e-3) + rng.normal(0, 2e-5, RATES.size)
        t = fit_rate_transfer(RATES, y, se)
        assert abs(t.asymmetry[0] - 1e-3) < 4 * t.asymmetry[1]
        assert abs(t.params[1] - 1 + 2e-4) < 4 * t.std(1)
        assert abs(t.params[3] - 2e-3 * (1 - 2e-4) ** 2) < 4 * t.std(3)


@pytest.mark.slow
def test_sigma_matches_the_monte_carlo_spread() -> None:
    rng = np.random.default_rng(7)
    se = np.linspace(1e-5, 3e-5, RATES.size)
    draws, sig = [], []
    for _ in range(2000):
        y = means(RATES, m=1e-4, asym=5e-4, k2=1e-3) + rng.normal(0, se)
        t = fit_rate_transfer(RATES, y, se)
        draws.append([t.params[0], t.params[1], t.asymmetry[0], t.params[3]])
        sig.append([t.std(0), t.std(1), t.asymmetry[1], t.std(3)])
    ratio = np.std(draws, axis=0) / np.sqrt(np.mean(np.square(sig), axis=0))
    assert np.all(np.abs(ratio - 1.0) < 0.15), ratio


def test_bad_inputs() -> None:
    x = np.deg2rad([10.0, -10.0, 20.0, -20.0])
    with pytest.raises(InsufficientExcitationError, match="≥ 3 magnitudes"):
        fit_rate_transfer(x, x, np.ones(4))
    with pytest.raises(InvalidInputError, match="equal-length"):
        fit_line(x, x[:3], np.ones(4))
    with pytest.raises(InvalidInputError, match="σ > 0"):
        fit_line(x, x, np.zeros(4))
