"""P3's plan generator: the round-robin's steps, their roles and tags, the rates, the checks."""

from __future__ import annotations

import math

import pytest
from typer.testing import CliRunner

from imucalib import units
from imucalib.cli import app
from imucalib.errors import ConfigurationError
from imucalib.plan.io import load_plan
from imucalib.plan.schema import CentrifugeStep, OperatorCheckStep
from imucalib.procedures import registry
from imucalib.procedures.p3.plan import UNIT_NAMES, generate_p3_plan, p3_rates_dps


def _by_role(plan, role):
    return [s for s in plan.steps if s.role == role]


def test_the_default_plan_runs_the_round_robin():
    plan = generate_p3_plan()
    assert plan.procedure == "p3" and registry.get("p3").generate_plan().name == plan.name
    # the first check names the units; A at +r_t/3, B at −r_t/3, the test unit at +r_t
    mount = plan.steps[0]
    assert isinstance(mount, OperatorCheckStep) and mount.role == "p3.mount"
    assert {f"{k}={v}" for k, v in UNIT_NAMES.items()} <= set(mount.tags)
    assert plan.twin is not None and plan.twin.fixture.kind == "arm"
    assert plan.twin.fixture.arm_radii_m == pytest.approx((1 / 3, -1 / 3, 1.0))
    # tumble: input axes up and down, then back
    tumble = _by_role(plan, "p3.tumble")
    assert [s.tags for s in tumble] == [("pose=+x",), ("pose=-x",)]
    assert [s.remount for s in _by_role(plan, "p3.mount")[1:]] == ["+x", "-x", "+z"]
    # three configurations: four rest positions before and after five rates
    for k in (1, 2, 3):
        rests = [s for s in _by_role(plan, "p3.rest") if f"config={k}" in s.tags]
        assert sorted((s.arm_position_deg, s.tags[-1]) for s in rests) == sorted(
            (a, f"phase={p}") for a in (0.0, 90.0, 180.0, 270.0) for p in ("before", "after"))
        rates = [s for s in _by_role(plan, "p3.rate") if f"config={k}" in s.tags]
        assert len(rates) == 5 and all(isinstance(s, CentrifugeStep) for s in rates)
        # 4 … 20 g at r_t = 1 m, each at least 60 s of whole revolutions
        g = [(s.rate_dps * units.DEG) ** 2 * 1.0 / units.G0_MPS2 for s in rates]
        assert g == pytest.approx([4.0, 8.0, 12.0, 16.0, 20.0])
        assert all(s.revolutions * 360.0 / s.rate_dps >= 60.0 for s in rates)
    swap, = _by_role(plan, "p3.swap")
    load, = _by_role(plan, "p3.load")
    assert swap.swap_units == ("REF-A", "REF-B") and swap.centrifuge_load_kg is None
    assert load.swap_units == ("REF-A", "REF-B") and load.centrifuge_load_kg == 2.0
    order = [plan.steps.index(s) for s in (swap, load)]
    first2 = min(i for i, s in enumerate(plan.steps) if "config=2" in s.tags and s.kind !=
                 "operator-check")
    first3 = min(i for i, s in enumerate(plan.steps) if "config=3" in s.tags and s.kind !=
                 "operator-check")
    assert order[0] < first2 < order[1] < first3
    # the twin's unbalance: 10 µm at the top rate with the load, half of it without
    fuge = plan.twin.centrifuge
    top = max(abs(s.rate_dps) for s in _by_role(plan, "p3.rate")) * units.DEG
    c_loaded = fuge.unbalance_c0_m_per_rps_sq + 2.0 * fuge.unbalance_c_m_per_rps_sq_per_kg
    assert c_loaded * top**2 == pytest.approx(10e-6)
    assert fuge.unbalance_c0_m_per_rps_sq * top**2 == pytest.approx(5e-6)
    assert plan.limits.max_centrifuge_rate_dps == pytest.approx(1.1 * top / units.DEG)


def test_options_change_the_plan():
    plan = generate_p3_plan(static_radius_m=0.6, test_range_g=10.0, n_rates=6,
                            both_directions=True, tumble=False, reference_radius_m=0.25)
    rates = [s.rate_dps for s in _by_role(plan, "p3.rate") if "config=1" in s.tags]
    assert len(rates) == 12 and sorted(rates)[0] < 0
    assert max(rates) == pytest.approx(math.sqrt(10 * units.G0_MPS2 / 0.6) / units.DEG)
    assert not _by_role(plan, "p3.tumble")
    assert plan.twin is not None and plan.twin.fixture.arm_radii_m[:2] == (0.25, -0.25)
    explicit = generate_p3_plan(rates_dps=[100, 200, 300, 400])
    assert sorted({abs(s.rate_dps) for s in _by_role(explicit, "p3.rate")}) == [100, 200,
                                                                                 300, 400]


def test_bad_options_are_refused():
    with pytest.raises(ConfigurationError, match="at least 4 rate points"):
        generate_p3_plan(n_rates=3)
    with pytest.raises(ConfigurationError, match="at least 4 rate points"):
        p3_rates_dps(1.0, 20.0, 2)
    with pytest.raises(ConfigurationError, match="at least 4 distinct"):
        generate_p3_plan(rates_dps=[100, 200, 200, 300])
    with pytest.raises(ConfigurationError, match="10 000"):
        generate_p3_plan(static_radius_m=0.01, test_range_g=1000.0)
    with pytest.raises(ConfigurationError, match="reference_radius_m"):
        generate_p3_plan(reference_radius_m=1.5)
    with pytest.raises(ConfigurationError, match="arm_positions_deg"):
        generate_p3_plan(arm_positions_deg=[0.0])


def test_cli_writes_a_p3_plan_and_refuses_p3_options_elsewhere(tmp_path):
    path = tmp_path / "p3.toml"
    res = CliRunner().invoke(app, ["plan", "new", "p3", "-o", str(path), "--radius-m", "0.8",
                                   "--n-rates", "4", "--test-load-kg", "5", "--no-tumble"])
    assert res.exit_code == 0, res.output
    plan = load_plan(path)
    assert plan.procedure == "p3" and plan.twin is not None
    assert plan.twin.centrifuge.static_radius_m == 0.8
    assert len([s for s in plan.steps if s.role == "p3.rate"]) == 12
    assert [s.centrifuge_load_kg for s in plan.steps if s.role == "p3.load"] == [5.0]
    res = CliRunner().invoke(app, ["plan", "new", "p3", "-o", str(tmp_path / "x.toml"),
                                   "--n-rates", "3"])
    assert res.exit_code == 2 and "--n-rates takes an integer in [4, 10000]; got '3'" in res.output
    res = CliRunner().invoke(app, ["plan", "new", "p1", "-o", str(tmp_path / "y.toml"),
                                   "--test-load-kg", "3"])
    assert res.exit_code == 2 and "plan new p3 --test-load-kg" in res.output


def test_arm_positions_must_cancel_a_once_per_revolution_leak():
    with pytest.raises(ConfigurationError, match="spread evenly"):
        generate_p3_plan(arm_positions_deg=[0.0, 180.0, 270.0])
    plan = generate_p3_plan(arm_positions_deg=[0.0, 120.0, 240.0])
    assert {s.arm_position_deg for s in plan.steps if s.role == "p3.rest"} == {0.0, 120.0,
                                                                               240.0}
