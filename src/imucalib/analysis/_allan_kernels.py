"""Kernels of the Allan-family deviations (private): a numba backend and its numpy twin.

Every kernel exists twice, once as plain Python written for numba (``_*_nb``) and once as numpy
(``_*_np``). The two perform the same IEEE operations in the same order, so they return
**bit-identical** results (``tests/analysis/test_kernels_streaming.py``,
``test_kernel_order.py``); numba is only faster. numba is imported on first use, never when
:mod:`imucalib` is imported, and the numpy twin is used when numba is missing, fails to
compile, or ``IMUCALIB_KERNELS=numpy`` is set.

Canonical arithmetic (both backends)
------------------------------------
Phase [1]_ eq. (2), ``x_0 = 0``, ``x_{j+1} = τ0·Σ_{i≤j}(y_i − ȳ)``, summed in phase blocks of
:data:`PHASE_BLOCK` samples: inside block b the partial sums ``L_j`` restart at zero and run
sequentially, the block carries ``C_{b+1} = C_b + L_last`` run sequentially, and
``x_{j+1} = (C_b + L_j)·τ0``. The blocks' sums are independent, so the kernel runs eight of them
side by side (the sequential sum was bound by the latency of one addition chain). The mean ȳ is
removed first, as allantools does, to keep the phase small. Calls start at a block boundary
(the streaming driver reads in multiples of the block).

Differences: second ``d = (x[i+2m] - 2·x[i+m]) + x[i]`` (Allan, total), third
``d = ((x[i+3m] - 3·x[i+2m]) + 3·x[i+m]) - x[i]`` (Hadamard, modified-Allan recursion).

Sums of squares of an overlapping estimator are taken in blocks of :data:`BLOCK` consecutive
terms e_0 … e_{BLOCK−1} (the last block zero-padded). Each block has :data:`LANES` lanes: lane
i sums e_i, e_{i+LANES}, e_{i+2·LANES}, … sequentially; the lanes are then reduced by repeated
halving (``s_i += s_{i+h}``, h = LANES/2, …, 1), and the block sums are added sequentially.
The lane loop reads each window front to back and vectorises without re-ordering; the rounding
error grows like BLOCK/LANES + log₂(LANES) per block instead of BLOCK. In the numba kernels
``(x[i+2m] − 2·x[i+m])`` is one fused multiply-add: 2·x is exact, so the single rounding of
the FMA equals the twin's rounding of the subtraction (bit-identical unless |x| ≥ 2^1023,
where the square overflows anyway). Other sums (non-overlapping estimators, the modified-Allan
running sum) are plain sequential sums.

Memory layout: a kernel sees one float64 buffer ``buf`` and the positions ``starts[k]`` in it of
the windows it needs; a job (one τ of one estimator) names its windows by index. The in-memory
driver passes the phase array itself with ``starts = block start + offsets`` (no copy); the
streaming driver passes windows read from its scratch file. Both feed the same blocks in the
same order, hence equal results.

References
----------
.. [1] W. J. Riley, "Handbook of Frequency Stability Analysis", NIST SP 1065, 2008.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "BLOCK",
    "PHASE_BLOCK",
    "backend_name",
    "get_kernels",
    "set_backend",
]

#: Terms per reduction block of the overlapping sums.
BLOCK = 1024
#: Partial sums (lanes) per block: lane i sums terms i, i + LANES, i + 2·LANES, … in order.
LANES = 64
#: Samples per block of the phase sum (the streaming driver's read size is a multiple of it).
PHASE_BLOCK = 4000  # not a power of two: eight streams 32 KiB apart would share cache sets

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]


# --------------------------------------------------------------------------- numba sources
def _local8_nb(rate: F64, mean: float, out: F64, o: int) -> None:
    """Local phase sums of the eight blocks from `o`, side by side (eight addition chains)."""
    pb = PHASE_BLOCK
    s0 = s1 = s2 = s3 = s4 = s5 = s6 = s7 = 0.0
    for j in range(pb):
        s0 += rate[o + j] - mean
        out[o + j] = s0
        s1 += rate[o + pb + j] - mean
        out[o + pb + j] = s1
        s2 += rate[o + 2 * pb + j] - mean
        out[o + 2 * pb + j] = s2
        s3 += rate[o + 3 * pb + j] - mean
        out[o + 3 * pb + j] = s3
        s4 += rate[o + 4 * pb + j] - mean
        out[o + 4 * pb + j] = s4
        s5 += rate[o + 5 * pb + j] - mean
        out[o + 5 * pb + j] = s5
        s6 += rate[o + 6 * pb + j] - mean
        out[o + 6 * pb + j] = s6
        s7 += rate[o + 7 * pb + j] - mean
        out[o + 7 * pb + j] = s7


def _phase_nb(rate: F64, mean: float, dt: float, out: F64, carry: float) -> float:
    pb = PHASE_BLOCK
    n = rate.size
    n_full = n // pb
    c = carry
    b = 0
    while b < n_full:  # local sums of eight blocks side by side, then their carries
        g = min(8, n_full - b)
        o = b * pb
        if g == 8:
            _local8_nb(rate, mean, out, o)
        else:
            for u in range(g):
                s = 0.0
                for j in range(o + u * pb, o + (u + 1) * pb):
                    s += rate[j] - mean
                    out[j] = s
        for u in range(g):
            ob = o + u * pb
            last = out[ob + pb - 1]
            for j in range(ob, ob + pb):
                out[j] = (c + out[j]) * dt
            c = c + last
        b += g
    s = 0.0
    for j in range(n_full * pb, n):  # the last, partial block
        s += rate[j] - mean
        out[j] = s
    for j in range(n_full * pb, n):
        out[j] = (c + out[j]) * dt
    if n > n_full * pb:
        c = c + s
    return c


def _phase_local_nb(rate: F64, mean: float, out: F64, ends: F64) -> None:
    """Phase pass 1 of a parallel split: out = L_j (local sums), ends[b] = L_last of block b."""
    pb = PHASE_BLOCK
    n = rate.size
    n_blocks = (n + pb - 1) // pb
    b = 0
    while b + 8 <= n // pb:
        o = b * pb
        _local8_nb(rate, mean, out, o)
        for u in range(8):
            ends[b + u] = out[o + u * pb + pb - 1]
        b += 8
    while b < n_blocks:
        s = 0.0
        for j in range(b * pb, min(n, (b + 1) * pb)):
            s += rate[j] - mean
            out[j] = s
        ends[b] = s
        b += 1


def _phase_fix_nb(out: F64, carries: F64, dt: float) -> None:
    """Phase pass 2 of a parallel split: out_j = (C_b + L_j)·τ0 for block b of j."""
    pb = PHASE_BLOCK
    n = out.size
    for b in range(carries.size):
        c = carries[b]
        for j in range(b * pb, min(n, (b + 1) * pb)):
            out[j] = (c + out[j]) * dt


def _tree_nb(buf: F64, h: int) -> float:
    while h >= 1:
        for i in range(h):
            buf[i] += buf[i + h]
        h >>= 1
    return buf[0]


def _fma(a: float, b: float, c: float) -> float:  # pragma: no cover - replaced for numba
    """a·b + c rounded once; the numba build replaces it with the ``llvm.fma.f64`` intrinsic."""
    raise RuntimeError("_fma is only defined inside the numba kernels")


def _reduce_nb(e: F64) -> float:
    """Reduce one block of BLOCK squared terms in the canonical order (module docstring)."""
    for r in range(1, BLOCK // LANES):
        o = r * LANES
        for i in range(LANES):
            e[i] += e[o + i]
    return _tree_nb(e, LANES >> 1)


def _chain1_nb(a: F64, b: F64, c: F64, acc: F64) -> float:
    """Block sum of one full block of d = (c − 2b) + a (2b is exact, so one fused step)."""
    for i in range(LANES):
        d = _fma(-2.0, b[i], c[i]) + a[i]
        acc[i] = d * d
    for r in range(1, BLOCK // LANES):
        o = r * LANES
        for i in range(LANES):
            d = _fma(-2.0, b[o + i], c[o + i]) + a[o + i]
            acc[i] += d * d
    return _tree_nb(acc, LANES >> 1)


def _chain2_nb(a: F64, w1: F64, w2: F64, w3: F64, acc0: F64, acc1: F64) -> tuple[float, float]:
    """Block sums of two chained octaves, m (windows a, w1, w2) and 2m (a, w2, w3)."""
    for i in range(LANES):
        x0 = a[i]
        x2 = w2[i]
        d = _fma(-2.0, w1[i], x2) + x0
        acc0[i] = d * d
        d = _fma(-2.0, x2, w3[i]) + x0
        acc1[i] = d * d
    for r in range(1, BLOCK // LANES):
        o = r * LANES
        for i in range(LANES):
            x0 = a[o + i]
            x2 = w2[o + i]
            d = _fma(-2.0, w1[o + i], x2) + x0
            acc0[i] += d * d
            d = _fma(-2.0, x2, w3[o + i]) + x0
            acc1[i] += d * d
    return _tree_nb(acc0, LANES >> 1), _tree_nb(acc1, LANES >> 1)


def _chain3_nb(a: F64, w1: F64, w2: F64, w3: F64, w4: F64, acc0: F64, acc1: F64,
               acc2: F64) -> tuple[float, float, float]:
    """Block sums of three chained octaves m, 2m, 4m: every window is read once for all three."""
    for i in range(LANES):
        x0 = a[i]
        x2 = w2[i]
        x3 = w3[i]
        d = _fma(-2.0, w1[i], x2) + x0
        acc0[i] = d * d
        d = _fma(-2.0, x2, x3) + x0
        acc1[i] = d * d
        d = _fma(-2.0, x3, w4[i]) + x0
        acc2[i] = d * d
    for r in range(1, BLOCK // LANES):
        o = r * LANES
        for i in range(LANES):
            x0 = a[o + i]
            x2 = w2[o + i]
            x3 = w3[o + i]
            d = _fma(-2.0, w1[o + i], x2) + x0
            acc0[i] += d * d
            d = _fma(-2.0, x2, x3) + x0
            acc1[i] += d * d
            d = _fma(-2.0, x3, w4[o + i]) + x0
            acc2[i] += d * d
    return (_tree_nb(acc0, LANES >> 1), _tree_nb(acc1, LANES >> 1),
            _tree_nb(acc2, LANES >> 1))


def _part2_nb(a: F64, b: F64, c: F64, n: int, buf: F64) -> float:
    """Block sum of a partial (last) block of n < BLOCK second differences, zero-padded."""
    for i in range(n):
        d = _fma(-2.0, b[i], c[i]) + a[i]
        buf[i] = d * d
    for i in range(n, BLOCK):
        buf[i] = 0.0
    return _reduce_nb(buf)


def _block3_nb(a: F64, b: F64, c: F64, e: F64, n: int, buf: F64) -> float:
    for i in range(n):
        d = ((e[i] - 3.0 * c[i]) + 3.0 * b[i]) - a[i]
        buf[i] = d * d
    for i in range(n, BLOCK):
        buf[i] = 0.0
    return _reduce_nb(buf)


def _sumsq_overlap_nb(buf: F64, starts: I64, win: I64, n_terms: I64, order: int,
                      totals: F64) -> None:
    """totals[t] += blocked sums of d² over the n_terms[t] terms of job t.

    Second differences: consecutive jobs t, t+1 with the same first window and
    ``win[t+1, 1] == win[t, 2]`` (τ and 2τ, as on an octave grid) are *chained*: up to three of
    them are computed in one pass over their full blocks, which reads the shared windows once.
    Every job's block sum is formed by the same operations whether chained or not.
    """
    s0 = np.empty(BLOCK)
    s1 = np.empty(BLOCK)
    s2 = np.empty(BLOCK)
    n_jobs = n_terms.size
    n_max = 0
    for t in range(n_jobs):
        n_max = max(n_max, n_terms[t])
    link = np.zeros(n_jobs, dtype=np.bool_)
    if order == 2:
        for t in range(n_jobs - 1):
            link[t] = win[t + 1, 0] == win[t, 0] and win[t + 1, 1] == win[t, 2]
    for p in range(0, n_max, BLOCK):
        t = 0
        while t < n_jobs:
            g = 1
            while g < 3 and link[t + g - 1]:
                g += 1
            full = True
            for u in range(t, t + g):
                if n_terms[u] - p < BLOCK:
                    full = False
            o0 = starts[win[t, 0]] + p
            o1 = starts[win[t, 1]] + p
            o2 = starts[win[t, 2]] + p
            if full and g == 3:
                o3 = starts[win[t + 1, 2]] + p
                o4 = starts[win[t + 2, 2]] + p
                r0, r1, r2 = _chain3_nb(buf[o0:o0 + BLOCK], buf[o1:o1 + BLOCK],
                                        buf[o2:o2 + BLOCK], buf[o3:o3 + BLOCK],
                                        buf[o4:o4 + BLOCK], s0, s1, s2)
                totals[t] += r0
                totals[t + 1] += r1
                totals[t + 2] += r2
            elif full and g == 2:
                o3 = starts[win[t + 1, 2]] + p
                r0, r1 = _chain2_nb(buf[o0:o0 + BLOCK], buf[o1:o1 + BLOCK],
                                    buf[o2:o2 + BLOCK], buf[o3:o3 + BLOCK], s0, s1)
                totals[t] += r0
                totals[t + 1] += r1
            else:
                for u in range(t, t + g):
                    n = min(BLOCK, n_terms[u] - p)
                    if n <= 0:
                        continue
                    o0 = starts[win[u, 0]] + p
                    o1 = starts[win[u, 1]] + p
                    o2 = starts[win[u, 2]] + p
                    if order == 3:
                        o3 = starts[win[u, 3]] + p
                        totals[u] += _block3_nb(buf[o0:o0 + n], buf[o1:o1 + n],
                                                buf[o2:o2 + n], buf[o3:o3 + n], n, s0)
                    elif n == BLOCK:
                        totals[u] += _chain1_nb(buf[o0:o0 + n], buf[o1:o1 + n],
                                                buf[o2:o2 + n], s0)
                    else:
                        totals[u] += _part2_nb(buf[o0:o0 + n], buf[o1:o1 + n],
                                               buf[o2:o2 + n], n, s0)
            t += g


def _sum_seq_nb(buf: F64, starts: I64, win: I64, n_terms: I64, order: int, power: int,
                acc: F64) -> None:
    """acc[t] += Σ d^power (power 1 or 2), sequentially, over the n_terms[t] terms of job t."""
    for t in range(n_terms.size):
        s0 = starts[win[t, 0]]
        s1 = starts[win[t, 1]]
        s2 = starts[win[t, 2]]
        s3 = starts[win[t, 3]] if order == 3 else 0
        a = acc[t]
        for i in range(n_terms[t]):
            if order == 2:
                d = (buf[s2 + i] - 2.0 * buf[s1 + i]) + buf[s0 + i]
            else:
                d = ((buf[s3 + i] - 3.0 * buf[s2 + i]) + 3.0 * buf[s1 + i]) - buf[s0 + i]
            if power == 2:
                a += d * d
            else:
                a += d
        acc[t] = a


def _mdev_running_nb(buf: F64, starts: I64, win: I64, n_terms: I64, v: F64,
                     totals: F64) -> None:
    """Run the modified Allan sum: v[t] += t_i, then totals[t] += v[t]², per third difference."""
    for t in range(n_terms.size):
        s0 = starts[win[t, 0]]
        s1 = starts[win[t, 1]]
        s2 = starts[win[t, 2]]
        s3 = starts[win[t, 3]]
        vv = v[t]
        tot = totals[t]
        for i in range(n_terms[t]):
            vv += ((buf[s3 + i] - 3.0 * buf[s2 + i]) + 3.0 * buf[s1 + i]) - buf[s0 + i]
            tot += vv * vv
        v[t] = vv
        totals[t] = tot


# --------------------------------------------------------------------------- numpy twins
def _phase_np(rate: F64, mean: float, dt: float, out: F64, carry: float) -> float:
    n = rate.size
    if n == 0:
        return carry
    pb = PHASE_BLOCK
    n_blocks = -(-n // pb)
    z = np.zeros(n_blocks * pb)
    np.subtract(rate, mean, out=z[:n])
    local = np.cumsum(z.reshape(n_blocks, pb), axis=1)  # sequential along each block
    ends = local[:, pb - 1] if n % pb == 0 else np.append(local[:-1, pb - 1], local[-1, n % pb - 1])
    chain = np.empty(n_blocks + 1)
    chain[0] = carry
    chain[1:] = ends
    np.add.accumulate(chain, out=chain)  # C_0 = carry, C_{b+1} = C_b + L_last(b)
    x = (chain[:-1, None] + local) * dt
    out[:] = x.reshape(-1)[:n]
    return float(chain[-1])


def _phase_local_np(rate: F64, mean: float, out: F64, ends: F64) -> None:
    n = rate.size
    if n == 0:
        return
    pb = PHASE_BLOCK
    n_blocks = -(-n // pb)
    z = np.zeros(n_blocks * pb)
    np.subtract(rate, mean, out=z[:n])
    local = np.cumsum(z.reshape(n_blocks, pb), axis=1)
    out[:] = local.reshape(-1)[:n]
    ends[:n_blocks] = local[:, pb - 1]
    if n % pb:
        ends[n_blocks - 1] = local[-1, n % pb - 1]


def _phase_fix_np(out: F64, carries: F64, dt: float) -> None:
    n = out.size
    pb = PHASE_BLOCK
    z = np.zeros(carries.size * pb)
    z[:n] = out
    out[:] = ((carries[:, None] + z.reshape(carries.size, pb)) * dt).reshape(-1)[:n]


def _diff_np(buf: F64, starts: I64, row: I64, p: int, n: int, order: int) -> F64:
    a = buf[starts[row[0]] + p:starts[row[0]] + p + n]
    b = buf[starts[row[1]] + p:starts[row[1]] + p + n]
    c = buf[starts[row[2]] + p:starts[row[2]] + p + n]
    if order == 2:
        out: F64 = (c - 2.0 * b) + a
        return out
    e = buf[starts[row[3]] + p:starts[row[3]] + p + n]
    out = ((e - 3.0 * c) + 3.0 * b) - a
    return out


def _seq_sum_np(start: float, values: F64) -> float:
    """Return start + v0 + v1 + … summed left to right (numpy's accumulate is sequential)."""
    if values.size == 0:
        return start
    acc = np.empty(values.size + 1)
    acc[0] = start
    acc[1:] = values
    return float(np.add.accumulate(acc)[-1])


def _sumsq_overlap_np(buf: F64, starts: I64, win: I64, n_terms: I64, order: int,
                      totals: F64) -> None:
    for t in range(n_terms.size):
        n = int(n_terms[t])
        if n <= 0:
            continue
        d = _diff_np(buf, starts, win[t], 0, n, order)
        n_blocks = -(-n // BLOCK)
        e = np.zeros(n_blocks * BLOCK)
        np.multiply(d, d, out=e[:n])
        e3 = e.reshape(n_blocks, BLOCK // LANES, LANES)
        acc = e3[:, 0, :].copy()
        for r in range(1, BLOCK // LANES):  # lane i: terms i, i + LANES, … in order
            acc += e3[:, r, :]
        h = LANES // 2
        while h >= 1:
            acc[:, :h] += acc[:, h:2 * h]
            h //= 2
        totals[t] = _seq_sum_np(float(totals[t]), acc[:, 0].copy())


def _sum_seq_np(buf: F64, starts: I64, win: I64, n_terms: I64, order: int, power: int,
                acc: F64) -> None:
    for t in range(n_terms.size):
        n = int(n_terms[t])
        if n <= 0:
            continue
        d = _diff_np(buf, starts, win[t], 0, n, order)
        acc[t] = _seq_sum_np(float(acc[t]), d * d if power == 2 else d)


def _mdev_running_np(buf: F64, starts: I64, win: I64, n_terms: I64, v: F64,
                     totals: F64) -> None:
    for t in range(n_terms.size):
        n = int(n_terms[t])
        if n <= 0:
            continue
        steps = _diff_np(buf, starts, win[t], 0, n, 3)
        run = np.empty(n + 1)
        run[0] = v[t]
        run[1:] = steps
        np.add.accumulate(run, out=run)
        vals = run[1:]
        totals[t] = _seq_sum_np(float(totals[t]), vals * vals)
        v[t] = run[-1]


# --------------------------------------------------------------------------- dispatch
_NUMPY: dict[str, Callable[..., Any]] = {
    "phase": _phase_np,
    "phase_local": _phase_local_np,
    "phase_fix": _phase_fix_np,
    "sumsq_overlap": _sumsq_overlap_np,
    "sum_seq": _sum_seq_np,
    "mdev_running": _mdev_running_np,
}
_STATE: dict[str, Any] = {"requested": None, "numba": None, "error": None}


def _compile_numba() -> dict[str, Callable[..., Any]] | None:
    if _STATE["numba"] is not None or _STATE["error"] is not None:
        cached: dict[str, Callable[..., Any]] | None = _STATE["numba"]
        return cached
    try:
        import numba

        jit = numba.njit(cache=True, nogil=True)
        inline = numba.njit(cache=True, nogil=True, inline="always")
        g = globals()
        # the helpers are resolved by name from this module's globals when numba compiles
        g["_fma"] = _fma_intrinsic()
        g["_tree_nb"] = inline(_tree_nb)
        g["_local8_nb"] = inline(_local8_nb)
        g["_reduce_nb"] = inline(_reduce_nb)
        for name in ("_chain1_nb", "_chain2_nb", "_chain3_nb", "_part2_nb", "_block3_nb"):
            g[name] = jit(g[name])
        kernels: dict[str, Callable[..., Any]] = {
            "phase": jit(_phase_nb),
            "phase_local": jit(_phase_local_nb),
            "phase_fix": jit(_phase_fix_nb),
            "sumsq_overlap": jit(_sumsq_overlap_nb),
            "sum_seq": jit(_sum_seq_nb),
            "mdev_running": jit(_mdev_running_nb),
        }
        _smoke_test(kernels)  # compile (or load from the cache) now, fall back on any failure
    except Exception as exc:  # pragma: no cover - depends on the environment
        _STATE["error"] = f"numba unavailable: {type(exc).__name__}: {exc}"
        return None
    _STATE["numba"] = kernels
    return kernels


def _fma_intrinsic() -> Any:
    """``_fma(a, b, c)`` = a·b + c rounded once (``llvm.fma.f64``; vectorised by LLVM).

    The kernels use it only as ``_fma(-2.0, b, c)``: 2b is exact in binary floating point, so
    this equals the numpy twin's ``c - 2.0 * b`` bit for bit (as long as 2b does not overflow,
    i.e. |b| < 2^1023, where d² would overflow anyway).
    """
    from llvmlite import ir
    from numba.core import cgutils, types
    from numba.extending import intrinsic

    @intrinsic
    def fma(typingctx: Any, a: Any, b: Any, c: Any) -> Any:
        sig = types.float64(types.float64, types.float64, types.float64)

        def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
            f64 = ir.DoubleType()
            fn = cgutils.get_or_insert_function(builder.module,
                                                ir.FunctionType(f64, [f64, f64, f64]),
                                                "llvm.fma.f64")
            return builder.call(fn, list(args))

        return sig, codegen

    return fma


def _smoke_test(kernels: dict[str, Callable[..., Any]]) -> None:
    """Run every kernel once on a small input (this triggers compilation)."""
    x = np.linspace(0.0, 1.0, 64) ** 2
    starts = np.array([0, 1, 2, 3], dtype=np.int64)
    win = np.array([[0, 1, 2, 3]], dtype=np.int64)
    n = np.array([8], dtype=np.int64)
    out = np.zeros(1)
    kernels["phase"](x, 0.5, 0.1, np.empty(64), 0.0)
    kernels["phase_local"](x, 0.5, np.empty(64), np.empty(1))
    kernels["phase_fix"](np.empty(64), np.zeros(1), 0.1)
    kernels["sumsq_overlap"](x, starts, win, n, 2, out)
    kernels["sumsq_overlap"](x, starts, win, n, 3, out)
    kernels["sum_seq"](x, starts, win, n, 2, 1, out)
    kernels["mdev_running"](x, starts, win, n, np.zeros(1), out)


def set_backend(name: str | None) -> str | None:
    """Choose the kernels: ``"numba"``, ``"numpy"`` or ``None`` (automatic); return the old choice.

    Raises
    ------
    ValueError
        For another name.
    """
    if name not in (None, "numba", "numpy"):
        raise ValueError(f"backend must be 'numba', 'numpy' or None; got {name!r}")
    old: str | None = _STATE["requested"]
    _STATE["requested"] = name
    return old


def _wanted() -> str:
    requested = _STATE["requested"]
    if requested is not None:
        return str(requested)
    env = os.environ.get("IMUCALIB_KERNELS", "").strip().lower()
    return "numpy" if env == "numpy" else "numba"


def get_kernels() -> dict[str, Callable[..., Any]]:
    """Return the kernels of the chosen backend (numba falls back to numpy if unavailable)."""
    if _wanted() == "numba":
        kernels = _compile_numba()
        if kernels is not None:
            return kernels
    return _NUMPY


def backend_name() -> str:
    """``"numba"`` or ``"numpy"``: the backend :func:`get_kernels` returns now."""
    return "numba" if get_kernels() is not _NUMPY else "numpy"
