"""The temperature model of one calibration parameter, as a calibration result carries it.

Contents
--------
:class:`ParameterTemperatureModel`
    One parameter's fitted model p(T, Ṫ, ℓ) (docs/processing-estimation.md, "Temperature
    models", Eq. (T1)): T0, c_0 … c_m, the optional rate and leg coefficients, their covariance,
    the fit's χ² and ν, the order criterion, the temperature range fitted and the held-out check.
:class:`HeldOutOutcome`
    The outcome of the held-out check (Eqs. (10)–(11) of
    :mod:`imucalib.estimation.temperature_model`).
:data:`ORDER_CRITERIA`
    ``("aicc", "cv", "fixed")``.

Model
-----
::

    p(T, Ṫ, ℓ) = Σ_{j=0..m} c_j (T − T0)^j + d·Ṫ + h·ℓ                                     (T1)
    σ_p² = aᵀ C a,  a = (1, T − T0, …, (T − T0)^m, Ṫ, ℓ)   (the terms present)             (T4)

ℓ = +1 on a heating leg, −1 on a cooling leg, 0 for the mean of both. The data class sits in
``models/`` so that a :class:`~imucalib.models.result.CalibrationResult` can hold it;
``estimation/`` (a higher layer) converts its fits into it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib.errors import InvalidInputError

__all__ = ["ORDER_CRITERIA", "HeldOutOutcome", "ParameterTemperatureModel"]

#: How a model's polynomial order was chosen: AICc, cross-validation, or given by the caller.
ORDER_CRITERIA: Final = ("aicc", "cv", "fixed")
#: Relative tolerance of the covariance's symmetry and of its smallest correlation eigenvalue.
_RTOL: Final = 1e-9
_EIG_TOL: Final = 1e-8


def _finite(value: object, name: str, *, nonnegative: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
        raise InvalidInputError(f"`{name}` must be a number; got {type(value).__name__}")
    x = float(value)
    if not math.isfinite(x):
        raise InvalidInputError(f"`{name}` must be finite; got {x!r}")
    if nonnegative and x < 0:
        raise InvalidInputError(f"`{name}` must be ≥ 0; got {x!r}")
    return x


def _count(value: object, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 0:
        raise InvalidInputError(f"`{name}` must be an integer ≥ 0; got {value!r}")
    return int(value)


@dataclass(frozen=True)
class HeldOutOutcome:
    """The held-out check of a temperature model at temperatures it was not fitted to.

    Attributes
    ----------
    max_abs_z : float
        max |z_i| of the normalised prediction errors. [–]
    chi2 : float
        χ²_h of the prediction errors (their correlations included). [–]
    dof : int
        ν_h, the number of held-out points.
    p_value : float
        P(χ²_ν ≥ χ²_h), in [0, 1].
    consistent : bool
        max |z| ≤ 3 and p ≥ 0.01 (or the limits the check was run with).

    Raises
    ------
    InvalidInputError
        A non-finite or negative number, a p-value outside [0, 1], ν not an integer ≥ 1, or a
        flag that is not a boolean.
    """

    max_abs_z: float
    chi2: float
    dof: int
    p_value: float
    consistent: bool

    def __post_init__(self) -> None:
        object.__setattr__(self, "max_abs_z", _finite(self.max_abs_z, "held_out.max_abs_z",
                                                      nonnegative=True))
        object.__setattr__(self, "chi2", _finite(self.chi2, "held_out.chi2", nonnegative=True))
        dof = _count(self.dof, "held_out.dof")
        if dof < 1:
            raise InvalidInputError(f"`held_out.dof` must be ≥ 1 (held-out points); got {dof}")
        object.__setattr__(self, "dof", dof)
        p = _finite(self.p_value, "held_out.p_value")
        if not 0.0 <= p <= 1.0:
            raise InvalidInputError(f"`held_out.p_value` must be in [0, 1]; got {p!r}")
        object.__setattr__(self, "p_value", p)
        if not isinstance(self.consistent, bool | np.bool_):
            raise InvalidInputError(f"`held_out.consistent` must be a boolean; got "
                                    f"{self.consistent!r}")
        object.__setattr__(self, "consistent", bool(self.consistent))


@dataclass(frozen=True, eq=False)
class ParameterTemperatureModel:
    """The fitted temperature model of one calibration parameter, Eq. (T1).

    Attributes
    ----------
    name : str
        The parameter's name in the result (``gyro_bias_x``, ``accel_M_zz`` …).
    reference_temperature_degc : float
        T0. [°C]
    coefficients : tuple of float
        c_0 … c_m (m ≥ 0); c_j in the parameter's unit per °C^j. c_0 is the value at T0 (the
        result's value of the parameter).
    rate_coefficient : float or None
        d, in the parameter's unit per (°C/s); None: no rate term.
    leg_coefficient : float or None
        h, half the heating − cooling difference, in the parameter's unit; None: no hysteresis
        term.
    covariance : ndarray, shape (q, q)
        The coefficients' covariance in the order c_0 … c_m, d, h (the terms present), q = m + 1
        (+1) (+1); symmetric positive semi-definite.
    chi2 : float
        χ² of the fit (Eq. (T3)). [–]
    dof : int
        ν = K − q of the fit.
    order_criterion : {"aicc", "cv", "fixed"}
        How the order m was chosen.
    temperature_range_degc : tuple of float or None
        (T_min, T_max), the temperatures the model was fitted over. [°C]
    held_out : HeldOutOutcome or None
        The held-out check, when one was made.

    Raises
    ------
    InvalidInputError
        Each defect, naming the field: an empty name, a non-finite number, no coefficients, a
        covariance of the wrong shape, asymmetric beyond 10⁻⁹ relative, with a negative variance
        or not positive semi-definite, a negative χ² or ν, an unknown criterion, or a range with
        T_min > T_max.
    """

    name: str
    reference_temperature_degc: float
    coefficients: tuple[float, ...]
    covariance: NDArray[np.float64]
    chi2: float
    dof: int
    order_criterion: str
    rate_coefficient: float | None = None
    leg_coefficient: float | None = None
    temperature_range_degc: tuple[float, float] | None = None
    held_out: HeldOutOutcome | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.strip():
            raise InvalidInputError(f"`name` must be a non-empty string; got {self.name!r}")
        w = f"temperature model of {self.name!r}: "
        try:
            self._check()
        except InvalidInputError as exc:
            raise InvalidInputError(w + str(exc)) from None

    def _check(self) -> None:
        set_ = object.__setattr__
        set_(self, "reference_temperature_degc",
             _finite(self.reference_temperature_degc, "reference_temperature_degc"))
        if isinstance(self.coefficients, str | bytes) or not hasattr(self.coefficients,
                                                                      "__len__"):
            raise InvalidInputError(f"`coefficients` must be a sequence of numbers; got "
                                    f"{type(self.coefficients).__name__}")
        coeffs = tuple(_finite(c, f"coefficients[{j}]") for j, c in enumerate(self.coefficients))
        if not coeffs:
            raise InvalidInputError("`coefficients` must hold c_0 at least")
        set_(self, "coefficients", coeffs)
        for key in ("rate_coefficient", "leg_coefficient"):
            value = getattr(self, key)
            if value is not None:
                set_(self, key, _finite(value, key))
        q = self.n_terms
        cov = _covariance(self.covariance, q)
        set_(self, "covariance", cov)
        set_(self, "chi2", _finite(self.chi2, "chi2", nonnegative=True))
        set_(self, "dof", _count(self.dof, "dof"))
        if self.order_criterion not in ORDER_CRITERIA:
            raise InvalidInputError(f"`order_criterion` must be one of {list(ORDER_CRITERIA)}; "
                                    f"got {self.order_criterion!r}")
        rng = self.temperature_range_degc
        if rng is not None:
            if isinstance(rng, str) or not hasattr(rng, "__len__") or len(rng) != 2:
                raise InvalidInputError("`temperature_range_degc` must be (T_min, T_max); got "
                                        f"{rng!r}")
            lo = _finite(rng[0], "temperature_range_degc[0]")
            hi = _finite(rng[1], "temperature_range_degc[1]")
            if lo > hi:
                raise InvalidInputError(f"`temperature_range_degc` must have T_min ≤ T_max; got "
                                        f"({lo!r}, {hi!r})")
            set_(self, "temperature_range_degc", (lo, hi))
        if self.held_out is not None and not isinstance(self.held_out, HeldOutOutcome):
            raise InvalidInputError(f"`held_out` must be a HeldOutOutcome or None; got "
                                    f"{type(self.held_out).__name__}")

    # --- access -----------------------------------------------------------------------------
    @property
    def order(self) -> int:
        """m, the polynomial order."""
        return len(self.coefficients) - 1

    @property
    def n_terms(self) -> int:
        """q, the number of coefficients: m + 1, plus one each for the rate and leg terms."""
        return (len(self.coefficients) + (self.rate_coefficient is not None)
                + (self.leg_coefficient is not None))

    @property
    def coefficient_vector(self) -> NDArray[np.float64]:
        """β = (c_0 … c_m, d, h) (the terms present), the order of :attr:`covariance`."""
        extra = [v for v in (self.rate_coefficient, self.leg_coefficient) if v is not None]
        return np.array([*self.coefficients, *extra], dtype=np.float64)

    def design(self, temperature_degc: ArrayLike, temperature_rate_degc_ps: ArrayLike | None = None,
               leg: ArrayLike | None = None) -> NDArray[np.float64]:
        """Return the rows a of Eq. (T4), shape (n, q), at the given points.

        Parameters
        ----------
        temperature_degc : float or array_like, shape (n,)
            T. [°C]
        temperature_rate_degc_ps : float or array_like, shape (n,), optional
            Ṫ; 0 when omitted. [°C/s]
        leg : float or array_like, shape (n,), optional
            ℓ ∈ {−1, 0, +1}; 0 (the mean of both legs) when omitted.
        """
        t = np.atleast_1d(np.asarray(temperature_degc, dtype=np.float64))
        if t.ndim != 1:
            raise InvalidInputError(f"`temperature_degc` must be a scalar or have shape (n,); "
                                    f"got {t.shape}")
        n = t.size
        x = t - self.reference_temperature_degc
        cols = [np.ones(n)]
        for _ in range(self.order):
            cols.append(cols[-1] * x)
        for value, key, present in ((temperature_rate_degc_ps, "temperature_rate_degc_ps",
                                     self.rate_coefficient is not None),
                                    (leg, "leg", self.leg_coefficient is not None)):
            if present:
                v = np.zeros(1) if value is None else np.atleast_1d(
                    np.asarray(value, dtype=np.float64))
                if v.ndim != 1 or v.size not in (1, n):
                    raise InvalidInputError(f"`{key}` must be a scalar or have shape ({n},); "
                                            f"got {v.shape}")
                cols.append(np.broadcast_to(v, (n,)))
        return np.stack(cols, axis=1)

    def evaluate(self, temperature_degc: ArrayLike,
                 temperature_rate_degc_ps: ArrayLike | None = None,
                 leg: ArrayLike | None = None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Return p(T, Ṫ, ℓ) of Eq. (T1) and its σ of Eq. (T4), each shape (n,).

        Arguments as :meth:`design`. σ propagates the coefficients' covariance only (not the
        noise of the temperature reading).
        """
        a = self.design(temperature_degc, temperature_rate_degc_ps, leg)
        value = a @ self.coefficient_vector
        var = np.einsum("ij,jk,ik->i", a, self.covariance, a)
        return value, np.sqrt(np.maximum(var, 0.0))


def _covariance(value: ArrayLike, q: int) -> NDArray[np.float64]:
    try:
        cov = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"`covariance` must be a {q} × {q} array of numbers") from exc
    if cov.shape != (q, q):
        raise InvalidInputError(f"`covariance` must have shape ({q}, {q}) (c_0 … c_m, d, h, "
                                f"the terms present); got {cov.shape}")
    if not np.all(np.isfinite(cov)):
        raise InvalidInputError("`covariance` must be finite")
    diag = np.diag(cov)
    if np.any(diag < 0):
        i = int(np.argmax(diag < 0))
        raise InvalidInputError(f"`covariance[{i}][{i}]` must be ≥ 0; got {float(diag[i])!r}")
    if np.any(np.abs(cov - cov.T) > _RTOL * np.maximum(np.abs(cov), np.abs(cov.T))):
        raise InvalidInputError("`covariance` must be symmetric")
    scale = np.sqrt(diag)
    zero = scale == 0.0
    if np.any(cov[zero] != 0.0):
        raise InvalidInputError("`covariance` has a zero variance with non-zero covariances")
    s = np.where(zero, 1.0, scale)
    lowest = float(np.linalg.eigvalsh(cov / np.outer(s, s)).min())
    if lowest < -_EIG_TOL:
        raise InvalidInputError(f"`covariance` must be positive semi-definite; its correlation "
                                f"matrix has the eigenvalue {lowest:.3g}")
    cov.setflags(write=False)
    return cov
