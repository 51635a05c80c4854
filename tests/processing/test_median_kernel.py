"""The running median of the outlier rule: compiled kernels equal the partition bit for bit."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from imucalib.processing._median_kernel import NETWORK_8, neighbour_median


def _reference(x: np.ndarray, h: int) -> np.ndarray:
    """The definition: the mean of order statistics h − 1 and h of the 2h neighbours."""
    out = np.zeros(x.size)
    for i in range(h, x.size - h):
        nb = np.sort(np.concatenate([x[i - h:i], x[i + 1:i + h + 1]]))
        out[i] = 0.5 * (nb[h - 1] + nb[h])
    return out


def test_network_sorts_every_binary_input():
    # the 0-1 principle: a comparator network that sorts all 2^8 binary inputs sorts any input
    for bits in itertools.product((0, 1), repeat=8):
        v = list(bits)
        for a, b in NETWORK_8:
            if v[a] > v[b]:
                v[a], v[b] = v[b], v[a]
        assert v == sorted(bits)


@pytest.mark.parametrize("h", [1, 2, 3, 4, 7])
@pytest.mark.parametrize("kind", ["normal", "ties", "constant", "ramp"])
def test_backends_equal_the_definition(h: int, kind: str):
    rng = np.random.default_rng(h)
    for n in (2 * h + 1, 2 * h + 2, 2 * h + 3, 600, 601):  # h = 4: pairs, and one left over
        x = {"normal": rng.normal(size=n), "ties": rng.integers(0, 4, n).astype(float),
             "constant": np.full(n, 2.5), "ramp": np.linspace(-1.0, 1.0, n)}[kind]
        want = _reference(x, h)
        for backend in ("auto", "numpy"):
            got = neighbour_median(x, h, backend=backend)
            assert np.array_equal(got[h:n - h], want[h:n - h]), (backend, n)


def test_shortest_column():
    x = np.arange(9.0)[::-1]
    assert neighbour_median(x, 4)[4] == 4.0


@pytest.mark.parametrize("h", [1, 2, 3, 4, 5, 8])
def test_curvature_margin_kernel_equals_the_numpy_path(h):
    """The edges' extrapolation and the curvature margin: one compiled pass, numpy's values."""
    from imucalib.processing import _median_kernel as mk
    from imucalib.processing._median_kernel import curvature_margin

    rng = np.random.default_rng(h)
    for n in (4 * h + 2, 4 * h + 3, 50, 1001, 20_000):
        x = np.cumsum(rng.normal(size=n)) + 5.0 * np.sin(np.arange(n) / 7.0)
        fast = mk.neighbour_median(x, h)
        slow = fast.copy()
        m_fast = curvature_margin(fast, h)
        m_slow = curvature_margin(slow, h, backend="numpy")
        assert mk._STATE["kernel"] is not None
        np.testing.assert_array_equal(fast, slow)
        np.testing.assert_array_equal(m_fast, m_slow)
        assert np.all(m_fast >= 0.0) and np.all(np.isfinite(fast))
