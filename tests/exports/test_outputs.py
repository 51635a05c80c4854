"""write_outputs: every output file of a procedure result, named and written in one place."""

from __future__ import annotations

import csv
import json
from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest

from imucalib.errors import InvalidInputError
from imucalib.exports.outputs import OUTPUT_FORMATS, formats_of, write_outputs
from imucalib.models.decision import Decision
from imucalib.models.procedure_result import ResultDefaults
from imucalib.models.result import CalibrationResult, triad_parameter_names
from imucalib.procedures import registry


@dataclass
class _P1Like(ResultDefaults):
    """Stands for a P1Analysis: a calibration result plus a report."""

    result: CalibrationResult
    procedure: str = "p1"
    passed: bool = True
    notes: tuple[str, ...] = ()

    @property
    def calibration(self) -> CalibrationResult:
        return self.result

    @property
    def decision(self) -> Decision:
        return Decision(passed=self.passed, rule="a stand-in rule")

    @property
    def fit_quality(self) -> tuple:
        return tuple(self.result.fit_quality)

    @property
    def unit(self) -> str:
        return self.result.sensor_id

    def to_dict(self) -> dict[str, Any]:
        return {"result": self.result.to_dict(), "decision": {"passed": self.passed}}


def _p1_like() -> _P1Like:
    names = (*triad_parameter_names("accel", "per-axis"),
             *triad_parameter_names("gyro", "per-axis"))
    values = np.r_[np.ones(3), np.zeros(3), np.ones(3), np.arange(3) * 1e-5]
    res = CalibrationResult(sensor_id="IMU-7", procedure="p1", model="per-axis",
                            param_names=names, values=values,
                            covariance=np.diag(np.arange(1, 13) * 1e-10),
                            units=dict.fromkeys(names, "1"))
    return _P1Like(res)


def test_p1_outputs_are_named_after_the_recording_unit_and_procedure(tmp_path):
    result = _p1_like()
    # P1's residual figure needs its analysis (its windows): not a stand-in's
    formats = [f for f in registry.get("p1").outputs if f != "residuals-png"]
    written = write_outputs(result, tmp_path / "new", formats, name="run")
    assert [p.name for p in written] == ["run.IMU-7.p1.result.json", "run.IMU-7.p1.report.json",
                                         "run.IMU-7.p1.report.pdf"]
    back = CalibrationResult.from_json(written[0].read_text())
    np.testing.assert_array_equal(back.values, result.result.values)
    assert json.loads(written[1].read_text())["decision"] == {"passed": True}


def test_parameters_csv_on_request(tmp_path):
    result = _p1_like()
    (path,) = write_outputs(result, tmp_path, ["parameters-csv"], name="run")
    rows = list(csv.reader(path.open()))
    assert rows[0] == ["parameter", "value", "std_uncertainty", "unit", "std_noise"]
    assert len(rows) == 13 and rows[1][0] == result.result.param_names[0]
    assert float(rows[12][1]) == pytest.approx(2e-5)
    assert float(rows[12][2]) == pytest.approx(np.sqrt(12e-10))


def test_refuses_unknown_and_impossible_formats(tmp_path):
    result = _p1_like()
    with pytest.raises(InvalidInputError, match=r"unknown output format\(s\) \['pdf'\]"):
        write_outputs(result, tmp_path, ["pdf"], name="run")
    # a noise format is Allan's own: not one a P1 result has, and refused for one read back
    with pytest.raises(InvalidInputError,
                       match=r"unknown output format\(s\) \['kalibr-yaml'\] for a p1 result"):
        write_outputs(result, tmp_path, ["kalibr-yaml"], name="run")
    assert set(OUTPUT_FORMATS) >= {"result-json", "report-json", "parameters-csv"}
    assert not set(OUTPUT_FORMATS) & {"noise-json", "figures", "residuals-png"}
    assert set(formats_of("allan")) >= {"result-json", "noise-json", "figures"}
    assert "residuals-png" in formats_of("p1") and "temperature-png" in formats_of("p2")
    import dataclasses

    from imucalib.models.result_document import stored_from_calibration

    stored = dataclasses.replace(stored_from_calibration(result.result), procedure="allan")
    with pytest.raises(InvalidInputError, match="'kalibr-yaml' needs a noise characterisation"):
        write_outputs(stored, tmp_path, ["kalibr-yaml"], name="run")


def test_parameters_csv_round_trips_every_value_exactly(tmp_path):
    result = _p1_like()
    (path,) = write_outputs(result, tmp_path, ["parameters-csv"], name="run")
    cal, std = result.result, result.result.std()
    rows = list(csv.reader(path.open()))[1:]
    assert [r[0] for r in rows] == list(cal.param_names)
    for name, value, sigma, unit, sigma_noise in rows:
        assert float(value) == cal.value(name) and float(sigma) == std[name]  # repr: exact
        assert unit == cal.units[name] and float(sigma_noise) == std[name]  # no misfit


def test_parameters_csv_gives_the_birge_scaled_sigma_of_a_misfit(tmp_path):
    """The σ a result reports (docs/processing-estimation.md): scaled where its fit is a misfit."""
    import dataclasses

    from imucalib.models.fit_quality import assess_fit

    cal = dataclasses.replace(_p1_like().result, fit_quality=(assess_fit("gyro", 40.0, 10),))
    (path,) = write_outputs(_P1Like(cal), tmp_path, ["parameters-csv"], name="run")
    rows = {r[0]: float(r[2]) for r in list(csv.reader(path.open()))[1:]}
    noise = cal.std()
    for name, sigma in rows.items():
        factor = 2.0 if name.startswith("gyro") else 1.0  # √(40/10)
        assert sigma == pytest.approx(factor * noise[name], rel=1e-12), name


def test_parameters_csv_writes_numpy_scalars_as_plain_numbers(tmp_path):
    """A procedure that hands a numpy scalar to a row gets the number, not ``np.float64(…)``."""
    from types import SimpleNamespace

    import numpy as np

    from imucalib.exports.outputs import _parameters_csv
    from imucalib.models.reported import ReportedParameter

    row = ReportedParameter("accel_M_zz_tc", np.float64(2.2e-4),
                            np.float64(7.6e-5), "1/K", np.float64(7.6e-5))
    fake = SimpleNamespace(parameter_rows=lambda: [row], procedure="field")
    (path,) = _parameters_csv(fake, tmp_path, "run")
    (_, (name, value, sigma, unit, noise)) = list(csv.reader(path.open()))
    assert (name, value, sigma, unit, noise) == ("accel_M_zz_tc", "0.00022", "7.6e-05", "1/K",
                                                 "7.6e-05")
