"""The robust rule's compiled residual and flag passes equal its numpy path bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.processing import _flag_kernel
from imucalib.processing.outliers import _robust_flags, reject_outliers_robust, robust_threshold


def _column(kind: str, n: int, rng: np.random.Generator) -> np.ndarray:
    i = np.arange(n, dtype=np.float64)
    if kind == "normal":
        return rng.normal(size=n)
    if kind == "spikes":
        x = rng.normal(size=n)
        x[rng.integers(0, n, max(1, n // 50))] += rng.choice([-1.0, 1.0]) * 12.0
        return x
    if kind == "quantised":  # many ties, the MAD can be 0
        return np.round(rng.normal(size=n) * 0.3)
    if kind == "constant":  # MAD 0 and standard deviation 0
        return np.full(n, 1.5)
    if kind == "sinusoid":  # curvature: the margin matters
        return 100.0 * np.sin(2.0 * np.pi * i / 60.0) + rng.normal(size=n)
    return 0.01 * i + rng.normal(size=n)  # "ramp": the edges' extrapolation matters


@pytest.mark.parametrize("h", [1, 2, 4, 5])
@pytest.mark.parametrize("kind", ["normal", "spikes", "quantised", "constant", "sinusoid",
                                  "ramp"])
def test_compiled_flags_equal_the_numpy_path(h: int, kind: str) -> None:
    assert _flag_kernel.kernels() is not None
    rng = np.random.default_rng(h)
    for n in (2 * (2 * h + 1) - 1, 2 * (2 * h + 1), 4 * h + 3, 101, 1000, 20_001):
        cols = np.column_stack([_column(kind, n, rng) for _ in range(3)])
        k_n = robust_threshold(n)
        fast = _robust_flags(cols, h, k_n)
        slow = _robust_flags(cols, h, k_n, backend="numpy")
        for a, b in zip(fast, slow, strict=True):
            np.testing.assert_array_equal(a, b)
        assert fast[1].tolist() == np.count_nonzero(fast[0], axis=1).tolist()


def test_result_counts_and_mask_agree() -> None:
    rng = np.random.default_rng(7)
    x = rng.normal(size=(5_000, 4))
    x[[10, 11, 4_000], [0, 0, 3]] = [15.0, -14.0, 11.0]
    res = reject_outliers_robust(x, time_s=np.arange(5_000) * 0.01)
    assert res.n_outliers.tolist() == res.outlier_mask.sum(axis=0).tolist() == [2, 0, 0, 1]
    assert [i.tolist() for i in res.outlier_indices] == [[10, 11], [], [], [4_000]]
    assert not res.outlier_mask.flags.writeable and not res.n_outliers.flags.writeable
