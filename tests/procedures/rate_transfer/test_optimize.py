"""``imucalib plan optimize rate-transfer`` (docs/test-design.md, "Rate transfer")."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.errors import ConfigurationError, InsufficientExcitationError
from imucalib.plan import load_plan
from imucalib.plan.budget import estimate_plan_recording
from imucalib.plan.schema import RateStep
from imucalib.procedures import registry
from imucalib.procedures.common.prediction import OptimizeRequest, Optimizing
from imucalib.procedures.rate_transfer.design import d_efficiency, move_time_s, station_time_s
from imucalib.procedures.rate_transfer.optimize import (
    candidate_designs,
    optimize_rate_transfer,
)
from imucalib.procedures.rate_transfer.plan import generate_rate_transfer_plan
from imucalib.procedures.rate_transfer.predict import predict_rate_transfer

from .._rate_twin import with_unit

runner = CliRunner()


def _turns(plan):  # type: ignore[no-untyped-def]
    return [s for s in plan.steps if isinstance(s, RateStep)]


def test_registered_as_optimizing() -> None:
    assert isinstance(registry.get("rate-transfer"), Optimizing)


@pytest.fixture(scope="module")
def default_optimum():  # type: ignore[no-untyped-def]
    return optimize_rate_transfer(generate_rate_transfer_plan(axes=("x",)), coarse=True)


def test_default_targets_met_in_less_time(default_optimum) -> None:  # type: ignore[no-untyped-def]
    best, ref = default_optimum.best, default_optimum.reference
    assert best.worst_ratio <= 1.0 + 1e-6
    assert ref.worst_ratio == pytest.approx(1.0)
    assert best.station_time_s <= ref.station_time_s
    # every target is the base plan's σ, and the plan written predicts what was printed
    again = predict_rate_transfer(best.plan).std()
    for name, target in default_optimum.targets.items():
        assert again[name] is not None and again[name] <= target * (1 + 1e-6), name
    turns = _turns(best.plan)
    mags = {round(abs(s.rate_dps), 6) for s in turns}
    assert len(mags) >= 3  # the second fit (RT-7) stays identified
    for m in mags:  # both directions at every magnitude, whole revolutions ≥ 2
        signs = {np.sign(s.rate_dps) for s in turns if round(abs(s.rate_dps), 6) == m}
        assert signs == {-1.0, 1.0}
    assert min(s.revolutions or 0 for s in turns) >= 2


def test_a_scale_factor_target_alone_saves_most_time() -> None:
    base = generate_rate_transfer_plan(axes=("x",))
    ref = predict_rate_transfer(base).std()["gyro_M_xx"]
    assert ref is not None
    opt = optimize_rate_transfer(base, targets={"gyro_M_xx": ref}, coarse=True)
    assert opt.best.ratios["gyro_M_xx"] <= 1.0 + 1e-6
    assert opt.best.station_time_s < 0.75 * opt.reference.station_time_s
    # M_xx alone: the line (RT-5) gives it (as the result does without a second fit), and
    # the line's D-optimal rates ±ω_max are the cheapest (eff_D (TD.R2) = 1 against 0.36)
    def eff(plan):  # type: ignore[no-untyped-def]
        t = _turns(plan)
        rates = np.array([s.rate_dps for s in t])
        dwell = np.array([(s.revolutions or 0) * 360.0 / abs(s.rate_dps) for s in t])
        return d_efficiency("poly1", rates / np.max(np.abs(rates)), dwell)
    assert opt.best.design.rates_dps == (60.0,)
    assert eff(opt.best.plan) == pytest.approx(1.0) and eff(base) < 0.4


def test_white_noise_the_bias_binds_the_default_targets() -> None:
    """With white noise a bias's σ is N/√(total time) at any rates: it sets the time needed.

    The D-optimal rates of (RT-7) then meet every default target a little sooner (the settling
    of fewer turns), with the scale factor's σ far below its target.
    """
    base = with_unit(generate_rate_transfer_plan(axes=("x",)))
    opt = optimize_rate_transfer(base)  # the full grid: 728 s against 787 s
    assert opt.best.worst_ratio <= 1.0 + 1e-6
    assert opt.best.worst_name.startswith("gyro_bias")
    assert opt.best.station_time_s < 0.95 * opt.reference.station_time_s
    assert opt.best.ratios["gyro_M_xx"] < 0.7


def test_budget_that_cannot_identify_the_second_fit_names_it() -> None:
    base = generate_rate_transfer_plan(axes=("x",))
    with pytest.raises(InsufficientExcitationError) as err:
        optimize_rate_transfer(base, time_budget_s=100.0, coarse=True)
    assert {"gyro_bias_up_x", "gyro_asymmetry_x", "gyro_E2_x"} <= set(err.value.unobservable)
    assert "confounded" in str(err.value)
    with pytest.raises(ConfigurationError, match="no rate-transfer design fits"):
        optimize_rate_transfer(base, time_budget_s=10.0, coarse=True)


def test_budget_gives_the_least_worst_ratio_within_it() -> None:
    base = generate_rate_transfer_plan(axes=("x",))
    budget = 0.8 * station_time_s(base)
    opt = optimize_rate_transfer(base, time_budget_s=budget, coarse=True)
    assert opt.best.station_time_s <= budget
    assert math.isfinite(opt.best.worst_ratio)


def test_candidates_keep_the_interval_and_least_revolutions() -> None:
    designs = candidate_designs((5.0, 12.5, 60.0), 2)
    assert any(d.label.startswith("D-optimal") for d in designs)
    for d in designs:
        assert min(d.rates_dps) >= 5.0 - 1e-9 and max(d.rates_dps) <= 60.0 + 1e-9
        assert min(d.revolutions) >= 2


def test_move_time_follows_the_table_acceleration() -> None:
    plan = generate_rate_transfer_plan(rates_dps=(30.0,), axes=("z",))
    assert move_time_s(plan) == 0.0  # 0.6 s moves inside the 10-s settle phase
    slow = plan.model_copy(update={"limits": plan.limits.model_copy(
        update={"max_accel_dps2": 1.0})})
    # from rest to +30 °/s (30 s), then to −30 °/s (60 s), with the 1-s settling check,
    # beyond the 10-s settle phase each
    assert move_time_s(slow) == pytest.approx((30.0 + 1.0 - 10.0) + (60.0 + 1.0 - 10.0))
    assert station_time_s(slow) == pytest.approx(
        estimate_plan_recording(slow).duration_s + move_time_s(slow))


def test_request_refusals_are_one_line() -> None:
    proc = registry.get("rate-transfer")
    assert isinstance(proc, Optimizing)
    for request, message in (
            (OptimizeRequest(targets="spec"), "--target-from-spec is not available"),
            (OptimizeRequest(criterion="D", time_budget_s=3600.0), "--criterion D"),
            (OptimizeRequest(grade="space"), "--grade must be"),
            (OptimizeRequest(targets="given", target_text="nope=1"), "names no rate-transfer")):
        with pytest.raises(ConfigurationError, match=message) as err:
            proc.optimize_plan(request)
        assert "\n" not in str(err.value)


def test_cli_writes_the_plan_and_refuses_in_one_line(tmp_path: Path) -> None:
    out = tmp_path / "rt-opt.toml"
    result = runner.invoke(app, ["plan", "optimize", "rate-transfer", "--coarse",
                                 "--target", "gyro_M=4e-6", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "rate-transfer: default plan" in result.stdout
    plan = load_plan(out)
    std = predict_rate_transfer(plan).std()
    assert all((std[f"gyro_M_{k}{k}"] or math.inf) <= 4e-6 for k in "xyz")
    bad = runner.invoke(app, ["plan", "optimize", "rate-transfer", "--coarse",
                              "--time-budget", "0.05", "--out", str(tmp_path / "x.toml")])
    assert bad.exit_code == 2, bad.output
    assert bad.stderr.startswith("error: ") and bad.stderr.count("\n") == 1
    assert "gyro_E2_x" in bad.stderr and "confounded" in bad.stderr
    assert "Traceback" not in bad.output
