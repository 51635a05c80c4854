"""Overlapping sums follow the documented order, chained or not, on any thread count."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest

from imucalib.analysis import _allan_engine as engine
from imucalib.analysis import _allan_kernels as kernels
from imucalib.analysis import set_kernel_backend


@pytest.fixture
def backend() -> Iterator[None]:
    old = set_kernel_backend(None)
    yield
    set_kernel_backend(old)


def canonical_sum(d: list[float]) -> float:
    """Σ d² in the order of the module docstring, in plain Python floats."""
    total = 0.0
    for b in range(0, len(d), kernels.BLOCK):
        e = [v * v for v in d[b:b + kernels.BLOCK]]
        e += [0.0] * (kernels.BLOCK - len(e))
        lanes = e[:kernels.LANES]
        for r in range(1, kernels.BLOCK // kernels.LANES):
            for i in range(kernels.LANES):
                lanes[i] += e[r * kernels.LANES + i]
        h = kernels.LANES // 2
        while h >= 1:
            for i in range(h):
                lanes[i] += lanes[i + h]
            h //= 2
        total += lanes[0]
    return total


@pytest.mark.parametrize("name", ["numba", "numpy"])
def test_second_difference_sums_follow_the_documented_order(name: str, backend: None) -> None:
    rng = np.random.default_rng(3)
    x = np.cumsum(rng.standard_normal(5000)) * 1e-3
    ms = np.array([1, 2, 4, 8, 16, 32, 100, 1000], dtype=np.int64)
    cnt = engine.n_terms("oadev", ms, x.size)
    set_kernel_backend(name)
    got = engine.sum_overlapping(engine.ArrayPhase(x), ms, cnt, 2)
    for t, m in enumerate(ms.tolist()):
        d = [(x[i + 2 * m] - 2.0 * x[i + m]) + x[i] for i in range(int(cnt[t]))]
        assert got[t] == canonical_sum(d), f"m={m}"


@pytest.mark.parametrize("threads", ["1", "2", "3"])
def test_chained_octaves_equal_the_numpy_twin_for_any_thread_count(
        threads: str, backend: None, monkeypatch: pytest.MonkeyPatch) -> None:
    """Octave and 1-2-4 decade grids are chained three at a time; partial blocks are not."""
    monkeypatch.setenv("IMUCALIB_THREADS", threads)
    rng = np.random.default_rng(11)
    x = np.cumsum(rng.standard_normal(70_001))
    grids = [2 ** np.arange(15), np.array([1, 2, 4, 10, 20, 40, 100, 200, 400, 1000, 2000,
                                           4000, 10_000, 20_000])]
    for ms in grids:
        ms = ms.astype(np.int64)
        for order, kind in ((2, "oadev"), (3, "ohdev")):
            cnt = engine.n_terms(kind, ms, x.size)
            set_kernel_backend("numpy")
            ref = engine.sum_overlapping(engine.ArrayPhase(x), ms, cnt, order)
            set_kernel_backend("numba")
            got = engine.sum_overlapping(engine.ArrayPhase(x), ms, cnt, order)
            np.testing.assert_array_equal(got, ref, err_msg=f"{kind} m={ms.tolist()}")


def test_job_groups_keep_runs_of_three_and_balance_terms(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("IMUCALIB_THREADS", "2")
    n = engine.n_terms("oadev", 2 ** np.arange(23, dtype=np.int64), 10**7)
    groups = engine._job_groups(n)
    assert sorted(np.concatenate(groups).tolist()) == list(range(23))
    for g in groups:  # each group is whole runs 3r, 3r+1, 3r+2 (the last run shorter), in order
        runs = sorted(set((g // 3).tolist()))
        assert g.tolist() == [j for r in runs for j in range(3 * r, min(3 * r + 3, 23))]
    loads = [int(n[g].sum()) for g in groups]
    assert max(loads) / min(loads) < 1.2


def test_fma_kernel_primitive_is_fused_and_exact_for_doubling() -> None:
    import numba

    kernels.get_kernels()  # builds the intrinsic
    fma = kernels.__dict__["_fma"]

    @numba.njit
    def call(a: float, b: float, c: float) -> float:
        return fma(a, b, c)

    eps = 2.0 ** -30
    assert call(1 + eps, 1 - eps, -1.0) == -(2.0 ** -60)  # unfused: (1 − 2^−60) − 1 rounds to 0
    rng = np.random.default_rng(0)
    b = rng.standard_normal(1000) * 10.0 ** rng.integers(-300, 300, 1000)
    c = rng.standard_normal(1000) * 10.0 ** rng.integers(-300, 300, 1000)
    b[:3] = [5e-324, -3e-310, 0.0]
    for bi, ci in zip(b, c, strict=True):
        assert call(-2.0, bi, ci) == ci - 2.0 * bi
