"""Where a time goes in a stream's sorted time column, without reading the column whole.

:func:`search_sorted_dataset` is the reader's row search (:meth:`imucalib.io.reader.Recording.
row_range`, ``read_stream``, ``iter_windows``): ``numpy.searchsorted`` on an HDF5 dataset with a
few small reads. :func:`scan_sorted_dataset` finds many times at once in one pass over the
column, a block at a time (memory bounded by the block, not the column).
"""

from __future__ import annotations

import math
from typing import Final

import h5py
import numpy as np
from numpy.typing import NDArray

__all__ = ["scan_sorted_dataset", "search_sorted_dataset"]

#: Rows of the time column read at once by :func:`scan_sorted_dataset` (8 MiB of float64).
_SCAN_BLOCK: Final = 1 << 20
#: Rows read at once by the search (one interpolation probe, then the final bracket).
_SEARCH_BLOCK: Final = 1 << 14


def search_sorted_dataset(ds: h5py.Dataset, n: int, t: float, side: str) -> int:
    """Find where `t` goes in the non-decreasing dataset `ds[:n]` without loading it whole.

    One interpolation probe first (sampling is nearly uniform, so it usually lands on the
    answer: three small reads), then bisection with single-element reads, then one block.
    """
    if math.isinf(t):
        return 0 if t < 0 else n
    lo, hi = 0, n  # the answer lies in [lo, hi]
    block = _SEARCH_BLOCK
    if n > block:
        t_first, t_last = float(ds[0]), float(ds[n - 1])
        if t_last > t_first:
            frac = min(max((t - t_first) / (t_last - t_first), 0.0), 1.0)
            a = min(max(int(frac * (n - 1)) - block // 2, 0), n - block)
            seg = ds[a:a + block]
            k = int(np.searchsorted(seg, t, side=side))  # type: ignore[call-overload]
            if 0 < k < block:
                return a + k
            if k == 0:
                hi = a
            else:
                lo = a + block
    while hi - lo > block:
        mid = (lo + hi) // 2
        v = float(ds[mid])
        if v < t or (side == "right" and v == t):
            lo = mid + 1
        else:
            hi = mid
    seg = ds[lo:hi]
    return lo + int(np.searchsorted(seg, t, side=side))  # type: ignore[call-overload]


def scan_sorted_dataset(ds: h5py.Dataset, n: int, times: NDArray[np.float64]
                        ) -> NDArray[np.int64]:
    """Return ``numpy.searchsorted(ds[:n], times, side="left")`` reading `ds` once, by blocks.

    Each time is placed in the first block whose last value is ≥ it: every value before that
    block is smaller (the column does not decrease), so the block's own search is the answer.
    """
    order = np.argsort(times, kind="stable")
    ordered = times[order]
    out = np.full(times.size, n, dtype=np.int64)
    done = 0
    for start in range(0, n, _SCAN_BLOCK):
        if done == ordered.size:
            break
        block = np.asarray(ds[start:min(n, start + _SCAN_BLOCK)])
        upto = int(np.searchsorted(ordered, block[-1], side="right"))
        if upto > done:
            out[order[done:upto]] = start + np.searchsorted(block, ordered[done:upto],
                                                            side="left")
            done = upto
    return out
