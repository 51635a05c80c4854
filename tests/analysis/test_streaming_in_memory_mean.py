"""A stream held in memory takes its canonical mean from the record itself, bit for bit.

docs/performance.md, "P2 and Allan: the fourth pass": an :class:`~imucalib.analysis.AllanStream`
that never spills sums its 2^20-sample mean chunks from the concatenated record when it is
computed (no running copy into a buffer), keeps arrays handed over with ``copy=False``, and one
that spills part-way accumulates the chunks it held when it spills. Every way gives the
in-memory :func:`~imucalib.analysis.compute_deviation` result.
"""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.analysis import AllanStream, compute_deviation

_TAUS = [0.001, 0.01, 0.1, 1.0]


def _record(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return 1e-3 * rng.standard_normal(n) + 2e-6 * np.cumsum(rng.standard_normal(n)) + 0.2


@pytest.mark.parametrize("n", [5_000, 1 << 20, (1 << 20) + 1, 2 << 20, (2 << 20) + 77_777])
@pytest.mark.parametrize(("limit", "copy"), [(1 << 30, True), (1 << 30, False),
                                             (700_000, True), (0, False)],
                         ids=["memory", "memory-kept", "spills-part-way", "spills-at-once"])
def test_stream_equals_the_in_memory_deviation(n: int, limit: int, copy: bool,
                                               tmp_path) -> None:
    y = _record(n, seed=n % 97)
    want = compute_deviation("oadev", y, 1000.0, taus=_TAUS)
    pieces = [y[a:a + 300_007].copy() for a in range(0, y.size, 300_007)]
    with AllanStream(1000.0, memory_limit_samples=limit, scratch_dir=tmp_path) as stream:
        for p in pieces:
            stream.append(p, copy=copy)
        got = stream.compute(["oadev"], taus=_TAUS)["oadev"]
    np.testing.assert_array_equal(got.deviation, want.deviation)
    np.testing.assert_array_equal(got.edf, want.edf)


def test_kept_arrays_are_not_copied_and_copies_are() -> None:
    y = _record(10_000, seed=1)
    kept, copied = AllanStream(100.0), AllanStream(100.0)
    kept.append(y, copy=False)
    copied.append(y)
    assert kept._chunks[0] is y
    assert copied._chunks[0] is not y and np.array_equal(copied._chunks[0], y)
    a = kept.compute(["oadev"])["oadev"]
    b = copied.compute(["oadev"])["oadev"]
    np.testing.assert_array_equal(a.deviation, b.deviation)
