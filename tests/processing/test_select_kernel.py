"""The exact median of processing._select_kernel: ``np.median``'s value bit for bit, faster.

Every comparison is of the IEEE bit patterns (a −0.0 for a +0.0, or a last-bit difference,
fails). The outlier rule must give the same result whether the kernel or numpy selects.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator

import numpy as np
import pytest

from imucalib.processing import _select_kernel as sk
from imucalib.processing.outliers import OutlierResult, reject_outliers_robust

SIZES = (1, 2, 3, 4, 5, 8, 255, 256, 257, 258, 999, 1000, 4097, 10_000, 10_001, 100_000)
KINDS = ("normal", "negative", "ties", "two-values", "constant", "one-off", "cauchy", "extreme",
         "integers", "sorted", "reversed", "zeros", "signed-zeros", "magnitudes")


def _bits(value: float) -> int:
    return int(np.array([value], dtype=np.float64).view(np.uint64)[0])


def _reference(x: np.ndarray) -> float:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # an overflowing mean of the middle two
        return float(np.median(x))


def _data(kind: str, n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    if kind == "normal":
        return rng.normal(size=n)
    if kind == "negative":
        return -rng.uniform(1.0, 2.0, n) * 1e-7
    if kind == "ties":
        return rng.integers(0, 4, n).astype(float)
    if kind == "two-values":
        return np.where(rng.random(n) < 0.5, 0.25, 0.75)
    if kind == "constant":
        return np.full(n, -3.5)
    if kind == "one-off":  # many equal values and a few others
        x = np.full(n, 1.0)
        x[rng.choice(n, max(1, n // 50), replace=False)] = rng.normal(size=max(1, n // 50))
        return x
    if kind == "cauchy":
        return rng.standard_cauchy(n)
    if kind == "extreme":
        return rng.choice([1e300, -1e300, 1e-300, -1e-300, 1.7e308, -1.7e308], n)
    if kind == "integers":
        return rng.integers(-1000, 1000, n).astype(float)
    if kind == "sorted":
        return np.sort(rng.normal(size=n))
    if kind == "reversed":
        return np.sort(rng.normal(size=n))[::-1].copy()
    if kind == "zeros":
        return -np.zeros(n)
    if kind == "signed-zeros":
        return rng.choice([0.0, -0.0, 1.0, -1.0], n, p=[0.4, 0.4, 0.1, 0.1])
    # "magnitudes": the two middle values of very different size and sign
    return rng.choice([1e16, 1.0, -3.0, 1e-20, -1e300, 7e-310], n) * rng.uniform(0.5, 2.0, n)


def _cases() -> Iterator[tuple[str, int, int]]:
    for kind in KINDS:
        for n in SIZES:
            yield kind, n, n * 31 + len(kind)


@pytest.fixture
def numba_kernel() -> object:
    kernel = sk._kernel()
    if kernel is None:
        pytest.skip(str(sk._STATE["error"]))
    return kernel


@pytest.mark.parametrize(("kind", "n", "seed"), list(_cases()))
def test_median_equals_numpy_bit_for_bit(kind: str, n: int, seed: int) -> None:
    x = _data(kind, n, seed)
    before = x.copy()
    assert _bits(sk.median(x)) == _bits(_reference(x))
    c = sk.median(x)
    assert _bits(sk.median_abs_deviation(x, c)) == _bits(_reference(np.abs(x - c)))
    assert np.array_equal(x, before, equal_nan=True)  # not modified


def test_many_random_arrays(numba_kernel: object) -> None:
    rng = np.random.default_rng(7)
    for _ in range(300):
        n = int(rng.integers(1, 3000))
        x = rng.normal(size=n) * 10.0 ** rng.integers(-30, 30)
        if rng.random() < 0.3:
            x = np.round(x, int(rng.integers(0, 3)))  # quantised: ties at the bracket
        assert _bits(sk.median(x)) == _bits(_reference(x))


@pytest.mark.parametrize("n", [300, 10_000, 600_001])
def test_the_kernel_answers_itself(numba_kernel: object, n: int) -> None:
    # the comparisons above must not pass by the numpy fallback alone
    x = np.random.default_rng(n).normal(size=n)
    for absdev in (False, True):
        status, low, high = sk._kernel()(x, 0.1, absdev)  # type: ignore[misc]
        assert status == sk._OK
        v = np.sort(np.abs(x - 0.1) if absdev else x)
        assert (low, high) == (v[(n - 1) // 2], v[n // 2])


def test_quantised_ties_at_the_bracket(numba_kernel: object) -> None:
    # 99 % of the values equal: lo = hi, answered from the counts without a buffer
    x = np.zeros(100_000)
    x[::100] = np.arange(1000.0) - 400.0
    status, low, high = sk._kernel()(x, 0.0, False)  # type: ignore[misc]
    assert status == sk._OK and low == high == 0.0
    assert _bits(sk.median(x)) == _bits(_reference(x))


def test_a_missed_bracket_falls_back(numba_kernel: object) -> None:
    # the median itself is the only value inside a wide gap: still numpy's answer
    rng = np.random.default_rng(3)
    n = 50_001
    x = np.concatenate([rng.uniform(-2.0, -1.0, n // 2), [0.0], rng.uniform(1.0, 2.0, n // 2)])
    assert _bits(sk.median(x)) == _bits(_reference(x))
    assert _bits(sk.median(rng.permutation(x))) == _bits(_reference(x))


@pytest.mark.parametrize("n", [5, 6, 1001, 100_000])
def test_nan_gives_numpy_nan(n: int) -> None:
    x = np.random.default_rng(n).normal(size=n)
    x[n // 3] = np.nan
    assert np.isnan(sk.median(x)) and np.isnan(sk.median_abs_deviation(x, 0.0))


def test_combination_of_the_middle_pair_is_numpys() -> None:
    # numpy: mean of the two → sum from +0.0, divided by 2; never a −0.0
    rng = np.random.default_rng(11)
    values = np.concatenate([rng.normal(size=200) * 10.0 ** rng.integers(-300, 300, 200),
                             [0.0, -0.0, 5e-324, -5e-324, 1.7e308, -1.7e308, 1.0, -1.0]])
    for a in values:
        for b in values[::7]:
            lo, hi = min(a, b), max(a, b)
            want = _reference(np.array([lo, hi]))
            assert _bits(sk._combine(float(lo), float(hi), True)) == _bits(want)
        assert _bits(sk._combine(float(a), float(a), False)) == _bits(_reference(np.array([a])))


def test_select_loop_guard_on_adversarial_order(numba_kernel: object) -> None:
    # organ-pipe and sawtooth orders: the sort fallback keeps FIND correct
    for x in (np.concatenate([np.arange(2000.0), np.arange(2000.0)[::-1]]),
              np.tile(np.arange(50.0), 80), np.full(4000, 2.0)):
        for r in (0, 1, 1999, 2000, 3999):
            buf = x.copy()
            assert sk._select_loop(buf, buf.size, r) == np.sort(x)[r]
            assert np.all(buf[:r] <= buf[r]) and np.all(buf[r + 1:] >= buf[r])


def test_numpy_backend() -> None:
    x = np.random.default_rng(0).normal(size=1001)
    assert sk.median(x, backend="numpy") == float(np.median(x))
    assert sk.median_abs_deviation(x, 0.5, backend="numpy") == float(
        np.median(np.abs(x - 0.5)))


# ---- the outlier rule: the kernel and numpy give the same result ---------------------------

def _robust_inputs() -> Iterator[tuple[str, np.ndarray]]:
    rng = np.random.default_rng(5)
    x = rng.normal(size=(20_000, 6)) * [1.0, 2.0, 1e-3, 5.0, 0.1, 1e4]
    x[rng.choice(20_000, 60, replace=False), rng.integers(0, 6, 60)] += 40.0
    yield "gaussian", x
    q = np.round(rng.normal(size=(5000, 3)) * 2.0)  # quantised: MAD ties, residual median 0
    q[[10, 11, 4000], [0, 0, 2]] = 30.0
    yield "quantised", q
    t = np.arange(3000.0)
    yield "sine", 100.0 * np.sin(2 * np.pi * t / 200.0) + rng.normal(size=3000)
    yield "short", rng.normal(size=(12, 2))
    yield "constant", np.full(1000, 4.25)


def _assert_same(a: OutlierResult, b: OutlierResult) -> None:
    for name in ("values", "outlier_mask", "kept", "n_outliers", "scale", "center",
                 "n_iterations"):
        x, y = np.asarray(getattr(a, name)), np.asarray(getattr(b, name))
        assert x.dtype == y.dtype and x.shape == y.shape, name
        assert x.tobytes() == y.tobytes(), name  # bit for bit
    assert _bits(a.threshold) == _bits(b.threshold)


@pytest.mark.parametrize("method", ["interpolate", "drop"])
@pytest.mark.parametrize(("name", "x"), list(_robust_inputs()))
def test_robust_rule_kernel_equals_numpy(monkeypatch: pytest.MonkeyPatch, numba_kernel: object,
                                         name: str, x: np.ndarray, method: str) -> None:
    fast = reject_outliers_robust(x, method=method)  # type: ignore[arg-type]
    monkeypatch.setitem(sk._STATE, "kernel", None)
    monkeypatch.setitem(sk._STATE, "error", "forced off by the test")
    assert sk._kernel() is None
    slow = reject_outliers_robust(x, method=method)  # type: ignore[arg-type]
    _assert_same(fast, slow)
    # and the centre is still the median of each column's kept input samples
    cols = x.reshape(x.shape[0], -1)
    mask = slow.outlier_mask.reshape(cols.shape)
    want = [float(np.median(cols[~mask[:, j], j])) for j in range(cols.shape[1])]
    assert [_bits(v) for v in fast.center] == [_bits(v) for v in want]


def test_center_is_lazy_cached_and_read_only() -> None:
    x = np.random.default_rng(2).normal(size=(3000, 2))
    x[100, 1] = 50.0
    res = reject_outliers_robust(x)
    assert callable(res._center)  # not computed yet
    c = res.center
    assert res.center is c and not c.flags.writeable
    with pytest.raises(ValueError):
        c[0] = 1.0
    assert c[1] == float(np.median(np.delete(x[:, 1], 100)))
