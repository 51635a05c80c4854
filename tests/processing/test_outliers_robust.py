"""Tests of imucalib.processing.outliers.reject_outliers_robust (docs/p1.md, processing rule 1).

The rule must leave Gaussian data essentially untouched (the default α = 0.01 is the probability
that a whole column loses any sample), find spikes and short clusters, and follow a slowly
varying signal. The last test documents why P1's default is no longer three passes of 3σ.
"""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.errors import InvalidInputError
from imucalib.processing.outliers import (
    reject_outliers_3sigma,
    reject_outliers_robust,
    robust_threshold,
)

LENGTHS = (1_000, 10_000, 100_000, 1_000_000)


def _spiky(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Unit Gaussian noise with 20 spike groups (1, 2 or 3 adjacent samples) of 8–50σ."""
    rng = np.random.default_rng(seed)
    x = rng.normal(size=n)
    starts = rng.choice(np.arange(0, n - 3, 10), 20, replace=False)
    starts[:2] = (0, n - 3)  # the edges too
    idx = []
    for i, s0 in enumerate(starts):
        for j in range(1 + i % 3):
            x[s0 + j] += rng.choice([-1.0, 1.0]) * rng.uniform(8.0, 50.0)
            idx.append(s0 + j)
    return x, np.unique(idx)


def test_threshold_follows_eq_2() -> None:
    # α_n = 1 − (1 − α)^{1/n}; k = Φ⁻¹(1 − α_n/2): the Gaussian window loses a sample w.p. α
    from scipy import stats
    for n in (10**3, 10**6):
        k = robust_threshold(n, 0.01)
        p_any = 1.0 - (1.0 - 2.0 * stats.norm.sf(k)) ** n
        assert p_any == pytest.approx(0.01, rel=1e-6)
    assert robust_threshold(5) == 3.5  # the floor
    assert robust_threshold(10**6) > robust_threshold(10**3) > 4.0
    with pytest.raises(InvalidInputError):
        robust_threshold(100, alpha=1.5)


def test_gaussian_data_loses_almost_nothing() -> None:
    total = lost = 0
    for n in LENGTHS:
        for seed in range(3):
            x = np.random.default_rng(seed + 10 * n).normal(size=(n, 2))
            res = reject_outliers_robust(x)
            total += x.size
            lost += int(res.n_outliers.sum())
            assert res.scale == pytest.approx(np.sqrt(1 + np.pi / 16), rel=0.1)
    assert lost / total < 1e-4, f"{lost} of {total} Gaussian samples flagged"


@pytest.mark.parametrize("n", LENGTHS)
@pytest.mark.parametrize("seed", [1, 2])
def test_spikes_and_short_clusters_are_all_caught(n: int, seed: int) -> None:
    x, idx = _spiky(n, seed)
    res = reject_outliers_robust(x)
    np.testing.assert_array_equal(res.outlier_indices[0], idx)
    assert res.n_outliers.tolist() == [idx.size]
    # replaced by the interpolation of the neighbours: back within the noise
    assert np.max(np.abs(res.values)) < 6.0


def test_smooth_sinusoid_is_followed_not_flagged() -> None:
    rng = np.random.default_rng(3)
    lost = total = 0
    for n, period in ((10_000, 2_500), (100_000, 20_000), (40_000, 200)):
        t = np.arange(n)
        for amplitude in (3.0, 100.0):  # a few σ; and gravity on a horizontal spin axis
            x = amplitude * np.sin(2 * np.pi * t / period + 0.3) + rng.normal(size=n)
            res = reject_outliers_robust(x)
            lost += int(res.n_outliers[0])
            total += n
    assert lost / total < 1e-4
    # the window median and MAD would see the sinusoid as noise and miss a 10σ spike on it
    n = 20_000
    x = 3.0 * np.sin(2 * np.pi * np.arange(n) / 4_000) + rng.normal(size=n)
    x[1_000] += 10.0  # at a crest: 13σ from the window median
    x[3_000] -= 10.0  # at a trough
    res = reject_outliers_robust(x)
    assert res.outlier_indices[0].tolist() == [1_000, 3_000]


def test_drop_and_interpolate_and_columns() -> None:
    x, idx = _spiky(5_000, 4)
    cols = np.column_stack([x, np.random.default_rng(5).normal(size=5_000)])
    t = np.arange(5_000) * 0.01
    res = reject_outliers_robust(cols, method="drop", time_s=t)
    assert res.test == "robust" and res.method == "drop"
    assert res.n_outliers.tolist() == [idx.size, 0]
    assert res.values.shape == (5_000 - idx.size, 2)
    np.testing.assert_array_equal(np.flatnonzero(~res.kept), idx)
    assert [i.tolist() for i in res.outlier_indices] == [idx.tolist(), []]
    assert res.threshold == pytest.approx(robust_threshold(5_000))
    with pytest.raises(InvalidInputError):
        reject_outliers_robust(cols, half_width=0)
    with pytest.raises(InvalidInputError):
        reject_outliers_robust(cols, method="zap")  # type: ignore[arg-type]


def test_short_and_constant_columns() -> None:
    x = np.array([0.1, -0.2, 0.0, 0.3, -0.1, 8.0, 0.2, -0.3, 0.1, 0.0])
    assert reject_outliers_robust(x).outlier_indices[0].tolist() == [5]
    assert reject_outliers_robust(np.ones(100)).n_outliers.tolist() == [0]


def test_three_passes_of_3sigma_eat_gaussian_data() -> None:
    """Why P1's default changed: the old rule removes a fixed fraction of good samples.

    Three passes of the robust 3σ rule flag the 0.27 % beyond 3σ and a little more, whatever
    the window length; the classical rule (mean and standard deviation) about 0.34 %.
    """
    n = 200_000
    x = np.random.default_rng(8).normal(size=n)
    old = reject_outliers_3sigma(x, max_iterations=3).n_outliers[0] / n
    classic = reject_outliers_3sigma(x, robust=False, max_iterations=3).n_outliers[0] / n
    new = reject_outliers_robust(x).n_outliers[0] / n
    assert 0.0025 < old < 0.0032
    assert 0.0030 < classic < 0.0040
    assert new < 1e-5
