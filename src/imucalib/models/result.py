"""The result of a calibration: parameters with their covariance, residuals and provenance.

Contents
--------
:class:`CalibrationResult`
    Frozen, one per IMU unit: parameter values by name, their covariance, units, the model they
    belong to, residual statistics per group, sensor identity, provenance, notes; a versioned
    JSON form (:meth:`~CalibrationResult.to_json`, :meth:`~CalibrationResult.from_json`) that
    round-trips exactly.
:class:`ResidualStats`, :class:`Provenance`
    Parts of it.
:data:`RESULT_FORMAT`, :data:`RESULT_FORMAT_VERSION`
    The JSON format's name and version (a newer version is refused with a clear message).

Parameter names
---------------
``<triad>_<symbol>_<axes>`` with triad ``accel`` or ``gyro``:

- ``bias_x`` … the bias b of y = b + (I + M)·x [m/s² | rad/s];
- ``M_xy`` … the scale/misalignment matrix M (row: sensor axis, column: input axis) [–];
- ``G_xy`` … gyro g-sensitivity, y += G·f [rad/s per m/s²];
- the per-axis model of SPEC.md P1, y_i = K_i·(x_i + b_i): ``K_x`` [–] and ``b_x`` (a bias in
  input units) [m/s² | rad/s].

A result's model (``"triad"`` or ``"per-axis"``) says which set it carries.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib.conventions import AXES
from imucalib.errors import InvalidInputError
from imucalib.models.triad import TriadKind, TriadModel

__all__ = [
    "RESULT_FORMAT",
    "RESULT_FORMAT_VERSION",
    "CalibrationResult",
    "Provenance",
    "ResidualStats",
    "triad_parameter_names",
]

RESULT_FORMAT: Final = "imucalib-calibration-result"
RESULT_FORMAT_VERSION: Final = 1
MODELS: Final = ("triad", "per-axis")


def triad_parameter_names(triad: str, model: str, *, g_sensitivity: bool = False
                          ) -> tuple[str, ...]:
    """Return the parameter names of one triad under `model` (module docstring)."""
    if model == "per-axis":
        return (*(f"{triad}_K_{a}" for a in AXES), *(f"{triad}_b_{a}" for a in AXES))
    names = [*(f"{triad}_bias_{a}" for a in AXES),
             *(f"{triad}_M_{i}{j}" for i in AXES for j in AXES)]
    if g_sensitivity:
        names += [f"{triad}_G_{i}{j}" for i in AXES for j in AXES]
    return tuple(names)


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
        :func:`imucalib.models.apply.correct_imu` refuses others.
    residuals : mapping of str to ResidualStats
        Residual statistics per group of observations.
    provenance : Provenance
    notes : tuple of str
        What the reader must know (e.g. that the Earth-rate projection was subtracted).
    format_version : int
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

    # --- access -----------------------------------------------------------------------------
    def std(self) -> dict[str, float]:
        """Return the standard uncertainty of each parameter (√diag of the covariance), SI."""
        return {n: float(math.sqrt(v)) for n, v in zip(self.param_names,
                                                         np.diag(self.covariance), strict=True)}

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

    def has_triad(self, triad: str) -> bool:
        """Whether the result calibrates the ``"gyro"`` or ``"accel"`` triad."""
        return any(n.startswith(f"{triad}_") for n in self.param_names)

    def triad_model(self, triad: TriadKind) -> TriadModel:
        """Return the deterministic model of one triad (bias, scale/misalignment, G).

        The per-axis model y_i = K_i·(x_i + b_i) becomes bias K_i·b_i and M = diag(K − 1).
        """
        if triad not in ("gyro", "accel"):
            raise InvalidInputError(f"`triad` must be 'gyro' or 'accel'; got {triad!r}")
        if not self.has_triad(triad):
            raise InvalidInputError(f"this result does not calibrate the {triad} triad")
        v = self.as_dict()
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
        return TriadModel(kind=triad, bias=bias, scale_misalignment=m, **kwargs)

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
        }

    def to_json(self) -> str:
        """Return the versioned JSON text; :meth:`from_json` rebuilds the result exactly."""
        return json.dumps(self.to_dict(), indent=1, allow_nan=False)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> CalibrationResult:
        """Rebuild a result from :meth:`to_dict`'s form.

        Raises
        ------
        InvalidInputError
            A foreign document, a newer format version, or missing or malformed fields.
        """
        if not isinstance(data, Mapping) or data.get("format") != RESULT_FORMAT:
            got = data.get("format") if isinstance(data, Mapping) else type(data).__name__
            raise InvalidInputError(f"not an imucalib calibration result: expected format "
                                    f"{RESULT_FORMAT!r}, got {got!r}")
        version = data.get("format_version")
        if not isinstance(version, int) or version > RESULT_FORMAT_VERSION or version < 1:
            raise InvalidInputError(
                f"calibration result format_version {version!r} is not supported; this "
                f"imucalib reads versions 1..{RESULT_FORMAT_VERSION} (upgrade imucalib)")
        try:
            params = data["parameters"]
            prov = data.get("provenance", {})
            return cls(
                sensor_id=str(data["sensor_id"]), procedure=str(data["procedure"]),
                model=str(data["model"]), param_names=tuple(p["name"] for p in params),
                values=np.array([p["value"] for p in params], dtype=np.float64),
                covariance=np.array(data["covariance"], dtype=np.float64),
                units={p["name"]: p["unit"] for p in params},
                input_units=dict(data["input_units"]),
                residuals={g: ResidualStats(tuple(r["mean"]), tuple(r["std"]), int(r["n"]),
                                            str(r["unit"]))
                           for g, r in data.get("residuals", {}).items()},
                provenance=Provenance(**{**prov, "details": dict(prov.get("details", {}))}),
                notes=tuple(data.get("notes", ())), format_version=version)
        except (KeyError, TypeError, ValueError) as exc:
            raise InvalidInputError(f"malformed calibration result: {exc!r}") from exc

    @classmethod
    def from_json(cls, text: str) -> CalibrationResult:
        """Rebuild a result from :meth:`to_json`'s text."""
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise InvalidInputError(f"calibration result is not valid JSON: {exc}") from exc
        return cls.from_dict(data)

    def isclose(self, other: CalibrationResult, *, rtol: float = 0.0, atol: float = 0.0
                ) -> bool:
        """Whether `other` has the same names and (within tolerance) values and covariance."""
        return (self.param_names == other.param_names and self.model == other.model
                and np.allclose(self.values, other.values, rtol=rtol, atol=atol)
                and np.allclose(self.covariance, other.covariance, rtol=rtol, atol=atol))
