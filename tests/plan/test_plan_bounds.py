"""Plan files: every duration, count, rate and temperature bounded, each refusal named exactly."""

from __future__ import annotations

import copy
import re
from typing import Any

import pytest
import tomli_w

from imucalib.errors import ConfigurationError
from imucalib.plan import parse_plan, plan_json_schema
from imucalib.procedures import generate_allan_plan, generate_p1_plan

BASE: dict[str, Any] = {
    "name": "bounds",
    "steps": [{"kind": "position", "angles_deg": [0.0, 0.0], "settle_s": 30.0,
               "record_s": 10.0}],
}


def plan_text(**changes: Any) -> str:
    """BASE with top-level tables or keys replaced (``steps=[...]``, ``limits={...}``)."""
    data = copy.deepcopy(BASE)
    data.update(changes)
    return tomli_w.dumps(data)


def step(kind: str, **fields: Any) -> list[dict[str, Any]]:
    return [{"kind": kind, **fields}]


def refused(text: str, message: str) -> None:
    with pytest.raises(ConfigurationError,
                       match="^" + re.escape(f"invalid plan p.toml: {message}") + "$"):
        parse_plan(text, "p.toml")


DAY = 86400.0


@pytest.mark.parametrize(("changes", "message"), [
    ({"steps": step("position", angles_deg=[0.0, 180.0], settle_s=1e308, record_s=10.0)},
     "steps.0.position.settle_s: Input should be less than or equal to 3600 (got 1e+308)"),
    ({"steps": step("position", angles_deg=[0.0], settle_s=30.0, record_s=8 * DAY)},
     "steps.0.position.record_s: Input should be less than or equal to 604800 (got 691200.0)"),
    ({"steps": step("position", angles_deg=[720.0], settle_s=30.0, record_s=1.0)},
     "steps.0.position.angles_deg.0: Input should be less than or equal to 360 (got 720.0)"),
    ({"steps": step("static", duration_s=float("nan"))},
     "steps.0.static.duration_s: Input should be a finite number (got nan)"),
    ({"steps": step("static", duration_s=float("inf"))},
     "steps.0.static.duration_s: Input should be a finite number (got inf)"),
    ({"steps": step("rate", rate_dps=50.0, settle_s=20.0, revolutions=10**6)},
     "steps.0.rate.revolutions: Input should be less than or equal to 100000 (got 1000000)"),
    ({"steps": step("rate", rate_dps=1e-4, settle_s=20.0, revolutions=1)},
     "steps.0.rate: 1 revolution(s) at 0.0001 °/s take 3.6e+06 s; a record may last at most "
     "604800 s (7 days)"),
    ({"steps": step("rate", rate_dps=600.0, revolutions=1)},
     "steps.0 (rate): rate_dps 600 exceeds limits.max_rate_dps 500"),
    ({"limits": {"max_rate_dps": 1e5}},
     "limits.max_rate_dps: Input should be less than or equal to 10000 (got 100000.0)"),
    ({"limits": {"max_accel_dps2": 1e9}},
     "limits.max_accel_dps2: Input should be less than or equal to 100000 (got 1000000000.0)"),
    ({"limits": {"max_centrifuge_rate_dps": 0.0}},
     "limits.max_centrifuge_rate_dps: Input should be greater than 0 (got 0.0)"),
    ({"limits": {"min_temperature_degc": -300.0}},
     "limits.min_temperature_degc: Input should be greater than or equal to -100 (got -300.0)"),
    ({"steps": step("soak", temperature_degc=1000.0)},
     "steps.0.soak.temperature_degc: Input should be less than or equal to 200 (got 1000.0)"),
    ({"steps": step("soak", temperature_degc=150.0)},
     "steps.0 (soak): temperature_degc 150 is outside limits [-55, 125] °C"),
    ({"steps": step("soak", temperature_degc=20.0, stable_for_s=7200.0, timeout_s=3600.0)},
     "steps.0.soak: stable_for_s (7200 s) exceeds timeout_s (3600 s): the soak could never end"),
    ({"steps": step("soak", temperature_degc=20.0, ramp_degc_per_min=1e4)},
     "steps.0.soak.ramp_degc_per_min: Input should be less than or equal to 600 (got 10000.0)"),
    ({"steps": step("soak", temperature_degc=20.0, ramp_degc_per_min=1e-320)},
     "steps.0.soak.ramp_degc_per_min: Input should be greater than or equal to 0.01 (got "
     "1e-320)"),
    ({"steps": step("warm-up", duration_s=1e9)},
     "steps.0.warm-up.duration_s: Input should be less than or equal to 172800 (got "
     "1000000000.0)"),
    ({"steps": step("warm-up", duration_s=9000.0)},
     "steps.0.warm-up: duration_s (9000 s) exceeds timeout_s (7200 s): the warm-up could never "
     "end"),
    ({"steps": step("centrifuge", rate_dps=2e4, revolutions=1)},
     "steps.0.centrifuge.rate_dps: Input should be less than or equal to 10000 (got 20000.0)"),
    ({"guards": {"settle_timeout_s": 1e308}},
     "guards.settle_timeout_s: Input should be less than or equal to 3600 (got 1e+308)"),
    ({"guards": {"settle_average_s": 5.0, "settle_check_s": 1.0}},
     "guards: settle_average_s (5 s) must not exceed settle_check_s (1 s): the fluctuation is "
     "taken over block means inside that span"),
    ({"guards": {"max_counter_gap_samples": 10**12}},
     "guards.max_counter_gap_samples: Input should be less than or equal to 1000000000 (got "
     "1000000000000)"),
    ({"equipment": {"acquisition_rate_min_hz": 0.5}},
     "equipment.acquisition_rate_min_hz: Input should be greater than or equal to 1 (got 0.5)"),
    ({"equipment": {"acquisition_rate_min_hz": 1e6}},
     "equipment.acquisition_rate_min_hz: Input should be less than or equal to 100000 (got "
     "1000000.0)"),
    ({"twin": {"imus": [{"name": "A", "sample_rate_hz": 1e6}]}},
     "twin.imus.0.sample_rate_hz: Input should be less than or equal to 100000 (got "
     "1000000.0)"),
    ({"twin": {"imus": [{"name": "A", "seed": -1}]}},
     "twin.imus.0.seed: Input should be greater than or equal to 0 (got -1)"),
    ({"steps": [{"kind": "static", "duration_s": 7 * DAY}] * 3},
     "the steps take at least 1.8144e+06 s (21 days); a plan may last at most 1209600 s "
     "(14 days)"),
    ({"steps": [{"kind": "operator-check", "item": "x"}] * 10001},
     "steps: Tuple should have at most 10000 items after validation, not 10001"),
    ({"steps": step("static", duration_s=1.0, tags=["t"] * 33)},
     "steps.0.static.tags: Tuple should have at most 32 items after validation, not 33"),
])
def test_out_of_bounds_plans_are_refused(changes, message):
    refused(plan_text(**changes), message)


def test_several_problems_are_listed_one_per_line():
    text = plan_text(steps=step("position", angles_deg=[0.0], settle_s=-1.0, record_s=1e9))
    with pytest.raises(ConfigurationError) as info:
        parse_plan(text, "p.toml")
    assert str(info.value).splitlines() == [
        "invalid plan p.toml:",
        "  steps.0.position.settle_s: Input should be greater than or equal to 0 (got -1.0)",
        "  steps.0.position.record_s: Input should be less than or equal to 604800 (got "
        "1000000000.0)",
    ]


def test_default_plans_and_their_extremes_are_within_the_bounds():
    for plan in (generate_p1_plan(), generate_p1_plan(grade="navigation", repetitions=5),
                 generate_allan_plan(), generate_allan_plan(grade="navigation",
                                                           record_s=3 * DAY,
                                                           temperatures_degc=[-40, 20, 85])):
        assert parse_plan(tomli_w.dumps(plan.model_dump(mode="json", exclude_none=True)))


def test_the_json_schema_shows_the_bounds():
    schema = plan_json_schema()
    defs = schema["$defs"]
    assert defs["PositionStep"]["properties"]["settle_s"]["maximum"] == 3600.0
    assert defs["PositionStep"]["properties"]["record_s"]["maximum"] == 7 * DAY
    assert defs["StaticStep"]["properties"]["duration_s"]["maximum"] == 7 * DAY
    assert defs["RateStep"]["properties"]["revolutions"]["anyOf"][0]["maximum"] == 100_000
    assert defs["PlanLimits"]["properties"]["max_rate_dps"]["maximum"] == 10_000.0
    assert defs["SoakStep"]["properties"]["temperature_degc"]["minimum"] == -100.0
    assert defs["ImuConfig"]["properties"]["sample_rate_hz"]["anyOf"][0] == {
        "maximum": 100000.0, "minimum": 1.0, "type": "number"}
    assert schema["properties"]["steps"]["maxItems"] == 10_000
