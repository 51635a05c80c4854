"""Stochastic noise of one sensor triad: the model and its Allan deviation.

Contents: :class:`NoiseModel` (per-axis coefficients of the IEEE 952 Annex C terms plus a
Gauss–Markov term), :func:`compute_theoretical_adev` (the model's Allan deviation,
docs/equations.md §8). Samples of a model's noise are made by
:mod:`imucalib.models.noise_generator` (:class:`~imucalib.models.noise_generator.NoiseGenerator`,
:func:`~imucalib.models.noise_generator.simulate_noise`).

Densities are the **two-sided** coefficients of IEEE 952 (docs/equations.md §1): white noise N has
the two-sided PSD N², σ_Allan(1 s) = N, and a sample at interval Δt has the standard deviation
N/√Δt. Datasheet densities are one-sided, ND = √2·N (:meth:`NoiseModel.from_datasheet`).
Units read [gyro | accelerometer].

References
----------
.. [1] IEEE Std 952-1997 (R2008), Annex C; docs/equations.md §1 and §8.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from functools import partial
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib import units
from imucalib._checks import as_array, check_positive
from imucalib.errors import InvalidInputError

__all__ = ["FLICKER_ALLAN_FACTOR", "NoiseModel", "compute_theoretical_adev"]

#: σ_Allan plateau of flicker noise divided by B: √(2·ln 2/π) (docs/equations.md §8).
FLICKER_ALLAN_FACTOR = math.sqrt(2.0 * math.log(2.0) / math.pi)

_ARRAY_FIELDS = ("white_density", "bias_instability", "random_walk", "rate_ramp", "quantization",
                 "markov_sigma", "markov_time_constant_s")
_CONVENTION = "two-sided"
_RT2 = math.sqrt(2.0)
_DATASHEET: dict[str, tuple[str, float, str]] = {  # argument: (field, SI factor, sensor kind)
    "noise_density_one_sided": ("white_density", 1 / _RT2, ""),
    "noise_density_dps_rthz": ("white_density", units.DEG_PER_S_PER_RTHZ / _RT2, "gyro"),
    "noise_density_ug_rthz": ("white_density", units.UG_PER_RTHZ / _RT2, "accel"),
    "arw_deg_rth": ("white_density", units.DEG_PER_RTH, "gyro"),
    "vrw_mps_rth": ("white_density", units.MPS_PER_RTH, "accel"),
    "bias_instability_dph": ("bias_instability", units.DEG_PER_H, "gyro"),
    "bias_instability_ug": ("bias_instability", units.UG, "accel"),
    "rrw_deg_h_rth": ("random_walk", units.DEG_PER_H_RTH, "gyro"),
    "random_walk_ug_rth": ("random_walk", units.UG / math.sqrt(units.HOUR), "accel"),
    "rate_ramp_dph_per_h": ("rate_ramp", units.DEG_PER_H / units.HOUR, "gyro"),
    "rate_ramp_ug_per_h": ("rate_ramp", units.UG / units.HOUR, "accel"),
    "quantization_arcsec": ("quantization", units.ARCSEC, "gyro"),
    "quantization_mps": ("quantization", 1.0, "accel"),
    "markov_sigma_dph": ("markov_sigma", units.DEG_PER_H, "gyro"),
    "markov_sigma_ug": ("markov_sigma", units.UG, "accel"),
    "markov_time_constant_s": ("markov_time_constant_s", 1.0, ""),
}


@dataclass(frozen=True, eq=False, init=False)
class NoiseModel:
    """Stochastic errors of one triad, per axis, SI, two-sided PSD coefficients.

    Each array has shape (3,) (a scalar is broadcast to the three axes) and is stored read-only.
    The Allan deviation of each term is in docs/equations.md §8 and in
    :func:`compute_theoretical_adev`.

    Parameters
    ----------
    white_density : array_like
        N, angle / velocity random walk [rad/√s | (m/s)/√s] (= [rad/s/√Hz | m/s²/√Hz], two-sided).
        σ_Allan(1 s) = N; per-sample standard deviation N/√Δt.
    bias_instability : array_like
        B [rad/s | m/s²]: flicker PSD B²/(2πf) between `bias_instability_low_hz` and
        `bias_instability_corner_hz`. σ_Allan plateau = 0.6643·B.
    bias_instability_corner_hz : float
        f0, upper edge of the flicker band (the IEEE model's cut-off). [Hz]
    random_walk : array_like
        K, rate / acceleration random walk [rad/s/√s | m/s²/√s]. σ_Allan(3 s) = K.
    rate_ramp : array_like
        R, a deterministic slope of the output [rad/s² | m/s³], sign kept. σ_Allan(√2 s) = |R|.
    quantization : array_like
        Q, angle / velocity quantization [rad | m/s]. σ_Allan(√3 s) = Q.
    markov_sigma : array_like
        Steady-state standard deviation of a first-order Gauss–Markov term [rad/s | m/s²].
    markov_time_constant_s : array_like
        T_c of that term [s]; must be > 0 where `markov_sigma` > 0, ignored elsewhere.
    bias_instability_low_hz : float
        f_low, lower edge of the flicker band: the Allan plateau holds up to τ ≈ 0.1/f_low. [Hz]

    Raises
    ------
    InvalidInputError
        If a coefficient is negative (except `rate_ramp`), NaN or infinite, an array does not
        have 3 entries, or the flicker band edges are not 0 < f_low < f0.
    """

    white_density: NDArray[np.float64] = field(default_factory=partial(np.zeros, 3))
    bias_instability: NDArray[np.float64] = field(default_factory=partial(np.zeros, 3))
    bias_instability_corner_hz: float = 1.0
    random_walk: NDArray[np.float64] = field(default_factory=partial(np.zeros, 3))
    rate_ramp: NDArray[np.float64] = field(default_factory=partial(np.zeros, 3))
    quantization: NDArray[np.float64] = field(default_factory=partial(np.zeros, 3))
    markov_sigma: NDArray[np.float64] = field(default_factory=partial(np.zeros, 3))
    markov_time_constant_s: NDArray[np.float64] = field(default_factory=partial(np.zeros, 3))
    bias_instability_low_hz: float = 1e-5

    def __init__(self, white_density: ArrayLike = 0.0, bias_instability: ArrayLike = 0.0,
                 bias_instability_corner_hz: float = 1.0, random_walk: ArrayLike = 0.0,
                 rate_ramp: ArrayLike = 0.0, quantization: ArrayLike = 0.0,
                 markov_sigma: ArrayLike = 0.0, markov_time_constant_s: ArrayLike = 0.0,
                 bias_instability_low_hz: float = 1e-5) -> None:
        # explicit so that scalars and lists type-check; the fields are (3,) float64 arrays
        given = locals()
        for name in _ARRAY_FIELDS:
            arr = as_array(given[name], name, allow_nan=True)
            if arr.ndim == 0:
                arr = np.full(3, float(arr))
            if arr.shape != (3,):
                raise InvalidInputError(
                    f"`{name}` must be a scalar or have shape (3,); got shape {arr.shape}"
                )
            bad = ~np.isfinite(arr) if name == "rate_ramp" else ~(np.isfinite(arr) & (arr >= 0))
            if bad.any():
                rule = "finite" if name == "rate_ramp" else "finite and ≥ 0"
                raise InvalidInputError(f"`{name}` must be {rule}; got {arr.tolist()}")
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        missing = (self.markov_sigma > 0) & (self.markov_time_constant_s <= 0)
        if missing.any():
            raise InvalidInputError(
                "`markov_time_constant_s` must be > 0 where `markov_sigma` > 0; got "
                f"{self.markov_time_constant_s.tolist()} with sigma {self.markov_sigma.tolist()}"
            )
        f0 = check_positive(bias_instability_corner_hz, "bias_instability_corner_hz")
        f_low = check_positive(bias_instability_low_hz, "bias_instability_low_hz")
        if f_low >= f0:
            raise InvalidInputError(
                f"`bias_instability_low_hz` must be below `bias_instability_corner_hz` ({f0} Hz);"
                f" got {f_low} Hz"
            )
        object.__setattr__(self, "bias_instability_corner_hz", f0)
        object.__setattr__(self, "bias_instability_low_hz", f_low)

    @classmethod
    def from_datasheet(
        cls, *,
        noise_density_one_sided: ArrayLike | None = None,
        noise_density_dps_rthz: ArrayLike | None = None,
        noise_density_ug_rthz: ArrayLike | None = None,
        arw_deg_rth: ArrayLike | None = None, vrw_mps_rth: ArrayLike | None = None,
        bias_instability_dph: ArrayLike | None = None,
        bias_instability_ug: ArrayLike | None = None,
        bias_instability_is_allan_minimum: bool = False,
        bias_instability_corner_hz: float = 1.0, bias_instability_low_hz: float = 1e-5,
        rrw_deg_h_rth: ArrayLike | None = None, random_walk_ug_rth: ArrayLike | None = None,
        rate_ramp_dph_per_h: ArrayLike | None = None,
        rate_ramp_ug_per_h: ArrayLike | None = None,
        quantization_arcsec: ArrayLike | None = None, quantization_mps: ArrayLike | None = None,
        markov_sigma_dph: ArrayLike | None = None, markov_sigma_ug: ArrayLike | None = None,
        markov_time_constant_s: ArrayLike | None = None,
    ) -> NoiseModel:
        """Build a model from datasheet figures, converting each to SI at the boundary.

        Each value is a scalar or a (3,) array. Give at most one value per term, and do not mix
        gyro and accelerometer units. Conversions (docs/equations.md §1; constants of
        :mod:`imucalib.units`):

        ===============================  ======================  =================================
        argument                         datasheet unit          SI coefficient
        ===============================  ======================  =================================
        ``noise_density_one_sided``      one-sided, SI           N = ND/√2
        ``noise_density_dps_rthz``       one-sided (°/s)/√Hz     N = ND·(π/180)/√2 [rad/√s]
        ``noise_density_ug_rthz``        one-sided µg/√Hz        N = ND·9.80665e-6/√2 [m/s/√s]
        ``arw_deg_rth``                  °/√h (two-sided N)      N = ARW·(π/180)/60 [rad/√s]
        ``vrw_mps_rth``                  (m/s)/√h                N = VRW/60 [(m/s)/√s]
        ``bias_instability_dph``         °/h                     B = ·π/(180·3600) [rad/s]
        ``bias_instability_ug``          µg                      B = ·9.80665e-6 [m/s²]
        ``rrw_deg_h_rth``                °/h/√h                  K = ·π/(180·3600^1.5) [rad/s/√s]
        ``random_walk_ug_rth``           µg/√h                   K = ·9.80665e-6/60 [m/s²/√s]
        ``rate_ramp_dph_per_h``          °/h/h                   R = ·π/(180·3600²) [rad/s²]
        ``rate_ramp_ug_per_h``           µg/h                    R = ·9.80665e-6/3600 [m/s³]
        ``quantization_arcsec``          ″                       Q = ·π/(180·3600) [rad]
        ``quantization_mps``             m/s                     Q [m/s]
        ``markov_sigma_dph`` / ``_ug``   °/h / µg                as B; needs the time constant
        ===============================  ======================  =================================

        So 0.008 (°/s)/√Hz one-sided is N = 0.3394 °/√h. With
        `bias_instability_is_allan_minimum` the datasheet figure is taken as the Allan minimum
        σ_min ("in-run bias stability") and B = σ_min/0.6643 (docs/equations.md §8).
        `bias_instability_corner_hz`, `bias_instability_low_hz` and `markov_time_constant_s`
        [s] pass through.

        Raises
        ------
        InvalidInputError
            If two values are given for one term, gyro and accelerometer units are mixed, a
            Markov σ comes without its time constant, or a value is invalid.
        """
        given = locals()
        bi = FLICKER_ALLAN_FACTOR if bias_instability_is_allan_minimum else 1.0
        values: dict[str, Any] = {}
        source: dict[str, str] = {}
        kinds: dict[str, str] = {}
        for arg, (target, factor, kind) in _DATASHEET.items():
            value = given[arg]
            if value is None:
                continue
            if target == "bias_instability":
                factor /= bi
            if target in source:
                raise InvalidInputError(
                    f"give one of `{source[target]}` and `{arg}`, not both (both set {target})"
                )
            if kind:
                kinds.setdefault(kind, arg)
            values[target] = as_array(value, arg, allow_nan=True) * factor
            source[target] = arg
        if len(kinds) > 1:
            raise InvalidInputError(
                f"gyro and accelerometer units are mixed: `{kinds['gyro']}` and "
                f"`{kinds['accel']}`; build one model per triad"
            )
        if "markov_sigma" in values and "markov_time_constant_s" not in values:
            raise InvalidInputError(
                f"`{source['markov_sigma']}` needs `markov_time_constant_s`; got none"
            )
        return cls(**values, bias_instability_corner_hz=bias_instability_corner_hz,
                   bias_instability_low_hz=bias_instability_low_hz)

    def is_zero(self) -> bool:
        """Return True if the model adds no noise at all."""
        return not any(
            np.any(getattr(self, name) != 0.0)
            for name in _ARRAY_FIELDS
            if name != "markov_time_constant_s"
        )

    def isclose(self, other: NoiseModel, *, atol: float) -> bool:
        """Return True if `other` has the same coefficients within `atol` (absolute, each in SI).

        The band edges and the Markov time constants (where either σ is non-zero) must agree to
        a relative 1e-9 instead, since they are not noise amplitudes.
        """
        if not isinstance(other, NoiseModel):
            return False
        for name in _ARRAY_FIELDS[:-1]:
            if not np.allclose(getattr(self, name), getattr(other, name), rtol=0.0, atol=atol):
                return False
        used = (self.markov_sigma > 0) | (other.markov_sigma > 0)
        return bool(
            np.allclose(self.markov_time_constant_s[used], other.markov_time_constant_s[used],
                        rtol=1e-9, atol=0.0)
            and np.allclose([self.bias_instability_corner_hz, self.bias_instability_low_hz],
                            [other.bias_instability_corner_hz, other.bias_instability_low_hz],
                            rtol=1e-9, atol=0.0)
        )

    def to_dict(self) -> dict[str, Any]:
        """Return a JSON-able description; :meth:`from_dict` rebuilds it exactly."""
        out: dict[str, Any] = {"density_convention": _CONVENTION}
        for f in fields(self):
            value = getattr(self, f.name)
            out[f.name] = value.tolist() if isinstance(value, np.ndarray) else float(value)
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> NoiseModel:
        """Rebuild a model written by :meth:`to_dict`.

        Raises InvalidInputError for a non-mapping, unknown keys, or a one-sided convention.
        """
        if not isinstance(data, Mapping):
            raise InvalidInputError(f"`data` must be a mapping; got {type(data).__name__}")
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - known - {"density_convention"})
        if unknown:
            raise InvalidInputError(
                f"unknown key(s) {unknown} in a NoiseModel description; expected {sorted(known)}"
            )
        convention = data.get("density_convention", _CONVENTION)
        if convention != _CONVENTION:
            raise InvalidInputError(
                f"`density_convention` must be {_CONVENTION!r} (divide one-sided densities by "
                f"√2, or use NoiseModel.from_datasheet); got {convention!r}"
            )
        return cls(**{k: v for k, v in data.items() if k in known})


@dataclass(frozen=True)
class _AdevTerms:
    """The squared coefficients of one model's Allan-variance terms (docs/equations.md §8).

    None for a term that is zero on every axis: it adds exactly 0, so leaving it out of the sum
    changes no bit of the result.
    """

    quantization: NDArray[np.float64] | None  # 3Q²
    white: NDArray[np.float64] | None  # N²
    random_walk: NDArray[np.float64] | None  # K²
    rate_ramp: NDArray[np.float64] | None  # R²
    flicker: NDArray[np.float64] | None  # B²
    markov: tuple[NDArray[np.bool_], NDArray[np.float64], NDArray[np.float64]] | None
    corner_hz: float


#: Per-model terms of :func:`compute_theoretical_adev`; models are immutable (read-only arrays),
#: so an entry never goes stale, and it goes with its model.
_ADEV_TERMS: weakref.WeakKeyDictionary[NoiseModel, _AdevTerms] = weakref.WeakKeyDictionary()


def _adev_terms(model: NoiseModel) -> _AdevTerms:
    """Return (and cache) the squared coefficients of `model`'s Allan-variance terms."""
    terms = _ADEV_TERMS.get(model)
    if terms is None:
        m = model
        used = m.markov_sigma > 0
        terms = _AdevTerms(
            quantization=3 * m.quantization**2 if np.any(m.quantization != 0) else None,
            white=m.white_density**2 if np.any(m.white_density != 0) else None,
            random_walk=m.random_walk**2 if np.any(m.random_walk != 0) else None,
            rate_ramp=m.rate_ramp**2 if np.any(m.rate_ramp != 0) else None,
            flicker=m.bias_instability**2 if np.any(m.bias_instability != 0) else None,
            markov=((used, np.where(used, m.markov_time_constant_s, 1.0), m.markov_sigma**2)
                    if used.any() else None),
            corner_hz=m.bias_instability_corner_hz)
        _ADEV_TERMS[model] = terms
    return terms


def compute_theoretical_adev(model: NoiseModel, tau_s: ArrayLike) -> NDArray[np.float64]:
    """Return the Allan deviation that `model` predicts, per axis.

    The Allan variances of the terms of docs/equations.md §8 are summed: 3Q²/τ² + N²/τ + flicker
    (IEEE closed form with cut-off f0, no low cut-off: valid for τ ≲ 0.1/f_low) + K²τ/3 +
    R²τ²/2 + Markov (q_c·T_c)²/τ·[1 − (T_c/2τ)(3 − 4e^(−τ/T_c) + e^(−2τ/T_c))], q_c² = 2σ²/T_c.
    A term whose coefficient is zero on every axis is left out of the sum (it adds exactly 0);
    the squared coefficients are computed once per model.

    `tau_s` (shape (m,), > 0) [s]; returns σ_Allan(τ), shape (m, 3) [rad/s | m/s²].
    """
    tau = as_array(tau_s, "tau_s").reshape(-1, 1)
    if np.any(tau <= 0):
        raise InvalidInputError(f"`tau_s` must be > 0; got minimum {tau.min()}")
    c = _adev_terms(model)
    avar = np.zeros((tau.shape[0], 3))
    if c.quantization is not None:
        avar = avar + c.quantization / tau**2
    if c.white is not None:
        avar = avar + c.white / tau
    if c.random_walk is not None:
        avar = avar + c.random_walk * tau / 3
    if c.rate_ramp is not None:
        avar = avar + c.rate_ramp * tau**2 / 2
    if c.flicker is not None:
        avar = avar + c.flicker * _flicker_avar_factor(np.pi * c.corner_hz * tau)
    if c.markov is not None:
        used, tc, sigma2 = c.markov
        r = tau / tc
        with np.errstate(divide="ignore", invalid="ignore"):
            bracket = 1 - (-4 * np.expm1(-r) + np.expm1(-2 * r)) / (2 * r)
        bracket = np.where(r < 1e-3, r**2 / 3 - r**3 / 4 + 7 * r**4 / 60, bracket)
        avar = avar + np.where(used, 2 * sigma2 * tc / tau * bracket, 0.0)
    out: NDArray[np.float64] = np.sqrt(avar)
    return out


def _flicker_avar_factor(x: NDArray[np.float64]) -> NDArray[np.float64]:
    """Return σ²_A/B² of flicker noise cut off at f0, x = π·f0·τ (docs/equations.md §8).

    The IEEE 952 Annex C closed form, (2/π)·[ln 2 − sin³x/(2x²)·(sin x + 4x·cos x) + Ci(2x) −
    Ci(4x)], with both cosine integrals from one ``scipy.special.sici`` call.
    """
    from scipy import special  # imported when used: importing this module stays cheap

    ci = special.sici(np.concatenate([2 * x, 4 * x]))[1]  # one call for Ci(2x) and Ci(4x)
    ci2, ci4 = ci[: x.shape[0]], ci[x.shape[0]:]
    sin_x = np.sin(x)
    out: NDArray[np.float64] = (2 / np.pi) * (math.log(2.0) - sin_x**3 / (2 * x**2)
                                              * (sin_x + 4 * x * np.cos(x)) + ci2 - ci4)
    return out
