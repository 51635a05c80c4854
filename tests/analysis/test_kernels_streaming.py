"""The numba kernels equal their numpy twin bit for bit; streamed results equal in-memory ones."""

from __future__ import annotations

import os
from collections.abc import Iterator

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imucalib.analysis import (
    DEVIATION_KINDS,
    AllanStream,
    compute_deviation,
    compute_deviations_streaming,
    kernel_backend,
    set_kernel_backend,
)
from imucalib.analysis import _allan_engine as engine
from imucalib.analysis import _allan_kernels as kernels
from imucalib.analysis.streaming import FilePhase
from imucalib.errors import InvalidInputError


@pytest.fixture
def backend() -> Iterator[None]:
    old = set_kernel_backend(None)
    yield
    set_kernel_backend(old)


def record(n: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return 1e-3 * rng.standard_normal(n) + 2e-6 * np.cumsum(rng.standard_normal(n)) + 0.2


def same(a: dict, b: dict) -> None:
    for kind in a:
        for field in ("taus_s", "deviation", "edf", "ci_low", "ci_high", "noise_alpha", "n_terms"):
            np.testing.assert_array_equal(getattr(a[kind], field), getattr(b[kind], field),
                                          err_msg=f"{kind}.{field}")


def test_numba_is_used_and_equals_the_numpy_twin(backend: None) -> None:
    y = record(300_001, seed=1)
    set_kernel_backend("numba")
    assert kernel_backend() == "numba"
    fast = {k: compute_deviation(k, y, 200.0) for k in DEVIATION_KINDS}
    set_kernel_backend("numpy")
    assert kernel_backend() == "numpy"
    slow = {k: compute_deviation(k, y, 200.0) for k in DEVIATION_KINDS}
    same(fast, slow)


def test_kernels_bit_identical_on_odd_lengths(backend: None) -> None:
    rng = np.random.default_rng(5)
    for n in (3, 7, 1023, 1024, 1025, 5000):
        x = np.cumsum(rng.standard_normal(n + 40))
        ms = np.array([1, 2, 3, 5, 8], dtype=np.int64)
        cnt = np.maximum(x.size - 3 * ms, 0).astype(np.int64)
        res = []
        for name in ("numba", "numpy"):
            set_kernel_backend(name)
            src = engine.ArrayPhase(x)
            res.append((engine.sum_overlapping(src, ms, cnt, 2),
                        engine.sum_overlapping(src, ms, cnt, 3),
                        engine.sums_mdev(src, ms), engine.sum_nonoverlapping(src, ms, 2),
                        engine.sums_totdev(src, ms[ms <= (x.size - 1) // 2])))
        for a, b in zip(*res, strict=True):
            np.testing.assert_array_equal(a, b)


def test_numpy_fallback_when_numba_is_unavailable(backend: None,
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(kernels._STATE, "numba", None)
    monkeypatch.setitem(kernels._STATE, "error", "numba unavailable: ImportError")
    assert kernel_backend() == "numpy"
    y = record(20_000)
    r = compute_deviation("oadev", y, 10.0)
    monkeypatch.undo()
    set_kernel_backend("numba")
    np.testing.assert_array_equal(r.deviation, compute_deviation("oadev", y, 10.0).deviation)


def test_environment_variable_selects_numpy(backend: None, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("IMUCALIB_KERNELS", "numpy")
    assert kernel_backend() == "numpy"
    monkeypatch.delenv("IMUCALIB_KERNELS")
    assert kernel_backend() == "numba"
    with pytest.raises(ValueError, match="backend must be 'numba', 'numpy' or None; got 'cuda'"):
        set_kernel_backend("cuda")


@pytest.mark.parametrize("limit", [0, 1 << 30], ids=["scratch-file", "in-memory"])
def test_streamed_equals_in_memory_bit_for_bit(limit: int, tmp_path) -> None:
    y = record(200_003, seed=2)
    rng = np.random.default_rng(9)
    cuts = np.sort(rng.choice(np.arange(1, y.size), 25, replace=False))
    ref = {k: compute_deviation(k, y, 100.0) for k in DEVIATION_KINDS}
    got = compute_deviations_streaming(np.split(y, cuts), 100.0, kinds=DEVIATION_KINDS,
                                       memory_limit_samples=limit, scratch_dir=tmp_path)
    same(ref, got)
    assert list(tmp_path.iterdir()) == []  # the scratch file is removed


def test_streamed_mean_chunks_cross_the_canonical_boundary(tmp_path) -> None:
    """More than one 2^20-sample mean chunk, fed in pieces that straddle it."""
    y = record((1 << 20) + 70_001, seed=4)
    ref = compute_deviation("oadev", y, 1000.0, taus=[0.001, 0.01, 0.1, 1.0])
    pieces = [y[a:a + 300_007] for a in range(0, y.size, 300_007)]
    got = compute_deviations_streaming(pieces, 1000.0, taus=[0.001, 0.01, 0.1, 1.0],
                                       memory_limit_samples=100_000, scratch_dir=tmp_path)
    np.testing.assert_array_equal(ref.deviation, got["oadev"].deviation)


@settings(max_examples=15, deadline=None)
@given(st.lists(st.integers(1, 3000), min_size=1, max_size=12),
       st.sampled_from(["rate", "angle"]))
def test_any_chunking_gives_the_same_result(sizes: list[int], data_type: str) -> None:
    y = record(sum(sizes) + 50, seed=len(sizes))
    pieces, a = [], 0
    for s in sizes:
        pieces.append(y[a:a + s])
        a += s
    pieces.append(y[a:])
    ref = compute_deviation("ohdev", y, 50.0, data_type=data_type)  # type: ignore[arg-type]
    got = compute_deviations_streaming(pieces, 50.0, kinds=["ohdev"],
                                       data_type=data_type,  # type: ignore[arg-type]
                                       memory_limit_samples=1000)
    np.testing.assert_array_equal(ref.deviation, got["ohdev"].deviation)


def test_file_phase_reads_match_the_array(tmp_path) -> None:
    rng = np.random.default_rng(0)
    x = rng.standard_normal(70_000)
    path = tmp_path / "x.f64"
    x[1:].tofile(path)
    fd = os.open(path, os.O_RDONLY)
    try:
        src = FilePhase(fd, x.size - 1, lead_zero=True)
        ref = x.copy()
        ref[0] = 0.0
        assert src.n_phase == x.size
        for start, stop, step in [(0, 10, 1), (5, 69_999, 1), (0, 70_000, 7), (3, 60_000, 5000),
                                  (1, 2, 1), (100, 100, 1)]:
            np.testing.assert_array_equal(src.read(start, stop, step), ref[start:stop:step])
        offsets = np.array([0, 3, 500, 40_000, 69_000], dtype=np.int64)
        buf, starts = src.gather(10, offsets, 2000)
        for o, s in zip(offsets, starts, strict=True):
            n = min(2000, x.size - (10 + o))
            np.testing.assert_array_equal(buf[s:s + n], ref[10 + o:10 + o + n])
    finally:
        os.close(fd)


def test_stream_state_and_errors(tmp_path) -> None:
    with AllanStream(100.0, scratch_dir=tmp_path / "scratch", memory_limit_samples=10) as s:
        s.append(record(5))
        assert s.scratch_path is None
        s.append(record(10))
        assert s.scratch_path is not None and s.scratch_path.exists()
        with pytest.raises(InvalidInputError,
                           match=r"sample 17 \(t = 0.17 s from the start\) is NaN"):
            s.append(np.array([0.1, 0.2, np.nan]))
        with pytest.raises(InvalidInputError, match=r"`samples` must be 1-D; got shape \(2, 2\)"):
            s.append(np.zeros((2, 2)))
        assert s.n_samples == 15
        s.compute()
        with pytest.raises(InvalidInputError, match="already computed; it takes no more samples"):
            s.append([1.0])
        path = s.scratch_path
    assert path is not None and not path.exists()
    with AllanStream(100.0) as s, pytest.raises(InvalidInputError,
                                                match="data too short: need at least"):
        s.append([1.0, 2.0])
        s.compute()
    with pytest.raises(InvalidInputError,
                       match="`memory_limit_samples` must be an int ≥ 0; got -1"):
        AllanStream(1.0, memory_limit_samples=-1)


@pytest.mark.parametrize("n", [5, 3999, 4000, 4001, 8 * 4000 + 17, 100_003])
def test_phase_blocks_numba_numpy_and_two_threads_agree(backend: None, n: int,
                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    """The blocked phase sum is the same bit for bit in numba, numpy and the two-thread split."""
    y = record(n, seed=n)
    mean = float(np.mean(y))
    got = {}
    for name, threads, split_min in [("numpy", "1", 1 << 40), ("numba", "1", 1 << 40),
                                     ("numba", "2", 1)]:
        set_kernel_backend(name)
        monkeypatch.setenv("IMUCALIB_THREADS", threads)
        monkeypatch.setattr(engine, "PARALLEL_PHASE_MIN", split_min)
        out = np.empty(n)
        engine.integrate_phase(y, mean, 0.01, out)
        got[(name, threads)] = out
    ref = got[("numpy", "1")]
    for key, out in got.items():
        np.testing.assert_array_equal(out, ref, err_msg=str(key))
    # and it is the phase: x_{j+1} = τ0·Σ_{i≤j}(y_i − ȳ) to rounding
    np.testing.assert_allclose(ref, 0.01 * np.cumsum(y - mean), rtol=1e-9, atol=1e-12)


def test_streamed_scratch_file_equals_the_parallel_in_memory_phase(
        tmp_path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Streamed phase (read in phase-block multiples) = in-memory phase split between threads."""
    monkeypatch.setenv("IMUCALIB_THREADS", "2")
    monkeypatch.setattr(engine, "PARALLEL_PHASE_MIN", 1)
    y = record(2 * 1_024_000 + 12_345, seed=11)
    ref = compute_deviation("oadev", y, 1000.0, taus=[0.001, 0.1, 10.0])
    pieces = [y[a:a + 777_777] for a in range(0, y.size, 777_777)]
    got = compute_deviations_streaming(pieces, 1000.0, taus=[0.001, 0.1, 10.0],
                                       memory_limit_samples=1000, scratch_dir=tmp_path)
    np.testing.assert_array_equal(ref.deviation, got["oadev"].deviation)


def test_data_too_large_to_sum_is_named() -> None:
    y = np.full(1000, 1.5e308)
    with pytest.raises(InvalidInputError, match="too large to sum in float64"):
        compute_deviation("oadev", y, 100.0)


@pytest.mark.parametrize("limit", [10, 1 << 30], ids=["scratch-file", "in-memory"])
def test_streamed_data_too_large_to_sum_is_named(tmp_path, limit: int) -> None:
    with AllanStream(100.0, scratch_dir=tmp_path, memory_limit_samples=limit) as s:
        s.append(np.full(1000, 1.5e308))
        with pytest.raises(InvalidInputError, match="too large to sum in float64"):
            s.compute()
