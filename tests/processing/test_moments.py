"""The long window's column sums and block means: numpy's values bit for bit, in one pass."""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.processing import moments
from imucalib.processing.moments import block_means, shifted_sums


@pytest.mark.parametrize("n", [1, 2, 7, 1000, 70_001])
def test_shifted_sums_equal_numpys(n):
    rng = np.random.default_rng(n)
    raw = rng.normal(size=(n, 6)) * 1e3 + 9.80665
    filt = raw + rng.normal(size=(n, 6)) * 1e-3
    shift = raw[: max(1, n // 3)].mean(axis=0)
    got = shifted_sums(raw, filt, shift)
    d = filt - shift
    for a, b in zip(got, ((raw - shift).sum(axis=0), d.sum(axis=0), (d * d).sum(axis=0)),
                    strict=True):
        np.testing.assert_array_equal(a, b)
    assert moments._STATE["kernels"] is not None, moments._STATE["error"]
    f_raw = np.asfortranarray(raw)  # another layout: numpy's own sums, whatever they are
    for a, b in zip(shifted_sums(f_raw, filt, shift),
                    ((f_raw - shift).sum(axis=0), d.sum(axis=0), (d * d).sum(axis=0)),
                    strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("m", [1, 2, 3, 4, 16, 64])
def test_block_means_equal_numpys(m):
    rng = np.random.default_rng(m)
    for n in (m - 1, m, 5 * m + 3, 10_000):
        x = rng.normal(size=(n, 6)) * 1e2 - 3.0
        g = n // m
        want = x[: g * m].reshape(-1, m, 6).mean(axis=1)
        got = block_means(x, m)
        assert got.shape == (g, 6)
        np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("k", [1, 3, 6])
def test_mean_rows_equals_numpys_mean(k):
    """x.mean(axis=0) of C-ordered slices bit for bit; other layouts go to numpy."""
    from imucalib.processing.moments import mean_rows

    rng = np.random.default_rng(k)
    big = rng.normal(size=(60_000, k)) * 3.0 + 9.80665
    for _ in range(50):
        a = int(rng.integers(0, 1_000))
        x = big[a:a + int(rng.integers(1, 50_000))]
        np.testing.assert_array_equal(mean_rows(x), x.mean(axis=0))
    assert moments._STATE["kernels"] is not None, moments._STATE["error"]
    strided = big[::3, :]
    np.testing.assert_array_equal(mean_rows(strided), strided.mean(axis=0))
