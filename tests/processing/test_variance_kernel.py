"""The detectors' compiled moving variance equals their numpy path bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.processing import _variance_kernel
from imucalib.processing.segmentation import (
    _block_means,
    _moving_mean_and_unsteadiness,
    _moving_unsteadiness,
    _runs,
)
from imucalib.processing.static_detector import _variance_norm


def _columns(kind: str, n: int, k: int, rng: np.random.Generator) -> np.ndarray:
    i = np.arange(n, dtype=np.float64)[:, None]
    scale = 10.0 ** rng.uniform(-4, 2, size=k)
    if kind == "noise":  # a large offset: the block means keep the variance exact
        return rng.normal(size=(n, k)) * scale + rng.normal(size=k) * 1e3
    if kind == "steps":  # poses: still, then moved
        return np.repeat(rng.normal(size=(n // 7 + 1, k)), 7, axis=0)[:n] + 1e-3 * rng.normal(
            size=(n, k))
    if kind == "quantised":  # raw counts: ties and windows of zero variance
        return np.round(rng.normal(size=(n, k)) * 2.0) * scale
    if kind == "constant":
        return np.full((n, k), 9.81)
    return np.sin(i / 17.0 + rng.uniform(size=k)) * scale  # "sinusoid"


#: (w, n): n == w, n < 2w, w = 1, w across numpy's pairwise block of 128 (the block means)
_SIZES = [(5, 5), (5, 6), (5, 9), (3, 4), (1, 1), (1, 4), (2, 2), (2, 7), (8, 8), (8, 25),
          (127, 127), (128, 300), (129, 400), (200, 1001), (1000, 3500)]


@pytest.mark.parametrize("kind", ["noise", "steps", "quantised", "constant", "sinusoid"])
@pytest.mark.parametrize("k", [1, 2, 3, 6])
def test_variance_norm_equals_the_numpy_path(kind: str, k: int) -> None:
    assert _variance_kernel.kernel() is not None
    rng = np.random.default_rng(k)
    for w, n in _SIZES:
        x = _columns(kind, n, k, rng)
        fast = _variance_norm(x, w)
        slow = _variance_norm(x, w, backend="numpy")
        assert fast.shape == (n,)
        np.testing.assert_array_equal(fast, slow)


@pytest.mark.parametrize("kind", ["noise", "steps", "quantised", "constant", "sinusoid"])
@pytest.mark.parametrize("k", [1, 3, 4])
def test_mean_and_unsteadiness_equal_the_numpy_path(kind: str, k: int) -> None:
    rng = np.random.default_rng(10 + k)
    for w, n in _SIZES:
        x = _columns(kind, n, k, rng)
        mean, zeta = _moving_mean_and_unsteadiness(x, w)
        mean_np, zeta_np = _moving_mean_and_unsteadiness(x, w, backend="numpy")
        np.testing.assert_array_equal(mean, mean_np)
        np.testing.assert_array_equal(zeta, zeta_np)


def test_non_contiguous_columns() -> None:
    """A column view of a wider array, and a strided one, as the detectors pass them."""
    rng = np.random.default_rng(3)
    wide = rng.normal(size=(4001, 8)) + 5.0
    for x in (wide[:, 2:5], wide[::2, ::3], np.asfortranarray(wide[:, :3])):
        assert not x.flags.c_contiguous
        for w in (1, 7, 50, 130):
            np.testing.assert_array_equal(_variance_norm(x, w),
                                          _variance_norm(x, w, backend="numpy"))
            for a, b in zip(_moving_mean_and_unsteadiness(x, w),
                            _moving_mean_and_unsteadiness(x, w, backend="numpy"), strict=True):
                np.testing.assert_array_equal(a, b)


def test_each_column_is_the_numpy_reference() -> None:
    """The kernel's per-column variance is _moving_unsteadiness of that column alone."""
    rng = np.random.default_rng(5)
    x = rng.normal(size=(3000, 3)) * [1e-3, 1.0, 1e2]
    for w in (5, 64, 129):
        for i in range(3):
            col = x[:, i:i + 1]
            got = _variance_kernel.moving_variance(col, _block_means(col, w), w,
                                                   _variance_kernel.NORM)[0]
            np.testing.assert_array_equal(got, np.sqrt(np.square(_moving_unsteadiness(col, w))))


def test_clipped_windows_at_the_ends() -> None:
    """Each sample takes its centred window's value, the first and last windows at the ends."""
    x = np.zeros((30, 1))
    x[0] = 1.0  # only window 0 holds it (w = 6)
    w = 6
    out, mean = _variance_kernel.moving_variance(x, _block_means(x, w), w, _variance_kernel.SUM)
    assert mean is not None
    expected_first = 1.0 / w - (1.0 / w) ** 2
    later = w // 2 + 1  # the cumulative sums leave rounding residues of 1e-17
    assert np.allclose(out[:later], expected_first) and np.allclose(out[later:], 0.0, atol=1e-15)
    assert np.allclose(mean[:later, 0], 1.0 / w)
    assert np.allclose(mean[later:], 0.0, atol=1e-15)


def test_bad_sizes_are_refused() -> None:
    """n < w has no window (the detectors ask for three at least); the kernel refuses it."""
    x = np.ones((4, 3))
    with pytest.raises(ValueError, match="w ≤ n"):
        _variance_kernel.moving_variance(x, np.ones((1, 3)), 5, _variance_kernel.NORM)
    with pytest.raises(ValueError, match="ref of shape"):
        _variance_kernel.moving_variance(x, np.ones((3, 3)), 2, _variance_kernel.NORM)


@pytest.mark.parametrize("labels", [[0, 0, 1, 1, 1, 0, 2, 2], [1], [0, 1], [2, 2, 2]])
def test_runs_of_int8_and_bool(labels: list[int]) -> None:
    arr = np.array(labels, dtype=np.int8)
    runs = _runs(arr)
    assert [lab for a, b, lab in runs for _ in range(b - a)] == labels
    assert all(runs[i][1] == runs[i + 1][0] for i in range(len(runs) - 1))
    if max(labels) <= 1:
        assert _runs(arr.astype(bool)) == runs


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_gap_angles_equal_the_numpy_path(seed: int) -> None:
    """The detector's trapezoid angles over its gaps (step 5), compiled against numpy."""
    from imucalib.processing import _angle_kernel
    from imucalib.processing.static_detector import _gap_angles

    assert _angle_kernel.kernel() is not None
    rng = np.random.default_rng(seed)
    n = 20_000
    t = np.cumsum(rng.uniform(0.9e-3, 1.1e-3, size=n)) + 1e4  # jittered, far from 0
    gyro = rng.normal(size=(n, 3)) * 0.02 + rng.normal(size=3)
    gyro[5_000:6_000] += [0.0, 0.0, 2.0]  # a rotation about z
    starts = np.sort(rng.choice(n - 3_000, size=40, replace=False))
    lengths = [2, 3, 9, 17, 128, 129, 1_000, 2_500] * 5  # two samples: one trapezoid
    spans = [(int(a), int(a) + m) for a, m in zip(starts, lengths, strict=True)]
    biases = [rng.normal(size=3) * 0.1 for _ in spans]
    fast = _gap_angles(t, gyro, spans, biases)
    slow = _gap_angles(t, gyro, spans, biases, backend="numpy")
    assert len(fast) == len(slow) == len(spans)
    for a, b in zip(fast, slow, strict=True):
        np.testing.assert_array_equal(a, b)
    assert _gap_angles(t, gyro, [], []) == []
