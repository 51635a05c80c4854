"""RunningRowMean: rows read in blocks give numpy's mean of them stacked, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.procedures.common.windows import RunningRowMean


@pytest.mark.parametrize("k", [2, 3, 6])
@pytest.mark.parametrize("block", [1, 7, 4096, 100_000])
def test_blocks_give_numpys_mean_bit_for_bit(k: int, block: int) -> None:
    rng = np.random.default_rng(k * 1000 + block)
    # a large offset and small scatter: the order of the additions shows in the last bits
    rows = 1.0 + 1e-3 * rng.standard_normal((30_001, k)) + np.linspace(0.0, 3.0, k)
    acc = RunningRowMean()
    for i in range(0, rows.shape[0], block):
        acc.add(rows[i:i + block])
    acc.add(rows[:0])  # an empty block changes nothing
    assert acc.n == rows.shape[0]
    assert np.array_equal(acc.mean, rows.mean(axis=0))


def test_pairwise_order_differs_so_the_test_can_fail() -> None:
    # the sequential order is what makes the blocks exact: a pairwise sum of the same rows (what
    # numpy does for one contiguous column) differs in the last bits
    rng = np.random.default_rng(5)
    rows = 1.0 + 1e-3 * rng.standard_normal((30_001, 2))
    acc = RunningRowMean()
    for i in range(0, rows.shape[0], 4096):
        acc.add(rows[i:i + 4096])
    pairwise = np.array([np.ascontiguousarray(rows[:, j]).mean() for j in range(2)])
    assert not np.array_equal(acc.mean, pairwise)
    np.testing.assert_allclose(acc.mean, pairwise, rtol=1e-14)
