"""The result of a calibration: parameters with their covariance, residuals and provenance.

Contents
--------
:class:`CalibrationResult`
    Frozen, one per IMU unit: parameter values by name, their covariance, units, the model they
    belong to, residual statistics per group, sensor identity, provenance, notes; a versioned
    JSON form (:meth:`~CalibrationResult.to_json`, :meth:`~CalibrationResult.from_json`,
    :meth:`~CalibrationResult.load` for a file) that round-trips exactly.
:class:`ResidualStats`, :class:`Provenance`
    Parts of it.
:data:`RESULT_FORMAT`, :data:`RESULT_FORMAT_VERSION`
    The JSON format's name and version (a newer version is refused with a clear message).
:data:`MAX_RESULT_BYTES`
    The largest result file read.

Parameter names
---------------
``<triad>_<symbol>_<axes>`` with triad ``accel`` or ``gyro``:

- ``bias_x`` … the bias b of y = b + (I + M)·x [m/s² | rad/s];
- ``M_xy`` … the scale/misalignment matrix M (row: sensor axis, column: input axis) [–];
- ``G_xy`` … gyro g-sensitivity, y += G·f [rad/s per m/s²];
- ``K2_x`` … accelerometer quadratic scale factor, y_i += K2_i·u_i² with u = (I + M)·x
  [1/(m/s²)] (procedure P2, docs/p2.md);
- ``K3_x`` … accelerometer cubic scale factor, y_i += K3_i·u_i³ [1/(m/s²)²] (the field
  calibration's terms chosen by the data, docs/field.md); after the K2 names when both are
  present. K2 and K3 are those of :class:`~imucalib.models.triad.TriadModel` (``k2``, ``k3``);
  a triad model's accelerometer may carry K2, K3, both or neither;
- the per-axis model of procedure P1 (docs/p1.md, steps 1 and 3), y_i = K_i·(x_i + b_i):
  ``K_x`` [–] and ``b_x`` (a bias in input units) [m/s² | rad/s].

A result's model (``"triad"`` or ``"per-axis"``) says which set it carries.

Reading a result file
---------------------
A result file is checked field by field before anything uses it
(:class:`imucalib.models._result_reader.ResultReader`); each defect is an
:class:`~imucalib.errors.InvalidInputError` whose one-line message names the file and the field
(``parameters[3].value``, ``covariance[2][5]``, ``residuals.<group>.n``):

- the file: unreadable, over :data:`MAX_RESULT_BYTES`, not UTF-8, not JSON (or nested too
  deeply), not an object whose ``format`` is :data:`RESULT_FORMAT`, a ``format_version`` other
  than an integer 1 … :data:`RESULT_FORMAT_VERSION`;
- the fields: exactly those :meth:`~CalibrationResult.to_dict` writes, at every level (a missing
  or an unknown field is refused; ``provenance.details`` alone is free-form);
- the values: strings where strings belong, numbers that are numbers (not strings, booleans or
  null) and finite (the JSON extensions NaN and Infinity are refused, in ``details`` too); the
  parameter names exactly one model's set per triad (optional G terms only for the gyro and
  K2 and/or K3 terms only for the accelerometer of a triad model); known ``input_units``; residual
  counts that are integers ≥ 0;
- the covariance: k × k for k parameters, variances ≥ 0, symmetric to a relative 10⁻⁹, each
  ``std`` equal to √ of its variance to 10⁻⁹ (a hand-edited value is caught), zero rows where
  a variance is zero, and positive semi-definite (the correlation matrix's smallest eigenvalue
  ≥ −10⁻⁸);
- the temperature models (format version 3, ``temperature_models[i].…``): each field as
  :class:`~imucalib.models.temperature_record.ParameterTemperatureModel` wants it (the rate and
  leg coefficients, the temperature range and the held-out check may be null), the covariance
  q × q for the terms present and checked like the result's, the name a parameter of the result
  and given once, one T0 for all, and c_0 equal to the parameter's value to 10⁻⁹ relative.
"""

from __future__ import annotations

import json
import math
import os
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib.conventions import AXES
from imucalib.errors import InvalidInputError
from imucalib.models._result_format import (
    MODELS,
    RESULT_DOCUMENT_VERSION,
    RESULT_FORMAT,
    RESULT_FORMAT_VERSION,
    RTOL,
    triad_parameter_names,
    triad_parameter_unit,
)
from imucalib.models._result_reader import ResultReader
from imucalib.models.fit_quality import FitQuality
from imucalib.models.temperature import TemperatureDependence
from imucalib.models.temperature_record import (
    HeldOutOutcome,
    ParameterTemperatureModel,
)
from imucalib.models.triad import TriadKind, TriadModel

__all__ = [
    "MAX_RESULT_BYTES",
    "RESULT_FORMAT",
    "RESULT_FORMAT_VERSION",
    "CalibrationResult",
    "FitQuality",
    "HeldOutOutcome",
    "ParameterTemperatureModel",
    "Provenance",
    "ResidualStats",
    "fit_quality_dict",
    "parse_result_json",
    "read_result_text",
    "triad_parameter_names",
    "triad_parameter_unit",
]

#: Largest result file :meth:`CalibrationResult.load` reads (a P1 result is about 40 kB). [B]
MAX_RESULT_BYTES: Final = 16 * 2**20


@dataclass(frozen=True)
class ResidualStats:
    """Residuals of one group of observations (one position, one rate point …).

    Attributes
    ----------
    mean, std : tuple of float
        Mean and standard deviation of the residuals per axis, in the group's unit.
    n : int
        Number of residual samples (or observations).
    unit : str
        Unit of `mean` and `std`.
    """

    mean: tuple[float, ...]
    std: tuple[float, ...]
    n: int
    unit: str


@dataclass(frozen=True)
class Provenance:
    """Where a result came from: plan and recording hashes, software, time, and free details."""

    plan_hash: str = ""
    recording_sha256: str = ""
    recording: str = ""
    software_version: str = ""
    created_utc: str = ""
    details: Mapping[str, Any] = field(default_factory=dict)


def _floats(values: ArrayLike, name: str, shape: tuple[int, ...]) -> NDArray[np.float64]:
    arr = np.array(values, dtype=np.float64)
    if arr.shape != shape:
        raise InvalidInputError(f"`{name}` must have shape {shape}; got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InvalidInputError(f"`{name}` must be finite; got {arr.tolist()}")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, kw_only=True, eq=False)
class CalibrationResult:
    """A calibration of one IMU unit.

    Attributes
    ----------
    sensor_id : str
        The unit's serial number (its stream name in the Recording).
    procedure : str
        ``"p1"``, ``"p2"`` …
    model : {"triad", "per-axis"}
        Which parameter set the result carries (module docstring).
    param_names : tuple of str
        Order of `values` and of the rows and columns of `covariance`.
    values : ndarray, shape (k,)
        The estimates, SI.
    covariance : ndarray, shape (k, k)
        Their covariance, SI.
    units : mapping of str to str
        The unit of each parameter.
    input_units : mapping of str to str
        The units of the data the result applies to (``{"gyro": "rad/s", "accel": "m/s^2"}``);
        :func:`imucalib.models.correct.correct_imu` refuses others.
    residuals : mapping of str to ResidualStats
        Residual statistics per group of observations.
    provenance : Provenance
    notes : tuple of str
        What the reader must know (e.g. that the Earth-rate projection was subtracted).
    fit_quality : tuple of FitQuality
        The goodness of fit of each fitted triad (format version 2). `covariance` is the
        noise-only covariance; where a triad's fit is a misfit, :meth:`covariance_scaled`
        scales its block by the Birge ratio (docs/processing-estimation.md).
    temperature_models : tuple of ParameterTemperatureModel
        The temperature model of each temperature-dependent parameter (format version 3;
        docs/processing-estimation.md, "Temperature models", Eq. (T1)): at most one per
        parameter, all about the same T0, and c_0 equal to the parameter's value in `values`
        (the values hold at T0). Parameters without one do not depend on temperature.
    format_version : int

    Raises
    ------
    InvalidInputError
        An unknown model, repeated names, arrays of the wrong shape or not finite, an asymmetric
        covariance or a negative variance, missing units, a group named twice in
        `fit_quality`, or temperature models that name an unknown parameter, name one twice,
        differ in T0, disagree with `values` at T0, or appear in a format version below 3.
    """

    sensor_id: str
    procedure: str
    model: str
    param_names: tuple[str, ...]
    values: NDArray[np.float64]
    covariance: NDArray[np.float64]
    units: Mapping[str, str]
    input_units: Mapping[str, str] = field(
        default_factory=lambda: {"gyro": "rad/s", "accel": "m/s^2"})
    residuals: Mapping[str, ResidualStats] = field(default_factory=dict)
    provenance: Provenance = field(default_factory=Provenance)
    notes: tuple[str, ...] = ()
    fit_quality: tuple[FitQuality, ...] = ()
    temperature_models: tuple[ParameterTemperatureModel, ...] = ()
    format_version: int = RESULT_FORMAT_VERSION

    def __post_init__(self) -> None:
        if self.model not in MODELS:
            raise InvalidInputError(f"`model` must be one of {MODELS}; got {self.model!r}")
        names = tuple(self.param_names)
        if len(set(names)) != len(names):
            raise InvalidInputError(f"`param_names` must be unique; got {names}")
        k = len(names)
        object.__setattr__(self, "param_names", names)
        object.__setattr__(self, "values", _floats(self.values, "values", (k,)))
        cov = _floats(self.covariance, "covariance", (k, k))
        if not np.allclose(cov, cov.T, rtol=1e-9, atol=0.0):
            raise InvalidInputError("`covariance` must be symmetric")
        if np.any(np.diag(cov) < 0):
            raise InvalidInputError("`covariance` must have a non-negative diagonal")
        object.__setattr__(self, "covariance", cov)
        missing = [n for n in names if n not in self.units]
        if missing:
            raise InvalidInputError(f"`units` lacks the parameter(s) {missing}")
        object.__setattr__(self, "units", dict(self.units))
        object.__setattr__(self, "input_units", dict(self.input_units))
        object.__setattr__(self, "residuals", dict(self.residuals))
        object.__setattr__(self, "notes", tuple(self.notes))
        object.__setattr__(self, "fit_quality", tuple(self.fit_quality))
        groups = [q.group for q in self.fit_quality]
        if len(set(groups)) != len(groups):
            raise InvalidInputError(f"`fit_quality` names a group twice: {groups}")
        self._check_temperature_models()

    def _check_temperature_models(self) -> None:
        models = tuple(self.temperature_models)
        object.__setattr__(self, "temperature_models", models)
        if not models:
            return
        if self.format_version < 3:
            raise InvalidInputError("`temperature_models` need result format version 3; got "
                                    f"`format_version` {self.format_version}")
        seen: set[str] = set()
        for i, tm in enumerate(models):
            where = f"`temperature_models[{i}]`"
            if not isinstance(tm, ParameterTemperatureModel):
                raise InvalidInputError(f"{where} must be a ParameterTemperatureModel; got "
                                        f"{type(tm).__name__}")
            if tm.name not in self.param_names:
                raise InvalidInputError(f"{where} names {tm.name!r}, not a parameter of this "
                                        "result")
            if tm.name in seen:
                raise InvalidInputError(f"{where} names {tm.name!r} a second time (one model "
                                        "per parameter)")
            seen.add(tm.name)
            t0 = models[0].reference_temperature_degc
            if tm.reference_temperature_degc != t0:
                raise InvalidInputError(
                    f"{where}: T0 = {tm.reference_temperature_degc!r} °C differs from "
                    f"{t0!r} °C of temperature_models[0] (one T0 per result: its values hold "
                    "there)")
            value = float(self.values[self.param_names.index(tm.name)])
            if not math.isclose(tm.coefficients[0], value, rel_tol=RTOL, abs_tol=0.0):
                raise InvalidInputError(
                    f"{where}: c_0 = {tm.coefficients[0]!r} of {tm.name!r} differs from its "
                    f"value {value!r} (the values hold at T0)")

    # --- access -----------------------------------------------------------------------------
    def std(self, *, scaled: bool = False) -> dict[str, float]:
        """Return the standard uncertainty of each parameter, SI.

        √diag of the noise-only covariance, or with ``scaled=True`` of
        :meth:`covariance_scaled` (σ × Birge ratio for a triad whose fit is a misfit).
        """
        cov = self.covariance_scaled if scaled else self.covariance
        return {n: float(math.sqrt(v)) for n, v in zip(self.param_names, np.diag(cov),
                                                         strict=True)}

    def sigma_scale(self, name: str) -> float:
        """Return the factor on a parameter's σ from its group's misfit (1 when none)."""
        group = name.split("_")[0]
        return next((q.sigma_scale for q in self.fit_quality if q.group == group), 1.0)

    @property
    def covariance_scaled(self) -> NDArray[np.float64]:
        """The covariance with each misfit group's rows and columns scaled by its Birge ratio."""
        s = np.array([self.sigma_scale(n) for n in self.param_names])
        return np.asarray(self.covariance * np.outer(s, s), dtype=np.float64)

    @property
    def misfit(self) -> bool:
        """Whether any fitted group's χ² exceeds its misfit threshold."""
        return any(q.misfit for q in self.fit_quality)

    def value(self, name: str) -> float:
        """Return one parameter's value, SI."""
        return float(self.values[self._index(name)])

    def sigma(self, name: str) -> float:
        """Return one parameter's standard uncertainty, SI."""
        i = self._index(name)
        return float(math.sqrt(self.covariance[i, i]))

    def as_dict(self) -> dict[str, float]:
        """Return the parameter values by name."""
        return {n: float(v) for n, v in zip(self.param_names, self.values, strict=True)}

    def _index(self, name: str) -> int:
        try:
            return self.param_names.index(name)
        except ValueError:
            raise InvalidInputError(
                f"no parameter {name!r} in this {self.model} result; have {self.param_names}"
            ) from None

    # --- temperature ------------------------------------------------------------------------
    @property
    def reference_temperature_degc(self) -> float | None:
        """T0 of the temperature models, at which `values` hold; None without any. [°C]"""
        return self.temperature_models[0].reference_temperature_degc \
            if self.temperature_models else None

    @property
    def temperature_range_degc(self) -> tuple[float, float] | None:
        """The narrowest (T_min, T_max) of the temperature models that state one; else None.

        The intersection: a temperature outside it is outside some parameter's fitted range.
        """
        ranges = [tm.temperature_range_degc for tm in self.temperature_models
                  if tm.temperature_range_degc is not None]
        if not ranges:
            return None
        return max(r[0] for r in ranges), min(r[1] for r in ranges)

    def temperature_model(self, name: str) -> ParameterTemperatureModel | None:
        """Return the temperature model of parameter `name`, or None when it has none."""
        self._index(name)
        return next((tm for tm in self.temperature_models if tm.name == name), None)

    def values_at(self, temperature_degc: ArrayLike,
                  temperature_rate_degc_ps: ArrayLike | None = None,
                  leg: ArrayLike | None = None
                  ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Return every parameter at the given temperatures, with its σ.

        p(T, Ṫ, ℓ) and σ_p² = aᵀ C a of docs/processing-estimation.md, Eqs. (T1) and (T4), for a
        parameter with a temperature model; its value and σ from `covariance` for one without.

        Parameters
        ----------
        temperature_degc : float or array_like, shape (n,)
            T. [°C]
        temperature_rate_degc_ps : float or array_like, shape (n,), optional
            Ṫ; 0 when omitted. [°C/s]
        leg : float or array_like, shape (n,), optional
            ℓ: +1 heating, −1 cooling, 0 (the default) the mean of both legs.

        Returns
        -------
        values, std : ndarray, shape (n, k)
            Columns in the order of `param_names`, SI.
        """
        t = np.atleast_1d(np.asarray(temperature_degc, dtype=np.float64))
        if t.ndim != 1 or not np.all(np.isfinite(t)):
            raise InvalidInputError("`temperature_degc` must be a finite scalar or shape (n,)")
        n, k = t.size, len(self.param_names)
        values = np.broadcast_to(self.values, (n, k)).copy()
        std = np.broadcast_to(np.sqrt(np.diag(self.covariance)), (n, k)).copy()
        for tm in self.temperature_models:
            i = self.param_names.index(tm.name)
            values[:, i], std[:, i] = tm.evaluate(t, temperature_rate_degc_ps, leg)
        return values, std

    def has_triad(self, triad: str) -> bool:
        """Whether the result calibrates the ``"gyro"`` or ``"accel"`` triad."""
        return any(n.startswith(f"{triad}_") for n in self.param_names)

    def triad_model(self, triad: TriadKind, *, leg: int = 0) -> TriadModel:
        """Return the deterministic model of one triad (bias, scale/misalignment, G, K2, K3).

        The per-axis model y_i = K_i·(x_i + b_i) becomes bias K_i·b_i and M = diag(K − 1).

        With temperature models, the triad model carries them as a
        :class:`~imucalib.models.temperature.TemperatureDependence` (T0, c_1 … c_m and d of
        Eq. (T1), docs/processing-estimation.md); a leg term cannot be held there, so the base
        values are c_0 + h·`leg` (``leg`` 0: the mean of both legs, ±1: heating or cooling).

        Raises
        ------
        InvalidInputError
            An unknown triad, one the result does not calibrate, a `leg` other than −1, 0, 1,
            or a per-axis result with temperature models (K_i·b_i is not a polynomial of the
            form of Eq. (T1); :meth:`values_at` and
            :func:`~imucalib.models.correct.correct_imu` handle it).
        """
        if leg not in (-1, 0, 1):
            raise InvalidInputError(f"`leg` must be -1, 0 or 1; got {leg!r}")
        if triad not in ("gyro", "accel"):
            raise InvalidInputError(f"`triad` must be 'gyro' or 'accel'; got {triad!r}")
        if not self.has_triad(triad):
            raise InvalidInputError(f"this result does not calibrate the {triad} triad")
        v = self.as_dict()
        mine = [tm for tm in self.temperature_models if tm.name.startswith(f"{triad}_")]
        if self.model == "per-axis" and mine:
            raise InvalidInputError(
                "the per-axis result's temperature models cannot be written as a triad model's "
                "TemperatureDependence (bias K_i·b_i is a product); use values_at or correct_imu")
        for tm in mine:
            if tm.leg_coefficient is not None:
                v[tm.name] += tm.leg_coefficient * leg
        if self.model == "per-axis":
            k = np.array([v[f"{triad}_K_{a}"] for a in AXES])
            b = np.array([v[f"{triad}_b_{a}"] for a in AXES])
            return TriadModel(kind=triad, bias=k * b, scale_misalignment=np.diag(k - 1.0))
        bias = np.array([v[f"{triad}_bias_{a}"] for a in AXES])
        m = np.array([[v[f"{triad}_M_{i}{j}"] for j in AXES] for i in AXES])
        kwargs: dict[str, Any] = {}
        if f"{triad}_G_xx" in v:
            kwargs["g_sensitivity"] = np.array([[v[f"{triad}_G_{i}{j}"] for j in AXES]
                                                for i in AXES])
        for symbol in ("K2", "K3"):  # y_i += K2_i·u_i² + K3_i·u_i³, u = (I + M)·x
            if f"{triad}_{symbol}_x" in v:
                kwargs[symbol.lower()] = np.array([v[f"{triad}_{symbol}_{a}"] for a in AXES])
        if mine:
            kwargs["temperature"] = self._temperature_dependence(triad, mine)
        return TriadModel(kind=triad, bias=bias, scale_misalignment=m, **kwargs)

    def _temperature_dependence(self, triad: str, models: list[ParameterTemperatureModel]
                                ) -> TemperatureDependence:
        """Return a triad's temperature models as a TriadModel's TemperatureDependence."""
        pairs = [((r, c), f"{i}{j}") for r, i in enumerate(AXES) for c, j in enumerate(AXES)]
        fields: dict[str, list[tuple[Any, str]]] = {
            "bias": [(r, f"{triad}_bias_{a}") for r, a in enumerate(AXES)],
            "scale_misalignment": [(pos, f"{triad}_M_{ij}") for pos, ij in pairs],
            "g_sensitivity": [(pos, f"{triad}_G_{ij}") for pos, ij in pairs],
            "k2": [(r, f"{triad}_K2_{a}") for r, a in enumerate(AXES)],
            "k3": [(r, f"{triad}_K3_{a}") for r, a in enumerate(AXES)]}
        by_name = {tm.name: tm for tm in models}
        coefficients: dict[str, NDArray[np.float64]] = {}
        rates: dict[str, NDArray[np.float64]] = {}
        for field_name, entries in fields.items():
            present = [(pos, by_name[n]) for pos, n in entries if n in by_name]
            if not present:
                continue
            shape = (3,) if field_name in ("bias", "k2", "k3") else (3, 3)
            order = max(tm.order for _, tm in present)
            if order > 0:
                poly = np.zeros((order, *shape))
                for pos, tm in present:
                    idx = (slice(0, tm.order), *np.atleast_1d(pos))
                    poly[idx] = tm.coefficients[1:]
                coefficients[field_name] = poly
            if any(tm.rate_coefficient is not None for _, tm in present):
                rate = np.zeros(shape)
                for pos, tm in present:
                    rate[pos] = tm.rate_coefficient or 0.0
                rates[field_name] = rate
        t0 = models[0].reference_temperature_degc
        return TemperatureDependence(t0, coefficients, rates)

    # --- JSON -------------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """Return the JSON-able form (see :meth:`to_json`)."""
        return {
            "format": RESULT_FORMAT,
            "format_version": self.format_version,
            "sensor_id": self.sensor_id,
            "procedure": self.procedure,
            "model": self.model,
            "parameters": [{"name": n, "value": float(v), "unit": self.units[n],
                            "std": float(math.sqrt(self.covariance[i, i]))}
                           for i, (n, v) in enumerate(zip(self.param_names, self.values,
                                                          strict=True))],
            "covariance": self.covariance.tolist(),
            "input_units": dict(self.input_units),
            "residuals": {g: {"mean": list(r.mean), "std": list(r.std), "n": r.n,
                              "unit": r.unit} for g, r in self.residuals.items()},
            "provenance": {"plan_hash": self.provenance.plan_hash,
                           "recording_sha256": self.provenance.recording_sha256,
                           "recording": self.provenance.recording,
                           "software_version": self.provenance.software_version,
                           "created_utc": self.provenance.created_utc,
                           "details": dict(self.provenance.details)},
            "notes": list(self.notes),
            **({"fit_quality": [fit_quality_dict(q) for q in self.fit_quality]}
               if self.format_version >= 2 else {}),
            **({"temperature_models": [_temperature_model_dict(tm)
                                       for tm in self.temperature_models]}
               if self.format_version >= 3 else {}),
        }

    def to_json(self) -> str:
        """Return the versioned JSON text; :meth:`from_json` rebuilds the result exactly."""
        return json.dumps(self.to_dict(), indent=1, allow_nan=False)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str = "<dict>") -> CalibrationResult:
        """Rebuild a result from :meth:`to_dict`'s form, checking every field.

        Parameters
        ----------
        data : mapping
            The parsed JSON document.
        source : str
            What to call the document in messages (the file name).

        Raises
        ------
        InvalidInputError
            A foreign document, a newer format version, a missing or unknown field, or a field
            of the wrong type or value (see the module docstring); the message names `source`
            and the field.
        """
        if isinstance(data, Mapping) and data.get("format") == RESULT_FORMAT \
                and data.get("format_version") == RESULT_DOCUMENT_VERSION:  # its calibration
            inner = data.get("calibration")
            if not isinstance(inner, Mapping):
                raise InvalidInputError(
                    f"{source} is a {data.get('procedure', '?')} result without a whole triad "
                    "model (its `calibration` is null or missing): read it with "
                    "imucalib.models.result_document.load_result")
            data = inner
        fields = ResultReader(source).read(data)
        residuals = {group: ResidualStats(**r) for group, r in fields.pop("residuals").items()}
        provenance = Provenance(**fields.pop("provenance"))
        try:
            return cls(**fields, residuals=residuals, provenance=provenance)
        except InvalidInputError as exc:  # pragma: no cover - the reader's checks come first
            raise InvalidInputError(f"calibration result {source}: {exc}") from exc

    @classmethod
    def from_json(cls, text: str | bytes, source: str = "<text>") -> CalibrationResult:
        """Rebuild a result from :meth:`to_json`'s text (see :meth:`from_dict`)."""
        return cls.from_dict(parse_result_json(text, source), source)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> CalibrationResult:
        """Read a result file written by ``imucalib calibrate`` (:meth:`to_json`'s text).

        Raises
        ------
        InvalidInputError
            A file that cannot be read, is larger than :data:`MAX_RESULT_BYTES`, is not UTF-8
            text or not valid JSON, or any defect :meth:`from_dict` names.
        """
        p = Path(path)
        return cls.from_json(read_result_text(p), str(p))

    def isclose(self, other: CalibrationResult, *, rtol: float = 0.0, atol: float = 0.0
                ) -> bool:
        """Whether `other` has the same names and (within tolerance) values and covariance."""
        return (self.param_names == other.param_names and self.model == other.model
                and np.allclose(self.values, other.values, rtol=rtol, atol=atol)
                and np.allclose(self.covariance, other.covariance, rtol=rtol, atol=atol))


class _HugeIntegerError(ValueError):
    """A JSON integer beyond the range of a float."""


def _json_int(text: str) -> int:
    """Return a JSON integer; refuse one beyond ±1.8e308 (the range of a float)."""
    digits = len(text.lstrip("-"))
    if digits > 309 or (digits == 309 and abs(int(text)) > sys.float_info.max):
        raise _HugeIntegerError(f"an integer of {digits} digits, beyond the range of a number "
                           f"(±{sys.float_info.max:.2g})")
    return int(text)


def parse_result_json(text: str | bytes, source: str) -> Any:
    """Parse a result file's JSON text.

    Raises
    ------
    InvalidInputError
        Not JSON, not UTF-8, nested too deeply, or an integer beyond the range of a number
        (JSON sets no bound; every number of a result is read as a float).
    """
    try:
        return json.loads(text, parse_int=_json_int)
    except _HugeIntegerError as exc:
        raise InvalidInputError(f"calibration result {source} holds {exc}") from None
    except json.JSONDecodeError as exc:
        raise InvalidInputError(f"calibration result {source} is not valid JSON: {exc}"
                                ) from exc
    except UnicodeDecodeError as exc:
        raise InvalidInputError(f"calibration result {source} is not UTF-8 text: {exc}"
                                ) from exc
    except RecursionError as exc:
        raise InvalidInputError(f"calibration result {source} is not a calibration result: "
                                "its JSON nests too deeply") from exc


def read_result_text(path: str | os.PathLike[str]) -> str:
    """Return a result file's text: at most :data:`MAX_RESULT_BYTES`, UTF-8 (a BOM allowed).

    Raises
    ------
    InvalidInputError
        A file that cannot be read, is too large, or is not UTF-8 text (byte and offset named).
    """
    p = Path(path)
    try:
        with open(p, "rb") as fh:
            raw = fh.read(MAX_RESULT_BYTES + 1)
    except OSError as exc:
        raise InvalidInputError(f"cannot read calibration result {p}: "
                                f"{exc.strerror or exc}") from exc
    if len(raw) > MAX_RESULT_BYTES:
        raise InvalidInputError(f"calibration result {p} is larger than "
                                f"{MAX_RESULT_BYTES // 2**20} MiB; a result is a few "
                                "kilobytes of JSON")
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InvalidInputError(
            f"calibration result {p} is not UTF-8 text: byte 0x{raw[exc.start]:02x} at "
            f"offset {exc.start} cannot be decoded (expected the JSON `imucalib calibrate` "
            "writes)") from exc


def _temperature_model_dict(tm: ParameterTemperatureModel) -> dict[str, Any]:
    ho = tm.held_out
    return {"name": tm.name, "reference_temperature_degc": tm.reference_temperature_degc,
            "coefficients": list(tm.coefficients), "rate_coefficient": tm.rate_coefficient,
            "leg_coefficient": tm.leg_coefficient, "covariance": tm.covariance.tolist(),
            "chi2": tm.chi2, "dof": tm.dof, "order_criterion": tm.order_criterion,
            "temperature_range_degc": None if tm.temperature_range_degc is None
            else list(tm.temperature_range_degc),
            "held_out": None if ho is None else {
                "max_abs_z": ho.max_abs_z, "chi2": ho.chi2, "dof": ho.dof,
                "p_value": ho.p_value, "consistent": ho.consistent}}


def fit_quality_dict(q: FitQuality) -> dict[str, Any]:
    """Return a FitQuality as JSON data (undefined ratios of ν = 0 as None)."""
    nan = math.isnan
    return {"group": q.group, "chi2": q.chi2, "dof": q.dof,
            "reduced_chi2": None if q.dof == 0 else q.reduced_chi2,
            "expected_low": None if nan(q.expected_low) else q.expected_low,
            "expected_high": None if nan(q.expected_high) else q.expected_high,
            "quantile": q.quantile, "misfit": q.misfit,
            "birge_ratio": None if q.dof == 0 else q.birge_ratio,
            "sigma_scale": q.sigma_scale}

