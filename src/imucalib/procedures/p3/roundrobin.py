"""P3's reduction: K2 of an accelerometer on a centrifuge whose centre moves under load.

A commercial centrifuge's rotor centre shifts with speed (dynamic unbalance): a point at static
radius r on the side the centre moves towards turns at r + c·ω², one on the far side at
r − c·ω² (c in m/(rad/s)²). The ω⁴ term this adds to an accelerometer's output is
indistinguishable from its quadratic coefficient K2 unless c is measured: two reference
accelerometers A and B at r_t/3 on opposite sides, swapped half-way, give c and their own K2;
with the test load mounted they give the loaded c′, and the test accelerometer's ω⁴ coefficient
minus c′ gives its K2 (the patent "一种基于动不平衡补偿的加速度计二次项系数精确标定方法";
docs/procedures.md, "P3"). This module is the pure reduction; the equations are
docs/equations.md §7 (the centrifuge input) and the following.

Model, per accelerometer j in configuration k, with Δ the whole-revolution mean output minus the
rest mean (four arm positions), K0/K1 its bias and scale factor (known from a tumble), ω_e the
inertial spin rate (table rate plus the vertical Earth rate), r_j its static radius and s_j = +1
on the side the centre moves towards, −1 on the other::

    Δ_j(ω)/K1_j = a + K2_j·a²,   a = ω_e²·(r_j + s_j·c_k·ω_e²)                     (P3.1)
               = r_j·ω_e² + (s_j·c_k + K2_j·r_j²)·ω_e⁴ + O(ω_e⁶)                     (P3.2)

so the ω_e⁴ coefficient of each series is m = s·c_k + K2·r² (the ω_e² one absorbs radius and
scale-factor errors). The seven series of the round-robin (A and B before and after their
swap, both with the test load, and the test accelerometer) give::

    m1 = c + K2_A·r_A²     m2 = −c + K2_B·r_B²      (A on the test side)
    m3 = −c + K2_A·r_A²    m4 = c + K2_B·r_B²       (swapped)
    m5 = c′ + K2_A·r_A²    m6 = −c′ + K2_B·r_B²     (test load, A on the test side)
    m7 = c′ + K2_T·r_t²                                                             (P3.3)

seven equations in (K2_A, K2_B, c, c′, K2_T), solved by weighted least squares with the m's
covariance (P3.4); the naive K2_T = m7/r_t² that ignores the unbalance is biased by c′/r_t².

Precision: with five rates up to 20 g at r_t = 0.6 m, window means good to σ give K2_T to
about 1.1e-6·σ/µg g/g² (tests/procedures/test_p3_roundrobin.py: 0.1 µg → 1.1e-7 g/g²,
0.03 µg → 3.2e-8): the method's 1e-7 g/g² needs means good to about 0.08 µg — a navigation
accelerometer averaged over minutes at each rate.

Each series' coefficients come from a weighted fit of Δ/K1 on (ω_e², ω_e⁴) over the rate
points (:func:`fit_series`), ≥ 4 rates (two degrees of freedom test the fit). The ω_e⁶ term
of (P3.1), 2·K2·r·s·c, is left out: it biases K2_T by about 2e-9 g/g² (tests), fifty times
below the method's claim, while fitting it would multiply the σ of m by about ten (its column
is nearly collinear with ω_e⁴).

Contents
--------
:class:`Series`, :func:`fit_series`, :class:`RoundRobinEstimate`, :func:`solve_round_robin`,
:data:`SERIES_NAMES`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib._checks import as_array
from imucalib.errors import InsufficientExcitationError, InvalidInputError
from imucalib.models.fit_quality import FitQuality, assess_fit

__all__ = ["PARAMETERS", "SERIES_NAMES", "RoundRobinEstimate", "Series", "fit_series",
           "solve_round_robin"]

_F64 = NDArray[np.float64]

#: The seven series of the round-robin, in the order of (P3.3).
SERIES_NAMES: Final = ("A1", "B1", "A2", "B2", "A3", "B3", "T3")
#: The unknowns of (P3.3), in the order of :attr:`RoundRobinEstimate.values`.
PARAMETERS: Final = ("K2_A", "K2_B", "c", "c_loaded", "K2_T")
#: Rate points a series needs (two polynomial terms and two degrees of freedom).
MIN_RATES: Final = 4


@dataclass(frozen=True)
class Series:
    """One accelerometer's ω_e⁴ coefficient in one configuration, from :func:`fit_series`.

    Attributes
    ----------
    m : float
        The ω_e⁴ coefficient of Δ/K1. [m/(rad/s)²]
    m_std : float
        Its standard uncertainty (noise and the Type B σ of K1 propagated). [m/(rad/s)²]
    radius_m : float
        The ω_e² coefficient: the accelerometer's effective radius. [m]
    quality : FitQuality
        χ²/ν of the series' fit.
    """

    m: float
    m_std: float
    radius_m: float
    quality: FitQuality


def fit_series(rate_rps: ArrayLike, delta_output: ArrayLike, delta_std: ArrayLike, *,
               k1: float, k1_std: float = 0.0, earth_rate_up_rps: float = 0.0,
               name: str = "series") -> Series:
    """Fit Δ/K1 = p1·ω_e² + p2·ω_e⁴ over the rate points, Eq. (P3.2).

    Parameters
    ----------
    rate_rps : array_like, shape (n,)
        The table's mean rates over whole revolutions, n ≥ :data:`MIN_RATES`, signed. [rad/s]
    delta_output, delta_std : array_like, shape (n,)
        Output at each rate minus the rest output, and its standard error. [output unit]
    k1, k1_std : float
        Scale factor (output unit per m/s²) and its standard uncertainty.
    earth_rate_up_rps : float
        The vertical Earth rate Ω_U added to the table rate (ω_e = ω + Ω_U). [rad/s]
    name : str
        For messages and the FitQuality.

    Raises
    ------
    InsufficientExcitationError
        Fewer than :data:`MIN_RATES` distinct |rates|.
    InvalidInputError
        Mis-shaped or non-finite inputs, a σ ≤ 0, K1 not positive.
    """
    w = as_array(rate_rps, "rate_rps", shape=(None,))
    n = w.size
    d = as_array(delta_output, "delta_output", shape=(n,))
    s = as_array(delta_std, "delta_std", shape=(n,))
    if np.any(s <= 0):
        raise InvalidInputError(f"{name}: `delta_std` must be positive")
    if not (np.isfinite(k1) and k1 > 0 and np.isfinite(k1_std) and k1_std >= 0):
        raise InvalidInputError(f"{name}: K1 must be a positive number and its σ ≥ 0; got "
                                f"{k1!r} ± {k1_std!r}")
    distinct = np.unique(np.round(np.abs(w), 9)).size
    if distinct < MIN_RATES:
        raise InsufficientExcitationError(
            [f"{name}: m (ω⁴ coefficient)"],
            f"{name}: {distinct} distinct rate(s); the ω⁴ coefficient needs at least "
            f"{MIN_RATES} rate points (ω² and ω⁴ terms and two degrees of freedom)")
    we2 = (w + earth_rate_up_rps) ** 2
    y = d / k1
    sy = s / k1
    h = np.column_stack([we2, we2**2])
    scale = np.abs(h).max(axis=0)
    hw = h / scale / sy[:, None]
    coef_s, *_ = np.linalg.lstsq(hw, y / sy, rcond=None)
    cov_s = np.linalg.inv(hw.T @ hw)
    coef = coef_s / scale
    cov = cov_s / np.outer(scale, scale)
    resid = (y - h @ coef) / sy
    quality = assess_fit(name, float(resid @ resid), n - 2)
    # a relative K1 error scales every coefficient alike (Type B): δm = −m·δK1/K1
    var_m = cov[1, 1] + (coef[1] * k1_std / k1) ** 2
    return Series(m=float(coef[1]), m_std=float(np.sqrt(var_m)), radius_m=float(coef[0]),
                  quality=quality)


@dataclass(frozen=True)
class RoundRobinEstimate:
    """The solution of (P3.3)–(P3.4).

    Attributes
    ----------
    values : ndarray, shape (5,)
        K2_A, K2_B [1/(m/s²)], c, c′ [m/(rad/s)²], K2_T [1/(m/s²)] (:data:`PARAMETERS`).
    covariance : ndarray, shape (5, 5)
    quality : FitQuality
        χ² of the seven equations against the m's σ (two degrees of freedom).
    naive_k2_t : float
        m7/r_t², the K2 an analysis ignoring the unbalance reports. [1/(m/s²)]
    """

    values: _F64
    covariance: _F64
    quality: FitQuality
    naive_k2_t: float

    def value(self, name: str) -> float:
        """Return one parameter of :data:`PARAMETERS`."""
        return float(self.values[PARAMETERS.index(name)])

    def std(self, name: str) -> float:
        """Return one parameter's standard uncertainty."""
        i = PARAMETERS.index(name)
        return float(np.sqrt(self.covariance[i, i]))


def solve_round_robin(series: Mapping[str, Series], *, radius_a_m: float, radius_b_m: float,
                      radius_t_m: float) -> RoundRobinEstimate:
    """Solve (P3.3) for K2_A, K2_B, c, c′ and K2_T by weighted least squares, Eq. (P3.4).

    Parameters
    ----------
    series : mapping of str to Series
        The seven series by :data:`SERIES_NAMES`.
    radius_a_m, radius_b_m, radius_t_m : float
        Static radii of the references and the test accelerometer (positive). [m]

    Raises
    ------
    InvalidInputError
        A missing series (naming it: the swap or the test load not recorded), radii not
        positive.
    """
    missing = [k for k in SERIES_NAMES if k not in series]
    if missing:
        raise InvalidInputError(
            f"the round-robin needs the series {list(SERIES_NAMES)}; missing {missing} (A1/B1 "
            "before the swap of A and B, A2/B2 after it, A3/B3/T3 with the test load)")
    for name, r in (("radius_a_m", radius_a_m), ("radius_b_m", radius_b_m),
                    ("radius_t_m", radius_t_m)):
        if not (np.isfinite(r) and r > 0):
            raise InvalidInputError(f"`{name}` must be a positive radius [m]; got {r!r}")
    ra2, rb2, rt2 = radius_a_m**2, radius_b_m**2, radius_t_m**2
    #            K2_A   K2_B   c     c′    K2_T
    h = np.array([[ra2, 0.0, 1.0, 0.0, 0.0],    # A1
                  [0.0, rb2, -1.0, 0.0, 0.0],   # B1
                  [ra2, 0.0, -1.0, 0.0, 0.0],   # A2
                  [0.0, rb2, 1.0, 0.0, 0.0],    # B2
                  [ra2, 0.0, 0.0, 1.0, 0.0],    # A3
                  [0.0, rb2, 0.0, -1.0, 0.0],   # B3
                  [0.0, 0.0, 0.0, 1.0, rt2]])   # T3
    m = np.array([series[k].m for k in SERIES_NAMES])
    sm = np.array([series[k].m_std for k in SERIES_NAMES])
    if np.any(sm <= 0):
        raise InvalidInputError("every series needs a positive σ of its ω⁴ coefficient")
    scale = np.abs(h).max(axis=0)
    hw = h / scale / sm[:, None]
    cov_s = np.linalg.inv(hw.T @ hw)
    theta = (cov_s @ hw.T @ (m / sm)) / scale
    cov = cov_s / np.outer(scale, scale)
    resid = (m - h @ theta) / sm
    quality = assess_fit("round-robin", float(resid @ resid), len(m) - len(PARAMETERS))
    return RoundRobinEstimate(values=theta, covariance=0.5 * (cov + cov.T), quality=quality,
                              naive_k2_t=float(series["T3"].m / rt2))
