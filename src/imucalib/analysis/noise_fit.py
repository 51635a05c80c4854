"""IMU noise terms from an overlapping Allan deviation: a GLS fit and slope-line readings.

Contents
--------
:func:`fit_noise_terms` → :class:`NoiseFit`
    All terms at once over the whole curve, with uncertainties.
:func:`read_slope_lines`
    The classical readings of docs/equations.md §8 (each on the points where
    its term dominates), plus the Allan minimum with and without the 0.664 factor.
:class:`NoiseTerm`, :func:`make_noise_term`, :data:`FIT_TERMS`, :func:`term_avar`

Model (docs/equations.md §8, two-sided densities; [1]_ Annex C)
--------------------------------------------------------------
σ²(τ) = 3Q²/τ² + N²/τ + (2 ln 2/π)·B² + K²τ/3 + R²τ²/2 [+ Markov σ_M² term], i.e.
σ² = Σ c_p·τ^p with p = −2 … 2 and c_p ≥ 0. The flicker term is the plateau
(2 ln 2/π)·B² = (0.6643·B)², reached for τ ≳ 2/f0; B is reported with the 0.664 factor applied.

Fit
---
Generalised least squares with non-negativity (NNLS on the Cholesky-whitened system) and the
*full* covariance Σ of the AVAR estimates, iterated: Σ is computed for the current coefficients
from the lag sums of :mod:`._avar_covariance` (exact Isserlis sums over the overlapping terms;
it reproduces Greenhall's EDF on the diagonal and the correlation ≈ 0.5 between neighbouring
octaves, which a diagonal weighting would ignore and so understate every uncertainty). The
coefficient covariance is (Xᵀ Σ⁻¹ X)⁻¹ over the terms found (> 0); each term's uncertainty
follows by the delta method (P = √(c/k) → u(P) = u(c)/(2kP)). A term is ``detected`` when
c > 2·u(c); otherwise its ``upper_bound_si`` is the coefficient of
c_max = max(c, 0) + 2·u(c) (P < √(c_max/k), the one-sided 97.7 % limit).
χ² = rᵀΣ⁻¹r is reported (about dof when the model fits). A term's τ range is the
span of points where it contributes ≥ 25 % of the fitted variance.

The ramp enters as a deterministic drift (σ_Allan(τ) = |R|τ/√2); quantization as white angle
noise (noise.py's model). The estimates must be overlapping ADEV (``kind="oadev"``).

References
----------
.. [1] IEEE Std 952-1997 (R2008), Annex C. .. [2] W. J. Riley, NIST SP 1065, 2008.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import linalg, optimize

from imucalib.analysis._avar_covariance import covariance_basis
from imucalib.analysis.allan import DeviationResult
from imucalib.analysis.bias_instability import read_allan_minimum
from imucalib.analysis.noise_units import (
    DENSITY_CONVENTION,
    SI_UNITS,
    TERM_LABELS,
    UnitValue,
    convert_noise_term,
)
from imucalib.errors import InvalidInputError
from imucalib.models.fit_quality import FitQuality, assess_fit
from imucalib.models.noise import FLICKER_ALLAN_FACTOR, NoiseModel, compute_theoretical_adev

__all__ = ["FIT_TERMS", "FLICKER_FACTOR", "NoiseFit", "NoiseTerm", "fit_noise_terms",
           "make_noise_term", "read_slope_lines", "term_avar"]

F64 = NDArray[np.float64]
#: Terms of the power-law model, in τ-power order −2 … 2.
FIT_TERMS = ("quantization", "white", "bias_instability", "random_walk", "rate_ramp")
_POWER = {"quantization": -2, "white": -1, "bias_instability": 0, "random_walk": 1,
          "rate_ramp": 2}
#: σ_Allan plateau of flicker noise divided by B: √(2 ln 2/π) = 0.6643 (models.noise's).
FLICKER_FACTOR = FLICKER_ALLAN_FACTOR
# c_p = k_p·P², P the physical coefficient
_K = {"quantization": 3.0, "white": 1.0, "bias_instability": FLICKER_FACTOR**2,
      "random_walk": 1 / 3, "rate_ramp": 0.5}
_COMPONENT = {"quantization": "Q", "white": "N", "bias_instability": "B", "random_walk": "K"}
_SHARE = 0.25


def term_avar(term: str, value_si: float, tau_s: ArrayLike,
              markov_time_constant_s: float | None = None) -> F64:
    """Allan variance of one term with coefficient `value_si` at `tau_s` [SI²]."""
    tau = np.asarray(tau_s, dtype=np.float64)
    if term == "markov_sigma":
        if not markov_time_constant_s:
            raise InvalidInputError("the Markov term needs its time constant")
        return value_si**2 * _markov_shape(tau, markov_time_constant_s)
    if term not in _K:
        raise InvalidInputError(f"unknown term {term!r}; expected one of {list(FIT_TERMS)}")
    out: F64 = _K[term] * value_si**2 * tau ** float(_POWER[term])
    return out


def _markov_shape(tau: F64, tc: float) -> F64:
    """Return the AVAR of a unit-variance first-order Gauss–Markov rate (docs/equations.md §8).

    2(T/τ)·[1 − (T/2τ)(3 − 4e^(−τ/T) + e^(−2τ/T))], as :func:`compute_theoretical_adev` of
    :mod:`imucalib.models.noise` gives it.
    """
    model = NoiseModel(markov_sigma=1.0, markov_time_constant_s=tc)
    out: F64 = compute_theoretical_adev(model, tau)[:, 0] ** 2
    return out


@dataclass(frozen=True)
class NoiseTerm:
    """One noise coefficient with its uncertainty, origin and conversions."""

    name: str  # key of noise_units.SI_UNITS
    label: str
    value_si: float
    std_si: float  # standard uncertainty (NaN when not available)
    unit_si: str
    tau_range_s: tuple[float, float]  # points it came from [s]
    method: str  # "gls-fit", "slope-line", "allan-minimum"
    detected: bool
    display: tuple[UnitValue, ...] = field(default=())
    convention: str = DENSITY_CONVENTION
    upper_bound_si: float | None = None  # when not detected: the value is below this (SI)

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form."""
        out = {f.name: getattr(self, f.name) for f in fields(self)}
        out["tau_range_s"] = list(self.tau_range_s)
        out["display"] = [vars(u) for u in self.display]
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> NoiseTerm:
        """Inverse of :meth:`to_dict`."""
        def num(v: Any) -> float:
            return math.nan if v is None else float(v)

        kw = dict(data)
        kw["value_si"], kw["std_si"] = num(kw["value_si"]), num(kw["std_si"])
        bound = kw.get("upper_bound_si")
        kw["upper_bound_si"] = None if bound is None else float(bound)
        kw["tau_range_s"] = tuple(num(v) for v in kw["tau_range_s"])
        kw["display"] = tuple(UnitValue(u["unit"], num(u["value"]), num(u["std"]),
                                        u.get("note", ""),
                                        None if u.get("upper") is None else float(u["upper"]))
                              for u in kw.get("display", ()))
        return cls(**kw)


def make_noise_term(sensor: str, name: str, value_si: float, std_si: float = math.nan,
                    tau_range_s: tuple[float, float] = (math.nan, math.nan),
                    method: str = "given", detected: bool = True,
                    upper_bound_si: float | None = None) -> NoiseTerm:
    """Build a :class:`NoiseTerm` (label, SI unit and conversions filled in).

    For values from elsewhere (a datasheet, another tool) that should be exported or tabulated
    like fitted ones. `value_si` is the two-sided SI coefficient (:mod:`.noise_units`);
    `upper_bound_si` the bound a term that was not detected lies below (docs/noise.md).

    Raises
    ------
    InvalidInputError
        Unknown sensor or term name.
    """
    if sensor not in SI_UNITS or name not in SI_UNITS[sensor]:
        raise InvalidInputError(f"unknown sensor/term {sensor!r}/{name!r}; terms: "
                                f"{sorted(SI_UNITS['gyro'])}")
    return NoiseTerm(name, TERM_LABELS[sensor][name], float(value_si), float(std_si),
                     SI_UNITS[sensor][name], (float(tau_range_s[0]), float(tau_range_s[1])),
                     method, bool(detected),
                     convert_noise_term(sensor, name, value_si, std_si, upper_bound_si),
                     upper_bound_si=None if upper_bound_si is None else float(upper_bound_si))


_make_term = make_noise_term


@dataclass(frozen=True, eq=False)
class NoiseFit:
    """Result of :func:`fit_noise_terms` (one channel)."""

    sensor: str
    terms: tuple[NoiseTerm, ...]
    slope_readings: tuple[NoiseTerm, ...]
    fitted_terms: tuple[str, ...]  # order of `coefficients`
    coefficients: F64  # c_p of σ² = Σ c_p τ^p [SI²·s^−p] (Markov: σ_M²)
    covariance: F64  # of `coefficients`
    chi2: float
    dof: int
    taus_s: F64  # points used [s]
    markov_time_constant_s: float | None = None

    @property
    def quality(self) -> FitQuality:
        """The fit's goodness: χ²/ν against the Allan covariance, expected range, misfit flag.

        :func:`~imucalib.models.fit_quality.assess_fit` of :attr:`chi2` and :attr:`dof`
        (docs/processing-estimation.md, "Goodness of fit"); not testable without a finite χ².
        """
        testable = math.isfinite(self.chi2) and self.chi2 >= 0 and self.dof > 0
        return assess_fit(self.sensor, self.chi2 if testable else 0.0,
                          self.dof if testable else 0)

    def term(self, name: str) -> NoiseTerm:
        """Return the fitted term `name` (InvalidInputError if it was not fitted)."""
        for t in self.terms:
            if t.name == name:
                return t
        raise InvalidInputError(f"no fitted term {name!r}; terms: {[t.name for t in self.terms]}")

    def reading(self, name: str) -> NoiseTerm | None:
        """Return the slope-line reading `name`, or None when no point allowed it."""
        return next((t for t in self.slope_readings if t.name == name), None)

    def model_avar(self, tau_s: ArrayLike) -> dict[str, F64]:
        """Fitted Allan variance per term and ``"total"`` at `tau_s` [SI²]."""
        tau = np.asarray(tau_s, dtype=np.float64)
        out: dict[str, F64] = {}
        for name, c in zip(self.fitted_terms, self.coefficients, strict=True):
            if name == "markov_sigma":
                out[name] = c * _markov_shape(tau, float(self.markov_time_constant_s or 1.0))
            else:
                out[name] = c * tau ** float(_POWER[name])
        out["total"] = sum(out.values(), np.zeros_like(tau))
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form; :meth:`from_dict` rebuilds it."""
        return {"sensor": self.sensor, "terms": [t.to_dict() for t in self.terms],
                "slope_readings": [t.to_dict() for t in self.slope_readings],
                "fitted_terms": list(self.fitted_terms),
                "coefficients": self.coefficients.tolist(),
                "covariance": self.covariance.tolist(), "chi2": self.chi2, "dof": self.dof,
                "taus_s": self.taus_s.tolist(),
                "markov_time_constant_s": self.markov_time_constant_s,
                "fit_quality": {"reduced_chi2": None if self.quality.dof == 0
                                else self.quality.reduced_chi2,
                                "expected_high": None if self.quality.dof == 0
                                else self.quality.expected_high,
                                "misfit": self.quality.misfit,
                                "sigma_scale": self.quality.sigma_scale}}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> NoiseFit:
        """Inverse of :meth:`to_dict`."""
        return cls(sensor=data["sensor"],
                   terms=tuple(NoiseTerm.from_dict(t) for t in data["terms"]),
                   slope_readings=tuple(NoiseTerm.from_dict(t) for t in data["slope_readings"]),
                   fitted_terms=tuple(data["fitted_terms"]),
                   coefficients=np.asarray(data["coefficients"], dtype=np.float64),
                   covariance=np.asarray(data["covariance"], dtype=np.float64).reshape(
                       len(data["fitted_terms"]), len(data["fitted_terms"])),
                   chi2=math.nan if data["chi2"] is None else float(data["chi2"]),
                   dof=int(data["dof"]),
                   taus_s=np.asarray(data["taus_s"], dtype=np.float64),
                   markov_time_constant_s=data.get("markov_time_constant_s"))


def _design(names: Sequence[str], tau: F64, tc: float | None) -> F64:
    cols = [_markov_shape(tau, float(tc or 1.0)) if n == "markov_sigma"
            else tau ** float(_POWER[n]) for n in names]
    return np.stack(cols, axis=1)


def _amplitudes(names: Sequence[str], c: F64) -> tuple[dict[str, float], float]:
    amps: dict[str, float] = {}
    ramp = 0.0
    for n, v in zip(names, c, strict=True):
        if n == "rate_ramp":
            ramp = math.sqrt(2 * max(v, 0.0))
        elif n == "markov_sigma":
            amps["M"] = float(v)
        else:
            amps[_COMPONENT[n]] = float(v) / _K[n]
    return amps, ramp


def _gls_fit(x: F64, a: F64, sigma: F64) -> tuple[F64, F64, F64]:
    """NNLS on the Cholesky-whitened system: the coefficients c, the factor L and 1/√diag Σ."""
    d = 1 / np.sqrt(np.diag(sigma))
    corr = sigma * np.outer(d, d)
    chol = linalg.cholesky(corr + 1e-12 * np.eye(d.size), lower=True)
    aw = linalg.solve_triangular(chol, a * d, lower=True)
    xw = linalg.solve_triangular(chol, x * d[:, None], lower=True)
    scale = 1 / np.maximum(np.linalg.norm(xw, axis=0), 1e-300)
    sol, _ = optimize.nnls(xw * scale, aw, maxiter=50 * x.shape[1])
    return sol * scale, chol, d


def _gls(x: F64, a: F64, sigma: F64) -> tuple[F64, F64]:
    """NNLS on the Cholesky-whitened system; return the coefficients c and Σ⁻¹."""
    c, chol, d = _gls_fit(x, a, sigma)
    inv = np.outer(d, d) * linalg.cho_solve((chol, True), np.eye(d.size))
    return c, inv


def _sigma(names: Sequence[str], c: F64, tau: F64, a: F64, edf: F64, ms: tuple[int, ...],
           n_phase: int, tau0: float, tc: float | None) -> F64:
    basis = covariance_basis(ms, n_phase, tau0, float(tc or 0.0))
    amps, ramp = _amplitudes(names, c)
    if not any(amps.values()):
        return np.diag(2 * a**2 / edf)
    sig = basis.covariance(amps, ramp)
    floor = (1e-9 * a) ** 2
    sig[np.diag_indices_from(sig)] = np.maximum(np.diag(sig), floor)
    return sig


def fit_noise_terms(result: DeviationResult, *, sensor: str = "gyro",
                    terms: Sequence[str] = FIT_TERMS,
                    tau_range_s: tuple[float, float] | None = None,
                    markov_time_constant_s: float | None = None,
                    max_iterations: int = 12) -> NoiseFit:
    """Fit the IMU noise terms to an overlapping Allan deviation (module docstring).

    Parameters
    ----------
    result : DeviationResult
        Overlapping ADEV (``kind="oadev"``) of a rate [rad/s | m/s²].
    sensor : {"gyro", "accel"}
        Chooses the display units and labels.
    terms : sequence of str
        Subset of :data:`FIT_TERMS` to fit (default all five), plus ``"markov_sigma"`` to add a
        first-order Gauss–Markov term.
    tau_range_s : (float, float), optional
        Only points with τ in this closed range [s].
    markov_time_constant_s : float, optional
        T_c of the Markov term [s]; when omitted with ``"markov_sigma"`` in `terms`, the T_c that
        minimises χ² on a log grid between 3τ0 and τ_max/3 is used (and reported, without
        uncertainty).
    max_iterations : int
        Re-weighting iterations of Σ (it converges in a few).

    Returns
    -------
    NoiseFit
        ``terms`` in SI with uncertainties and conversions; ``slope_readings`` from
        :func:`read_slope_lines`.

    Raises
    ------
    InvalidInputError
        Not an overlapping ADEV, unknown sensor or term, fewer points than terms, or an Allan
        variance that is zero or not finite at a τ (a constant signal).
    """
    if not isinstance(result, DeviationResult) or result.kind != "oadev":
        got = getattr(result, "kind", type(result).__name__)
        raise InvalidInputError(f"`result` must be an overlapping Allan deviation (kind 'oadev'); "
                                f"got {got!r}")
    if sensor not in SI_UNITS:
        raise InvalidInputError(f"`sensor` must be 'gyro' or 'accel'; got {sensor!r}")
    names = tuple(terms)
    unknown = [n for n in names if n not in _POWER and n != "markov_sigma"]
    if unknown or not names:
        raise InvalidInputError(f"unknown noise term(s) {unknown}; expected from "
                                f"{[*FIT_TERMS, 'markov_sigma']}")
    tau_all = result.taus_s
    keep = np.ones(tau_all.size, dtype=bool)
    if tau_range_s is not None:
        keep = (tau_all >= tau_range_s[0]) & (tau_all <= tau_range_s[1])
    if keep.sum() <= len(names):
        raise InvalidInputError(f"{int(keep.sum())} Allan point(s) in range for {len(names)} "
                                f"term(s); need more points than terms")
    tau = tau_all[keep]
    a = result.variance[keep]
    edf = result.edf[keep]
    flat = ~(np.isfinite(a) & (a > 0))
    if flat.any():
        k = int(np.argmax(flat))
        raise InvalidInputError(
            f"the Allan variance is {a[k]:g} at τ = {tau[k]:.6g} s ({int(flat.sum())} of "
            f"{a.size} points); a noise fit needs a signal that varies at every τ (a column "
            "of zeros, a stuck sensor, or values coarser than the noise?)")
    ms = tuple(int(m) for m in result.averaging_factors[keep])
    n_phase = result.n_samples + 1
    tau0 = 1.0 / result.sample_rate_hz
    tc = markov_time_constant_s
    search = "markov_sigma" in names and tc is None
    sigma = np.diag(2 * a**2 / edf)
    if search:
        tc = _best_markov_tc(names, tau, a, sigma, tau0)
    x = _design(names, tau, tc)
    c = _gls_fit(x, a, sigma)[0]  # the re-weighting reads only c
    for it in range(max_iterations):
        sigma = _sigma(names, c, tau, a, edf, ms, n_phase, tau0, tc)
        if search and it < 3:  # T_c against the full covariance, a few times
            tc = _best_markov_tc(names, tau, a, sigma, tau0)
            x = _design(names, tau, tc)
        c_new = _gls_fit(x, a, sigma)[0]
        done = np.allclose(c_new, c, rtol=1e-7, atol=1e-12 * float(np.max(np.abs(c_new)) + 1e-300))
        c = c_new
        if done:
            break
    _, inv = _gls(x, a, sigma)
    resid = a - x @ c
    chi2 = float(resid @ inv @ resid)
    active = c > 0
    cov = np.full((len(names), len(names)), np.nan)
    full = np.linalg.pinv(x.T @ inv @ x)  # unconstrained: the scale of absent terms
    if active.any():
        xa = x[:, active]
        cov_a = np.linalg.pinv(xa.T @ inv @ xa)
        cov[np.ix_(active, active)] = cov_a
    model = x * c[None, :]
    total = np.maximum(model.sum(axis=1), 1e-300)
    out_terms = []
    for k, name in enumerate(names):
        ck = float(c[k])
        uc = math.sqrt(cov[k, k]) if active[k] else math.sqrt(max(full[k, k], 0.0))
        share = model[:, k] / total
        sel = share >= _SHARE
        rng = (tau[sel].min(), tau[sel].max()) if sel.any() else (
            (float(tau[np.argmax(share)]),) * 2)
        if name == "markov_sigma":
            val = math.sqrt(max(ck, 0.0))
            std = uc / (2 * val) if val > 0 else math.sqrt(uc)
        else:
            val = math.sqrt(max(ck, 0.0) / _K[name])
            std = uc / (2 * _K[name] * val) if val > 0 else math.sqrt(uc / _K[name])
        detected = bool(active[k] and ck > 2 * uc)
        c_max = max(ck, 0.0) + 2 * uc
        upper = None if detected else (
            math.sqrt(c_max) if name == "markov_sigma" else math.sqrt(c_max / _K[name]))
        out_terms.append(_make_term(sensor, name, val, std, rng, "gls-fit", detected, upper))
    if "markov_sigma" in names and tc is not None:
        out_terms.append(_make_term(sensor, "markov_time_constant", tc, math.nan,
                                    out_terms[names.index("markov_sigma")].tau_range_s,
                                    "grid-search" if markov_time_constant_s is None else "given",
                                    out_terms[names.index("markov_sigma")].detected))
    fit = NoiseFit(sensor=sensor, terms=tuple(out_terms), slope_readings=(),
                   fitted_terms=names, coefficients=c, covariance=cov, chi2=chi2,
                   dof=int(tau.size - active.sum()), taus_s=tau, markov_time_constant_s=tc)
    readings = read_slope_lines(result, fit)
    return NoiseFit(sensor=sensor, terms=fit.terms, slope_readings=readings,
                    fitted_terms=names, coefficients=c, covariance=cov, chi2=chi2, dof=fit.dof,
                    taus_s=tau, markov_time_constant_s=tc)


def _best_markov_tc(names: Sequence[str], tau: F64, a: F64, w: F64, tau0: float) -> float:
    """T_c minimising χ² for the AVAR covariance `w`: a log grid, then Brent's method."""

    def chi2(log_tc: float) -> float:
        x = _design(names, tau, math.exp(log_tc))
        c, inv = _gls(x, a, w)
        r = a - x @ c
        return float(r @ inv @ r)

    grid = np.linspace(math.log(max(3 * tau0, tau[0])), math.log(tau[-1] / 3), 30)
    values = [chi2(v) for v in grid]
    k = int(np.argmin(values))
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]
    best = optimize.minimize_scalar(chi2, bounds=(lo, hi), method="bounded",
                                    options={"xatol": 1e-3})
    return float(math.exp(best.x if best.fun <= values[k] else grid[k]))


_SLOPES = {  # term: (log-log slope of σ, τ where σ reads the coefficient, σ(τ_read) = value)
    "quantization": (-1.0, math.sqrt(3.0)),
    "white": (-0.5, 1.0),
    "random_walk": (0.5, 3.0),
    "rate_ramp": (1.0, math.sqrt(2.0)),
}


def read_slope_lines(result: DeviationResult, fit: NoiseFit) -> tuple[NoiseTerm, ...]:
    """Classical slope-line readings (docs/equations.md §8) on the measured deviation.

    For quantization (slope −1, read at τ = √3 s), white noise (−½, τ = 1 s), random walk
    (+½, τ = 3 s) and ramp (+1, τ = √2 s): a line of the fixed slope through the points where the
    term supplies ≥ 50 % of the fitted variance (log-space mean weighted by EDF), read at its
    τ. Its uncertainty treats the points as fully correlated (conservative): the EDF-weighted
    mean of their relative standard errors 1/√(2·edf). Bias instability: the minimum σ_min of
    the measured curve over the τ with enough EDF (``bias_instability_allan_minimum``, no
    factor, what many datasheets quote) and σ_min/0.6643 (``bias_instability``), detected only
    when the curve has flattened there, otherwise reported with the upper bound the curve gives
    (:func:`~imucalib.analysis.bias_instability.read_allan_minimum`, docs/noise.md). A term
    without a dominant point has no reading.
    """
    tau = result.taus_s
    dev = result.deviation
    rel = 1 / np.sqrt(2 * result.edf)
    comps = fit.model_avar(tau)
    total = np.maximum(comps["total"], 1e-300)
    out: list[NoiseTerm] = []
    for name, (slope, t_read) in _SLOPES.items():
        if name not in comps:
            continue
        sel = comps[name] / total >= 0.5
        if not sel.any():
            continue
        w = result.edf[sel]
        level = np.sum(w * (np.log(dev[sel]) - slope * np.log(tau[sel]))) / np.sum(w)
        value = math.exp(level) * t_read**slope
        std = value * float(np.sum(w * rel[sel]) / np.sum(w))
        out.append(_make_term(fit.sensor, name, value, std, (tau[sel].min(), tau[sel].max()),
                              "slope-line", True))
    amin = read_allan_minimum(result)
    if not math.isfinite(amin.value):
        return tuple(out)
    span = (amin.tau_s, amin.tau_s)
    upper = None if amin.detected else amin.upper_bound
    out.append(_make_term(fit.sensor, "bias_instability_allan_minimum", amin.value, amin.std,
                          span, "allan-minimum", amin.detected, upper))
    out.append(_make_term(fit.sensor, "bias_instability", amin.value / FLICKER_FACTOR,
                          amin.std / FLICKER_FACTOR, span, "allan-minimum", amin.detected,
                          None if upper is None else upper / FLICKER_FACTOR))
    return tuple(out)
