"""P3's reduction: K2 of an accelerometer on a centrifuge whose centre moves under load.

A commercial centrifuge's rotor centre shifts with speed (dynamic unbalance): a point at static
radius r on the side the centre moves towards turns at r + c·ω², one on the far side at
r − c·ω² (c in m/(rad/s)²). The ω⁴ term this adds to an accelerometer's output is
indistinguishable from its quadratic coefficient K2 unless c is measured: two reference
accelerometers A and B at r_t/3 on opposite sides, swapped half-way, give c and their own K2;
with the test load mounted they give the loaded c′, and the test accelerometer's ω⁴ coefficient
minus c′ gives its K2 (the patent "一种基于动不平衡补偿的加速度计二次项系数精确标定方法";
docs/p3.md derives every equation). This module is the pure reduction.

Model, per accelerometer j in configuration k, with V its mean output (at rest: averaged over
the four arm positions; spinning: over whole revolutions), K1 its scale factor (from the 1 g
tumble), ω the table rate, Ω_U the vertical Earth rate, r_j its static radius and s_j = +1 on
the side the centre moves towards, −1 on the other::

    V/K1 = p0 + a + K2_j·a²,   a = x·(r_j + s_j·c_k·ω²),   x = (ω + Ω_U)² − Ω_U²         (P3.1)
         = p0 + r_j·x + (s_j·c_k + K2_j·r_j²)·x² + O(x³)                               (P3.2)

(p0 = K0/K1 plus whatever the rest records share with the spinning ones: cross-axis gravity,
the constant K2·g²·sin²θ/2 of a tilted spin axis; x·ω² = x² to 2Ω_U/ω ≈ 1e-5 of the c term).
So the x² coefficient of each series is m = s·c_k + K2·r², and its x coefficient is the
accelerometer's effective radius (it absorbs the errors of the static radius and of K1, as
IEEE Std 836 prescribes: the linear term left free). The seven series of the round-robin (A
and B before and after their swap, both with the test load, and the test accelerometer)
give::

    m1 = c + K2_A·r₁²     m2 = −c + K2_B·r₂²      (A on the test side)
    m3 = −c + K2_A·r₃²    m4 = c + K2_B·r₄²       (swapped)
    m5 = c′ + K2_A·r₅²    m6 = −c′ + K2_B·r₆²     (test load, A on the test side)
    m7 = c′ + K2_T·r₇²                                                              (P3.3)

seven equations in (K2_A, K2_B, c, c′, K2_T), r_k the series' own effective radius (so that a
reference that sits at another radius after the swap costs nothing), solved by generalised
least squares with the m's full covariance (P3.4): the noise of each series' fit and the Type B
uncertainty of each K1, which scales every m of one accelerometer alike (δm = −m·δK1/K1) and
so correlates its three series. The naive K2_T = m7/r₇² that ignores the unbalance is biased
by c′/r₇².

Precision: with five rates up to 20 g at r_t = 1 m, series means good to σ give K2_T to about
1.1e-8·σ/µg g/g² (tests/procedures/test_p3_roundrobin.py): the method's 1e-7 g/g² needs means
good to a few µg — a navigation-grade accelerometer averaged for a minute.

Each series' coefficients come from a weighted fit of V/K1 on (1, x, x²) over its rest and rate
points (:func:`fit_series`), ≥ 4 distinct rates and at least one rest point (the rate points
give x and x² with two degrees of freedom to test the fit, the rest points p0). The x³ term of
(P3.1), 2·K2·r·s·c, is left out: it biases K2_T by about 1e-9 g/g² (tests), a hundred times
below the method's claim, while fitting it would multiply the σ of m by about ten (its column
is nearly collinear with x²).

Both fits, each series' and the round-robin's GLS, are solved by
:func:`~imucalib.estimation.linear.solve_weighted_lsq` (σ per point, or the full covariance
(P3.4) by its Cholesky factor), which also makes the misfit test (Eq. (6) there).

Misfit (:func:`scale_for_misfit`): a series whose χ² exceeds its 99 % quantile has the σ of
its m scaled by its Birge ratio, every series by the Birge ratio of the pooled χ² when the pool
is a misfit; a round-robin misfit (the seven equations inconsistent beyond their σ, ν = 2)
scales the covariance of the five unknowns by its own (docs/processing-estimation.md). The
covariance before either scaling (:attr:`RoundRobinEstimate.covariance_unscaled`) is the
reported estimate's GLS operator applied to the m's covariance from the means' standard errors
and the K1's Type B σ alone.

Contents
--------
:class:`Series`, :func:`fit_series`, :class:`RoundRobinEstimate`, :func:`solve_round_robin`,
:data:`SERIES_NAMES`, :data:`PARAMETERS`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib._checks import as_array
from imucalib.errors import InsufficientExcitationError, InvalidInputError
from imucalib.estimation.linear import solve_weighted_lsq
from imucalib.models.fit_quality import FitQuality, assess_fit

__all__ = ["MIN_RATES", "PARAMETERS", "SERIES_NAMES", "RoundRobinEstimate", "Series",
           "fit_series", "scale_for_misfit", "series_covariance", "solve_round_robin"]

_F64 = NDArray[np.float64]

#: The seven series of the round-robin, in the order of (P3.3).
SERIES_NAMES: Final = ("A1", "B1", "A2", "B2", "A3", "B3", "T3")
#: The unknowns of (P3.3), in the order of :attr:`RoundRobinEstimate.values`.
PARAMETERS: Final = ("K2_A", "K2_B", "c", "c_loaded", "K2_T")
#: Distinct rates a series needs (the x and x² terms and two degrees of freedom).
MIN_RATES: Final = 4


@dataclass(frozen=True)
class Series:
    """One accelerometer's coefficients in one configuration, from :func:`fit_series`.

    Attributes
    ----------
    m : float
        The x² coefficient of V/K1, Eq. (P3.2). [m/(rad/s)²]
    m_std : float
        Its standard uncertainty: the fit's (Birge-scaled on a misfit) and the Type B σ of K1.
        [m/(rad/s)²]
    m_fit_std : float
        The fit's part alone (× `sigma_scale`). [m/(rad/s)²]
    k1_rel_std : float
        σ(K1)/K1, common to every series of the accelerometer.
    radius_m, radius_std_m : float
        The x coefficient (the effective radius) and its σ. [m]
    rest_output : float
        p0·K1, the fitted output at rest. [output unit]
    quality : FitQuality
        χ²/ν of the series' fit.
    m_noise_std, radius_noise_std_m : float
        The fit's σ of m and of the radius from the means' standard errors alone.
    sigma_scale : float
        The factor on the noise-only σ (:func:`scale_for_misfit`; 1 from :func:`fit_series`).
    """

    m: float
    m_std: float
    m_fit_std: float
    k1_rel_std: float
    radius_m: float
    radius_std_m: float
    rest_output: float
    quality: FitQuality
    m_noise_std: float = float("nan")
    radius_noise_std_m: float = float("nan")
    sigma_scale: float = 1.0

    def scaled(self, factor: float) -> Series:
        """Return the series with its noise-only σ multiplied by `factor` (≥ 1)."""
        fit = self.m_noise_std * factor
        return dataclasses.replace(
            self, m_fit_std=fit, m_std=float(np.hypot(fit, self.m * self.k1_rel_std)),
            radius_std_m=float(np.hypot(self.radius_noise_std_m * factor,
                                        self.radius_m * self.k1_rel_std)),
            sigma_scale=factor)


def fit_series(rate_rps: ArrayLike, output: ArrayLike, output_std: ArrayLike, *,
               k1: float, k1_std: float = 0.0, earth_rate_up_rps: float = 0.0,
               time_s: ArrayLike | None = None, name: str = "series") -> Series:
    """Fit V/K1 = p0 + p1·x + p2·x² over a series' rest and rate points, Eq. (P3.2).

    Parameters
    ----------
    rate_rps : array_like, shape (n,)
        The table's mean rate over each record's whole revolutions, 0 for a rest record (the
        mean over the four arm positions), signed. [rad/s]
    output, output_std : array_like, shape (n,)
        Mean output of each record and its standard error. [output unit]
    k1, k1_std : float
        Scale factor (output unit per m/s²) and its standard uncertainty.
    earth_rate_up_rps : float
        The vertical Earth rate Ω_U (x = (ω + Ω_U)² − Ω_U²). [rad/s]
    time_s : array_like, shape (n,), optional
        When each record was made: a drift linear in time is fitted too (p0 + d·(t − t̄)),
        which needs rest records before and after the rates. [s]
    name : str
        For messages and the FitQuality.

    Raises
    ------
    InsufficientExcitationError
        Fewer than :data:`MIN_RATES` distinct non-zero |rates|, or no rest record.
    InvalidInputError
        Mis-shaped or non-finite inputs, a σ ≤ 0, K1 not positive.
    """
    w = as_array(rate_rps, "rate_rps", shape=(None,))
    n = w.size
    v = as_array(output, "output", shape=(n,))
    s = as_array(output_std, "output_std", shape=(n,))
    if np.any(s <= 0):
        raise InvalidInputError(f"{name}: `output_std` must be positive")
    if not (np.isfinite(k1) and k1 > 0 and np.isfinite(k1_std) and k1_std >= 0):
        raise InvalidInputError(f"{name}: K1 must be a positive number and its σ ≥ 0; got "
                                f"{k1!r} ± {k1_std!r}")
    spinning = np.abs(w) > 0
    distinct = np.unique(np.round(np.abs(w[spinning]), 9)).size
    if distinct < MIN_RATES:
        raise InsufficientExcitationError(
            [f"{name}: m (x² coefficient)"],
            f"{name}: {distinct} distinct rate(s); the ω⁴ coefficient needs at least "
            f"{MIN_RATES} rate points (ω² and ω⁴ terms and two degrees of freedom)")
    if spinning.all():
        raise InsufficientExcitationError(
            [f"{name}: p0 (rest output)"],
            f"{name}: no rest record; the rest output (the four arm positions at ω = 0) is "
            "what the spinning outputs are measured from")
    x = (w + earth_rate_up_rps) ** 2 - earth_rate_up_rps**2
    y = v / k1
    sy = s / k1
    cols = [np.ones(n), x, x**2]
    if time_s is not None:
        t = as_array(time_s, "time_s", shape=(n,))
        rest_t = t[~spinning]
        if rest_t.size < 2 or not (rest_t.min() < t[spinning].min()
                                   and rest_t.max() > t[spinning].max()):
            raise InsufficientExcitationError(
                [f"{name}: drift"], f"{name}: a drift needs rest records before and after "
                "the rates")
        cols.append(t - t.mean())
    fit = solve_weighted_lsq(np.column_stack(cols), y, sigma=sy, group=name,
                             param_names=("p0", "radius", "m", "drift")[:len(cols)],
                             context=f"{name} series design",
                             advice="the rates do not separate the x and x² terms")
    coef, cov, quality = fit.estimate, fit.covariance_noise, fit.fit_quality
    fit_std = float(np.sqrt(cov[2, 2]))
    radius_std = float(np.sqrt(cov[1, 1]))
    rel = float(k1_std / k1)
    # a relative K1 error scales every coefficient alike (Type B): δm = −m·δK1/K1
    return Series(m=float(coef[2]), m_std=float(np.hypot(fit_std, coef[2] * rel)),
                  m_fit_std=fit_std, k1_rel_std=rel, radius_m=float(coef[1]),
                  radius_std_m=float(np.hypot(radius_std, coef[1] * rel)),
                  rest_output=float(coef[0] * k1), quality=quality, m_noise_std=fit_std,
                  radius_noise_std_m=radius_std)


def scale_for_misfit(series: Mapping[str, Series]) -> tuple[dict[str, Series], FitQuality]:
    """Scale the σ of misfit series by their Birge ratio; return them and the pooled test.

    A series is scaled by the larger of its own Birge ratio (when its own χ² is a misfit) and
    the Birge ratio of the χ² pooled over every series (when the pool is a misfit): one series
    with ν = 4 detects only gross misfit, while noise correlated from record to record (bias
    instability, random walk: means that scatter beyond their white-noise σ) raises every
    series' χ² a little, which the pool (ν = 28 for the round-robin) detects
    (docs/p3.md, "Uncertainty when the model does not fit").
    """
    pooled = assess_fit("series (pooled)", float(sum(s.quality.chi2 for s in series.values())),
                        int(sum(s.quality.dof for s in series.values())))
    out = {k: s.scaled(max(s.quality.sigma_scale, pooled.sigma_scale))
           for k, s in series.items()}
    return out, pooled


@dataclass(frozen=True)
class RoundRobinEstimate:
    """The solution of (P3.3)–(P3.4).

    Attributes
    ----------
    values : ndarray, shape (5,)
        K2_A, K2_B [1/(m/s²)], c, c′ [m/(rad/s)²], K2_T [1/(m/s²)] (:data:`PARAMETERS`).
    covariance : ndarray, shape (5, 5)
        Their covariance, Birge-scaled when the seven equations are a misfit.
    covariance_noise : ndarray, shape (5, 5)
        Before that scaling.
    quality : FitQuality
        χ² of the seven equations against the m's covariance (two degrees of freedom).
    naive_k2_t, naive_k2_t_std : float
        m7/r₇², the K2 an analysis ignoring the unbalance reports, and its σ. [1/(m/s²)]
    radii_m : ndarray, shape (7,)
        The radius of each series used in (P3.3). [m]
    covariance_unscaled : ndarray, shape (5, 5), optional
        Before any Birge scaling, neither the series' (:func:`scale_for_misfit`) nor the
        round-robin's: K·C_m⁰·Kᵀ, K = (HᵀC_m⁻¹H)⁻¹HᵀC_m⁻¹ the GLS operator of the estimate
        (C_m the m's covariance as scaled) and C_m⁰ that covariance from the series'
        noise-only σ (:func:`series_covariance` ``noise_only``); equal to `covariance_noise`
        when no series is scaled. None when a series lacks its noise-only σ (then
        :meth:`std_unscaled` gives `covariance_noise`'s).
    naive_k2_t_noise_std : float
        The naive K2_T's σ before the series' scaling. [1/(m/s²)]
    """

    values: _F64
    covariance: _F64
    covariance_noise: _F64
    quality: FitQuality
    naive_k2_t: float
    naive_k2_t_std: float
    radii_m: _F64
    covariance_unscaled: _F64 | None = None
    naive_k2_t_noise_std: float = float("nan")

    def value(self, name: str) -> float:
        """Return one parameter of :data:`PARAMETERS`."""
        return float(self.values[PARAMETERS.index(name)])

    def std(self, name: str) -> float:
        """Return one parameter's standard uncertainty."""
        i = PARAMETERS.index(name)
        return float(np.sqrt(self.covariance[i, i]))

    def std_unscaled(self, name: str) -> float:
        """Return one parameter's standard uncertainty before any Birge scaling."""
        i = PARAMETERS.index(name)
        cov = self.covariance_noise if self.covariance_unscaled is None \
            else self.covariance_unscaled
        return float(np.sqrt(cov[i, i]))


def series_covariance(series: Mapping[str, Series], *, noise_only: bool = False) -> _F64:
    """Return the 7×7 covariance of the m's of :data:`SERIES_NAMES`, Eq. (P3.4).

    Each series' fit variance on the diagonal (with `noise_only`, its noise-only one,
    ``m_noise_std``, before :func:`scale_for_misfit`); m_i·m_j·(σ(K1)/K1)² between series of
    the same accelerometer (A, B or the test one: the series' first letter).
    """
    m = np.array([series[k].m for k in SERIES_NAMES])
    fit = np.array([series[k].m_noise_std if noise_only else series[k].m_fit_std
                    for k in SERIES_NAMES])
    rel = np.array([series[k].k1_rel_std for k in SERIES_NAMES])
    same = np.array([[a[0] == b[0] for b in SERIES_NAMES] for a in SERIES_NAMES])
    return np.diag(fit**2) + np.where(same, np.outer(m * rel, m * rel), 0.0)


def solve_round_robin(series: Mapping[str, Series], *,
                      radii_m: Mapping[str, float] | None = None) -> RoundRobinEstimate:
    """Solve (P3.3) for K2_A, K2_B, c, c′ and K2_T by generalised least squares, Eq. (P3.4).

    Parameters
    ----------
    series : mapping of str to Series
        The seven series by :data:`SERIES_NAMES`.
    radii_m : mapping of str to float, optional
        The radius of each series in (P3.3) (e.g. the nominal r_t/3 and r_t, to see what the
        nominal geometry costs); default each series' own effective radius.

    Raises
    ------
    InvalidInputError
        A missing series (naming it: the swap or the test load not recorded), a radius not
        positive, a covariance that is not positive definite.
    """
    missing = [k for k in SERIES_NAMES if k not in series]
    if missing:
        raise InvalidInputError(
            f"the round-robin needs the series {list(SERIES_NAMES)}; missing {missing} (A1/B1 "
            "before the swap of A and B, A2/B2 after it, A3/B3/T3 with the test load)")
    radii = np.array([float((radii_m or {}).get(k, series[k].radius_m)) for k in SERIES_NAMES])
    bad = [k for k, r in zip(SERIES_NAMES, radii, strict=True) if not (np.isfinite(r) and r > 0)]
    if bad:
        raise InvalidInputError(f"the radii of the series {bad} must be positive [m]; got "
                                f"{[float(r) for r in radii]} (an input axis pointing outward "
                                "reads −ω²r: mount the accelerometers pointing inward)")
    r2 = radii**2
    #                K2_A   K2_B   c     c′    K2_T
    h = np.array([[r2[0], 0.0, 1.0, 0.0, 0.0],     # A1
                  [0.0, r2[1], -1.0, 0.0, 0.0],    # B1
                  [r2[2], 0.0, -1.0, 0.0, 0.0],    # A2
                  [0.0, r2[3], 1.0, 0.0, 0.0],     # B2
                  [r2[4], 0.0, 0.0, 1.0, 0.0],     # A3
                  [0.0, r2[5], 0.0, -1.0, 0.0],    # B3
                  [0.0, 0.0, 0.0, 1.0, r2[6]]])    # T3
    m = np.array([series[k].m for k in SERIES_NAMES])
    cm = series_covariance(series)
    try:
        np.linalg.cholesky(cm)  # the solver's whitening; checked here for this message
    except np.linalg.LinAlgError:
        raise InvalidInputError("the covariance of the series' ω⁴ coefficients is not positive "
                                "definite (a σ of zero?)") from None
    fit = solve_weighted_lsq(h, m, covariance=cm, param_names=PARAMETERS, group="round-robin",
                             context="round-robin design (P3.3)")
    cm0 = series_covariance(series, noise_only=True)
    unscaled: _F64 | None
    if not np.all(np.isfinite(cm0)):  # a series without its noise-only σ (built by hand)
        unscaled = None
    elif np.array_equal(cm0, cm):  # no series scaled
        unscaled = fit.covariance_noise
    else:
        cih = np.linalg.solve(cm, h)
        k = np.linalg.solve(h.T @ cih, cih.T)  # the GLS operator: values = k·m
        unscaled = k @ cm0 @ k.T
    return RoundRobinEstimate(values=fit.estimate, covariance=fit.covariance_birge,
                              covariance_noise=fit.covariance_noise, quality=fit.fit_quality,
                              naive_k2_t=float(m[6] / r2[6]),
                              naive_k2_t_std=float(np.sqrt(cm[6, 6]) / r2[6]), radii_m=radii,
                              covariance_unscaled=unscaled,
                              naive_k2_t_noise_std=float(np.sqrt(cm0[6, 6]) / r2[6]))
