"""The guards' rolling window: what `rows` returns, however often it is asked.

`RollingWindow` keeps its kept blocks joined once `rows` has been asked for them (a soak guard
asks every tick); the rows must be those of joining the kept blocks afresh, bit for bit.
"""

from __future__ import annotations

import numpy as np

from imucalib.station.guards import RollingWindow


def _fresh(blocks: list[tuple[np.ndarray, np.ndarray]], span_s: float,
           since_s: float | None) -> tuple[np.ndarray, np.ndarray]:
    """The rows of a window that joins its kept blocks on every call (the reference)."""
    kept: list[tuple[np.ndarray, np.ndarray]] = []
    for t, v in blocks:
        kept.append((t, v))
        while kept and kept[0][0][-1] < t[-1] - span_s:
            kept.pop(0)
    t = np.concatenate([b[0] for b in kept])
    v = np.concatenate([b[1] for b in kept])
    keep = t >= (t[-1] - span_s if since_s is None else max(since_s, t[-1] - span_s))
    return t[keep], v[keep]


def test_rows_equal_a_fresh_join_whenever_they_are_asked():
    rng = np.random.default_rng(7)
    window = RollingWindow(span_s=5.0)
    pushed: list[tuple[np.ndarray, np.ndarray]] = []
    clock = 0.0
    for tick in range(400):
        n = int(rng.integers(0, 6))
        t = clock + np.cumsum(rng.uniform(0.01, 0.2, n))
        clock = float(t[-1]) if n else clock
        v = rng.normal(size=(n, 3))
        window.push(t, v)
        if n:
            pushed.append((t, v))
        if pushed and tick % int(rng.integers(1, 4)) == 0:  # asked irregularly
            since = None if tick % 2 else clock - float(rng.uniform(0.0, 8.0))
            got, want = window.rows(since), _fresh(pushed, 5.0, since)
            assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1])
        if tick == 250:
            window.clear()
            pushed.clear()
            assert window.rows()[0].size == 0
    assert window.covers(float(window.rows()[0][0]))
