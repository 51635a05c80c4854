"""The classical tests decide against the unit's specification (docs/procedures.md, the contract).

Each of the six classical tests (tumble, rate transfer, installation, g-sensitivity, Earth-rate
bias, random drift) judges the triad parameters it hands on against the recording's
``[imu.limits]`` under its ``[acceptance]`` rule, as P1 does
(``procedures/common/spec_decision.py``): with limits above every value, PASS; with one limit
below some values, FAIL, the check ``specification`` failing exactly the rows beyond it; with
no limit that covers its quantities, an explicit NO DECISION whose rule names the limits that
would. A twin run whose plan carries limits and a guarded rule decides from its recording.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from imucalib import units
from imucalib.cli import app
from imucalib.errors import InvalidInputError
from imucalib.io.context import RecordingContext
from imucalib.models.fit_quality import assess_fit
from imucalib.models.result_document import result_document
from imucalib.plan.schema import AcceptanceConfig, ImuSpecConfig, SpecLimits
from imucalib.procedures.common.drift_model import DriftFit
from imucalib.procedures.common.spec_decision import (
    SPEC_CHECK,
    Specification,
    decide_against,
    spec_field,
    triad_specification_rows,
)
from imucalib.procedures.earth_rate_bias.analysis import analyze_earth_rate_bias
from imucalib.procedures.earth_rate_bias.plan import generate_earth_rate_bias_plan
from imucalib.procedures.g_sensitivity.analysis import GSensitivityResult
from imucalib.procedures.random_drift.analysis import RandomDriftResult
from imucalib.procedures.random_drift.scatter import random_drift, scatter

from ._p4_twin import run_twin
from .test_result_contract_classical_a import _installation, _rate_transfer, _three, _tumble

G = 9.80665


# --- the helper -----------------------------------------------------------------------------

@pytest.mark.parametrize(("name", "field"), [
    ("accel_bias_x", "accel_bias_ug"), ("accel_M_yy", "accel_scale_ppm"),
    ("accel_M_xz", "accel_misalignment_urad"), ("gyro_bias_z", "gyro_bias_dph"),
    ("gyro_M_zz", "gyro_scale_ppm"), ("gyro_M_yx", "gyro_misalignment_urad"),
    ("gyro_G_xz", "gyro_g_sensitivity_dph_per_g"), ("gyro_K_x", "gyro_scale_ppm"),
    ("accel_b_y", "accel_bias_ug"), ("accel_K2_x", None), ("accel_G_xy", None),
    ("gyro_scale_factor_x", None), ("gyro_nonlinearity_x", None)])
def test_each_triad_parameter_has_the_limit_p1_gives_it(name: str, field: str | None) -> None:
    got = spec_field(name)
    assert (None if got is None else got[2]) == field


def test_rows_are_in_the_display_units_of_the_limits() -> None:
    names = ["accel_bias_x", "gyro_M_xx", "gyro_G_xy", "gyro_K_y", "accel_K2_x"]
    values = [100 * units.UG, 250e-6, 2.0 * units.DEG_PER_H / G, 1.0 + 30e-6, 1e-4]
    cov = np.diag([(10 * units.UG) ** 2, (5e-6) ** 2, (0.1 * units.DEG_PER_H / G) ** 2,
                   (1e-6) ** 2, 1e-10])
    rows = triad_specification_rows(names, values, cov, {"gyro_scale_ppm": 300.0})
    assert [r[0] for r in rows] == names[:4]  # K2 has no limit in a specification
    assert [r[4] for r in rows] == ["µg", "ppm", "(°/h)/g", "ppm"]
    for row, (value, u) in zip(rows, [(100, 10), (250, 5), (2.0, 0.1), (30, 1)], strict=True):
        assert row[1] == pytest.approx(value) and row[2] == pytest.approx(u)
    assert [r[3] for r in rows] == [None, 300.0, None, 300.0]


def test_the_specification_is_the_recordings_and_is_checked() -> None:
    context = RecordingContext(spec_limits={"gyro_bias_dph": 5.0}, acceptance="guarded",
                               guard_band_k=3.0)
    spec = Specification.of_context(context)
    assert spec.limits == {"gyro_bias_dph": 5.0} and spec.rule == "guarded"
    assert spec.guard_band_k == 3.0 and "guarded acceptance" in spec.rule_text
    bare = Specification.of_context(RecordingContext())
    assert bare.limits == {} and bare.rule == "simple" and bare.guard_band_k == 2.0
    with pytest.raises(InvalidInputError, match="'simple' or 'guarded'"):
        Specification.of_context(RecordingContext(acceptance="lenient"))
    with pytest.raises(InvalidInputError, match="not SpecLimits fields"):
        Specification({"gyro_bias": 1.0})
    with pytest.raises(InvalidInputError, match="finite number"):
        Specification({"gyro_bias_dph": math.nan})


def test_guarded_acceptance_fails_a_value_whose_band_reaches_the_limit() -> None:
    rows = [("gyro_bias_x", 4.0, 0.6, 5.0, "°/h"), ("gyro_bias_y", -1.0, 0.1, 5.0, "°/h")]
    simple = decide_against(Specification(), rows, test="t", what="w")
    assert simple.verdict == "PASS"
    guarded = decide_against(Specification(rule="guarded"), rows, test="t", what="w")
    assert guarded.verdict == "FAIL" and guarded.failed == (SPEC_CHECK,)
    (check,) = guarded.checks
    assert [r.passed for r in check.rows] == [False, True]
    assert check.rows[0].value == pytest.approx(4.0 + 2 * 0.6)
    assert "guarded acceptance" in guarded.rule and "gyro_bias_dph" in guarded.rule
    none = decide_against(Specification(), [(r[0], r[1], r[2], None, r[4]) for r in rows],
                          test="the test", what="it measures biases")
    assert none.verdict == "NO DECISION" and none.checks == ()
    assert none.rule.startswith("the test has no acceptance limits")
    assert "gyro_bias_dph" in none.rule and "it measures biases" in none.rule


# --- each classical test --------------------------------------------------------------------

def _g_sensitivity() -> GSensitivityResult:
    """D0 of 1–3 °/h and G of 0.5–4.5 (°/h)/g, σ 5 % of each, no misfit."""
    rng = np.random.default_rng(11)
    coefficients = np.zeros((3, 4))
    coefficients[:, 0] = np.array([1.0, -2.0, 3.0]) * units.DEG_PER_H
    coefficients[:, 1:] = rng.uniform(0.5, 4.5, (3, 3)) * rng.choice([-1, 1], (3, 3)) \
        * units.DEG_PER_H / G
    cov = np.diag((0.05 * coefficients.ravel()) ** 2)
    fit = DriftFit(coefficients=coefficients, covariance=cov,
                   fits=tuple(assess_fit(f"gyro {a}", 10.0, 10) for a in "xyz"),
                   residuals=np.zeros((12, 3)))
    return GSensitivityResult(unit="U1", fit=fit, windows=[], gravity_mps2=G, latitude_deg=45.0)


def _random_drift() -> RandomDriftResult:
    """Four repetitions of D0, G and the accelerometer bias scattering about known means."""
    rng = np.random.default_rng(12)
    r = 4
    mean = np.zeros((3, 4))
    mean[:, 0] = np.array([2.0, -1.0, 0.5]) * units.DEG_PER_H
    mean[:, 1:] = np.array([[1.0, -2.0, 0.3], [0.5, 1.5, -1.0], [2.0, 0.2, -0.7]]) \
        * units.DEG_PER_H / G
    drift = mean + rng.normal(0.0, 0.02, (r, 3, 4)) * np.abs(mean)
    accel = np.array([300.0, -150.0, 80.0]) * units.UG + rng.normal(0.0, 5 * units.UG, (r, 3))
    sc = [[scatter(drift[:, i, k], f"D{k} {a}") for k in range(4)] for i, a in enumerate("xyz")]
    return RandomDriftResult(
        unit="U1", repetitions=list(range(r)),
        times_s=np.arange(r, dtype=np.float64) * 600.0, drift=drift,
        drift_std=np.full((r, 3, 4), 1e-9), accel_bias=accel,
        accel_bias_std=np.full((r, 3), 1e-6), drift_scatter=sc,
        accel_zero_stability=[scatter(accel[:, i]) for i in range(3)],
        random_drift_rps=np.array([random_drift(sc[i][0].std, [s.std for s in sc[i][1:]], G, r)
                                   for i in range(3)]),
        allan_d0_rps=np.zeros(3), allan_accel_mps2=np.zeros(3), interval_s=600.0,
        gravity_mps2=G)


#: Each classical test's result without limits, and the limits that cover its quantities.
CASES: dict[str, tuple[Any, set[str]]] = {
    "tumble": (lambda: _tumble(_three(np.random.default_rng(1))),
               {"accel_bias_ug", "accel_scale_ppm", "accel_misalignment_urad"}),
    "rate-transfer": (lambda: _rate_transfer(np.random.default_rng(4)), {"gyro_scale_ppm"}),
    "installation": (lambda: _installation(np.random.default_rng(7)),
                     {"gyro_misalignment_urad"}),
    "g-sensitivity": (_g_sensitivity, {"gyro_bias_dph", "gyro_g_sensitivity_dph_per_g"}),
    "random-drift": (_random_drift,
                     {"gyro_bias_dph", "gyro_g_sensitivity_dph_per_g", "accel_bias_ug"}),
}


def _field(name: str) -> str:
    spec = spec_field(name)
    assert spec is not None, name
    return spec[2]


def _by_field(result: Any) -> dict[str, list[float]]:
    """|value| of every row the specification can bound, by its SpecLimits field."""
    names, values, cov = result.triad_parameters()
    out: dict[str, list[float]] = defaultdict(list)
    for label, value, _u, _limit, _unit in triad_specification_rows(names, values, cov, {}):
        out[_field(label)].append(abs(value))
    return out


def assert_decides_on_its_rows(result: Any, fields: set[str]) -> None:
    """PASS within wide limits, FAIL exactly on the rows beyond a tight one, NO DECISION bare."""
    assert result.specification.limits == {}
    bare = result.decision
    assert bare.passed is None and bare.verdict == "NO DECISION" and result.passed is None
    assert "no acceptance limits" in bare.rule and all(f in bare.rule for f in fields)
    by_field = _by_field(result)
    assert set(by_field) == fields
    triad_names, values, cov = result.triad_parameters()
    names = [r[0] for r in triad_specification_rows(triad_names, values, cov, {})]
    wide = {f: 2.0 * max(v) for f, v in by_field.items()}
    ok = dataclasses.replace(result, specification=Specification(wide))
    decision = ok.decision
    assert decision.verdict == "PASS" and ok.passed is True and decision.failed == ()
    (check,) = decision.checks
    assert check.name == SPEC_CHECK and check.passed is True
    assert [r.name for r in check.rows] == names and all(r.passed for r in check.rows)
    assert "simple acceptance" in decision.rule
    assert result_document(ok)["decision"]["verdict"] == "PASS"
    for tight_field in sorted(fields):
        values = sorted(by_field[tight_field])
        limit = 0.5 * (values[-1] + (values[-2] if len(values) > 1 else 0.0))
        bad = dataclasses.replace(result, specification=Specification({**wide,
                                                                       tight_field: limit}))
        decision = bad.decision
        assert decision.verdict == "FAIL" and bad.passed is False
        assert decision.failed == (SPEC_CHECK,)
        (check,) = decision.checks
        beyond = [r.name for r in check.rows if r.value > r.limit]
        assert beyond and [r.name for r in check.rows if not r.passed] == beyond
        assert all(_field(n) == tight_field for n in beyond)
        assert result_document(bad)["decision"]["failed"] == [SPEC_CHECK]
    # limits of quantities the test does not estimate: still no decision
    other = {"gyro_arw_deg_rth": 1.0, "accel_vrw_ug_rthz": 1.0}
    assert dataclasses.replace(result, specification=Specification(other)).decision.passed \
        is None
    # one of its limits only: judged on that one, the others named as not specified
    first = sorted(fields)[0]
    part = dataclasses.replace(result, specification=Specification({first: wide[first]}))
    (check,) = part.decision.checks
    assert part.passed is True
    assert {_field(r.name) for r in check.rows} == {first}
    if len(fields) > 1:
        assert "not specified, not judged" in check.summary


@pytest.mark.parametrize("name", sorted(CASES))
def test_a_classical_test_decides_on_its_rows_against_the_limits(name: str) -> None:
    make, fields = CASES[name]
    assert_decides_on_its_rows(make(), fields)


def test_the_misfit_notes_stay_with_a_decision() -> None:
    result = _rate_transfer(np.random.default_rng(5), k3=2e-4)
    wide = {"gyro_scale_ppm": 2.0 * max(_by_field(result)["gyro_scale_ppm"])}
    decided = dataclasses.replace(result, specification=Specification(wide)).decision
    assert decided.notes == result.decision.notes and any("MISFIT" in n for n in decided.notes)


# --- from a recording: the Earth-rate bias on the twin ----------------------------------------

@pytest.fixture(scope="module")
def earth_rate_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A short Earth-rate bias run whose plan states gyro bias limits and a guarded rule."""
    plan = generate_earth_rate_bias_plan(record_s=60.0, settle_s=5.0, warm_up_s=10.0,
                                         sample_rate_hz=20.0, noise="white", seed=3)
    plan = plan.model_copy(update={
        "imu": ImuSpecConfig(grade="navigation", limits=SpecLimits(gyro_bias_dph=1e4,
                                                                   accel_bias_ug=1.0)),
        "acceptance": AcceptanceConfig(rule="guarded", guard_band_k=2.0)})
    return run_twin(plan, tmp_path_factory.mktemp("erb") / "e.h5")


def test_the_earth_rate_bias_decides_from_its_recordings_limits_and_rule(earth_rate_run: Path
                                                                         ) -> None:
    result = analyze_earth_rate_bias(earth_rate_run)
    spec = result.specification
    assert spec.limits == {"gyro_bias_dph": 1e4, "accel_bias_ug": 1.0}
    assert spec.rule == "guarded" and spec.guard_band_k == 2.0
    decision = result.decision
    assert decision.verdict == "PASS" and "guarded acceptance" in decision.rule
    (check,) = decision.checks
    assert [r.name for r in check.rows] == ["gyro_bias_x", "gyro_bias_y", "gyro_bias_z"]
    for row, axis in zip(check.rows, result.axes, strict=True):  # |b| + 2u, in °/h
        b, u = axis.up_down.value_rps, axis.up_down.std_rps
        assert row.value == pytest.approx((abs(b) + 2 * u) / units.DEG_PER_H)
        assert row.limit == 1e4 and row.passed
    assert_decides_on_its_rows(dataclasses.replace(result, specification=Specification()),
                               {"gyro_bias_dph"})


def test_calibrate_exits_1_when_the_earth_rate_bias_fails_its_limit(earth_rate_run: Path,
                                                                    tmp_path: Path) -> None:
    """The twin's biases, guarded, against a limit of 1e-3 °/h: FAIL, the exit code says so."""
    import h5py

    copy = tmp_path / "tight.h5"
    copy.write_bytes(earth_rate_run.read_bytes())
    with h5py.File(copy, "r+") as f:
        imu = dict(RecordingContext.of(dict(f.attrs)).imu_table)
        imu["limits"] = {"gyro_bias_dph": 1e-3}
        f.attrs["imu_spec_json"] = json.dumps(imu)
    result = analyze_earth_rate_bias(copy)
    assert result.passed is False and result.decision.failed == (SPEC_CHECK,)
    res = CliRunner().invoke(app, ["calibrate", str(copy), "--out", str(tmp_path / "out"),
                                   "--no-record", "-q"])
    assert res.exit_code == 1, res.output
