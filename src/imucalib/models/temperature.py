"""Temperature dependence of any error-model parameter.

Every deterministic parameter of a triad (bias, scale factor and misalignment, nonlinearity,
g-sensitivity, …) may drift with the sensor's temperature T, through thermal stress and the
Shupe effect with its rate of change dT/dt, and through thermal hysteresis with the direction from
which T was reached. This module holds that dependence, separately from the parameters themselves,
so that any model can carry it.

Contents
--------
:class:`TemperatureDependence`
    Polynomial coefficients in (T − T0), temperature-rate coefficients and hysteresis amplitudes,
    per parameter name, and the hysteresis width.
:func:`evaluate_parameter`
    The value of one parameter at given temperatures, temperature rates and hysteresis states.
:func:`hysteresis_state`
    The hysteresis state s along a temperature history.

Model
-----
For a parameter p with value p0 at the reference temperature T0 [°C] (docs/equations.md §4)::

    p(T, dT/dt, s) = p0 + Σ_{k=1..K} c_k·(T − T0)^k + d·dT/dt + h·s

This is the static soak polynomial plus the first dynamic term of docs/equations.md §4 (the
temperature-rate term D_Ṫ of IEEE 952, docs/equations.md §3), plus a hysteresis term. Units of
c_k are the parameter's unit per °C^k; units of d are the parameter's unit per (°C/s); h is in the
parameter's unit and s is dimensionless.

Hysteresis (docs/equations.md §4, eq. 4.2) follows a rate-independent Duhem model (A. Visintin,
*Differential Models of Hysteresis*, Springer 1994, ch. 5): the state s ∈ [−1, 1] obeys::

    ds = (sign(dT) − s)·|dT| / w

with w > 0 the hysteresis width [°C]. It depends on the path of T, not on time: s is constant
while T is constant, tends to +1 after heating by several widths and to −1 after cooling, and
keeps that value during a soak. So the same soaked temperature gives p + h after a heating
approach and p − h after a cooling one. For T linear between two samples (ΔT = T_k − T_{k−1})
the equation is solved exactly::

    s_k = σ + (s_{k−1} − σ)·exp(−|ΔT|/w),  σ = sign(ΔT)
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib._checks import as_array, check_finite_scalar, check_positive
from imucalib.errors import InvalidInputError

__all__ = ["TemperatureDependence", "evaluate_parameter", "hysteresis_state"]


_DEFAULT_WIDTH_DEGC = 5.0
#: Largest |ΔT|/w of one step used (exp(−40) ≈ 4e-18: the state has reached ±1 to within rounding).
_MAX_STEP = 40.0
#: Largest growth of the cumulated |ΔT|/w within one block of the vectorised recurrence: e^C
#: stays moderate and the rounding of s near 30·ε (about 1e-14).
_MAX_BLOCK = 30.0


class _ReadOnlyMapping(Mapping[str, NDArray[np.float64]]):
    """A picklable, read-only mapping from parameter name to a read-only array."""

    __slots__ = ("_data",)

    def __init__(self, data: dict[str, NDArray[np.float64]]) -> None:
        self._data = data

    def __getitem__(self, key: str) -> NDArray[np.float64]:
        return self._data[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._data)

    def __len__(self) -> int:
        return len(self._data)

    def __repr__(self) -> str:
        items = ", ".join(f"{k!r}: {v!r}" for k, v in self._data.items())
        return "{" + items + "}"


def _frozen_arrays(value: Any, name: str, *, polynomial: bool) -> _ReadOnlyMapping:
    if not isinstance(value, Mapping):
        raise InvalidInputError(
            f"`{name}` must be a mapping from parameter name to array; got {type(value).__name__}"
        )
    out: dict[str, NDArray[np.float64]] = {}
    for key, raw in value.items():
        if not isinstance(key, str) or not key:
            raise InvalidInputError(f"`{name}` keys must be parameter names; got {key!r}")
        arr = as_array(raw, f"{name}[{key!r}]")
        if polynomial and (arr.ndim == 0 or arr.shape[0] == 0):
            raise InvalidInputError(
                f"`{name}[{key!r}]` must have shape (K, *parameter_shape) with K ≥ 1 "
                f"(row k-1 multiplies (T - T0)^k); got {arr.shape}"
            )
        arr.setflags(write=False)
        out[key] = arr
    return _ReadOnlyMapping(out)


@dataclass(frozen=True, eq=False)
class TemperatureDependence:
    """Temperature dependence of named parameters (docs/equations.md §4).

    ``p(T, dT/dt, s) = p0 + Σ_{k=1..K} c_k·(T − T0)^k + d·dT/dt + h·s``

    Parameters
    ----------
    reference_temperature_degc : float
        T0, the temperature at which the parameters take their base values. [°C]
    coefficients : mapping of str to array_like, shape (K, *parameter_shape)
        Polynomial coefficients per parameter name; row k-1 multiplies (T − T0)^k, so it is in the
        parameter's unit per °C^k. K may differ between parameters.
    rate_coefficients : mapping of str to array_like, shape parameter_shape
        Coefficient d of the temperature rate dT/dt per parameter name. [parameter unit per °C/s]
    hysteresis : mapping of str to array_like, shape parameter_shape
        Hysteresis amplitude h per parameter name: the parameter reads p + h after heating by
        several widths and p − h after cooling (state s = ±1, :func:`hysteresis_state`).
        [parameter unit]
    hysteresis_width_degc : float
        w, the temperature change over which the hysteresis state relaxes by 1/e towards ±1
        (:func:`hysteresis_state`). [°C]

    Raises
    ------
    InvalidInputError
        If T0 is not finite, a coefficient array is not finite, a polynomial array has no rows,
        or the hysteresis width is not finite and positive.

    Notes
    -----
    The arrays are copied and made read-only. The owning model (for example
    :class:`~imucalib.models.triad.TriadModel`) checks the names and the parameter shapes.
    A parameter absent from every mapping does not depend on temperature.
    """

    reference_temperature_degc: float = 25.0
    coefficients: Mapping[str, NDArray[np.float64]] = field(default_factory=dict)
    rate_coefficients: Mapping[str, NDArray[np.float64]] = field(default_factory=dict)
    hysteresis: Mapping[str, NDArray[np.float64]] = field(default_factory=dict)
    hysteresis_width_degc: float = _DEFAULT_WIDTH_DEGC

    def __post_init__(self) -> None:
        t0 = check_finite_scalar(self.reference_temperature_degc, "reference_temperature_degc")
        object.__setattr__(self, "reference_temperature_degc", t0)
        width = check_positive(self.hysteresis_width_degc, "hysteresis_width_degc")
        object.__setattr__(self, "hysteresis_width_degc", width)
        object.__setattr__(
            self, "hysteresis", _frozen_arrays(self.hysteresis, "hysteresis", polynomial=False)
        )
        object.__setattr__(
            self, "coefficients", _frozen_arrays(self.coefficients, "coefficients", polynomial=True)
        )
        object.__setattr__(
            self,
            "rate_coefficients",
            _frozen_arrays(self.rate_coefficients, "rate_coefficients", polynomial=False),
        )

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """Names of the parameters that depend on temperature, its rate or its history, sorted."""
        return tuple(sorted(set(self.coefficients) | set(self.rate_coefficients)
                            | set(self.hysteresis)))

    @property
    def has_hysteresis(self) -> bool:
        """True if some hysteresis amplitude is non-zero."""
        return any(bool(np.any(h != 0.0)) for h in self.hysteresis.values())

    def depends_on(self, name: str) -> bool:
        """Return True if parameter `name` has a non-zero temperature, rate or hysteresis term."""
        arrays = [self.coefficients.get(name), self.rate_coefficients.get(name),
                  self.hysteresis.get(name)]
        return any(a is not None and bool(np.any(a != 0.0)) for a in arrays)

    def isclose(self, other: TemperatureDependence, *, atol: float) -> bool:
        """Return True if both describe the same dependence within `atol` (absolute, per entry).

        A parameter missing from one side counts as all-zero coefficients, and polynomials of
        different degree are compared after padding the shorter with zeros. The reference
        temperatures must agree within `atol` [°C], and so must the hysteresis widths when either
        side has a non-zero hysteresis amplitude.
        """
        if not isinstance(other, TemperatureDependence):
            return False
        if abs(self.reference_temperature_degc - other.reference_temperature_degc) > atol:
            return False
        if ((self.has_hysteresis or other.has_hysteresis)
                and abs(self.hysteresis_width_degc - other.hysteresis_width_degc) > atol):
            return False
        for mine, theirs, poly in (
            (self.coefficients, other.coefficients, True),
            (self.rate_coefficients, other.rate_coefficients, False),
            (self.hysteresis, other.hysteresis, False),
        ):
            for name in set(mine) | set(theirs):
                a, b = mine.get(name), theirs.get(name)
                if a is None or b is None:
                    present = b if a is None else a
                    if present is not None and np.any(np.abs(present) > atol):
                        return False
                    continue
                if poly and a.shape[1:] == b.shape[1:] and a.shape[0] != b.shape[0]:
                    k = max(a.shape[0], b.shape[0])
                    a = np.concatenate([a, np.zeros((k - a.shape[0], *a.shape[1:]))])
                    b = np.concatenate([b, np.zeros((k - b.shape[0], *b.shape[1:]))])
                if a.shape != b.shape or not np.allclose(a, b, rtol=0.0, atol=atol):
                    return False
        return True

    def to_dict(self) -> dict[str, Any]:
        """Return a JSON-able description; :meth:`from_dict` rebuilds it exactly.

        The hysteresis keys are written only when there is a hysteresis term or a non-default
        width, so that descriptions of models without hysteresis keep their former form.
        """
        out: dict[str, Any] = {
            "reference_temperature_degc": float(self.reference_temperature_degc),
            "coefficients": {k: v.tolist() for k, v in self.coefficients.items()},
            "rate_coefficients": {k: v.tolist() for k, v in self.rate_coefficients.items()},
        }
        if self.hysteresis or self.hysteresis_width_degc != _DEFAULT_WIDTH_DEGC:
            out["hysteresis"] = {k: v.tolist() for k, v in self.hysteresis.items()}
            out["hysteresis_width_degc"] = float(self.hysteresis_width_degc)
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> TemperatureDependence:
        """Rebuild a dependence written by :meth:`to_dict`.

        Raises
        ------
        InvalidInputError
            If `data` is not a mapping or has keys other than those :meth:`to_dict` writes.
        """
        if not isinstance(data, Mapping):
            raise InvalidInputError(f"`data` must be a mapping; got {type(data).__name__}")
        known = {"reference_temperature_degc", "coefficients", "rate_coefficients", "hysteresis",
                 "hysteresis_width_degc"}
        unknown = sorted(set(data) - known)
        if unknown:
            raise InvalidInputError(
                f"unknown key(s) {unknown} in a TemperatureDependence description; "
                f"expected {sorted(known)}"
            )
        return cls(
            reference_temperature_degc=data.get("reference_temperature_degc", 25.0),
            coefficients=data.get("coefficients", {}),
            rate_coefficients=data.get("rate_coefficients", {}),
            hysteresis=data.get("hysteresis", {}),
            hysteresis_width_degc=data.get("hysteresis_width_degc", _DEFAULT_WIDTH_DEGC),
        )


def _as_temperature_vector(value: ArrayLike, name: str) -> NDArray[np.float64]:
    arr = as_array(value, name)
    if arr.ndim > 1:
        raise InvalidInputError(f"`{name}` must be a scalar or have shape (n,); got {arr.shape}")
    return arr.reshape(-1)


def hysteresis_state(
    temperature_degc: ArrayLike,
    state0: float = 0.0,
    width_degc: float = _DEFAULT_WIDTH_DEGC,
) -> tuple[NDArray[np.float64], float]:
    """Return the hysteresis state along a sampled temperature history.

    ``ds = (sign(dT) − s)·|dT| / w`` (rate-independent Duhem model, docs/equations.md §4), solved
    exactly for T linear between samples: ``s_k = σ + (s_{k−1} − σ)·exp(−|T_k − T_{k−1}|/w)``
    with σ = sign(T_k − T_{k−1}).

    Parameters
    ----------
    temperature_degc : float or array_like, shape (n,)
        The temperature history T_0 … T_{n−1}, in time order. [°C]
    state0 : float
        s_0, the state at the first sample, in [−1, 1]. [–]
    width_degc : float
        w, the hysteresis width. [°C]

    Returns
    -------
    states : numpy.ndarray, shape (n,)
        s_k at every sample (s_0 = `state0`), within [−1, 1]. [–]
    final : float
        s_{n−1}, the state to continue from (`state0` for an empty history).

    Raises
    ------
    InvalidInputError
        If the temperatures are not finite or not one-dimensional, `state0` is outside [−1, 1],
        or `width_degc` is not positive.

    Notes
    -----
    To continue a history in chunks, pass the last temperature of the previous chunk first with
    its final state, and drop the first returned state: the result does not depend on the
    chunking (up to rounding). The linear recurrence s_k = a_k·s_{k−1} + (1 − a_k)·σ_k is
    vectorised as s_k = e^{−C_k}·(s_0 + Σ_{j≤k} e^{C_j}·(1 − a_j)·σ_j) with C_k = Σ_{j≤k} |ΔT_j|/w,
    in blocks over which C grows by at most 30, so that e^{C} stays moderate and the rounding
    error of s about 1e-14. A constant temperature leaves s unchanged exactly.
    """
    temp = _as_temperature_vector(temperature_degc, "temperature_degc")
    s0 = check_finite_scalar(state0, "state0")
    if abs(s0) > 1.0:
        raise InvalidInputError(f"`state0` must be within [-1, 1]; got {s0}")
    width = check_positive(width_degc, "width_degc")
    n = temp.size
    states = np.empty(n)
    if n == 0:
        return states, s0
    states[0] = s0
    if n == 1:
        return states, s0
    dt = np.diff(temp)
    step = np.minimum(np.abs(dt) / width, _MAX_STEP)  # beyond: s = σ to within rounding
    drive = -np.expm1(-step) * np.sign(dt)  # (1 − a_k)·σ_k
    cum = np.concatenate([[0.0], np.cumsum(step)])  # C_0 … C_{n−1}
    start = 0
    while start < n - 1:
        # the block ends at the last sample with C − C_start ≤ _MAX_BLOCK (at least one step)
        end = int(np.searchsorted(cum, cum[start] + _MAX_BLOCK, side="right")) - 1
        end = max(end, start + 1)
        c = np.cumsum(step[start:end])  # C_k − C_start, summed within the block (exact at 0)
        acc = states[start] + np.cumsum(np.exp(c) * drive[start:end])
        states[start + 1:end + 1] = np.exp(-c) * acc
        start = end
    np.clip(states, -1.0, 1.0, out=states)
    return states, float(states[-1])


def evaluate_parameter(
    base: ArrayLike,
    name: str,
    dep: TemperatureDependence | None,
    temperature_degc: ArrayLike | None,
    temperature_rate_degc_ps: ArrayLike | None,
    hysteresis_state: ArrayLike | None = None,
) -> NDArray[np.float64]:
    """Evaluate one parameter at given temperatures.

    ``p(T, dT/dt, s) = p0 + Σ_{k=1..K} c_k·(T − T0)^k + d·dT/dt + h·s`` (docs/equations.md §4).

    Parameters
    ----------
    base : array_like, shape parameter_shape
        p0, the value at the reference temperature. [parameter unit]
    name : str
        The parameter's name, the key looked up in `dep`.
    dep : TemperatureDependence or None
        The dependence; None means none.
    temperature_degc : float or array_like, shape (n,), or None
        Sensor temperature T. Required when `name` depends on temperature. [°C]
    temperature_rate_degc_ps : float or array_like, shape (n,), or None
        Temperature rate dT/dt; None means 0. A scalar is broadcast to every temperature. [°C/s]
    hysteresis_state : float or array_like, shape (n,), or None
        Hysteresis state s in [−1, 1] (:func:`hysteresis_state`); None means 0, the state of a
        sensor without thermal history. A scalar is broadcast to every temperature. [–]

    Returns
    -------
    numpy.ndarray
        `base` itself (float64, shape parameter_shape) when `name` does not appear in `dep`, or
        has only a hysteresis term and `hysteresis_state` is None; otherwise shape
        (n, *parameter_shape), one value per temperature (n = 1 for scalars).

    Raises
    ------
    InvalidInputError
        If the temperature is needed but missing, the temperature, its rate or the state has the
        wrong shape, or the coefficients do not match `base`'s shape.
    """
    p0 = np.asarray(base, dtype=np.float64)
    if dep is None:
        return p0
    thermal = name in dep.coefficients or name in dep.rate_coefficients
    hyst = dep.hysteresis.get(name) if hysteresis_state is not None else None
    if not thermal and hyst is None:
        return p0
    temp = rate = np.zeros(1)
    if thermal:
        if temperature_degc is None:
            raise InvalidInputError(
                f"`temperature_degc` is required: parameter {name!r} depends on temperature"
            )
        temp = _as_temperature_vector(temperature_degc, "temperature_degc")
        if temperature_rate_degc_ps is not None:
            rate = _as_temperature_vector(temperature_rate_degc_ps, "temperature_rate_degc_ps")
        if temp.size != rate.size and rate.size != 1 and temp.size != 1:
            raise InvalidInputError(
                f"`temperature_rate_degc_ps` must be a scalar or have shape ({temp.size},) like "
                f"`temperature_degc`; got {rate.shape}"
            )
    state = np.zeros(1)
    if hyst is not None and hysteresis_state is not None:
        state = _as_temperature_vector(hysteresis_state, "hysteresis_state")
        size = max(temp.size, rate.size)
        if state.size != size and state.size != 1 and size != 1:
            raise InvalidInputError(
                f"`hysteresis_state` must be a scalar or have shape ({size},) like "
                f"`temperature_degc`; got {state.shape}"
            )
    (n,) = np.broadcast_shapes(temp.shape, rate.shape, state.shape)
    expand = (slice(None),) + (None,) * p0.ndim
    out: NDArray[np.float64] = np.broadcast_to(p0, (n, *p0.shape))
    coeffs = dep.coefficients.get(name)
    if coeffs is not None:
        if coeffs.shape[1:] != p0.shape:
            raise InvalidInputError(
                f"`coefficients[{name!r}]` must have shape (K, {', '.join(map(str, p0.shape))}) "
                f"to match the parameter; got {coeffs.shape}"
            )
        dt = np.broadcast_to(temp - dep.reference_temperature_degc, (n,))[expand]
        # Horner: Σ_k c_k dt^k = (((c_K dt + c_{K-1}) dt + …) + c_1) dt
        acc = coeffs[-1] * dt
        for c_k in coeffs[-2::-1]:
            acc += c_k
            acc *= dt
        out = out + acc
    d = dep.rate_coefficients.get(name)
    if d is not None:
        if d.shape != p0.shape:
            raise InvalidInputError(
                f"`rate_coefficients[{name!r}]` must have shape {p0.shape} to match the "
                f"parameter; got {d.shape}"
            )
        out = out + d * np.broadcast_to(rate, (n,))[expand]
    if hyst is not None:
        if hyst.shape != p0.shape:
            raise InvalidInputError(
                f"`hysteresis[{name!r}]` must have shape {p0.shape} to match the parameter; "
                f"got {hyst.shape}"
            )
        out = out + hyst * np.broadcast_to(state, (n,))[expand]
    return np.array(out, dtype=np.float64)  # a writable copy even when only broadcast
