"""Equivalent degrees of freedom, χ² confidence intervals and power-law noise identification.

Contents
--------
:func:`compute_edf_greenhall`
    EDF of the Allan and Hadamard variances, overlapping or not, modified or not, for a
    power-law noise S_y(f) ∝ f^α (Greenhall and Riley's algorithm [1]_, used by NIST SP 1065 [2]_
    §5.3 and Stable32).
:func:`compute_edf_totdev`
    EDF of the total variance (NIST SP 1065 Table 7).
:func:`compute_edf`
    Either of the above for an estimator name (``"adev"``, ``"oadev"``, ``"mdev"``, ``"tdev"``,
    ``"hdev"``, ``"ohdev"``, ``"totdev"``).
:func:`compute_confidence_interval`
    χ² interval of a deviation (NIST SP 1065 eq. (45)).
:func:`identify_noise_lag1`, :class:`NoiseIdentification`
    The power-law exponent α from the lag-1 autocorrelation of τ-averages [3]_.
:data:`ONE_SIGMA`, :data:`NOISE_TYPES`

Here y is the *rate* (gyro angular rate or accelerometer specific force; the "frequency" of the
time-and-frequency literature) and x its integral, the angle or velocity (the "phase").
The IMU terms map to α: quantization ↔ +2 (white PM), angle/velocity random walk ↔ 0 (white FM),
bias instability ↔ −1 (flicker FM), rate/acceleration random walk ↔ −2 (random-walk FM).

References
----------
.. [1] C. A. Greenhall and W. J. Riley, "Uncertainty of stability variances based on finite
   differences", Proc. 35th PTTI Meeting, 2003, pp. 267–280 (eqs. (7)–(13), Tables 1–3).
.. [2] W. J. Riley, "Handbook of Frequency Stability Analysis", NIST SP 1065, 2008.
.. [3] W. J. Riley and C. A. Greenhall, "Power law noise identification using the lag 1
   autocorrelation", Proc. 18th EFTF, 2004.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import special, stats

from imucalib._checks import as_array
from imucalib.errors import InvalidInputError

__all__ = [
    "NOISE_TYPES",
    "ONE_SIGMA",
    "NoiseIdentification",
    "compute_confidence_interval",
    "compute_edf",
    "compute_edf_greenhall",
    "compute_edf_totdev",
    "identify_noise_lag1",
]

#: Probability content of ±1σ of a normal distribution, erf(1/√2) = 0.682689…
ONE_SIGMA = float(special.erf(1.0 / math.sqrt(2.0)))

#: Power-law exponent α of the rate PSD S_y(f) ∝ f^α → name (IMU term in brackets).
NOISE_TYPES: dict[int, str] = {
    2: "white angle / white PM (quantization)",
    1: "flicker angle / flicker PM",
    0: "white rate / white FM (angle or velocity random walk)",
    -1: "flicker rate / flicker FM (bias instability)",
    -2: "random-walk rate / random-walk FM (rate or acceleration random walk)",
    -3: "flicker-walk rate / flicker-walk FM",
    -4: "random-run rate / random-run FM",
}

_J_MAX = 100
# Greenhall & Riley (2003) Table 1 (modified variances), Table 2 (unmodified), rows α = 2 … −4,
# columns d = 1, 2, 3: (a0, a1); None where α + 2d ≤ 1.
_TABLE1: dict[int, tuple[tuple[float, float] | None, ...]] = {
    2: ((2 / 3, 1 / 3), (7 / 9, 1 / 2), (22 / 25, 2 / 3)),
    1: ((0.840, 0.345), (0.997, 0.616), (1.141, 0.843)),
    0: ((1.079, 0.368), (1.033, 0.607), (1.184, 0.848)),
    -1: (None, (1.048, 0.534), (1.180, 0.816)),
    -2: (None, (1.302, 0.535), (1.175, 0.777)),
    -3: (None, None, (1.194, 0.703)),
    -4: (None, None, (1.489, 0.702)),
}
_TABLE2: dict[int, tuple[tuple[float, float] | None, ...]] = {
    2: ((3 / 2, 1 / 2), (35 / 18, 1.0), (231 / 100, 3 / 2)),
    1: ((78.6, 25.2), (790.0, 410.0), (9950.0, 6520.0)),
    0: ((2 / 3, 1 / 6), (2 / 3, 1 / 3), (7 / 9, 1 / 2)),
    -1: (None, (0.852, 0.375), (0.997, 0.617)),
    -2: (None, (1.079, 0.368), (1.033, 0.607)),
    -3: (None, None, (1.053, 0.553)),
    -4: (None, None, (1.302, 0.535)),
}
_TABLE3: tuple[tuple[float, float], ...] = ((6.0, 4.0), (15.23, 12.0), (47.8, 40.0))  # α = 1
# NIST SP 1065 Table 7: total variance EDF = b·(T/τ) − c for α = 0, −1, −2.
_TOTDEV_TABLE7: dict[int, tuple[float, float]] = {0: (1.50, 0.0), -1: (1.17, 0.22),
                                                  -2: (0.93, 0.36)}
_DIFF_COEF = {1: (2.0, -1.0), 2: (6.0, -4.0, 1.0), 3: (20.0, -15.0, 6.0, -1.0)}


def _sw(t: NDArray[np.float64], alpha: int) -> NDArray[np.float64]:
    """Generalised autocovariance of the twice-integrated phase, eq. (7) of [1] (up to sign).

    Even α: ±|t|^(3−α); odd α: ±t^(3−α)·ln|t| (0 at t = 0); only the requested term is computed.
    """
    a = np.abs(t)
    power = 3 - alpha
    sign = 1.0 if alpha in (0, -4, 1, -3) else -1.0
    if alpha % 2 == 0:
        out: NDArray[np.float64] = a**power if sign > 0 else -(a**power)
        return out
    with np.errstate(divide="ignore", invalid="ignore"):
        log = np.where(a > 0, np.log(np.where(a > 0, a, 1.0)), 0.0)
    out = t**power * log if sign > 0 else -(t**power) * log
    return out


def _sx(t: NDArray[np.float64], big_f: float, alpha: int) -> NDArray[np.float64]:
    """Phase autocovariance after the filter of factor F (eq. (8) of [1]); F = ∞ allowed."""
    if math.isinf(big_f):
        return _sw(t, alpha + 2)
    return big_f**2 * (2 * _sw(t, alpha) - _sw(t - 1 / big_f, alpha) - _sw(t + 1 / big_f, alpha))


def _sz(t: NDArray[np.float64] | float, big_f: float, alpha: int, d: int) -> NDArray[np.float64]:
    """Autocovariance of the d-th difference at lag t·τ (eq. (9) of [1])."""
    tt = np.asarray(t, dtype=np.float64)
    coef = _DIFF_COEF[d]
    out = coef[0] * _sx(tt, big_f, alpha)
    for k, c in enumerate(coef[1:], start=1):
        out = out + c * (_sx(tt - k, big_f, alpha) + _sx(tt + k, big_f, alpha))
    return out


def _basic_sum(j: int, big_m: float, s: float, big_f: float, alpha: int, d: int) -> float:
    """Eq. (10) of [1]: sz(0)² + 2Σ_{k<J}(1 − k/M)·sz(k/S)² + (1 − J/M)·sz(J/S)²."""
    k = np.arange(1, j)
    inner = float(np.sum((1 - k / big_m) * _sz(k / s, big_f, alpha, d) ** 2))
    first = float(_sz(0.0, big_f, alpha, d)) ** 2
    last = (1 - j / big_m) * float(_sz(j / s, big_f, alpha, d)) ** 2
    return first + 2 * inner + last


def _white_pm_inverse_edf(d: int, big_m: float, r: float) -> float:
    """Return 1/edf for white phase noise (α = 2), unmodified variance (case 4 of [1]).

    The d-th differences of white phase correlate only at lags k·S (k ≤ d), with
    ρ_k = (−1)^k·C(2d, d+k)/C(2d, d). Summing over the pairs gives
    (1/M)·Σ_{|k|<r} (1 − |k|/r)·ρ_k², which is (a0 − a1/r)/M with a0 = C(4d,2d)/C(2d,d)²,
    a1 = d/2 when r > d.
    """
    norm = special.comb(2 * d, d, exact=True)
    total = 1.0
    for k in range(1, d + 1):
        if k >= r:
            break
        rho = special.comb(2 * d, d + k, exact=True) / norm
        total += 2 * (1 - k / r) * rho**2
    return total / big_m


@functools.lru_cache(maxsize=4096)
def compute_edf_greenhall(alpha: int, order: int, m: int, n_phase: int, *, overlapping: bool,
                          modified: bool) -> float:
    """Equivalent degrees of freedom of a difference variance for power-law noise.

    A pure function of its arguments, remembered: the channels of one record (and the records
    of one length) ask for the same (α, m, N) again.

    Parameters
    ----------
    alpha : int
        Exponent of the rate PSD S_y ∝ f^α, −4 … 2, with α + 2·order > 1.
    order : int
        Order d of the phase difference: 2 Allan, 3 Hadamard (1 also accepted).
    m : int
        Averaging factor, τ = m·τ0.
    n_phase : int
        Number of phase points (rate samples + 1).
    overlapping : bool
        Stride τ0 (overlapping, S = m) instead of τ (S = 1).
    modified : bool
        Modified variance (phase averaged over τ, F = 1) instead of unmodified (F = m).

    Returns
    -------
    float
        The EDF, to be used as the χ² degrees of freedom of ν·σ̂²/σ².

    Raises
    ------
    InvalidInputError
        If α + 2·order ≤ 1, α or order out of range, or the record has no complete term.

    Notes
    -----
    Greenhall and Riley's algorithm [1]_: L = m/F + m·d, M = 1 + ⌊S(N − L)/m⌋,
    J = min(M, (d + 1)·S), r = M/S; exact sums (eq. (10)) while J ≤ 100, otherwise the
    asymptotic forms 1/edf = (a0 − a1/r)/r (Tables 1–3) or the reduced sum with m' = 100/r.
    """
    if alpha not in _TABLE1 or order not in (1, 2, 3):
        raise InvalidInputError(f"`alpha` must be an integer in −4 … 2 and `order` 1, 2 or 3; "
                                f"got alpha={alpha!r}, order={order!r}")
    if alpha + 2 * order <= 1:
        raise InvalidInputError(f"the order-{order} variance is not defined for alpha={alpha} "
                                f"(needs alpha + 2·order > 1)")
    d = order
    big_f = 1.0 if modified else float(m)
    s = float(m) if overlapping else 1.0
    length = m / big_f + m * d
    big_m = 1 + math.floor(s * (n_phase - length) / m)
    if big_m < 1:
        raise InvalidInputError(f"no complete term: m={m} needs more than {length:g} phase points; "
                                f"got {n_phase}")
    j = int(min(big_m, (d + 1) * s))
    r = big_m / s
    if modified:
        s0 = float(_sz(0.0, 1.0, alpha, d)) ** 2
        if j <= _J_MAX:
            inv = _basic_sum(j, big_m, s, 1.0, alpha, d) / (s0 * big_m)
        elif r > d + 1:
            a0, a1 = _TABLE1[alpha][d - 1]  # type: ignore[misc]
            inv = (a0 - a1 / r) / r
        else:
            m_p = _J_MAX / r
            inv = _basic_sum(_J_MAX, _J_MAX, m_p, 1.0, alpha, d) / (s0 * _J_MAX)
    elif alpha <= 0:
        if j <= _J_MAX:
            f_p = float(m) if m * (d + 1) <= _J_MAX else math.inf
            s0 = float(_sz(0.0, f_p, alpha, d)) ** 2
            inv = _basic_sum(j, big_m, s, f_p, alpha, d) / (s0 * big_m)
        elif r > d + 1:
            a0, a1 = _TABLE2[alpha][d - 1]  # type: ignore[misc]
            inv = (a0 - a1 / r) / r
        else:
            m_p = _J_MAX / r
            s0 = float(_sz(0.0, math.inf, alpha, d)) ** 2
            inv = _basic_sum(_J_MAX, _J_MAX, m_p, math.inf, alpha, d) / (s0 * _J_MAX)
    elif alpha == 1:
        b0, b1 = _TABLE3[d - 1]
        if j <= _J_MAX:
            s0 = float(_sz(0.0, float(m), 1, d)) ** 2
            inv = _basic_sum(j, big_m, s, float(m), 1, d) / (s0 * big_m)
        elif r > d + 1:
            a0, a1 = _TABLE2[1][d - 1]  # type: ignore[misc]
            inv = (a0 - a1 / r) / ((b0 + b1 * math.log(m)) ** 2 * r)
        else:
            m_p = _J_MAX / r
            inv = (_basic_sum(_J_MAX, _J_MAX, m_p, m_p, 1, d)
                   / ((b0 + b1 * math.log(m)) ** 2 * _J_MAX))
    else:  # alpha == 2, unmodified
        inv = _white_pm_inverse_edf(d, big_m, r)
    return 1.0 / inv


def compute_edf_totdev(alpha: int, m: int, n_phase: int) -> float:
    """EDF of the total variance: b·(T/τ) − c (NIST SP 1065 Table 7) for α = 0, −1, −2.

    T/τ = (n_phase − 1)/m. For other α the overlapping-Allan EDF of
    :func:`compute_edf_greenhall` is returned (the total variance has at least as many degrees
    of freedom; SP 1065 gives no table for them). Raises InvalidInputError for m < 1.
    """
    if m < 1:
        raise InvalidInputError(f"`m` must be ≥ 1; got {m}")
    if alpha in _TOTDEV_TABLE7:
        b, c = _TOTDEV_TABLE7[alpha]
        return max(b * (n_phase - 1) / m - c, 1.0)
    return compute_edf_greenhall(max(alpha, -2), 2, m, n_phase, overlapping=True, modified=False)


def compute_edf(kind: str, alpha: int, m: int, n_phase: int) -> float:
    """EDF of estimator `kind` (see module docstring) at averaging factor `m`.

    α is clipped into the range where the variance converges (≥ −2 for the Allan family,
    ≥ −4 for Hadamard). Raises InvalidInputError for an unknown kind.
    """
    if kind in ("adev", "oadev", "mdev", "tdev", "totdev"):
        alpha = int(min(max(alpha, -2), 2))
    elif kind in ("hdev", "ohdev"):
        alpha = int(min(max(alpha, -4), 2))
    else:
        raise InvalidInputError(f"unknown deviation kind {kind!r}")
    if kind == "totdev":
        return compute_edf_totdev(alpha, m, n_phase)
    order = 3 if kind in ("hdev", "ohdev") else 2
    return compute_edf_greenhall(alpha, order, m, n_phase,
                                 overlapping=kind not in ("adev", "hdev"),
                                 modified=kind in ("mdev", "tdev"))


def compute_confidence_interval(deviation: ArrayLike, edf: ArrayLike,
                                confidence: float = ONE_SIGMA
                                ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Two-sided χ² interval of a deviation σ̂ with `edf` degrees of freedom.

    σ² lies in [ν·σ̂²/χ²_{(1+p)/2}(ν), ν·σ̂²/χ²_{(1−p)/2}(ν)] with probability p = `confidence`
    (NIST SP 1065 eq. (45)); the interval of σ is its square root.

    Returns
    -------
    (low, high) : ndarray
        Same shape as `deviation`, same units.

    Raises
    ------
    InvalidInputError
        If `confidence` is not in (0, 1) or an edf is not > 0.
    """
    if not 0.0 < confidence < 1.0:
        raise InvalidInputError(f"`confidence` must be in (0, 1); got {confidence!r}")
    dev = np.asarray(deviation, dtype=np.float64)
    nu = np.asarray(edf, dtype=np.float64)
    if np.any(~(nu > 0)):
        raise InvalidInputError(f"`edf` must be > 0; got minimum {float(np.min(nu))!r}")
    hi_q = stats.chi2.ppf((1 + confidence) / 2, nu)
    lo_q = stats.chi2.ppf((1 - confidence) / 2, nu)
    return dev * np.sqrt(nu / hi_q), dev * np.sqrt(nu / lo_q)


@dataclass(frozen=True)
class NoiseIdentification:
    """Result of :func:`identify_noise_lag1`."""

    alpha: int  # dominant power-law exponent of the rate PSD
    alpha_estimate: float  # the continuous estimate −2(δ + d)
    n_differences: int  # d
    rho: float  # δ = r1/(1 + r1)
    n_points: int  # τ-averages used


def _lag1(z: NDArray[np.float64]) -> float:
    z = z - z.mean()
    den = float(np.dot(z, z))
    return float(np.dot(z[:-1], z[1:]) / den) if den > 0 else 0.0


def _detrended(z: NDArray[np.float64]) -> NDArray[np.float64]:
    """Return z minus its least-squares straight line on the index 0 … n − 1.

    In closed form on centred data (k̄ = (n − 1)/2 exactly): b̂ = Σ(k − k̄)(z − z̄)/Σ(k − k̄)²,
    the line z̄ + b̂·(k − k̄). ``np.polyfit``'s Vandermonde matrix and SVD give the same line to
    rounding (the residuals' last bits: ρ moves by ~1e-13, α, an integer, not at all) at four
    times the cost; an Allan record identifies 90 τ-averages series, a tenth of its analysis.
    """
    dk = np.arange(z.size, dtype=np.float64) - (z.size - 1) / 2.0
    z_bar = float(z.mean())
    slope = float(dk @ (z - z_bar)) / float(dk @ dk)
    return np.asarray(z - (z_bar + slope * dk), dtype=np.float64)


def identify_noise_lag1(averages: ArrayLike, *, max_differences: int = 2,
                        min_points: int = 30) -> NoiseIdentification:
    """Identify the dominant power-law noise of consecutive τ-averages of the rate.

    The averages are detrended (straight line), then differenced until the lag-1 autocorrelation
    r1 gives δ = r1/(1 + r1) < 0.25 or `max_differences` is reached; α = −2(δ + d), rounded to
    −round(2δ) − 2d ([3]_, for frequency data). Use `max_differences` = 2 for the Allan family
    and 3 for Hadamard.

    Raises
    ------
    InvalidInputError
        Fewer than `min_points` averages (30 per [3]_), or non-finite values.
    """
    z = as_array(averages, "averages", shape=(None,))
    if z.size < min_points:
        raise InvalidInputError(f"noise identification needs at least {min_points} τ-averages; "
                                f"got {z.size}")
    n_points = int(z.size)
    z = _detrended(z)
    d = 0
    while True:
        r1 = _lag1(z)
        delta = r1 / (1 + r1)
        if delta < 0.25 or d >= max_differences:
            alpha = int(-round(2 * delta) - 2 * d)
            return NoiseIdentification(alpha, -2 * (delta + d), d, delta, n_points)
        z = np.diff(z)
        d += 1
