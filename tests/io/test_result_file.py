"""CalibrationResult.load / from_json: every defect of a result file named with file and field."""

from __future__ import annotations

import copy
import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from imucalib.errors import InvalidInputError
from imucalib.models.result import (
    CalibrationResult,
    Provenance,
    ResidualStats,
    triad_parameter_names,
)


def make_result() -> CalibrationResult:
    names = (*triad_parameter_names("accel", "per-axis"),
             *triad_parameter_names("gyro", "per-axis"))
    k = len(names)
    a = np.random.default_rng(0).normal(size=(k, k))
    values = np.r_[1.01, 0.99, 1.0, 0.1, -0.2, 0.0, 1.0, 1.0, 1.02, 0.0, 0.0, 1e-3]
    return CalibrationResult(
        sensor_id="IMU-7", procedure="p1", model="per-axis", param_names=names, values=values,
        covariance=a @ a.T * 1e-8, units=dict.fromkeys(names, "1"),
        residuals={"accel: Z up": ResidualStats((1e-4, -2e-4, 3.5e-5), (1e-3,) * 3, 2000,
                                                "m/s^2")},
        provenance=Provenance(plan_hash="ab" * 32, recording="run.h5", details={"n": 3}),
        notes=("gyro bias excludes Earth rate",))


@pytest.fixture
def doc() -> dict[str, Any]:
    return json.loads(make_result().to_json())


def load(tmp_path: Path, content: str | bytes | dict[str, Any]) -> CalibrationResult:
    path = tmp_path / "r.json"
    if isinstance(content, dict):
        content = json.dumps(content, allow_nan=True)
    if isinstance(content, str):
        content = content.encode("utf-8")
    path.write_bytes(content)
    return CalibrationResult.load(path)


def expect(tmp_path: Path, content: Any, message: str) -> None:
    text = message.format(p=tmp_path / "r.json")
    with pytest.raises(InvalidInputError, match="^" + re.escape(text) + "$"):
        load(tmp_path, content)


def test_a_valid_file_round_trips(tmp_path):
    res = make_result()
    back = load(tmp_path, res.to_json())
    assert back.to_json() == res.to_json()
    np.testing.assert_array_equal(back.covariance, res.covariance)


@pytest.mark.parametrize(("content", "message"), [
    (b"\xff\xfe{\x00}", "calibration result {p} is not UTF-8 text: byte 0xff at offset 0 cannot "
                        "be decoded (expected the JSON `imucalib calibrate` writes)"),
    ("", "calibration result {p} is not valid JSON: Expecting value: line 1 column 1 (char 0)"),
    ('{"format": ', "calibration result {p} is not valid JSON: Expecting value: line 1 column 12 "
                    "(char 11)"),
    ("[" * 100000 + "]" * 100000,
     "calibration result {p} is not a calibration result: its JSON nests too deeply"),
    ("[1, 2]", "{p} is not an imucalib calibration result: expected a JSON object with format "
               "'imucalib-calibration-result'; got an array"),
    ('{"sensor_id": "x"}', "{p} is not an imucalib calibration result: expected a JSON object "
                           "with format 'imucalib-calibration-result'; got no `format` field"),
    ('{"format": "imucalib-allan-result"}',
     "{p} is not an imucalib calibration result: expected a JSON object with format "
     "'imucalib-calibration-result'; got the string \"imucalib-allan-result\""),
])
def test_unreadable_and_foreign_files(tmp_path, content, message):
    expect(tmp_path, content, message)


def test_missing_file(tmp_path):
    with pytest.raises(InvalidInputError, match=re.escape(
            f"cannot read calibration result {tmp_path / 'x.json'}: No such file or directory")):
        CalibrationResult.load(tmp_path / "x.json")


def edit(doc: dict[str, Any], path: str, value: Any) -> dict[str, Any]:
    """Set (or, with value ..., delete) a field given as a dotted path with [i] indexes."""
    out = copy.deepcopy(doc)
    keys: list[Any] = [int(k) if k.isdigit() else k for k in re.split(r"\.|\[|\]\.?", path) if k]
    node = out
    for k in keys[:-1]:
        node = node[k]
    if value is ...:
        del node[keys[-1]]
    else:
        node[keys[-1]] = value
    return out


NOT_SUPPORTED = ("calibration result {p}: format_version {v} is not supported; this imucalib "
                 "reads versions 1..4 (a newer version needs a newer imucalib)")


@pytest.mark.parametrize(("path", "value", "message"), [
    ("format_version", 5, NOT_SUPPORTED.replace("{v}", "5")),
    ("format_version", "1", NOT_SUPPORTED.replace("{v}", 'the string "1"')),
    ("format_version", True, NOT_SUPPORTED.replace("{v}", "a boolean")),
    ("notes", ..., "calibration result {p}: field '(top level)': missing field(s) ['notes']"),
    ("extra", 1, "calibration result {p}: field '(top level)': unknown field(s) ['extra']; "
                 "expected exactly ['format', 'format_version', 'sensor_id', 'procedure', "
                 "'model', 'parameters', 'covariance', 'input_units', 'residuals', "
                 "'provenance', 'notes', 'fit_quality', 'temperature_models']"),
    ("sensor_id", "", "calibration result {p}: field 'sensor_id': expected a non-empty string"),
    ("model", "magic", "calibration result {p}: field 'model': expected one of ['triad', "
                       "'per-axis']; got 'magic'"),
    ("parameters", {}, "calibration result {p}: field 'parameters': expected an array; got an "
                       "object"),
    ("parameters[3].std", ..., "calibration result {p}: field 'parameters[3]': missing "
                               "field(s) ['std']"),
    ("parameters[3].sigma", 1.0, "calibration result {p}: field 'parameters[3]': unknown "
                                 "field(s) ['sigma']; expected exactly ['name', 'value', "
                                 "'unit', 'std']"),
    ("parameters[3].value", float("nan"), "calibration result {p}: field "
                                          "'parameters[3].value': expected a finite number; "
                                          "got NaN"),
    ("parameters[3].value", float("inf"), "calibration result {p}: field "
                                          "'parameters[3].value': expected a finite number; "
                                          "got Infinity"),
    ("parameters[3].value", "0.1", "calibration result {p}: field 'parameters[3].value': "
                                   "expected a number; got the string \"0.1\""),
    ("parameters[3].value", None, "calibration result {p}: field 'parameters[3].value': "
                                  "expected a number; got null"),
    ("parameters[3].std", -1.0, "calibration result {p}: field 'parameters[3].std': expected a "
                                "number ≥ 0; got -1.0"),
    ("parameters[3].name", "accel_b_x2", "calibration result {p}: field 'parameters': the "
                                         "accel parameters of a per-axis result must be "
                                         "['accel_K_x', 'accel_K_y', 'accel_K_z', 'accel_b_x', "
                                         "'accel_b_y', 'accel_b_z']; missing ['accel_b_x'], "
                                         "unexpected ['accel_b_x2']"),
    ("parameters[3].name", "accel_K_x", "calibration result {p}: field 'parameters': repeated "
                                        "parameter name(s) ['accel_K_x']"),
    ("parameters[3].name", "magnet_b_x", "calibration result {p}: field 'parameters': expected "
                                         "the parameters of the accel and/or gyro triad (names "
                                         "`accel_…`, `gyro_…`); got ['accel_K_x', 'accel_K_y', "
                                         "'accel_K_z', 'accel_b_y', 'accel_b_z', 'gyro_K_x']"),
    ("covariance", [[0.0] * 12] * 11, "calibration result {p}: field 'covariance': expected 12 "
                                      "elements; got 11"),
    ("covariance[2]", [0.0] * 13, "calibration result {p}: field 'covariance[2]': expected 12 "
                                  "elements; got 13"),
    ("covariance[2][5]", float("-inf"), "calibration result {p}: field 'covariance[2][5]': "
                                        "expected a finite number; got -Infinity"),
    ("covariance[2][5]", "x", "calibration result {p}: field 'covariance[2][5]': expected a "
                              "number; got the string \"x\""),
    ("input_units.gyro", "furlong/s", "calibration result {p}: field 'input_units.gyro': "
                                      "unknown unit 'furlong/s' (expected e.g. 'rad/s' or "
                                      "'m/s^2')"),
    ("input_units.magnet", "T", "calibration result {p}: field 'input_units.magnet': expected "
                                "only the keys 'gyro' and 'accel'"),
    ("residuals.accel: Z up.n", 2.5, "calibration result {p}: field 'residuals.accel: Z up.n': "
                                     "expected a count (an integer ≥ 0); got 2.5"),
    ("residuals.accel: Z up.std", [1.0], "calibration result {p}: field 'residuals.accel: Z "
                                         "up.std': expected 3 elements; got 1"),
    ("provenance.details", {"x": [1.0, float("nan")]},
     "calibration result {p}: field 'provenance.details.x[1]': expected finite numbers; got NaN"),
    ("provenance.plan_hash", 7, "calibration result {p}: field 'provenance.plan_hash': expected "
                                "a string; got 7"),
    ("notes", [1], "calibration result {p}: field 'notes[0]': expected a string; got 1"),
])
def test_malformed_fields_are_named(tmp_path, doc, path, value, message):
    expect(tmp_path, edit(doc, path, value), message)


def test_covariance_must_be_a_covariance(tmp_path, doc):
    cov = np.array(doc["covariance"])
    bad = cov.copy()
    bad[1, 4] *= 1.5
    expect(tmp_path, edit(doc, "covariance", bad.tolist()),
           f"calibration result {{p}}: field 'covariance': must be symmetric; [1][4] = "
           f"{float(bad[1, 4])!r} but [4][1] = {float(bad[4, 1])!r}")
    neg = edit(doc, "covariance[2][2]", -1e-8)
    expect(tmp_path, neg, "calibration result {p}: field 'covariance[2][2]': a variance must be "
                          "≥ 0; got -1e-08")
    std_off = edit(doc, "parameters[2].std", 2 * doc["parameters"][2]["std"])
    expect(tmp_path, std_off,
           f"calibration result {{p}}: field 'parameters[2].std': "
           f"{2 * doc['parameters'][2]['std']!r} disagrees with √covariance[2][2] = "
           f"{doc['parameters'][2]['std']!r} (a hand-edited file?)")
    indefinite = np.eye(12) * 1e-8
    indefinite[0, 1] = indefinite[1, 0] = 2e-8  # correlation 2
    d = edit(doc, "covariance", indefinite.tolist())
    for p in d["parameters"]:
        p["std"] = 1e-4
    expect(tmp_path, d, "calibration result {p}: field 'covariance': must be positive "
                        "semi-definite; the correlation matrix has the eigenvalue -1")
    zero = np.eye(12) * 1e-8
    zero[0, 0] = 0.0
    zero[0, 1] = zero[1, 0] = 1e-9
    d = edit(doc, "covariance", zero.tolist())
    for p in d["parameters"]:
        p["std"] = 1e-4
    d["parameters"][0]["std"] = 0.0
    expect(tmp_path, d, "calibration result {p}: field 'covariance': row 0 has a zero variance "
                        "but non-zero covariances")


def test_a_triad_result_may_carry_the_gyro_g_terms_only(tmp_path):
    names = (*triad_parameter_names("accel", "triad", g_sensitivity=True),)
    k = len(names)
    res = CalibrationResult(sensor_id="u", procedure="p1", model="triad", param_names=names,
                            values=np.zeros(k), covariance=np.eye(k) * 1e-12,
                            units=dict.fromkeys(names, "1"))
    with pytest.raises(InvalidInputError, match=re.escape(
            "field 'parameters': the accel parameters of a triad result must be")):
        load(tmp_path, res.to_json())
    gyro = triad_parameter_names("gyro", "triad", g_sensitivity=True)
    res = CalibrationResult(sensor_id="u", procedure="p1", model="triad", param_names=gyro,
                            values=np.zeros(21), covariance=np.eye(21) * 1e-12,
                            units=dict.fromkeys(gyro, "1"))
    assert load(tmp_path, res.to_json()).param_names == gyro
