"""The one result file (format version 4): document, JSON Schema, reader, partial models."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import jsonschema
import numpy as np
import pytest
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.errors import InvalidInputError
from imucalib.models.decision import Decision, no_decision
from imucalib.models.fit_quality import assess_fit
from imucalib.models.procedure_result import ProcedureResult, ResultDefaults
from imucalib.models.reported import ReportedParameter
from imucalib.models.result import CalibrationResult, Provenance, triad_parameter_names
from imucalib.models.result_document import (
    RESULT_DOCUMENT_VERSION,
    StoredResult,
    applicable_calibration,
    load_result,
    result_document,
    result_schema,
    stored_from_calibration,
)

GYRO = triad_parameter_names("gyro", "triad")


def _validate(doc: dict) -> None:
    jsonschema.Draft202012Validator(result_schema()).validate(doc)


@dataclasses.dataclass(frozen=True)
class _Part(ResultDefaults):
    """A classical test's result: part of the gyro triad, one misfit fit, no limits."""

    names: tuple[str, ...]
    values: np.ndarray
    cov_noise: np.ndarray
    unit: str = "U-1"
    procedure: str = "rate-transfer"
    notes: tuple[str, ...] = ("synthetic",)

    @property
    def fit_quality(self):
        return (assess_fit("gyro", 40.0, 10),)  # χ²/ν = 4: a misfit, σ × 2

    @property
    def decision(self) -> Decision:
        return no_decision("the plan gives no acceptance limits")

    def parameter_rows(self):
        s = self.fit_quality[0].sigma_scale
        return [ReportedParameter(n, float(v), float(np.sqrt(c)) * s, "rad/s", float(np.sqrt(c)))
                for n, v, c in zip(self.names, self.values, np.diag(self.cov_noise),
                                   strict=True)]

    def triad_parameters(self):
        s = self.fit_quality[0].sigma_scale
        return list(self.names), self.values, self.cov_noise * s**2

    def to_dict(self):
        return {"anything": [1.0, float("nan")], "names": list(self.names)}


def _part() -> _Part:
    names = tuple(n for n in GYRO if "_bias_" in n or n[-1] == n[-2])  # biases, scale factors
    rng = np.random.default_rng(3)
    a = rng.normal(size=(6, 6)) * 1e-6
    return _Part(names, rng.normal(0, 1e-4, 6), a @ a.T + np.eye(6) * 1e-12)


def test_the_schema_is_a_valid_draft_2020_12_schema_and_the_cli_prints_it():
    jsonschema.Draft202012Validator.check_schema(result_schema())
    done = CliRunner().invoke(app, ["schema", "result"])
    assert done.exit_code == 0, done.output
    assert json.loads(done.output) == result_schema()


def test_a_partial_triad_result_round_trips_with_reported_and_noise_sigma(tmp_path):
    part = _part()
    assert isinstance(part, ProcedureResult)
    doc = result_document(part, provenance=Provenance(recording="x.h5"))
    _validate(doc)
    assert doc["format_version"] == RESULT_DOCUMENT_VERSION
    assert doc["calibration"] is None and doc["decision"]["verdict"] == "NO DECISION"
    assert doc["details"]["anything"] == [1.0, None]  # NaN is no JSON: null
    for p in doc["parameters"]:
        assert p["std"] == pytest.approx(2.0 * p["std_noise"])  # the misfit's Birge ratio
    path = tmp_path / "a.result.json"
    path.write_text(json.dumps(doc, allow_nan=False))
    back = load_result(path)
    assert isinstance(back, ProcedureResult)
    assert back.parameter_rows() == part.parameter_rows()
    names, values, cov = back.triad_parameters()
    assert names == list(part.names)
    np.testing.assert_array_equal(values, part.values)
    np.testing.assert_allclose(cov, part.triad_parameters()[2], rtol=1e-15)
    assert back.provenance.recording == "x.h5" and back.decision == part.decision


def test_a_partial_model_is_applied_with_the_rest_nominal_and_said_so():
    part = _part()
    cal, notes = applicable_calibration(part)
    assert cal.param_names == GYRO
    off = [n for n in GYRO if n not in part.names]
    assert all(cal.value(n) == 0.0 and cal.sigma(n) == 0.0 for n in off)
    assert cal.value("gyro_bias_y") == part.values[1]
    assert len(notes) == 1 and "6 gyro parameter(s)" in notes[0] and "nominal" in notes[0]


def test_a_result_without_triad_parameters_cannot_be_applied():
    part = dataclasses.replace(_part(), names=(), values=np.zeros(0),
                               cov_noise=np.zeros((0, 0)), procedure="allan")
    with pytest.raises(InvalidInputError, match="allan result estimates no triad parameter"):
        applicable_calibration(part)


def test_a_version_3_calibration_file_is_read_as_a_result(tmp_path):
    names = (*triad_parameter_names("accel", "triad"), *GYRO)
    cal = CalibrationResult(sensor_id="U-3", procedure="p1", model="triad", param_names=names,
                            values=np.arange(len(names)) * 1e-5,
                            covariance=np.eye(len(names)) * 1e-10,
                            units={n: "1" for n in names},
                            fit_quality=(assess_fit("accel", 90.0, 10),))
    path = tmp_path / "old.result.json"
    path.write_text(cal.to_json())
    back = load_result(path)
    assert back.calibration is not None and back.calibration.isclose(cal)
    assert back.decision.passed is None and "holds no decision" in back.decision.rule
    rows = {r.name: r for r in back.parameter_rows()}
    assert rows["accel_bias_x"].std == pytest.approx(3.0 * rows["accel_bias_x"].std_noise)
    assert rows["gyro_bias_x"].std == rows["gyro_bias_x"].std_noise
    # written again as version 4, it validates and its calibration reads back with v3's reader
    doc = result_document(back)
    _validate(doc)
    path4 = tmp_path / "new.result.json"
    path4.write_text(json.dumps(doc))
    assert CalibrationResult.load(path4).isclose(cal)
    assert applicable_calibration(load_result(path4))[0].isclose(cal)


def test_a_version_4_file_without_a_model_is_named_when_read_as_a_calibration(tmp_path):
    path = tmp_path / "p.result.json"
    path.write_text(json.dumps(result_document(_part())))
    with pytest.raises(InvalidInputError, match="rate-transfer result without a whole triad"):
        CalibrationResult.load(path)


@pytest.mark.parametrize(("edit", "message"), [
    (lambda d: d.pop("decision"), "`decision` expected present"),
    (lambda d: d["parameters"][0].update(std="big"), r"`parameters\[0\].std` expected a number"),
    (lambda d: d["covariance"].update(matrix=[[1.0]]), "`covariance.matrix` expected a finite"),
    (lambda d: d["decision"].update(passed="yes"), "decision.passed must be true, false or "),
    (lambda d: d.update(notes="one"), "`notes` expected a list of strings"),
])
def test_a_malformed_field_is_named(tmp_path, edit, message):
    doc = result_document(_part())
    edit(doc)
    path = tmp_path / "bad.result.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(InvalidInputError, match=message):
        load_result(path)


def test_the_schema_refuses_what_the_contract_forbids():
    doc = result_document(_part())
    for bad in ({**doc, "format_version": 3}, {**doc, "parameters": [{"name": "x"}]},
                {**doc, "decision": {**doc["decision"], "verdict": "MAYBE"}}):
        with pytest.raises(jsonschema.ValidationError):
            _validate(bad)


def test_a_combination_of_stored_results_via_the_cli(tmp_path: Path):
    """`imucalib combine`: two tests, each half of the gyro triad, make one applicable model."""
    part = _part()
    rest = tuple(n for n in GYRO if n not in part.names)
    rng = np.random.default_rng(5)
    other = _Part(rest, rng.normal(0, 1e-4, 6), np.eye(6) * 1e-12, procedure="installation")
    files = []
    for i, r in enumerate((part, other)):
        files.append(tmp_path / f"{i}.result.json")
        files[-1].write_text(json.dumps(result_document(r)))
    out = tmp_path / "combined.result.json"
    done = CliRunner().invoke(app, ["combine", *map(str, files), "--out", str(out)])
    assert done.exit_code == 0, done.output
    doc = json.loads(out.read_text())
    _validate(doc)
    back = load_result(out)
    assert back.procedure == "combined" and back.calibration is not None
    assert back.calibration.param_names == GYRO
    for r in (part, other):
        names, values, _ = r.triad_parameters()
        for n, v in zip(names, values, strict=True):
            assert back.calibration.value(n) == pytest.approx(v, rel=1e-12)
    # an incomplete triad is named
    done = CliRunner().invoke(app, ["combine", str(files[0]), "--out", str(out)])
    assert done.exit_code != 0 and "incomplete" in done.output
    assert "Traceback" not in done.output


def test_stored_from_calibration_keeps_a_given_decision():
    names = (*GYRO,)
    cal = CalibrationResult(sensor_id="U", procedure="combined", model="triad",
                            param_names=names, values=np.zeros(12), covariance=np.eye(12),
                            units={n: "1" for n in names})
    d = Decision(passed=True, rule="r")
    assert stored_from_calibration(cal, decision=d).passed is True
    assert isinstance(stored_from_calibration(cal), StoredResult)
