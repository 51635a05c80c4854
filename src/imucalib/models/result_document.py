"""The one result file of every procedure (format version 4), its reader and its JSON Schema.

Every procedure's result is written as one JSON document built from the result contract
(:class:`~imucalib.models.procedure_result.ProcedureResult`; docs/procedures.md, "The result
file"):

=================  ============================================================================
key                content
=================  ============================================================================
``format``         ``"imucalib-calibration-result"``; ``format_version`` 4
``procedure``      the procedure that made it; ``unit`` the IMU
``parameters``     every reported quantity: ``name``, ``value``, ``std`` (the σ the tool
                   reports: Birge-scaled where its fit is a misfit), ``std_noise`` (before that
                   scaling), ``unit`` (SI); a quantity not estimated has ``null`` σ
``covariance``     ``{"names", "values", "matrix"}``: the triad parameters with their joint
                   covariance as reported (those of ``calibration``, else the procedure's
                   triad part, which ``imucalib combine`` fuses), or ``null`` for a result
                   without one (a noise characterisation)
``fit_quality``    each fit's χ², ν, expected range, misfit flag and Birge ratio
``decision``       ``passed`` (true, false, or null for *no decision*), the rule, the checks
``notes``          what the reader must know
``provenance``     recording and its SHA-256, plan hash, software version, creation time
``calibration``    the triad model ``apply`` uses, in the calibration-result form of
                   :mod:`imucalib.models.result` (format version ≤ 3), or ``null``
``details``        the procedure's own data (its ``to_dict()``), free-form
=================  ============================================================================

:func:`load_result` reads a version-4 document, or a calibration result of versions 1–3 (the
files ``imucalib calibrate`` wrote before), into a :class:`StoredResult`, which satisfies the
result contract, so ``apply``, ``export``, ``report``, ``combine`` and the records take either.
:func:`result_schema` is the JSON Schema (draft 2020-12) of version 4; ``imucalib schema
result`` prints it.

Contents
--------
:data:`RESULT_DOCUMENT_VERSION`, :func:`result_document`, :func:`result_schema`,
:class:`StoredResult`, :func:`load_result`, :func:`stored_from_calibration`,
:func:`applicable_calibration`, :func:`json_data`, :func:`provenance_dict`
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final

import numpy as np
from numpy.typing import NDArray

from imucalib.errors import InvalidInputError
from imucalib.models._result_format import (
    RESULT_DOCUMENT_VERSION,
    RESULT_FORMAT,
    triad_parameter_names,
    triad_parameter_unit,
)
from imucalib.models.decision import Decision, decision_from_dict, no_decision
from imucalib.models.fit_quality import FitQuality
from imucalib.models.procedure_result import ProcedureResult, TriadParameters, calibration_rows
from imucalib.models.reported import ReportedParameter
from imucalib.models.result import (
    CalibrationResult,
    Provenance,
    fit_quality_dict,
    parse_result_json,
    read_result_text,
)

__all__ = ["RESULT_DOCUMENT_VERSION", "StoredResult", "applicable_calibration", "json_data",
           "load_result", "provenance_dict", "result_document", "result_schema",
           "stored_from_calibration"]



def json_data(value: Any) -> Any:
    """Return `value` as strict JSON data: numpy to Python, non-finite numbers to None."""
    if isinstance(value, Mapping):
        return {str(k): json_data(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_data(v) for v in value]
    if isinstance(value, np.ndarray):
        return json_data(value.tolist())
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        v = float(value)
        return v if math.isfinite(v) else None
    if value is None or isinstance(value, str):
        return value
    return str(value)


def provenance_dict(prov: Provenance) -> dict[str, Any]:
    """Return a :class:`~imucalib.models.result.Provenance` as JSON data."""
    return {"plan_hash": prov.plan_hash, "recording_sha256": prov.recording_sha256,
            "recording": prov.recording, "software_version": prov.software_version,
            "created_utc": prov.created_utc, "details": json_data(dict(prov.details))}


def _covariance(result: ProcedureResult) -> dict[str, Any] | None:
    cal = result.calibration
    if cal is not None:
        return {"names": list(cal.param_names), "values": json_data(cal.values),
                "matrix": json_data(cal.covariance_scaled)}
    names, values, cov = result.triad_parameters()
    if not names:
        return None
    return {"names": list(names), "values": json_data(np.asarray(values, dtype=float)),
            "matrix": json_data(np.asarray(cov, dtype=float))}


def result_document(result: ProcedureResult, *, provenance: Provenance | None = None
                    ) -> dict[str, Any]:
    """Return the version-4 result document of one unit's result (module docstring).

    Parameters
    ----------
    result : ProcedureResult
        One unit's result (a batch's members are written one by one).
    provenance : Provenance, optional
        Where it came from; default: the result's own, else an empty one.

    Raises
    ------
    InvalidInputError
        A batch (it has members).
    """
    if result.members:
        raise InvalidInputError("a result document is of one unit; write a batch's members "
                                "one by one")
    cal = result.calibration
    prov = provenance or result.provenance or Provenance()
    return {
        "format": RESULT_FORMAT,
        "format_version": RESULT_DOCUMENT_VERSION,
        "procedure": str(result.procedure),
        "unit": str(result.unit),
        "parameters": [{"name": r.name, "value": json_data(r.value), "std": json_data(r.std),
                        "std_noise": json_data(r.std_noise), "unit": r.unit}
                       for r in result.parameter_rows()],
        "covariance": _covariance(result),
        "fit_quality": [fit_quality_dict(q) for q in result.fit_quality],
        "decision": json_data(result.decision.to_dict()),
        "notes": [str(n) for n in result.notes],
        "provenance": provenance_dict(prov),
        "calibration": None if cal is None else cal.to_dict(),
        "details": json_data(result.to_dict()),
    }


@dataclass(frozen=True, eq=False)
class StoredResult:
    """A result read back from its file: the result contract, without the analysis behind it.

    Built by :func:`load_result` from a version-4 document or from a calibration result of
    versions 1–3 (then its procedure's parameters and decision are those the file holds:
    the calibration's, and *no decision*, the file holding none).
    """

    procedure: str
    unit: str
    rows: tuple[ReportedParameter, ...]
    covariance_names: tuple[str, ...]
    covariance_values: NDArray[np.float64]
    covariance: NDArray[np.float64]
    fit_quality: tuple[FitQuality, ...]
    decision: Decision
    notes: tuple[str, ...]
    provenance: Provenance
    calibration: CalibrationResult | None
    details: Mapping[str, Any] = field(default_factory=dict)
    source: str = ""

    @property
    def passed(self) -> bool | None:
        """``decision.passed``."""
        return self.decision.passed

    @property
    def members(self) -> tuple[ProcedureResult, ...]:
        """None: a file holds one unit's result."""
        return ()

    @property
    def error(self) -> str:
        """None: a stored result was calibrated."""
        return ""

    @property
    def omitted(self) -> tuple[str, ...]:
        """The parts its analysis left out, as its details say (a field result's ``omitted``)."""
        parts = self.details.get("omitted", ())
        return tuple(str(p) for p in parts) if isinstance(parts, list | tuple) else ()

    def parameter_rows(self) -> list[ReportedParameter]:
        """Return the reported parameters as stored."""
        return list(self.rows)

    def triad_parameters(self) -> TriadParameters:
        """Return the stored covariance block's triad parameters (or none)."""
        keep = [i for i, n in enumerate(self.covariance_names) if _is_triad_name(n)]
        names = [self.covariance_names[i] for i in keep]
        return (names, np.asarray(self.covariance_values[keep], dtype=float),
                np.asarray(self.covariance[np.ix_(keep, keep)], dtype=float))

    def to_dict(self) -> dict[str, Any]:
        """Return the procedure's own data, as stored (``details``)."""
        return dict(self.details)


def _is_triad_name(name: str) -> bool:
    triad = name.split("_")[0]
    return triad in ("accel", "gyro") and name in triad_parameter_names(
        triad, "triad", g_sensitivity=True, k2=True, k3=True)


def stored_from_calibration(cal: CalibrationResult, *, decision: Decision | None = None,
                            details: Mapping[str, Any] | None = None, source: str = ""
                            ) -> StoredResult:
    """Return a calibration as a result of the contract (a file of versions 1–3, a fusion).

    Its parameters are the calibration's (σ Birge-scaled per misfit group), its covariance the
    scaled one; `decision` defaults to *no decision* (such a calibration holds none).
    """
    return StoredResult(
        procedure=cal.procedure, unit=cal.sensor_id, rows=tuple(calibration_rows(cal)),
        covariance_names=tuple(cal.param_names), covariance_values=cal.values,
        covariance=cal.covariance_scaled,
        fit_quality=tuple(cal.fit_quality),
        decision=decision or no_decision(
            f"a calibration result of format version {cal.format_version} holds no decision"),
        notes=tuple(cal.notes), provenance=cal.provenance, calibration=cal,
        details=dict(details or {}), source=source)


def _fail(source: str, where: str, expected: str, got: Any) -> InvalidInputError:
    text = repr(got)
    return InvalidInputError(f"result {source}: `{where}` expected {expected}; got "
                             f"{text[:80] + '…' if len(text) > 80 else text}")


def _number(value: Any, source: str, where: str, *, optional: bool = False) -> float:
    if value is None and optional:
        return math.nan
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise _fail(source, where, "a number" + (" or null" if optional else ""), value)
    return float(value)


def _text(value: Any, source: str, where: str) -> str:
    if not isinstance(value, str):
        raise _fail(source, where, "a string", value)
    return value


def _from_document(doc: Mapping[str, Any], source: str) -> StoredResult:
    for key in ("procedure", "unit", "parameters", "covariance", "fit_quality", "decision",
                "notes", "provenance", "calibration", "details"):
        if key not in doc:
            raise _fail(source, key, "present (a version-4 result document)", "nothing")
    params = doc["parameters"]
    if not isinstance(params, list):
        raise _fail(source, "parameters", "a list", params)
    rows = []
    for i, p in enumerate(params):
        if not isinstance(p, Mapping):
            raise _fail(source, f"parameters[{i}]", "an object", p)
        rows.append(ReportedParameter(
            _text(p.get("name"), source, f"parameters[{i}].name"),
            _number(p.get("value"), source, f"parameters[{i}].value", optional=True),
            _number(p.get("std"), source, f"parameters[{i}].std", optional=True),
            _text(p.get("unit"), source, f"parameters[{i}].unit"),
            _number(p.get("std_noise"), source, f"parameters[{i}].std_noise", optional=True)))
    cal = None
    if doc["calibration"] is not None:
        if not isinstance(doc["calibration"], Mapping):
            raise _fail(source, "calibration", "an object or null", doc["calibration"])
        cal = CalibrationResult.from_dict(doc["calibration"], f"{source} (calibration)")
    names: tuple[str, ...] = ()
    values = np.zeros(0)
    cov = np.zeros((0, 0))
    if doc["covariance"] is not None:
        c = doc["covariance"]
        if not isinstance(c, Mapping) or not all(isinstance(c.get(k), list) for k in (
                "names", "values", "matrix")):
            raise _fail(source, "covariance",
                        "{names: [...], values: [...], matrix: [[...]]} or null", c)
        names = tuple(_text(n, source, "covariance.names[]") for n in c["names"])
        values = np.array([_number(v, source, f"covariance.values[{i}]")
                           for i, v in enumerate(c["values"])], dtype=float)
        if values.shape != (len(names),):
            raise _fail(source, "covariance.values", f"{len(names)} numbers (one per name)",
                        f"{values.size}")
        try:
            cov = np.array(c["matrix"], dtype=float)
        except (TypeError, ValueError):
            raise _fail(source, "covariance.matrix", "a square matrix of numbers",
                        c["matrix"]) from None
        if cov.shape != (len(names), len(names)) or not np.all(np.isfinite(cov)):
            raise _fail(source, "covariance.matrix",
                        f"a finite {len(names)}×{len(names)} matrix", f"shape {cov.shape}")
    decision = doc["decision"]
    if not isinstance(decision, Mapping):
        raise _fail(source, "decision", "an object", decision)
    from imucalib.models._result_reader import ResultReader

    reader = ResultReader(source)
    quality = doc["fit_quality"]
    if not isinstance(quality, list):
        raise _fail(source, "fit_quality", "a list", quality)
    prov = doc["provenance"]
    if not isinstance(prov, Mapping):
        raise _fail(source, "provenance", "an object", prov)
    notes = doc["notes"]
    if not isinstance(notes, list) or not all(isinstance(n, str) for n in notes):
        raise _fail(source, "notes", "a list of strings", notes)
    details = doc["details"]
    if not isinstance(details, Mapping):
        raise _fail(source, "details", "an object", details)
    try:
        texts = {k: _text(prov[k], source, f"provenance.{k}") for k in (
            "plan_hash", "recording_sha256", "recording", "software_version", "created_utc")}
    except KeyError as exc:
        raise _fail(source, f"provenance.{exc.args[0]}", "present", "nothing") from None
    prov_details = prov.get("details") or {}
    if not isinstance(prov_details, Mapping):
        raise _fail(source, "provenance.details", "an object", prov_details)
    provenance = Provenance(**texts, details=dict(prov_details))
    return StoredResult(
        procedure=_text(doc["procedure"], source, "procedure"),
        unit=_text(doc["unit"], source, "unit"), rows=tuple(rows), covariance_names=names,
        covariance_values=values, covariance=cov,
        fit_quality=tuple(reader.fit_quality(q, f"fit_quality[{i}]")
                          for i, q in enumerate(quality)),
        decision=decision_from_dict(decision, f"result {source}"), notes=tuple(notes),
        provenance=provenance, calibration=cal, details=dict(details), source=source)


def load_result(path: str | os.PathLike[str]) -> StoredResult:
    """Read a result file: format version 4, or a calibration result of versions 1–3.

    Raises
    ------
    InvalidInputError
        A file that cannot be read, is too large, is not UTF-8 JSON, is not an imucalib
        result, or has a malformed field (named).
    """
    p = Path(path)
    doc = parse_result_json(read_result_text(p), str(p))
    if isinstance(doc, Mapping) and doc.get("format") == RESULT_FORMAT \
            and doc.get("format_version") == RESULT_DOCUMENT_VERSION:
        return _from_document(doc, str(p))
    return stored_from_calibration(CalibrationResult.from_dict(doc, str(p)), source=str(p))


def applicable_calibration(result: ProcedureResult) -> tuple[CalibrationResult, tuple[str, ...]]:
    """Return the triad model to apply from a result, and notes on what it takes as nominal.

    A result with a whole triad model (``calibration``) gives it. A result with part of one
    (a classical test's triad parameters: the tumble's accelerometer scale and misalignment,
    the Earth-rate test's gyro bias) gives a triad model of the triads it names whose other
    bias and scale/misalignment parameters are nominal (zero, with zero variance), each triad
    so completed named in a note; a triad it does not name is left uncorrected.

    Raises
    ------
    InvalidInputError
        A result with no triad parameters at all (a noise characterisation).
    """
    cal = result.calibration
    if cal is not None:
        return cal, ()
    names, values, cov = result.triad_parameters()
    if not names:
        raise InvalidInputError(
            f"a {result.procedure} result estimates no triad parameter (it holds "
            f"{', '.join(r.name for r in result.parameter_rows()[:4]) or 'nothing'}"
            f"{'…' if len(result.parameter_rows()) > 4 else ''}): there is no model to apply")
    full: list[str] = []
    notes = []
    for triad in ("accel", "gyro"):
        mine = [n for n in names if n.startswith(triad + "_")]
        if not mine:
            continue
        want = triad_parameter_names(triad, "triad", g_sensitivity=any("_G_" in n for n in mine),
                                     k2=any("_K2_" in n for n in mine),
                                     k3=any("_K3_" in n for n in mine))
        nominal = [n for n in want if n not in mine]
        if nominal:
            notes.append(f"{result.procedure} does not estimate {len(nominal)} {triad} "
                         f"parameter(s) ({', '.join(nominal[:4])}{'…' if len(nominal) > 4 else ''}"
                         "): applied as nominal (zero)")
        full += list(want)
    index = {n: i for i, n in enumerate(names)}
    k = len(full)
    v = np.zeros(k)
    c = np.zeros((k, k))
    for a, na in enumerate(full):
        if na in index:
            v[a] = values[index[na]]
            for b, nb in enumerate(full):
                if nb in index:
                    c[a, b] = cov[index[na], index[nb]]
    cal = CalibrationResult(sensor_id=str(result.unit), procedure=str(result.procedure),
                            model="triad", param_names=tuple(full), values=v,
                            covariance=0.5 * (c + c.T),
                            units={n: triad_parameter_unit(n) for n in full},
                            notes=tuple(notes))
    return cal, tuple(notes)


_NUMBER_OR_NULL: Final = {"type": ["number", "null"]}


def result_schema() -> dict[str, Any]:
    """Return the JSON Schema (draft 2020-12) of the result document, version 4."""
    strings = {"type": "array", "items": {"type": "string"}}
    fit = {"type": "object",
           "required": ["group", "chi2", "dof", "reduced_chi2", "expected_low",
                        "expected_high", "quantile", "misfit", "birge_ratio", "sigma_scale"],
           "properties": {"group": {"type": "string", "minLength": 1},
                          "chi2": {"type": "number", "minimum": 0},
                          "dof": {"type": "integer", "minimum": 0},
                          "reduced_chi2": _NUMBER_OR_NULL, "expected_low": _NUMBER_OR_NULL,
                          "expected_high": _NUMBER_OR_NULL, "quantile": {"type": "number"},
                          "misfit": {"type": "boolean"}, "birge_ratio": _NUMBER_OR_NULL,
                          "sigma_scale": {"type": "number", "minimum": 1}}}
    check = {"type": "object", "required": ["name", "passed", "summary", "rows"],
             "properties": {"name": {"type": "string"},
                            "passed": {"type": ["boolean", "null"]},
                            "summary": {"type": "string"},
                            "rows": {"type": "array", "items": {
                                "type": "object",
                                "required": ["name", "value", "limit", "unit", "passed"],
                                "properties": {"name": {"type": "string"},
                                               "value": _NUMBER_OR_NULL,
                                               "limit": _NUMBER_OR_NULL,
                                               "unit": {"type": "string"},
                                               "passed": {"type": "boolean"},
                                               "detail": {"type": "string"}}}}}}
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "$id": "https://imucalib.example/schema/result-v4.json",
        "title": "imucalib result (format version 4)",
        "description": "One procedure's result for one IMU (docs/procedures.md, \"The result "
                       "file\"). All values SI.",
        "type": "object",
        "required": ["format", "format_version", "procedure", "unit", "parameters",
                     "covariance", "fit_quality", "decision", "notes", "provenance",
                     "calibration", "details"],
        "properties": {
            "format": {"const": RESULT_FORMAT},
            "format_version": {"const": RESULT_DOCUMENT_VERSION},
            "procedure": {"type": "string", "minLength": 1},
            "unit": {"type": "string"},
            "parameters": {"type": "array", "items": {
                "type": "object", "required": ["name", "value", "std", "std_noise", "unit"],
                "additionalProperties": False,
                "properties": {"name": {"type": "string", "minLength": 1},
                               "value": _NUMBER_OR_NULL,
                               "std": {"type": ["number", "null"], "minimum": 0},
                               "std_noise": {"type": ["number", "null"], "minimum": 0},
                               "unit": {"type": "string"}}}},
            "covariance": {"oneOf": [
                {"type": "null"},
                {"type": "object", "required": ["names", "values", "matrix"],
                 "properties": {"names": strings,
                                "values": {"type": "array", "items": {"type": "number"}},
                                "matrix": {"type": "array", "items": {
                                    "type": "array", "items": {"type": "number"}}}}}]},
            "fit_quality": {"type": "array", "items": fit},
            "decision": {"type": "object",
                         "required": ["passed", "verdict", "rule", "failed", "not_assessed",
                                      "notes", "checks"],
                         "properties": {"passed": {"type": ["boolean", "null"]},
                                        "verdict": {"enum": ["PASS", "FAIL", "NO DECISION"]},
                                        "rule": {"type": "string", "minLength": 1},
                                        "failed": strings, "not_assessed": strings,
                                        "notes": strings,
                                        "checks": {"type": "array", "items": check},
                                        "summary": {"type": "string"}}},
            "notes": strings,
            "provenance": {"type": "object",
                           "required": ["plan_hash", "recording_sha256", "recording",
                                        "software_version", "created_utc", "details"],
                           "properties": {k: {"type": "string"} for k in (
                               "plan_hash", "recording_sha256", "recording",
                               "software_version", "created_utc")}},
            "calibration": {"oneOf": [
                {"type": "null"},
                {"type": "object", "required": ["format", "format_version", "sensor_id",
                                                "procedure", "model", "parameters",
                                                "covariance"],
                 "properties": {"format": {"const": RESULT_FORMAT},
                                "format_version": {"type": "integer", "minimum": 1,
                                                   "maximum": 3},
                                "model": {"enum": ["triad", "per-axis"]}}}]},
            "details": {"type": "object"},
        },
    }
