"""The strict reader of a calibration result's JSON (docs in :mod:`imucalib.models.result`).

:class:`ResultReader` checks a decoded result document field by field (every defect one
:class:`~imucalib.errors.InvalidInputError` naming the file and the field) and returns the
checked fields as plain data, from which ``CalibrationResult.from_dict`` (its only caller)
builds the :class:`~imucalib.models.result.CalibrationResult`. Kept apart from the result
itself, whose module holds the data and its writing; what both need (the format's name and
version, the models, the parameter names) is in :mod:`imucalib.models._result_format`, so this
module does not import the result's.
"""

from __future__ import annotations

import json
import math
from typing import Any, Final, NoReturn

import numpy as np
from numpy.typing import NDArray

from imucalib.errors import InvalidInputError
from imucalib.models._result_format import (
    MODELS,
    RESULT_DOCUMENT_VERSION,
    RESULT_FORMAT,
    RESULT_FORMAT_VERSION,
    RTOL,
    triad_parameter_names,
)
from imucalib.models.fit_quality import FitQuality
from imucalib.models.temperature_record import (
    ORDER_CRITERIA,
    HeldOutOutcome,
    ParameterTemperatureModel,
)
from imucalib.units import parse_unit

__all__ = ["ResultReader"]

_FIELDS_V1: Final = ("format", "format_version", "sensor_id", "procedure", "model",
                     "parameters", "covariance", "input_units", "residuals", "provenance",
                     "notes")
_FIELDS_V2: Final = (*_FIELDS_V1, "fit_quality")
_FIELDS: Final = (*_FIELDS_V2, "temperature_models")
_TEMPERATURE_MODEL_FIELDS: Final = ("name", "reference_temperature_degc", "coefficients",
                                    "rate_coefficient", "leg_coefficient", "covariance", "chi2",
                                    "dof", "order_criterion", "temperature_range_degc",
                                    "held_out")
_HELD_OUT_FIELDS: Final = ("max_abs_z", "chi2", "dof", "p_value", "consistent")
_FIT_QUALITY_FIELDS: Final = ("group", "chi2", "dof", "reduced_chi2", "expected_low",
                              "expected_high", "quantile", "misfit", "birge_ratio",
                              "sigma_scale")
_PARAMETER_FIELDS: Final = ("name", "value", "unit", "std")
_RESIDUAL_FIELDS: Final = ("mean", "std", "n", "unit")
_PROVENANCE_FIELDS: Final = ("plan_hash", "recording_sha256", "recording", "software_version",
                             "created_utc", "details")
#: Tolerance of the checks of symmetry, of √diag(covariance) against ``std`` and of the
#: smallest eigenvalue of the correlation matrix (round-off of a computed covariance).
_EIG_TOL: Final = 1e-8


def _kind(value: object) -> str:
    if isinstance(value, bool):
        return "a boolean"
    if value is None:
        return "null"
    if isinstance(value, float) and not math.isfinite(value):
        return "NaN" if math.isnan(value) else ("Infinity" if value > 0 else "-Infinity")
    text = json.dumps(value, allow_nan=True) if isinstance(value, int | float | str) else ""
    if len(text) > 40:
        text = text[:40] + "…"
    names = {dict: "an object", list: "an array", str: f"the string {text}",
             int: text, float: text}
    return names.get(type(value), type(value).__name__)


class ResultReader:
    """Check a parsed result document field by field; every message names the source."""

    def __init__(self, source: str) -> None:
        self.source = source

    def fail(self, where: str, text: str) -> NoReturn:
        raise InvalidInputError(f"calibration result {self.source}: field {where!r}: {text}")

    def obj(self, value: object, where: str, fields: tuple[str, ...] | None) -> dict[str, Any]:
        if not isinstance(value, dict):
            self.fail(where, f"expected an object; got {_kind(value)}")
        if fields is not None:
            missing = [f for f in fields if f not in value]
            extra = sorted(str(k) for k in value if k not in fields)
            if missing:
                self.fail(where, f"missing field(s) {missing}")
            if extra:
                self.fail(where, f"unknown field(s) {extra}; expected exactly {list(fields)}")
        return value

    def array(self, value: object, where: str, length: int | None = None) -> list[Any]:
        if not isinstance(value, list):
            self.fail(where, f"expected an array; got {_kind(value)}")
        if length is not None and len(value) != length:
            self.fail(where, f"expected {length} elements; got {len(value)}")
        return value

    def text(self, value: object, where: str, *, nonempty: bool = False) -> str:
        if not isinstance(value, str):
            self.fail(where, f"expected a string; got {_kind(value)}")
        if nonempty and not value.strip():
            self.fail(where, "expected a non-empty string")
        return value

    def number(self, value: object, where: str, *, nonnegative: bool = False) -> float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            self.fail(where, f"expected a number; got {_kind(value)}")
        try:
            x = float(value)
        except OverflowError:  # an integer beyond the largest float (JSON has no bound)
            self.fail(where, "expected a finite number; got an integer of about "
                      f"{int(abs(int(value)).bit_length() * math.log10(2)) + 1} digits")
        if not math.isfinite(x):
            self.fail(where, f"expected a finite number; got {_kind(value)}")
        if nonnegative and x < 0:
            self.fail(where, f"expected a number ≥ 0; got {value!r}")
        return x

    def numbers(self, value: object, where: str, length: int | None = None, *,
                nonnegative: bool = False) -> list[float]:
        return [self.number(v, f"{where}[{i}]", nonnegative=nonnegative)
                for i, v in enumerate(self.array(value, where, length))]

    def unit(self, value: object, where: str) -> str:
        unit = self.text(value, where, nonempty=True)
        try:
            parse_unit(unit)
        except InvalidInputError:
            self.fail(where, f"unknown unit {unit!r} (expected e.g. 'rad/s' or 'm/s^2')")
        return unit

    def free(self, value: object, where: str) -> None:
        """Refuse NaN and infinities anywhere in a free-form value (JSON has neither)."""
        if isinstance(value, float) and not math.isfinite(value):
            self.fail(where, f"expected finite numbers; got {_kind(value)}")
        if isinstance(value, dict):
            for k, v in value.items():
                self.free(v, f"{where}.{k}")
        elif isinstance(value, list):
            for i, v in enumerate(value):
                self.free(v, f"{where}[{i}]")

    # --- the document ---------------------------------------------------------------------
    def header(self, data: object) -> int:
        if not isinstance(data, dict) or data.get("format") != RESULT_FORMAT:
            got = (_kind(data.get("format")) if isinstance(data, dict) and "format" in data
                   else "no `format` field" if isinstance(data, dict) else _kind(data))
            raise InvalidInputError(
                f"{self.source} is not an imucalib calibration result: expected a JSON object "
                f"with format {RESULT_FORMAT!r}; got {got}")
        version = data.get("format_version")
        if isinstance(version, bool) or not isinstance(version, int) \
                or not 1 <= version <= RESULT_FORMAT_VERSION:
            raise InvalidInputError(
                f"calibration result {self.source}: format_version {_kind(version)} is not "
                f"supported; this imucalib reads versions 1..{RESULT_DOCUMENT_VERSION} (a "
                "newer version needs a newer imucalib)")
        return version

    def names(self, names: list[str], model: str) -> None:
        triads = {n.split("_")[0] for n in names}
        unknown = sorted(t for t in triads if t not in ("accel", "gyro"))
        if unknown or not names:
            self.fail("parameters", "expected the parameters of the accel and/or gyro triad "
                      f"(names `accel_…`, `gyro_…`); got {sorted(set(names))[:6]}")
        for triad in sorted(triads):
            have = {n for n in names if n.startswith(f"{triad}_")}
            base = set(triad_parameter_names(triad, model))
            # a triad model may add the gyro's G terms, or the accelerometer's K2 terms, K3
            # terms or both (each term all three axes or none)
            extra = {"gyro": "G terms", "accel": "K2 terms, the K3 terms or both"}[triad] \
                if model == "triad" else ""
            accel = triad == "accel" and model == "triad"
            allowed = [set(triad_parameter_names(triad, model, g_sensitivity=g, k2=k2, k3=k3))
                       for g in ((False, True) if triad == "gyro" and extra else (False,))
                       for k2 in ((False, True) if accel else (False,))
                       for k3 in ((False, True) if accel else (False,))]
            full = set().union(*allowed)
            if have in allowed:
                continue
            # an optional term present on some axes only lacks the others
            partial = {n for n in full - base
                       if any(h.rsplit("_", 1)[0] == n.rsplit("_", 1)[0] for h in have)}
            self.fail("parameters", f"the {triad} parameters of a {model} result must be "
                      f"{sorted(base)}" + (f" (and optionally the {extra}, each on all three "
                                           "axes)" if extra else "")
                      + f"; missing {sorted((base | partial) - have)}, unexpected "
                      f"{sorted(have - full)}")

    def covariance(self, value: object, std: list[float]) -> NDArray[np.float64]:
        k = len(std)
        rows = self.array(value, "covariance", k)
        cov = np.array([self.numbers(r, f"covariance[{i}]", k) for i, r in enumerate(rows)],
                       dtype=np.float64).reshape(k, k)
        diag = np.diag(cov)
        if np.any(diag < 0):
            i = int(np.argmax(diag < 0))
            self.fail(f"covariance[{i}][{i}]",
                      f"a variance must be ≥ 0; got {float(diag[i])!r}")
        asym = np.abs(cov - cov.T) > RTOL * np.maximum(np.abs(cov), np.abs(cov.T))
        if asym.any():
            i, j = (int(v) for v in np.argwhere(asym)[0])
            self.fail("covariance", f"must be symmetric; [{i}][{j}] = {float(cov[i, j])!r} but "
                      f"[{j}][{i}] = {float(cov[j, i])!r}")
        for i in range(k):
            root = math.sqrt(diag[i])
            if abs(std[i] - root) > RTOL * max(root, abs(std[i])):
                self.fail(f"parameters[{i}].std", f"{std[i]!r} disagrees with "
                          f"√covariance[{i}][{i}] = {root!r} (a hand-edited file?)")
        scale = np.sqrt(diag)
        zero = scale == 0.0
        if np.any(cov[zero] != 0.0):
            i = int(np.flatnonzero(zero)[0])
            self.fail("covariance", f"row {i} has a zero variance but non-zero covariances")
        s = np.where(zero, 1.0, scale)
        corr = cov / np.outer(s, s)
        lowest = float(np.linalg.eigvalsh(corr).min()) if k else 0.0
        if lowest < -_EIG_TOL:
            self.fail("covariance", "must be positive semi-definite; the correlation matrix "
                      f"has the eigenvalue {lowest:.3g}")
        return cov

    def fit_quality(self, value: object, where: str) -> FitQuality:
        q = self.obj(value, where, _FIT_QUALITY_FIELDS)
        dof = q["dof"]
        if isinstance(dof, bool) or not isinstance(dof, int) or dof < 0:
            self.fail(f"{where}.dof", f"expected an integer ≥ 0; got {_kind(dof)}")
        misfit = q["misfit"]
        if not isinstance(misfit, bool):
            self.fail(f"{where}.misfit", f"expected true or false; got {_kind(misfit)}")

        def optional(key: str) -> float:
            v = q[key]
            return math.nan if v is None and dof == 0 else self.number(v, f"{where}.{key}")

        out = FitQuality(group=self.text(q["group"], f"{where}.group", nonempty=True),
                         chi2=self.number(q["chi2"], f"{where}.chi2", nonnegative=True),
                         dof=dof, expected_low=optional("expected_low"),
                         expected_high=optional("expected_high"), misfit=misfit,
                         quantile=self.number(q["quantile"], f"{where}.quantile"))
        for key, derived in (("reduced_chi2", out.reduced_chi2), ("birge_ratio",
                                                                   out.birge_ratio),
                             ("sigma_scale", out.sigma_scale)):
            given = optional(key)
            if not (math.isnan(derived) and math.isnan(given)) and not math.isclose(
                    given, derived, rel_tol=RTOL):
                self.fail(f"{where}.{key}", f"{given!r} disagrees with χ² and ν "
                          f"({derived!r}; a hand-edited file?)")
        return out

    def integer(self, value: object, where: str, *, low: int = 0) -> int:
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            self.fail(where, f"expected an integer ≥ {low}; got {_kind(value)}")
        return value

    def optional_number(self, value: object, where: str) -> float | None:
        return None if value is None else self.number(value, where)

    def held_out(self, value: object, where: str) -> HeldOutOutcome | None:
        if value is None:
            return None
        h = self.obj(value, where, _HELD_OUT_FIELDS)
        consistent = h["consistent"]
        if not isinstance(consistent, bool):
            self.fail(f"{where}.consistent", f"expected true or false; got {_kind(consistent)}")
        p = self.number(h["p_value"], f"{where}.p_value", nonnegative=True)
        if p > 1.0:
            self.fail(f"{where}.p_value", f"expected a probability in [0, 1]; got {p!r}")
        return HeldOutOutcome(
            max_abs_z=self.number(h["max_abs_z"], f"{where}.max_abs_z", nonnegative=True),
            chi2=self.number(h["chi2"], f"{where}.chi2", nonnegative=True),
            dof=self.integer(h["dof"], f"{where}.dof", low=1), p_value=p,
            consistent=consistent)

    def temperature_model(self, value: object, where: str) -> ParameterTemperatureModel:
        d = self.obj(value, where, _TEMPERATURE_MODEL_FIELDS)
        name = self.text(d["name"], f"{where}.name", nonempty=True)
        coefficients = self.numbers(d["coefficients"], f"{where}.coefficients")
        if not coefficients:
            self.fail(f"{where}.coefficients", "expected c_0 … c_m (at least c_0); got []")
        rate = self.optional_number(d["rate_coefficient"], f"{where}.rate_coefficient")
        leg = self.optional_number(d["leg_coefficient"], f"{where}.leg_coefficient")
        q = len(coefficients) + (rate is not None) + (leg is not None)
        rows = self.array(d["covariance"], f"{where}.covariance", q)
        cov = [self.numbers(r, f"{where}.covariance[{i}]", q) for i, r in enumerate(rows)]
        criterion = self.text(d["order_criterion"], f"{where}.order_criterion")
        if criterion not in ORDER_CRITERIA:
            self.fail(f"{where}.order_criterion",
                      f"expected one of {list(ORDER_CRITERIA)}; got {criterion!r}")
        rng = d["temperature_range_degc"]
        span = None if rng is None else self.numbers(rng, f"{where}.temperature_range_degc", 2)
        if span is not None and span[0] > span[1]:
            self.fail(f"{where}.temperature_range_degc",
                      f"expected [T_min, T_max] with T_min ≤ T_max; got {span}")
        held_out = self.held_out(d["held_out"], f"{where}.held_out")
        t0 = self.number(d["reference_temperature_degc"], f"{where}.reference_temperature_degc")
        chi2 = self.number(d["chi2"], f"{where}.chi2", nonnegative=True)
        dof = self.integer(d["dof"], f"{where}.dof")
        try:
            return ParameterTemperatureModel(
                name=name, reference_temperature_degc=t0, coefficients=tuple(coefficients),
                covariance=np.array(cov, dtype=np.float64), chi2=chi2, dof=dof,
                order_criterion=criterion,
                rate_coefficient=rate, leg_coefficient=leg,
                temperature_range_degc=None if span is None else (span[0], span[1]),
                held_out=held_out)
        except InvalidInputError as exc:  # the covariance's symmetry and PSD checks
            self.fail(f"{where}.covariance", str(exc))

    def temperature_models(self, value: object, names: list[str], values: list[float]
                           ) -> tuple[ParameterTemperatureModel, ...]:
        out: list[ParameterTemperatureModel] = []
        for i, v in enumerate(self.array(value, "temperature_models")):
            where = f"temperature_models[{i}]"
            tm = self.temperature_model(v, where)
            if tm.name not in names:
                self.fail(f"{where}.name", f"{tm.name!r} is not a parameter of this result")
            if any(o.name == tm.name for o in out):
                self.fail(f"{where}.name", f"{tm.name!r} has a temperature model already "
                          "(one per parameter)")
            if out and tm.reference_temperature_degc != out[0].reference_temperature_degc:
                self.fail(f"{where}.reference_temperature_degc",
                          f"{tm.reference_temperature_degc!r} differs from "
                          f"{out[0].reference_temperature_degc!r} of temperature_models[0] "
                          "(one T0 per result)")
            value0 = values[names.index(tm.name)]
            if not math.isclose(tm.coefficients[0], value0, rel_tol=RTOL, abs_tol=0.0):
                self.fail(f"{where}.coefficients[0]",
                          f"c_0 = {tm.coefficients[0]!r} differs from the value {value0!r} of "
                          f"{tm.name!r} (the values hold at T0)")
            out.append(tm)
        return tuple(out)

    def read(self, data: object) -> dict[str, Any]:
        """Check a whole document; return the keyword arguments of a ``CalibrationResult``.

        ``residuals`` maps each group to the keyword arguments of a ``ResidualStats`` and
        ``provenance`` holds those of a ``Provenance`` (the caller builds both); every other
        value is the field as the result holds it.
        """
        version = self.header(data)
        doc = self.obj(data, "(top level)", {1: _FIELDS_V1, 2: _FIELDS_V2}.get(version, _FIELDS))
        sensor_id = self.text(doc["sensor_id"], "sensor_id", nonempty=True)
        procedure = self.text(doc["procedure"], "procedure")
        model = self.text(doc["model"], "model")
        if model not in MODELS:
            self.fail("model", f"expected one of {list(MODELS)}; got {model!r}")
        params = [self.obj(p, f"parameters[{i}]", _PARAMETER_FIELDS)
                  for i, p in enumerate(self.array(doc["parameters"], "parameters"))]
        names = [self.text(p["name"], f"parameters[{i}].name", nonempty=True)
                 for i, p in enumerate(params)]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            self.fail("parameters", f"repeated parameter name(s) {dup}")
        self.names(names, model)
        values = [self.number(p["value"], f"parameters[{i}].value") for i, p in enumerate(params)]
        units = {n: self.text(p["unit"], f"parameters[{i}].unit", nonempty=True)
                 for i, (n, p) in enumerate(zip(names, params, strict=True))}
        std = [self.number(p["std"], f"parameters[{i}].std", nonnegative=True)
               for i, p in enumerate(params)]
        cov = self.covariance(doc["covariance"], std)
        input_units = self.obj(doc["input_units"], "input_units", None)
        for key, unit in input_units.items():
            if key not in ("gyro", "accel"):
                self.fail(f"input_units.{key}", "expected only the keys 'gyro' and 'accel'")
            self.unit(unit, f"input_units.{key}")
        residuals: dict[str, dict[str, Any]] = {}
        for group, r in self.obj(doc["residuals"], "residuals", None).items():
            where = f"residuals.{group}"
            r = self.obj(r, where, _RESIDUAL_FIELDS)
            mean = self.numbers(r["mean"], f"{where}.mean")
            spread = self.numbers(r["std"], f"{where}.std", len(mean), nonnegative=True)
            n = r["n"]
            if isinstance(n, bool) or not isinstance(n, int) or n < 0:
                self.fail(f"{where}.n", f"expected a count (an integer ≥ 0); got {_kind(n)}")
            residuals[group] = {"mean": tuple(mean), "std": tuple(spread), "n": n,
                                "unit": self.text(r["unit"], f"{where}.unit")}
        prov = self.obj(doc["provenance"], "provenance", _PROVENANCE_FIELDS)
        texts = {f: self.text(prov[f], f"provenance.{f}") for f in _PROVENANCE_FIELDS[:-1]}
        details = self.obj(prov["details"], "provenance.details", None)
        self.free(details, "provenance.details")
        notes = tuple(self.text(v, f"notes[{i}]")
                      for i, v in enumerate(self.array(doc["notes"], "notes")))
        fit_quality = tuple(self.fit_quality(q, f"fit_quality[{i}]") for i, q in enumerate(
            self.array(doc["fit_quality"], "fit_quality"))) if version >= 2 else ()
        groups = [q.group for q in fit_quality]
        if len(set(groups)) != len(groups):
            self.fail("fit_quality", f"a group appears twice: {groups}")
        temperature_models = self.temperature_models(
            doc["temperature_models"], names, values) if version >= 3 else ()
        return {"sensor_id": sensor_id, "procedure": procedure, "model": model,
                "param_names": tuple(names), "values": np.array(values, dtype=np.float64),
                "covariance": cov, "units": units, "input_units": dict(input_units),
                "residuals": residuals, "provenance": {**texts, "details": details},
                "notes": notes, "fit_quality": fit_quality,
                "temperature_models": temperature_models, "format_version": version}
