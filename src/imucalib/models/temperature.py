"""Temperature dependence of any error-model parameter.

Every deterministic parameter of a triad (bias, scale factor and misalignment, nonlinearity,
g-sensitivity, …) may drift with the sensor's temperature T and, through thermal stress and the
Shupe effect, with its rate of change dT/dt. This module holds that dependence, separately from the
parameters themselves, so that any model can carry it.

Contents
--------
:class:`TemperatureDependence`
    Polynomial coefficients in (T − T0) and temperature-rate coefficients, per parameter name.
:func:`evaluate_parameter`
    The value of one parameter at given temperatures and temperature rates.

Model
-----
For a parameter p with value p0 at the reference temperature T0 [°C]::

    p(T, dT/dt) = p0 + Σ_{k=1..K} c_k·(T − T0)^k + d·dT/dt

This is the static soak polynomial plus the first dynamic term of
docs/equations.md §4 (the temperature-rate term D_Ṫ of IEEE 952, docs/equations.md §3). Units of
c_k are the parameter's unit per °C^k; units of d are the parameter's unit per (°C/s).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib._checks import as_array, check_finite_scalar
from imucalib.errors import InvalidInputError

__all__ = ["TemperatureDependence", "evaluate_parameter"]


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

    ``p(T, dT/dt) = p0 + Σ_{k=1..K} c_k·(T − T0)^k + d·dT/dt``

    Parameters
    ----------
    reference_temperature_degc : float
        T0, the temperature at which the parameters take their base values. [°C]
    coefficients : mapping of str to array_like, shape (K, *parameter_shape)
        Polynomial coefficients per parameter name; row k-1 multiplies (T − T0)^k, so it is in the
        parameter's unit per °C^k. K may differ between parameters.
    rate_coefficients : mapping of str to array_like, shape parameter_shape
        Coefficient d of the temperature rate dT/dt per parameter name. [parameter unit per °C/s]

    Raises
    ------
    InvalidInputError
        If T0 is not finite, a coefficient array is not finite, or a polynomial array has no rows.

    Notes
    -----
    The arrays are copied and made read-only. The owning model (for example
    :class:`~imucalib.models.triad.TriadModel`) checks the names and the parameter shapes.
    A parameter absent from both mappings does not depend on temperature.
    """

    reference_temperature_degc: float = 25.0
    coefficients: Mapping[str, NDArray[np.float64]] = field(default_factory=dict)
    rate_coefficients: Mapping[str, NDArray[np.float64]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        t0 = check_finite_scalar(self.reference_temperature_degc, "reference_temperature_degc")
        object.__setattr__(self, "reference_temperature_degc", t0)
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
        """Names of the parameters that depend on temperature or its rate, sorted."""
        return tuple(sorted(set(self.coefficients) | set(self.rate_coefficients)))

    def depends_on(self, name: str) -> bool:
        """Return True if parameter `name` has a non-zero temperature or rate coefficient."""
        arrays = [self.coefficients.get(name), self.rate_coefficients.get(name)]
        return any(a is not None and bool(np.any(a != 0.0)) for a in arrays)

    def isclose(self, other: TemperatureDependence, *, atol: float) -> bool:
        """Return True if both describe the same dependence within `atol` (absolute, per entry).

        A parameter missing from one side counts as all-zero coefficients, and polynomials of
        different degree are compared after padding the shorter with zeros. The reference
        temperatures must agree within `atol` [°C].
        """
        if not isinstance(other, TemperatureDependence):
            return False
        if abs(self.reference_temperature_degc - other.reference_temperature_degc) > atol:
            return False
        for mine, theirs, poly in (
            (self.coefficients, other.coefficients, True),
            (self.rate_coefficients, other.rate_coefficients, False),
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
        """Return a JSON-able description; :meth:`from_dict` rebuilds it exactly."""
        return {
            "reference_temperature_degc": float(self.reference_temperature_degc),
            "coefficients": {k: v.tolist() for k, v in self.coefficients.items()},
            "rate_coefficients": {k: v.tolist() for k, v in self.rate_coefficients.items()},
        }

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
        known = {"reference_temperature_degc", "coefficients", "rate_coefficients"}
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
        )


def _as_temperature_vector(value: ArrayLike, name: str) -> NDArray[np.float64]:
    arr = as_array(value, name)
    if arr.ndim > 1:
        raise InvalidInputError(f"`{name}` must be a scalar or have shape (n,); got {arr.shape}")
    return arr.reshape(-1)


def evaluate_parameter(
    base: ArrayLike,
    name: str,
    dep: TemperatureDependence | None,
    temperature_degc: ArrayLike | None,
    temperature_rate_degc_ps: ArrayLike | None,
) -> NDArray[np.float64]:
    """Evaluate one parameter at given temperatures.

    ``p(T, dT/dt) = p0 + Σ_{k=1..K} c_k·(T − T0)^k + d·dT/dt`` (docs/equations.md §4).

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

    Returns
    -------
    numpy.ndarray
        `base` itself (float64, shape parameter_shape) when `name` does not appear in `dep`;
        otherwise shape (n, *parameter_shape), one value per temperature (n = 1 for a scalar
        temperature).

    Raises
    ------
    InvalidInputError
        If the temperature is needed but missing, the temperature or its rate has the wrong shape,
        or the coefficients do not match `base`'s shape.
    """
    p0 = np.asarray(base, dtype=np.float64)
    if dep is None or (name not in dep.coefficients and name not in dep.rate_coefficients):
        return p0
    if temperature_degc is None:
        raise InvalidInputError(
            f"`temperature_degc` is required: parameter {name!r} depends on temperature"
        )
    temp = _as_temperature_vector(temperature_degc, "temperature_degc")
    if temperature_rate_degc_ps is None:
        rate = np.zeros(1)
    else:
        rate = _as_temperature_vector(temperature_rate_degc_ps, "temperature_rate_degc_ps")
    if temp.size != rate.size and rate.size != 1 and temp.size != 1:
        raise InvalidInputError(
            f"`temperature_rate_degc_ps` must be a scalar or have shape ({temp.size},) like "
            f"`temperature_degc`; got {rate.shape}"
        )
    (n,) = np.broadcast_shapes(temp.shape, rate.shape)
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
    return np.array(out, dtype=np.float64)  # a writable copy even when only broadcast
