"""SamplingCheck accepts and refuses exactly what its stamp-by-stamp checks do, with their messages.

docs/performance.md, "P2 and Allan: the fourth pass": a chunk whose shortest and longest
intervals pass is accepted from those two alone; anything else goes through the stamp-by-stamp
checks (``_check``), which name the defect. The reference below is that stamp-by-stamp check
applied to every chunk, as before.
"""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.analysis import SamplingCheck
from imucalib.errors import InvalidInputError


def _outcome(chunks: list[np.ndarray], rtol: float, reference: bool) -> tuple[object, ...]:
    check = SamplingCheck(rtol=rtol)
    for i, c in enumerate(chunks):
        try:
            if reference:  # the stamp-by-stamp path for every chunk
                t = np.asarray(c, dtype=np.float64).ravel()
                if t.size:
                    check._check(t)
                    if check._first is None:
                        check._first = float(t[0])
                    check._last = float(t[-1])
                    check._count += t.size
            else:
                check.update(c)
        except InvalidInputError as exc:
            return ("error", i, str(exc))
    return ("ok", check.n_samples, check.t_first_s, check.t_last_s,
            check.sample_rate_hz() if check.n_samples > 1 else None, check._nominal)


def _stamps(rng: np.random.Generator) -> np.ndarray:
    n = int(rng.integers(1, 400))
    dt = np.full(n, 0.01) * (1.0 + rng.normal(0.0, rng.choice([0.0, 1e-4, 3e-3, 2e-2]), n))
    t = 100.0 + np.cumsum(dt)
    kind = rng.integers(0, 8)
    i = int(rng.integers(0, n))
    if kind == 1:
        t[i:] += 0.05  # a gap
    elif kind == 2 and n > 2:
        t[i] = t[max(i - 1, 0)]  # a repeated stamp
    elif kind == 3:
        t[i] = np.nan
    elif kind == 4:
        t[i] = np.inf
    elif kind == 5:
        t[i:] += 0.0102  # just over and under the tolerance
    return t


def test_update_equals_the_stamp_by_stamp_checks() -> None:
    rng = np.random.default_rng(21)
    for _ in range(3000):
        t = _stamps(rng)
        cuts = np.sort(rng.choice(np.arange(0, t.size + 1), int(rng.integers(0, 4))))
        chunks = np.split(t, cuts)
        rtol = float(rng.choice([0.01, 0.001, 0.5]))
        assert _outcome(chunks, rtol, False) == _outcome(chunks, rtol, True)


@pytest.mark.filterwarnings("ignore:overflow encountered")
@pytest.mark.parametrize("chunks", [
    [np.array([1.0])], [np.array([1.0]), np.array([1.01, 1.02])],
    [np.array([]), np.array([2.0, 2.5])], [np.array([1.0, 1.0])],
    [np.array([1e308, -1e308])], [np.array([3.0, 2.0, 1.0])],
])
def test_edge_chunks(chunks: list[np.ndarray]) -> None:
    assert _outcome(chunks, 0.01, False) == _outcome(chunks, 0.01, True)
