"""The result contract of g-sensitivity, Earth-rate bias, random drift and the example plug-in.

Each result is a :class:`~imucalib.models.procedure_result.ProcedureResult`: its parameter rows
are :class:`~imucalib.models.reported.ReportedParameter` with std ≥ std_noise ≥ 0 (std =
std_noise × the fit's ``sigma_scale`` on a misfit: the default g-sensitivity twin run is one,
χ²/ν 11–19), its triad covariance gives the rows' σ, its decision is an explicit *no decision*
(``passed`` None, as before), and its version-4 result document is strict JSON that reads back.
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import pytest

from imucalib.models.fit_quality import assess_fit
from imucalib.models.procedure_result import ProcedureResult
from imucalib.models.reported import ReportedParameter
from imucalib.models.result_document import load_result, result_document
from imucalib.procedures.earth_rate_bias.analysis import analyze_earth_rate_bias
from imucalib.procedures.earth_rate_bias.plan import generate_earth_rate_bias_plan
from imucalib.procedures.g_sensitivity.analysis import analyze_g_sensitivity
from imucalib.procedures.g_sensitivity.plan import generate_g_sensitivity_plan
from imucalib.procedures.random_drift.analysis import analyze_random_drift
from imucalib.procedures.random_drift.plan import generate_random_drift_plan

from ._p4_twin import run_twin

EXAMPLE_SRC = Path(__file__).resolve().parents[2] / "examples" / "imucalib-scale-factor" / "src"


def _check_contract(result: Any, tmp_path: Path) -> dict[str, Any]:
    """Assert what every result of these procedures holds; return its result document."""
    assert isinstance(result, ProcedureResult)
    assert result.calibration is None and result.members == () and result.error == ""
    assert isinstance(result.notes, tuple) and all(isinstance(n, str) for n in result.notes)
    rows = result.parameter_rows()
    assert rows and all(isinstance(r, ReportedParameter) for r in rows)
    for r in rows:
        if math.isfinite(r.std):
            assert r.std >= r.std_noise >= 0.0, r
    # the triad covariance is the one as reported: its σ are the rows' std of the same names
    # (the result file keeps the triad values in its covariance block)
    names, values, cov = result.triad_parameters()
    by_name = {r.name: r for r in rows}
    for k, n in enumerate(names):
        if n not in by_name:
            continue
        assert by_name[n].value == values[k]
        assert math.sqrt(cov[k, k]) == pytest.approx(by_name[n].std, rel=1e-12)
    # no acceptance limits: an explicit no decision, passed None as before
    assert result.decision.passed is None and result.passed is None
    assert result.decision.verdict == "NO DECISION" and "no acceptance limits" in \
        result.decision.rule
    doc = result_document(result)
    text = json.dumps(doc, allow_nan=False)
    assert doc["decision"]["verdict"] == "NO DECISION" and doc["calibration"] is None
    assert [p["name"] for p in doc["parameters"]] == [r.name for r in rows]
    path = tmp_path / f"{result.procedure}.result.json"
    path.write_text(text, encoding="utf-8")
    back = load_result(path)
    stored = back.parameter_rows()
    assert [(r.name, r.unit) for r in stored] == [(r.name, r.unit) for r in rows]
    for a, b in zip(stored, rows, strict=True):
        for x, y in ((a.value, b.value), (a.std, b.std), (a.std_noise, b.std_noise)):
            assert x == y or (math.isnan(x) and not math.isfinite(y)), (a, b)
    assert back.passed is None and back.decision.verdict == "NO DECISION"
    stored_names, stored_values, stored_cov = back.triad_parameters()
    assert stored_names == list(names)
    np.testing.assert_array_equal(stored_values, values)
    np.testing.assert_allclose(stored_cov, cov, rtol=1e-15, atol=0.0)
    return doc


def _assert_scaled(rows: list[ReportedParameter], scales: list[float]) -> None:
    """Each row's std is its std_noise times its fit's sigma_scale (bit for bit up to 1 ulp)."""
    for r, s in zip(rows, scales, strict=True):
        assert r.std == pytest.approx(r.std_noise * s, rel=1e-14), (r, s)


def test_g_sensitivity_default_twin_run_is_a_misfit_scaled_in_std_only(tmp_path: Path) -> None:
    path = run_twin(generate_g_sensitivity_plan(), tmp_path / "g.h5")
    result = analyze_g_sensitivity(path)
    quality = result.fit_quality
    assert len(quality) == 3 and all(q.misfit for q in quality)  # χ²/ν 11–19 on this twin
    rows = result.parameter_rows()
    assert len(rows) == 12
    _assert_scaled(rows, [quality[k // 4].sigma_scale for k in range(12)])
    assert all(r.std > r.std_noise for r in rows)
    # std is the σ reported before the contract: √diag of the fit's (Birge-scaled) covariance
    assert [r.std for r in rows] == [float(math.sqrt(v)) for v in np.diag(result.fit.covariance)]
    assert len(result.decision.notes) == 3 and "MISFIT" in result.decision.notes[0]
    doc = _check_contract(result, tmp_path)
    assert [q["misfit"] for q in doc["fit_quality"]] == [True] * 3
    assert doc["covariance"]["names"][0] == "gyro_bias_x"


def test_earth_rate_bias_rows_have_no_birge_scaling(tmp_path: Path) -> None:
    plan = generate_earth_rate_bias_plan(record_s=60.0, settle_s=5.0, warm_up_s=10.0,
                                         sample_rate_hz=20.0, noise="white", seed=3)
    result = analyze_earth_rate_bias(run_twin(plan, tmp_path / "e.h5"))
    rows = result.parameter_rows()
    assert len(rows) == 15 and result.fit_quality == ()
    assert all(r.std == r.std_noise for r in rows)
    assert rows[0] == ReportedParameter("gyro_bias_x", result.axes[0].up_down.value_rps,
                                        result.axes[0].up_down.std_rps, "rad/s",
                                        result.axes[0].up_down.std_rps)
    doc = _check_contract(result, tmp_path)
    assert doc["covariance"]["names"] == ["gyro_bias_x", "gyro_bias_y", "gyro_bias_z"]


def test_random_drift_rows_and_the_within_repetition_sigma(tmp_path: Path) -> None:
    plan = generate_random_drift_plan(repetitions=3, span_s=600.0, record_s=30.0, settle_s=5.0,
                                      warm_up_s=10.0, sample_rate_hz=20.0, noise="white",
                                      seed=3)
    result = analyze_random_drift(run_twin(plan, tmp_path / "r.h5"))
    rows = result.parameter_rows()
    assert len(rows) == 18 and all(r.std == r.std_noise for r in rows)  # no fit
    assert len(result.fit_quality) == 3 * len(result.repetitions)
    _check_contract(result, tmp_path)
    # drift_std is the fit's σ (Birge-scaled on a misfit); drift_std_noise before the scaling
    assert not any(q.misfit for q in result.fit_quality)
    np.testing.assert_array_equal(result.drift_std_noise, result.drift_std)
    misfit = assess_fit("gyro y", 40.0, 2)
    fits = list(result.drift_fits)
    fits[1] = misfit  # repetition 0, gyro y
    scaled = dataclasses.replace(result, drift_fits=tuple(fits))
    expected = result.drift_std.copy()
    expected[0, 1] /= misfit.sigma_scale
    np.testing.assert_allclose(scaled.drift_std_noise, expected, rtol=1e-15)
    assert json.dumps(scaled.to_dict(), allow_nan=False)


@pytest.fixture
def plugin(monkeypatch: pytest.MonkeyPatch) -> ModuleType:
    """The example plug-in's analysis module, importable from its source tree."""
    monkeypatch.syspath_prepend(str(EXAMPLE_SRC))
    import importlib

    return importlib.import_module("imucalib_scale_factor.analysis")


def test_plugin_result_scales_a_misfit_in_std_only(plugin: ModuleType, tmp_path: Path) -> None:
    x = np.array([0.5, -0.5, 1.0, -1.0, 1.5, -1.5])
    y = 1.001 * x + 2e-4 + np.array([1, -1, -1, 1, 1, -1]) * 1e-3
    se = np.full(6, 1e-5)
    est, cov, res, quality = plugin.fit_scale_factor(x, y, se)
    assert quality.misfit
    std = np.sqrt(np.diag(cov))
    result = plugin.ScaleFactorResult(
        unit="U", k1=float(est[0]), k1_std=float(std[0]), bias_rps=float(est[1]),
        bias_std_rps=float(std[1]), correlation=float(cov[0, 1] / (std[0] * std[1])),
        input_rps=x, output_rps=y, se_rps=se, residuals_rps=res, quality=(quality,))
    rows = result.parameter_rows()
    assert [r.name for r in rows] == ["gyro_K1_z", "gyro_bias_z"]
    assert [r.std for r in rows] == [result.k1_std, result.bias_std_rps]
    _assert_scaled(rows, [quality.sigma_scale] * 2)
    assert result.triad_parameters()[0] == []
    doc = _check_contract(result, tmp_path)
    assert doc["covariance"] is None and doc["details"]["k1"] == result.k1
    assert "MISFIT" in result.decision.summary()
