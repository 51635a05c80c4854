"""Temperature models of calibration parameters: GLS fit, order choice, held-out check.

A calibration parameter (a bias, a scale factor, …) estimated at K soak temperatures T_k gives
estimates p_k with a covariance C (K×K, correlated across temperatures when the estimates share
reference data or slowly varying noise). This module fits the model of
:mod:`imucalib.models.temperature` (docs/equations.md §4; IEEE Std 952-1997 and IEEE Std
1293-2018 temperature terms; the thermal calibration of Aggarwal et al. 2008) to them, with
uncertainty, and chooses the polynomial order by a stated criterion. The equations are those of
docs/processing-estimation.md, "Temperature models".

Equations
---------
Model, with T0 the reference temperature, m the order, optional rate and leg terms::

    p(T, Ṫ, ℓ) = Σ_{j=0..m} c_j (T − T0)^j + d·Ṫ + h·ℓ,   ℓ = +1 heating, −1 cooling      (1)

Generalised least squares with C = L Lᵀ (Cholesky), design A (rows a_kᵀ of Eq. (1)), β the
q = m + 1 (+1 rate) (+1 leg) coefficients, by :func:`~imucalib.estimation.linear.solve_weighted_lsq`
(full C); computed on the scaled variable x = (T − T0)/s::

    β̂ = argmin ‖L⁻¹(p − Aβ)‖²,  C_β = (Aᵀ C⁻¹ A)⁻¹                                        (2)
    χ² = (p − Aβ̂)ᵀ C⁻¹ (p − Aβ̂),  ν = K − q                                               (3)

Weighted least squares with weights V ≠ C (`weights`: a caller whose estimator is fixed, such
as P2's, docs/p2.md "Temperature models"): the estimate keeps V's gain W and its covariance is
the sandwich under the estimates' true C (Huber 1967; White 1980, *Econometrica* 48:817)::

    β̂ = W·p,  W = (Aᵀ V⁻¹ A)⁻¹ Aᵀ V⁻¹,  C_β = W C Wᵀ                                       (2b)
    χ² = min_β (p − Aβ)ᵀ C⁻¹ (p − Aβ) = rᵀ M r,  M = C⁻¹ − C⁻¹A(AᵀC⁻¹A)⁻¹AᵀC⁻¹               (3b)

for any residual r = p − Aβ̂ (M·A = 0): the GLS χ² of Eq. (3), χ²_ν distributed under C
whatever the estimator, so the order choice (6), (9) and the misfit test use C in both cases.
    c_j = b_j / s^j  (b_j the coefficient of x^j);  C_c = S C_b S,  S = diag(s^−j)          (4)
    p̂(T) = aᵀ β̂,  σ_pred² = aᵀ C_β a                                                       (5)

Order choice over m = 0 … m_max (Akaike 1974; Hurvich and Tsai 1989 for the small-sample
correction; −2 log L = χ² + const for Gaussian noise of known C)::

    AICc(m) = χ² + 2q + 2q(q + 1)/(K − q − 1)   (∞ when K − q − 1 ≤ 0)                       (6)

Leave-one-temperature-out cross-validation (Hastie, Tibshirani and Friedman, *The Elements of
Statistical Learning*, 2nd ed., §7.10): for each k, fit on the other points (their covariance
C₋ₖ) and predict p_k by the best linear unbiased predictor given the others' residuals
(Goldberger 1962), which accounts for the correlation of p_k with them; the score is the sum
of the whitened prediction errors::

    e_k = p_k − a_kᵀβ̂₋ₖ − C_{k,−k} C₋ₖ⁻¹ (p₋ₖ − A₋ₖ β̂₋ₖ)                                   (7)
    v_k = C_kk − C_{k,−k} C₋ₖ⁻¹ C_{−k,k} + g_kᵀ C_β,₋ₖ g_k,  g_k = a_k − A₋ₖᵀ C₋ₖ⁻¹ C_{−k,k}   (8)
    CV(m) = Σ_k e_k² / v_k   (≈ K for a right model)                                        (9)

A misfit (χ² above its 99 % quantile, :func:`imucalib.models.fit_quality.assess_fit`) scales
C_β by the Birge ratio squared R_B² = χ²/ν (docs/processing-estimation.md, "Goodness of fit").

Held-out check at temperatures not used in the fit, with estimates of standard deviation σ_i::

    z_i = (p̂(T_i) − p_i) / √(σ_pred,i² + σ_i²)                                               (10)
    χ²_h = rᵀ (A_h C_β A_hᵀ + diag σ²)⁻¹ r,  r = p̂ − p,  ν_h = n_h;  consistent ⇔
        max|z_i| ≤ 3 and P(χ²_{ν_h} ≥ χ²_h) ≥ 0.01                                          (11)

Contents
--------
:class:`TemperaturePolynomial` (the model of Eq. (1)), :class:`TemperatureModelFit`,
:func:`fit_temperature_model`, :func:`predict_temperature_model` (→
:class:`TemperaturePrediction`), :func:`check_held_out` (→ :class:`HeldOutCheck`). The fitted
models in the twin's and a result's forms: :mod:`imucalib.estimation.temperature_forms`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Final, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import stats

from imucalib._checks import as_array, check_finite_scalar
from imucalib.errors import InsufficientExcitationError, InvalidInputError
from imucalib.estimation._common import Whitener, make_whitener
from imucalib.estimation.linear import _solve_known, solve_weighted_lsq
from imucalib.models.fit_quality import FitQuality, assess_fit

__all__ = [
    "DEFAULT_MAX_ORDER",
    "HeldOutCheck",
    "TemperatureModelFit",
    "TemperaturePolynomial",
    "TemperaturePrediction",
    "check_held_out",
    "fit_temperature_model",
    "gls_weights",
    "predict_temperature_model",
]

#: The highest polynomial order tried by default, Eq. (6)/(9).
DEFAULT_MAX_ORDER: Final = 3
#: Condition number of the column-scaled whitened design above which it counts as singular.
_COND_LIMIT: Final = 1e10

Criterion = Literal["aicc", "cv"]


@dataclass(frozen=True)
class TemperaturePolynomial:
    """The model of Eq. (1): p(T, Ṫ, ℓ) = Σ c_j (T − T0)^j + d·Ṫ + h·ℓ.

    Attributes
    ----------
    reference_temperature_degc : float
        T0. [°C]
    coefficients : tuple of float
        c_0 … c_m; c_j in the parameter's unit per °C^j (c_0 is the value at T0).
    rate_coefficient : float or None
        d, in the parameter's unit per (°C/s); None when the model has no rate term.
    leg_coefficient : float or None
        h, half the heating − cooling difference (ℓ = ±1), in the parameter's unit; None when
        the model has no hysteresis term.
    """

    reference_temperature_degc: float
    coefficients: tuple[float, ...]
    rate_coefficient: float | None = None
    leg_coefficient: float | None = None

    @property
    def order(self) -> int:
        """m, the polynomial order."""
        return len(self.coefficients) - 1


@dataclass(frozen=True)
class TemperatureModelFit:
    """A GLS fit of Eq. (1) with its chosen order, Eqs. (2)–(9).

    Attributes
    ----------
    name : str
        The parameter's name.
    model : TemperaturePolynomial
        The fitted coefficients (c_j about T0, d, h).
    covariance : numpy.ndarray, shape (q, q)
        C_β of Eq. (4) (the sandwich of Eq. (2b) when the fit had `weights`) from the
        estimates' covariance alone, ordered c_0 … c_m, d, h (the terms present).
    covariance_scaled : numpy.ndarray, shape (q, q)
        R_B²·C_β when the fit is a misfit, else equal to `covariance`.
    chi2 : float
        χ² of Eq. (3) (Eq. (3b) with `weights`: the GLS χ² under the covariance).
    dof : int
        ν = K − q.
    quality : FitQuality
        χ²/ν, its expected range, the misfit flag and the Birge ratio.
    criterion : str
        ``"aicc"``, ``"cv"`` or ``"fixed"`` (order given by the caller).
    aicc : mapping of int to float
        AICc(m) of Eq. (6) per order tried (∞ where undefined).
    cv : mapping of int to float
        CV(m) of Eq. (9) per order tried (∞ where a point cannot be left out).
    note : str
        What was chosen and why, and whether σ were Birge-scaled.
    """

    name: str
    model: TemperaturePolynomial
    covariance: NDArray[np.float64]
    covariance_scaled: NDArray[np.float64]
    chi2: float
    dof: int
    quality: FitQuality
    criterion: str
    aicc: Mapping[int, float]
    cv: Mapping[int, float]
    note: str

    @property
    def order(self) -> int:
        """m, the chosen polynomial order."""
        return self.model.order

    def std(self, *, scaled: bool = True) -> NDArray[np.float64]:
        """Return the coefficients' σ (Birge-scaled for a misfit by default)."""
        cov = self.covariance_scaled if scaled else self.covariance
        return np.sqrt(np.diag(cov))


@dataclass(frozen=True)
class TemperaturePrediction:
    """p̂(T) and σ_pred of Eq. (5) at the requested temperatures."""

    value: NDArray[np.float64]
    std: NDArray[np.float64]
    covariance: NDArray[np.float64]


@dataclass(frozen=True)
class HeldOutCheck:
    """Eqs. (10)–(11): a fitted model against estimates it did not see.

    Attributes
    ----------
    normalised_residuals : numpy.ndarray
        z_i of Eq. (10).
    chi2 : float
        χ²_h of Eq. (11) (prediction correlations included).
    dof : int
        The number of held-out points.
    p_value : float
        P(χ²_ν ≥ χ²_h).
    consistent : bool
        max|z_i| ≤ `limit` and p ≥ `alpha`.
    """

    normalised_residuals: NDArray[np.float64]
    chi2: float
    dof: int
    p_value: float
    consistent: bool


# ---------------------------------------------------------------------------------------------
# input checks


def _vector(value: ArrayLike, name: str, n: int | None = None) -> NDArray[np.float64]:
    arr = as_array(value, name)
    if arr.ndim == 0:
        arr = arr.reshape(1)
    if arr.ndim != 1 or (n is not None and arr.size != n):
        want = "(K,)" if n is None else f"({n},)"
        raise InvalidInputError(f"`{name}` must have shape {want}; got {arr.shape}")
    return arr


def _optional_extra(value: ArrayLike | None, name: str, n: int) -> NDArray[np.float64] | None:
    if value is None:
        return None
    arr = as_array(value, name)
    if arr.ndim == 0:
        arr = np.full(n, float(arr))
    if arr.shape != (n,):
        raise InvalidInputError(f"`{name}` must be a scalar or have shape ({n},); got {arr.shape}")
    return arr


def _check_leg(leg: NDArray[np.float64] | None) -> None:
    if leg is not None and not np.all(np.isin(leg, (-1.0, 1.0))):
        raise InvalidInputError("`leg` must be +1 (heating) or −1 (cooling) for every point")


def _cholesky(covariance: ArrayLike, n: int, name: str = "covariance") -> NDArray[np.float64]:
    cov = as_array(covariance, name)
    if cov.ndim == 1:
        if cov.shape != (n,):
            raise InvalidInputError(
                f"`{name}` must have shape ({n}, {n}) or ({n},) (variances); got {cov.shape}")
        cov = np.diag(cov)
    if cov.shape != (n, n):
        raise InvalidInputError(f"`{name}` must have shape ({n}, {n}); got {cov.shape}")
    # np.allclose(cov, cov.T, rtol=1e-10, atol=0) for the finite values as_array passes,
    # without its general-case machinery
    if not (np.abs(cov - cov.T) <= 1e-10 * np.abs(cov.T)).all():
        raise InvalidInputError(f"`{name}` must be symmetric")
    try:
        return np.asarray(np.linalg.cholesky(cov), dtype=np.float64)
    except np.linalg.LinAlgError as exc:
        raise InvalidInputError(f"`{name}` must be positive definite") from exc


# ---------------------------------------------------------------------------------------------
# design and GLS, Eqs. (1)–(5)


@dataclass(frozen=True)
class _Scaling:
    t0: float
    s_temp: float
    s_rate: float


def _design(temp: NDArray[np.float64], rate: NDArray[np.float64] | None,
            leg: NDArray[np.float64] | None, order: int, sc: _Scaling) -> NDArray[np.float64]:
    """Rows of Eq. (1) in the scaled variables x = (T − T0)/s, Ṫ/s_rate, ℓ."""
    x = (temp - sc.t0) / sc.s_temp
    cols = [x**j for j in range(order + 1)]
    if rate is not None:
        cols.append(rate / sc.s_rate)
    if leg is not None:
        cols.append(leg)
    return np.column_stack(cols)


def _unscale(order: int, has_rate: bool, has_leg: bool, sc: _Scaling) -> NDArray[np.float64]:
    """Return diag S of Eq. (4): c_j = b_j / s^j, d = b_d / s_rate, h = b_h."""
    factors = [sc.s_temp ** (-j) for j in range(order + 1)]
    if has_rate:
        factors.append(1.0 / sc.s_rate)
    if has_leg:
        factors.append(1.0)
    return np.array(factors)


def _gls(a: NDArray[np.float64], p: NDArray[np.float64], cov: NDArray[np.float64],
         noise: tuple[Whitener, NDArray[np.float64]] | None = None
         ) -> tuple[NDArray[np.float64], NDArray[np.float64], float] | None:
    """β̂, C_β, χ² of Eqs. (2)–(3) by the one solver; None when the design is singular.

    `noise`: the whitening of `cov` and W·p, which :func:`fit_temperature_model` makes once for
    all its orders (:func:`make_whitener` of `cov`, as the solver's own checks would); then a
    finite design goes through the solver's core without the checks it has passed.
    """
    names = tuple(f"beta_{j}" for j in range(a.shape[1]))
    try:
        if noise is not None and np.isfinite(a).all():
            core = _solve_known(a, p, noise[0], names, cond_limit=_COND_LIMIT, yw=noise[1])
            return core.estimate, core.covariance_noise, core.chi2
        fit = solve_weighted_lsq(a, p, covariance=cov, cond_limit=_COND_LIMIT,
                                 param_names=names)
    except InsufficientExcitationError:
        return None
    return fit.estimate, fit.covariance_noise, fit.chi2


def _sandwich(a: NDArray[np.float64], p: NDArray[np.float64], cov: NDArray[np.float64],
              weights: NDArray[np.float64],
              noise: tuple[Whitener, NDArray[np.float64]] | None = None
              ) -> tuple[NDArray[np.float64], NDArray[np.float64], float] | None:
    """β̂ = W·p and C_β = W·C·Wᵀ of Eq. (2b), χ² of Eq. (3b); None when the design is singular.

    W is the gain of the weighted least squares with V = `weights`
    (:func:`~imucalib.estimation.linear.solve_weighted_lsq`); χ² the GLS χ² under `cov` (the
    GLS fit of Eq. (2), whose χ² is rᵀMr for any residual).
    """
    names = tuple(f"beta_{j}" for j in range(a.shape[1]))
    gls = _gls(a, p, cov, noise)
    if gls is None:
        return None
    try:
        fit = solve_weighted_lsq(a, p, covariance=weights, cond_limit=_COND_LIMIT,
                                 param_names=names, gain=True)
    except InsufficientExcitationError:
        return None
    gain = np.asarray(fit.gain, dtype=np.float64)
    cov_beta = gain @ cov @ gain.T
    return np.asarray(fit.estimate, dtype=np.float64), 0.5 * (cov_beta + cov_beta.T), gls[2]


def _n_extra(rate: object, leg: object) -> int:
    return int(rate is not None) + int(leg is not None)


def _order_error(order: int, temp: NDArray[np.float64], n_extra: int, why: str
                 ) -> InsufficientExcitationError:
    k = temp.size
    distinct = np.unique(temp).size
    names = [f"c_{j}" for j in range(order + 1)]
    return InsufficientExcitationError(
        names,
        f"a temperature model of order {order} ({order + 1 + n_extra} coefficients with "
        f"{n_extra} rate/leg term(s)) cannot be resolved by {k} temperature point(s) "
        f"({distinct} distinct temperature(s)): {why}",
    )


def _aicc(chi2: float, q: int, k: int) -> float:
    """Eq. (6)."""
    if k - q - 1 <= 0:
        return math.inf
    return chi2 + 2.0 * q + 2.0 * q * (q + 1) / (k - q - 1)


def _cv_score(a: NDArray[np.float64], p: NDArray[np.float64], cov: NDArray[np.float64]) -> float:
    """Eqs. (7)–(9): leave-one-temperature-out whitened prediction error."""
    k, q = a.shape
    if k - 1 < q:
        return math.inf
    total = 0.0
    for i in range(k):
        keep = np.arange(k) != i
        c_rest = cov[np.ix_(keep, keep)]
        try:
            fit = _gls(a[keep], p[keep], c_rest)
        except InvalidInputError:  # C₋ₖ not positive definite
            return math.inf
        if fit is None:
            return math.inf
        beta, cov_beta, _ = fit
        c_cross = cov[keep, i]
        w = np.linalg.solve(c_rest, c_cross)  # C₋ₖ⁻¹ C_{−k,k}
        e = p[i] - a[i] @ beta - w @ (p[keep] - a[keep] @ beta)
        g = a[i] - a[keep].T @ w
        v = cov[i, i] - c_cross @ w + g @ cov_beta @ g
        total += e * e / v
    return float(total)


def fit_temperature_model(
    temperature_degc: ArrayLike,
    estimates: ArrayLike,
    covariance: ArrayLike,
    *,
    name: str = "p",
    order: int | None = None,
    max_order: int = DEFAULT_MAX_ORDER,
    criterion: Criterion = "aicc",
    reference_temperature_degc: float | None = None,
    temperature_rate_degc_ps: ArrayLike | None = None,
    leg: ArrayLike | None = None,
    compute_cv: bool = True,
    weights: ArrayLike | None = None,
) -> TemperatureModelFit:
    """Fit Eq. (1) to per-temperature estimates by GLS and choose its order, Eqs. (2)–(9).

    Parameters
    ----------
    temperature_degc : array_like, shape (K,)
        T_k, K ≥ 2. [°C]
    estimates : array_like, shape (K,)
        p_k. [parameter unit]
    covariance : array_like, shape (K, K) or (K,)
        Covariance of the estimates (full, possibly correlated across temperatures), or their
        variances. [parameter unit²]
    name : str
        The parameter's name (for the result and its FitQuality).
    order : int or None
        A fixed order m; None chooses m = 0 … `max_order` by `criterion`.
    max_order : int
        The highest order tried, capped at K − 1 − (number of rate/leg terms).
    criterion : {"aicc", "cv"}
        Eq. (6) (default) or Eq. (9).
    reference_temperature_degc : float or None
        T0; None uses the mean of T_k. [°C]
    temperature_rate_degc_ps : array_like, shape (K,), or None
        Mean dT/dt of each point; given, the model has the rate term d. [°C/s]
    leg : array_like of ±1, shape (K,), or None
        +1 heating, −1 cooling; given, the model has the hysteresis term h.
    compute_cv : bool
        Compute CV(m) of Eq. (9) for every order also when AICc chooses (for comparison);
        False leaves it NaN then (it costs K fits per order: most of a fit's time).
    weights : array_like, shape (K, K) or (K,), or None
        The estimator's V of Eq. (2b) (full or variances): β̂ by weighted least squares with V,
        its covariance the sandwich W·C·Wᵀ under `covariance`, χ² by Eq. (3b). None: V = C,
        the GLS of Eq. (2). [parameter unit²]

    Returns
    -------
    TemperatureModelFit

    Raises
    ------
    InvalidInputError
        Fewer than 2 points, non-finite inputs, wrong shapes, a covariance that is not symmetric
        positive definite, a leg other than ±1, an unknown criterion.
    InsufficientExcitationError
        A fixed `order` with more coefficients than points, or a design made singular (for
        example by duplicated temperatures not told apart by rate or leg); it names the order
        and the number of temperatures.
    """
    temp = _vector(temperature_degc, "temperature_degc")
    k = temp.size
    if k < 2:
        raise InvalidInputError(f"a temperature model needs K ≥ 2 temperatures; got {k}")
    p = _vector(estimates, "estimates", k)
    chol = _cholesky(covariance, k)
    cov = chol @ chol.T
    rate = _optional_extra(temperature_rate_degc_ps, "temperature_rate_degc_ps", k)
    legs = _optional_extra(leg, "leg", k)
    _check_leg(legs)
    if criterion not in ("aicc", "cv"):
        raise InvalidInputError(f"`criterion` must be 'aicc' or 'cv'; got {criterion!r}")
    n_extra = _n_extra(rate, legs)
    t0 = (float(np.mean(temp)) if reference_temperature_degc is None
          else check_finite_scalar(reference_temperature_degc, "reference_temperature_degc"))
    s_temp = float(np.max(np.abs(temp - t0))) or 1.0
    s_rate = float(np.max(np.abs(rate))) if rate is not None else 1.0
    sc = _Scaling(t0=t0, s_temp=s_temp, s_rate=s_rate or 1.0)

    if order is not None:
        if isinstance(order, bool) or not isinstance(order, int) or order < 0:
            raise InvalidInputError(f"`order` must be an int ≥ 0; got {order!r}")
        if order + 1 + n_extra > k:
            raise _order_error(order, temp, n_extra, "more coefficients than points")
        orders = [order]
    else:
        if isinstance(max_order, bool) or not isinstance(max_order, int) or max_order < 0:
            raise InvalidInputError(f"`max_order` must be an int ≥ 0; got {max_order!r}")
        top = min(max_order, k - 1 - n_extra)
        if top < 0:
            raise _order_error(0, temp, n_extra, "more coefficients than points")
        orders = list(range(top + 1))

    fits: dict[int, tuple[NDArray[np.float64], NDArray[np.float64], float]] = {}
    aicc: dict[int, float] = {}
    cv: dict[int, float] = {}
    noise: tuple[Whitener, NDArray[np.float64]] | None = None  # C's whitening, made once
    v_chol = None if weights is None else _cholesky(weights, k, "weights")
    v_cov = None if v_chol is None else v_chol @ v_chol.T
    for m in orders:
        a = _design(temp, rate, legs, m, sc)
        if noise is None and np.isfinite(a).all():
            whitener = make_whitener(k, covariance=cov)[0]
            noise = (whitener, whitener.whiten(p))
        fit = _gls(a, p, cov, noise) if v_cov is None else _sandwich(a, p, cov, v_cov, noise)
        if fit is None:
            if order is not None or m == 0:
                raise _order_error(m, temp, n_extra,
                                   "the design is singular (duplicated temperatures not told "
                                   "apart by rate or leg, or a constant rate/leg column)")
            break  # higher orders are singular too
        fits[m] = fit
        aicc[m] = _aicc(fit[2], a.shape[1], k)
        wanted = order is None and (compute_cv or criterion == "cv")
        cv[m] = _cv_score(a, p, cov) if wanted else math.nan

    if order is not None:
        chosen, used, why = order, "fixed", f"order {order} given"
    else:
        scores = aicc if criterion == "aicc" else cv
        finite = {m: v for m, v in scores.items() if math.isfinite(v)}
        used = criterion
        if finite:
            chosen = min(finite, key=lambda m: finite[m])
            why = (f"order {chosen} of 0…{max(fits)} chosen by {criterion.upper()} "
                   f"({criterion.upper()} = {finite[chosen]:.4g})")
        else:
            chosen = 0
            why = (f"{criterion.upper()} undefined for every order with K = {k} "
                   "(too few points); order 0 used")

    beta_s, cov_s, chi2 = fits[chosen]
    q = beta_s.size
    unscale = _unscale(chosen, rate is not None, legs is not None, sc)
    beta = beta_s * unscale
    cov_beta = cov_s * np.outer(unscale, unscale)
    quality = assess_fit(name, chi2, k - q)
    cov_scaled = cov_beta * quality.sigma_scale**2
    note = why
    if quality.misfit:
        note += (f"; MODEL MISFIT: χ²/ν = {quality.reduced_chi2:.3g} (ν = {quality.dof}), "
                 f"coefficient σ scaled by the Birge ratio {quality.birge_ratio:.3g}")
    m_terms = chosen + 1
    model = TemperaturePolynomial(
        reference_temperature_degc=t0,
        coefficients=tuple(float(c) for c in beta[:m_terms]),
        rate_coefficient=float(beta[m_terms]) if rate is not None else None,
        leg_coefficient=float(beta[-1]) if legs is not None else None,
    )
    for arr in (cov_beta, cov_scaled):
        arr.setflags(write=False)
    return TemperatureModelFit(
        name=name, model=model, covariance=cov_beta, covariance_scaled=cov_scaled, chi2=chi2,
        dof=k - q, quality=quality, criterion=used, aicc=aicc, cv=cv, note=note,
    )


def _model_design(model: TemperaturePolynomial, temp: NDArray[np.float64],
                  rate: ArrayLike | None, leg: ArrayLike | None) -> NDArray[np.float64]:
    """Rows a of Eq. (1) in physical units (T − T0)^j, Ṫ, ℓ for the terms `model` has."""
    n = temp.size
    cols = [(temp - model.reference_temperature_degc) ** j for j in range(model.order + 1)]
    if model.rate_coefficient is not None:
        r = _optional_extra(rate, "temperature_rate_degc_ps", n)
        cols.append(np.zeros(n) if r is None else r)
    if model.leg_coefficient is not None:
        lg = _optional_extra(leg, "leg", n)
        _check_leg(lg)
        if lg is None:
            raise InvalidInputError("`leg` is required: the model has a hysteresis term")
        cols.append(lg)
    return np.column_stack(cols)


def gls_weights(fit: TemperatureModelFit, temperature_degc: ArrayLike, variances: ArrayLike,
                temperature_rate_degc_ps: ArrayLike | None = None,
                leg: ArrayLike | None = None) -> NDArray[np.float64]:
    """Return W with β̂ = W·p: the fitted model's GLS estimator for independent estimates.

    ``W = (Aᵀ V⁻¹ A)⁻¹ Aᵀ V⁻¹`` (the gain of :func:`~imucalib.estimation.linear.solve_weighted_lsq`)
    with A the model's design at the fit's points (Eq. (2),
    physical units) and V = diag(`variances`); row 0 gives c_0. It carries the covariance of
    several parameters' estimates at the same temperatures into their models' coefficients:
    Cov(β_i, β_j) = W_i C_ij W_jᵀ (docs/p2.md, Eq. (P2.12)).

    Raises
    ------
    InvalidInputError
        Mis-shaped or non-finite inputs, a variance ≤ 0, a missing leg.
    """
    temp = _vector(temperature_degc, "temperature_degc")
    var = _vector(variances, "variances", temp.size)
    if np.any(var <= 0):
        raise InvalidInputError("`variances` must be positive")
    a = _model_design(fit.model, temp, temperature_rate_degc_ps, leg)
    names = tuple(f"beta_{j}" for j in range(a.shape[1]))
    if np.isfinite(a).all():  # the solver's checks passed (V's as make_whitener's): its core
        gain = _solve_known(a, np.zeros(temp.size), Whitener(np.sqrt(var), None), names,
                            gain=True).gain
    else:
        gain = solve_weighted_lsq(a, np.zeros(temp.size), covariance=var, gain=True,
                                  param_names=names).gain
    assert gain is not None  # asked for
    return np.array(gain)  # K of Eq. (1) of estimation.linear


def _coefficient_vector(model: TemperaturePolynomial) -> NDArray[np.float64]:
    extra = [c for c in (model.rate_coefficient, model.leg_coefficient) if c is not None]
    return np.array([*model.coefficients, *extra])


def predict_temperature_model(
    fit: TemperatureModelFit,
    temperature_degc: ArrayLike,
    temperature_rate_degc_ps: ArrayLike | None = None,
    leg: ArrayLike | None = None,
    *,
    scaled: bool = True,
) -> TemperaturePrediction:
    """Return p̂(T) and σ_pred of Eq. (5).

    Parameters
    ----------
    fit : TemperatureModelFit
    temperature_degc : float or array_like, shape (n,)
        [°C]
    temperature_rate_degc_ps : float or array_like, shape (n,), or None
        dT/dt where the model has a rate term (None: 0). [°C/s]
    leg : ±1 or array_like, shape (n,), or None
        Required when the model has a hysteresis term.
    scaled : bool
        Use the Birge-scaled covariance (default; equal to the unscaled for a good fit).

    Raises
    ------
    InvalidInputError
        Non-finite or mis-shaped inputs, a missing leg.
    """
    temp = _vector(temperature_degc, "temperature_degc")
    a = _model_design(fit.model, temp, temperature_rate_degc_ps, leg)
    cov_c = fit.covariance_scaled if scaled else fit.covariance
    cov = a @ cov_c @ a.T
    return TemperaturePrediction(value=a @ _coefficient_vector(fit.model),
                                 std=np.sqrt(np.diag(cov)), covariance=cov)


def check_held_out(
    fit: TemperatureModelFit,
    temperature_degc: ArrayLike,
    estimates: ArrayLike,
    sigma: ArrayLike,
    temperature_rate_degc_ps: ArrayLike | None = None,
    leg: ArrayLike | None = None,
    *,
    limit: float = 3.0,
    alpha: float = 0.01,
) -> HeldOutCheck:
    """Compare a fitted model with estimates it did not see, Eqs. (10)–(11).

    Parameters
    ----------
    fit : TemperatureModelFit
    temperature_degc, estimates, sigma : array_like, shape (n,)
        Held-out T_i [°C], p_i and their standard deviations σ_i (independent of the fit's
        data) [parameter unit].
    temperature_rate_degc_ps, leg
        As for :func:`predict_temperature_model`.
    limit : float
        The bound on |z_i|.
    alpha : float
        The smallest acceptable χ² p-value.

    Raises
    ------
    InvalidInputError
        Mis-shaped or non-finite inputs, a σ ≤ 0.
    """
    temp = _vector(temperature_degc, "temperature_degc")
    n = temp.size
    p = _vector(estimates, "estimates", n)
    sig = _vector(sigma, "sigma", n)
    if np.any(sig <= 0):
        raise InvalidInputError("`sigma` must be > 0 for every held-out point")
    pred = predict_temperature_model(fit, temp, temperature_rate_degc_ps, leg)
    r = pred.value - p
    z = r / np.sqrt(pred.std**2 + sig**2)
    total = pred.covariance + np.diag(sig**2)
    chi2 = float(r @ np.linalg.solve(total, r))
    p_value = float(stats.chi2.sf(chi2, n))
    return HeldOutCheck(normalised_residuals=z, chi2=chi2, dof=n, p_value=p_value,
                        consistent=bool(np.max(np.abs(z)) <= limit and p_value >= alpha))
