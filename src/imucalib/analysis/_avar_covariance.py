"""Covariance matrix of overlapping Allan-variance estimates for a noise model (private).

The estimates at τ_i = m_i·τ0 are σ̂²_i = Σ_k Δ_i(k)²/(2τ_i²·n_i), Δ_i(k) the second
difference x[k+2m_i] − 2x[k+m_i] + x[k] of the phase (angle), n_i = n − 2m_i terms. For Gaussian
noise plus a deterministic ramp (which adds μ_i = R·τ_i² to every Δ_i)

    Cov(σ̂²_i, σ̂²_j) = [2·Σ_h w_ij(h)·g_ij(h)² + 4·μ_i·μ_j·Σ_h w_ij(h)·g_ij(h)] / (4τ_i²τ_j²n_i n_j)

where g_ij(h) = Cov(Δ_i(k), Δ_j(k+h)) and w_ij(h) counts the pairs (k, k+h) in range (the
double sum over k, l grouped by lag; Isserlis' theorem for the fourth moments). With the phase
generalised autocovariance R(t) of each noise term [1]_ (second differences cancel the
polynomial ambiguity), g_ij(h) = Σ_{a,b} c_a·c_b·R((h + b·m_j − a·m_i)·τ0), c = (1, −2, 1):

=====================  =====================================  ==================================
term (coefficient)     R(t), unit coefficient                 AVAR (check)
=====================  =====================================  ==================================
quantization (Q²)      δ(t) (white angle, discrete)           3Q²/τ²
white rate (N²)        −|t|/2                                 N²/τ
flicker rate (B²)      t²·ln|t|/(2π)                          (2 ln 2/π)·B²
random-walk rate (K²)  |t|³/12                                K²τ/3
Markov (σ², T_c)       −(T_c|t| − T_c²(1 − e^(−|t|/T_c)))      docs/equations.md §8
=====================  =====================================  ==================================

g is linear in the coefficients, so the lag sums Σ w·g^p·g^q and Σ w·g^p are computed once
per τ grid (:class:`CovarianceBasis`) and the matrix for any coefficients is a weighted sum.
Lags are summed exactly when m_i + m_j ≤ 128; otherwise the sum is replaced by the integral over
the lag (Gauss–Legendre between the kinks of w and g), evaluated in units of max(m_i, m_j) using
the scale invariance of the power laws (R(λt) = λ^γ·R(t) up to a cancelled polynomial), which
avoids cancellation. The flicker term's tail is cut at 64·(m_i + m_j) (relative error < 1e-4).
The quantization term is a set of spikes at h = a·m_i − b·m_j, always summed exactly.

References
----------
.. [1] C. A. Greenhall and W. J. Riley, "Uncertainty of stability variances based on finite
   differences", Proc. 35th PTTI Meeting, 2003 (generalised autocovariances, eq. (7)).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

__all__ = ["COMPONENTS", "CovarianceBasis", "covariance_basis", "markov_r"]

F64 = NDArray[np.float64]
#: Continuous components and their scaling exponent γ (R(λt) = λ^γ R(t) + polynomial).
_GAMMA = {"N": 1, "B": 2, "K": 3}
COMPONENTS = ("Q", "N", "B", "K")
_C = np.array([1.0, -2.0, 1.0])
_EXACT_LIMIT = 128
_TAIL = 64.0
_GL_X, _GL_W = np.polynomial.legendre.leggauss(12)


def _r(comp: str, t: F64) -> F64:
    a = np.abs(t)
    if comp == "N":
        return -a / 2
    if comp == "K":
        out: F64 = a**3 / 12
        return out
    # flicker
    with np.errstate(divide="ignore", invalid="ignore"):
        log = np.where(a > 0, np.log(np.where(a > 0, a, 1.0)), 0.0)
    out = t * t * log / (2 * math.pi)
    return out


def markov_r(t_s: F64, tc_s: float) -> F64:
    """Phase generalised autocovariance of a unit-variance Gauss–Markov rate [s²]."""
    a = np.abs(t_s)
    out: F64 = -(tc_s * a + tc_s**2 * np.expm1(-a / tc_s))
    return out


def _combos(mi: float, mj: float) -> tuple[F64, F64]:
    """Shifts b·m_j − a·m_i and weights c_a·c_b of the nine terms of g."""
    a = np.arange(3)[:, None]
    b = np.arange(3)[None, :]
    shift = (b * mj - a * mi).ravel().astype(np.float64)
    weight = (_C[:, None] * _C[None, :]).ravel()
    return shift, weight


def _g(comp: str, lag: F64, mi: float, mj: float, scale_s: float, tc_s: float = 0.0) -> F64:
    """Return g for a unit coefficient at lags `lag` (lag units: factors are mi, mj).

    The result is in seconds to the power γ: `scale_s` is the length of one lag unit [s].
    """
    shift, weight = _combos(mi, mj)
    t = lag[:, None] + shift[None, :]
    if comp == "M":
        vals = markov_r(t * scale_s, tc_s)
        out: F64 = vals @ weight
        return out
    return (_r(comp, t) @ weight) * scale_s ** _GAMMA[comp]


def _w(lag: F64, ni: int, nj: int) -> F64:
    """Pairs (k, k + h) with 0 ≤ k < n_i, 0 ≤ k + h < n_j."""
    out: F64 = np.maximum(0.0, np.minimum(ni, nj - lag) - np.maximum(0.0, -lag))
    return out


def _spikes(mi: int, mj: int) -> tuple[NDArray[np.int64], F64]:
    """Lags h = a·m_i − b·m_j and g^Q(h) = Σ c_a c_b over the (a, b) that give h."""
    vals: dict[int, float] = {}
    for a in range(3):
        for b in range(3):
            h = a * mi - b * mj
            vals[h] = vals.get(h, 0.0) + _C[a] * _C[b]
    lags = np.array(sorted(vals), dtype=np.int64)
    return lags, np.array([vals[int(h)] for h in lags])


def _nodes(mi: int, mj: int, ni: int, nj: int, tail: float) -> tuple[F64, F64, float]:
    """Lag nodes and weights (in units of s = max(m_i, m_j) lags) for the integral, and s."""
    s = float(max(mi, mj))
    ai, bj = mi / s, mj / s
    lo, hi = -2 * bj - tail, 2 * ai + tail
    lo, hi = max(lo, -ni / s), min(hi, nj / s)
    brk = {lo, hi}
    for a in range(3):
        for b in range(3):
            brk.add(a * ai - b * bj)
    brk |= {-ni / s, 0.0, (nj - ni) / s, nj / s}
    core_lo, core_hi = max(lo, -2 * bj), min(hi, 2 * ai)
    step = 1.0
    edge = core_hi
    while edge + step < hi:  # geometric tail intervals
        brk.add(edge + step)
        step *= 2
    step = 1.0
    edge = core_lo
    while edge - step > lo:
        brk.add(edge - step)
        step *= 2
    pts = np.array(sorted(b for b in brk if lo <= b <= hi))
    left, right = pts[:-1], pts[1:]
    half = (right - left)[:, None] / 2
    x = (left[:, None] + right[:, None]) / 2 + half * _GL_X[None, :]
    wts = half * _GL_W[None, :]
    return x.ravel(), wts.ravel(), s


@dataclass(frozen=True, eq=False)
class CovarianceBasis:
    """Lag sums for one τ grid: ``cross[(p, q)]`` = Σ w·g^p·g^q, ``linear[p]`` = Σ w·g^p.

    Components p: ``"Q"``, ``"N"``, ``"B"``, ``"K"`` and, when built with a Markov time constant,
    ``"M"``. Matrices are (n_tau, n_tau).
    """

    ms: tuple[int, ...]
    n_phase: int
    tau0_s: float
    markov_tc_s: float
    cross: dict[tuple[str, str], F64] = field(repr=False)
    linear: dict[str, F64] = field(repr=False)

    def covariance(self, amplitudes: dict[str, float], ramp: float = 0.0) -> F64:
        """Return Cov(σ̂²_i, σ̂²_j) for the given amplitudes and ramp.

        `amplitudes` maps "Q", "N", "B", "K" ("M") to Q², N², B², K² (σ_M²) in SI; `ramp` is R
        [rate/s].
        """
        ms = np.array(self.ms, dtype=np.float64)
        tau = ms * self.tau0_s
        n = self.n_phase - 2 * ms
        acc = np.zeros((ms.size, ms.size))
        comps = [p for p in self.linear if amplitudes.get(p, 0.0) != 0.0]
        for p in comps:
            for q in comps:
                key = (p, q) if (p, q) in self.cross else (q, p)
                acc += 2 * amplitudes[p] * amplitudes[q] * self.cross[key]
        if ramp:
            mu = ramp * tau**2
            lin = sum((amplitudes[p] * self.linear[p] for p in comps), np.zeros_like(acc))
            acc += 4 * np.outer(mu, mu) * lin
        scale = 4 * np.outer(tau**2, tau**2) * np.outer(n, n)
        out: F64 = acc / scale
        return out


def _pair_sums(mi: int, mj: int, ni: int, nj: int, tau0: float, comps: tuple[str, ...],
               tc_s: float) -> tuple[dict[tuple[str, str], float], dict[str, float]]:
    tail = _TAIL if ("B" in comps or "M" in comps) else 0.0
    if mi + mj <= _EXACT_LIMIT:
        span_tail = int(tail * (mi + mj))
        if "M" in comps:  # the Markov tail ~ e^(−|h|τ0/T_c), capped (small τ: ≪ other terms)
            span_tail = max(span_tail, min(int(30 * tc_s / tau0), 4096))
        lo = max(-2 * mj - span_tail, -ni + 1)
        hi = min(2 * mi + span_tail, nj - 1)
        lag = np.arange(lo, hi + 1, dtype=np.float64)
        wts = np.ones_like(lag)
        unit, scale = 1.0, tau0
        gi, gj = float(mi), float(mj)
    else:
        extra = tail
        if "M" in comps:
            extra = max(extra, 30 * tc_s / (tau0 * max(mi, mj)))
        lag, wts, unit = _nodes(mi, mj, ni, nj, extra)
        scale = unit * tau0
        gi, gj = mi / unit, mj / unit
    w = _w(lag * unit, ni, nj) * wts * unit
    cont = [p for p in comps if p != "Q"]
    g = {p: _g(p, lag, gi, gj, scale, tc_s) for p in cont}
    cross: dict[tuple[str, str], float] = {}
    linear: dict[str, float] = {}
    for x, p in enumerate(cont):
        linear[p] = float(np.sum(w * g[p]))
        for q in cont[x:]:
            cross[(p, q)] = float(np.sum(w * g[p] * g[q]))
    if "Q" in comps:
        lags, gq = _spikes(mi, mj)
        ws = _w(lags.astype(np.float64), ni, nj)
        linear["Q"] = float(np.sum(ws * gq))
        cross[("Q", "Q")] = float(np.sum(ws * gq * gq))
        for p in cont:
            if mi + mj <= _EXACT_LIMIT:
                gp = _g(p, lags.astype(np.float64), float(mi), float(mj), tau0, tc_s)
            else:
                u = float(max(mi, mj))
                gp = _g(p, lags / u, mi / u, mj / u, u * tau0, tc_s)
            cross[("Q", p)] = float(np.sum(ws * gq * gp))
    return cross, linear


@lru_cache(maxsize=64)
def covariance_basis(ms: tuple[int, ...], n_phase: int, tau0_s: float,
                     markov_tc_s: float = 0.0) -> CovarianceBasis:
    """Build (and cache) the lag sums of the τ grid `ms` for a record of `n_phase` points."""
    comps: tuple[str, ...] = COMPONENTS + (("M",) if markov_tc_s > 0 else ())
    k = len(ms)
    cross: dict[tuple[str, str], F64] = {}
    linear: dict[str, F64] = {p: np.zeros((k, k)) for p in comps}
    for i in range(k):
        for j in range(i, k):
            ni, nj = n_phase - 2 * ms[i], n_phase - 2 * ms[j]
            c, lin = _pair_sums(ms[i], ms[j], ni, nj, tau0_s, comps, markov_tc_s)
            for key, v in c.items():
                mat = cross.setdefault(key, np.zeros((k, k)))
                mat[i, j] = mat[j, i] = v
            for p, v in lin.items():
                linear[p][i, j] = linear[p][j, i] = v
    return CovarianceBasis(tuple(ms), n_phase, tau0_s, markov_tc_s, cross, linear)
