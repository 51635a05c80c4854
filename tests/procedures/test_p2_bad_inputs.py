"""P2 bad inputs on the twin: typed errors naming unit, temperature and step; the rest go on."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.errors import ConfigurationError, InvalidInputError
from imucalib.plan.schema import Plan, RateStep, SoakStep
from imucalib.procedures.p2.analysis import P2Options
from imucalib.procedures.p2.batch import analyze_p2
from imucalib.procedures.p2.plan import generate_p2_plan, sweep

from ._p2_twin import run_twin_p2, twin_equipment, twin_plan

_SMALL = dict(temperatures_degc=(10.0, 40.0), held_out_degc=(), hysteresis=False)


def _replace_step(plan: Plan, index: int, step: object) -> Plan:
    steps = list(plan.steps)
    steps[index] = step  # type: ignore[call-overload]
    return plan.model_copy(update={"steps": tuple(steps)})


def test_one_unit_with_dropouts_fails_alone(tmp_path):
    equipment = twin_equipment(2, drop={"U1": 0.03})
    plan = twin_plan(equipment, **_SMALL)
    # the counter-gap guard would stop the run; the analysis must catch the dropouts itself
    plan = plan.model_copy(update={"guards": plan.guards.model_copy(
        update={"max_counter_gap_samples": 10**6})})
    path = run_twin_p2(plan, tmp_path / "drops.h5", truth_streams=False)
    batch = analyze_p2(path)
    by = {r.unit: r for r in batch.results}
    assert by["U0"].error == "" and by["U0"].result is not None
    assert by["U1"].error_type == "MissingSegmentError" and by["U1"].passed is False
    assert "unit U1, temperature point 0 (" in by["U1"].error
    assert "step " in by["U1"].error and "lost to dropouts" in by["U1"].error
    assert not batch.passed


def test_a_turn_short_of_a_revolution_is_named(tmp_path):
    plan = twin_plan(twin_equipment(1), **_SMALL)
    i = next(i for i, s in enumerate(plan.steps) if isinstance(s, RateStep))
    step = plan.steps[i]
    assert isinstance(step, RateStep)
    short = step.model_copy(update={"revolutions": None, "record_s": 2.0})  # 240° at 120 °/s
    path = run_twin_p2(_replace_step(plan, i, short), tmp_path / "short.h5",
                       truth_streams=False)
    (result,) = analyze_p2(path).results
    assert result.error_type == "MissingSegmentError"
    assert f"step {i} " in result.error and "at least one revolution" in result.error
    assert "temperature point 0" in result.error


def test_a_temperature_never_reached_is_named(tmp_path):
    plan = twin_plan(twin_equipment(1), **_SMALL)
    soaks = [i for i, s in enumerate(plan.steps) if isinstance(s, SoakStep)
             and s.temperature_degc == 40.0]
    step = plan.steps[soaks[0]]
    assert isinstance(step, SoakStep)
    # 40 °C needs minutes; give it 20 s
    impossible = step.model_copy(update={"timeout_s": 20.0, "stable_for_s": 15.0})
    path = run_twin_p2(_replace_step(plan, soaks[0], impossible), tmp_path / "cold.h5",
                       truth_streams=False, must_finish=False)
    (result,) = analyze_p2(path).results
    assert result.error_type == "MissingSegmentError"
    assert "temperature point 1 (+40 °C)" in result.error
    assert "never reached" in result.error


def test_options_and_plans_refuse_bad_values():
    with pytest.raises(InvalidInputError, match="lever_arm"):
        P2Options(lever_arm="sometimes")  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="max_order"):
        P2Options(max_order=9)
    with pytest.raises(ConfigurationError, match="at least 2"):
        sweep([20.0], [], hysteresis=False)
    with pytest.raises(ConfigurationError, match="repeated"):
        sweep([0.0, 20.0], [20.0], hysteresis=False)
    with pytest.raises(ConfigurationError, match="n_imus"):
        generate_p2_plan(n_imus=65)


def test_cli_refuses_p2_options_on_other_procedures_and_bad_p2_options(tmp_path, consumer_run):
    res = CliRunner().invoke(app, ["calibrate", str(consumer_run), "--lever-arm", "cancel",
                                   "--out", str(tmp_path)])
    assert res.exit_code == 2 and "does not take --lever-arm" in res.output
    res = CliRunner().invoke(app, ["plan", "new", "p1", "-o", str(tmp_path / "x.toml"),
                                   "--n-imus", "4"])
    assert res.exit_code == 2 and "plan new p2 --n-imus" in res.output
    res = CliRunner().invoke(app, ["plan", "new", "p2", "-o", str(tmp_path / "p2.toml"),
                                   "--held-out", "ten"])
    assert res.exit_code == 2 and "--held-out takes numbers" in res.output
    assert Path(tmp_path / "p2.toml").exists() is False


def test_cli_writes_a_p2_plan_with_its_options(tmp_path):
    from imucalib.plan.io import load_plan

    path = tmp_path / "p2.toml"
    res = CliRunner().invoke(app, ["plan", "new", "p2", "-o", str(path), "--n-imus", "12",
                                   "--hysteresis", "--temperatures=-30,0,30,60",
                                   "--held-out", "15", "--rate-dps", "90"])
    assert res.exit_code == 0, res.output
    plan = load_plan(path)
    assert plan.procedure == "p2" and plan.twin is not None and len(plan.twin.imus) == 12
    legs = {t for s in plan.steps if s.role == "p2.soak" for t in s.tags if t.startswith("leg=")}
    assert legs == {"leg=heating", "leg=cooling"}
    rates = {abs(s.rate_dps) for s in plan.steps if isinstance(s, RateStep)}
    assert rates == {90.0}
    remounts = [s.remount for s in plan.steps if getattr(s, "remount", None)]
    assert remounts[:6] == ["+z", "-z", "+y", "-y", "+x", "-x"]


def test_a_zero_resoak_leaves_the_resoak_out():
    """resoak_s=0 is the option's minimum: no re-soak after a remount, not an invalid step."""
    with_resoak = generate_p2_plan(resoak_s=120.0)
    without = generate_p2_plan(resoak_s=0.0)
    resoaks = [s for s in with_resoak.steps
               if isinstance(s, SoakStep) and (s.label or "").startswith("re-soak")]
    assert resoaks and all(s.stable_for_s == 120.0 for s in resoaks)
    assert not [s for s in without.steps
                if isinstance(s, SoakStep) and (s.label or "").startswith("re-soak")]
    assert len(without.steps) == len(with_resoak.steps) - len(resoaks)
