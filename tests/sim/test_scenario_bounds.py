"""Scenario files: every duration, count, rate and temperature bounded, each refusal named."""

from __future__ import annotations

import copy
import re
from typing import Any

import pytest
import tomli_w

from imucalib.errors import ConfigurationError
from imucalib.sim.scenario import BUILTIN_SCENARIOS, ScenarioFormatWarning, load_scenario

BASE: dict[str, Any] = {
    "name": "bounds",
    "table": {"kind": "single-axis"},
    "imus": [{"name": "IMU-1"}],
    "steps": [{"kind": "static", "duration_s": 10.0}],
}
DAY = 86400.0


def refused(tmp_path, changes: dict[str, Any], message: str) -> None:
    data = copy.deepcopy(BASE)
    data.update(changes)
    path = tmp_path / "s.toml"
    path.write_text(tomli_w.dumps(data), encoding="utf-8")
    with pytest.raises(ConfigurationError,
                       match="^" + re.escape(f"invalid scenario {path}: {message}") + "$"):
        load_scenario(path)


@pytest.mark.parametrize(("changes", "message"), [
    ({"steps": [{"kind": "position", "angles_deg": [0.0], "settle_s": 1e308}]},
     "steps.0.position.settle_s: Input should be less than or equal to 3600 (got 1e+308)"),
    ({"steps": [{"kind": "static", "duration_s": float("nan")}]},
     "steps.0.static.duration_s: Input should be a finite number (got nan)"),
    ({"steps": [{"kind": "static", "duration_s": 1e7}]},
     "steps.0.static.duration_s: Input should be less than or equal to 604800 (got "
     "10000000.0)"),
    ({"steps": [{"kind": "static", "duration_s": 6 * DAY}] * 3},
     "the steps take at least 1.5552e+06 s (18 days); a scenario may last at most 1209600 s "
     "(14 days)"),
    ({"steps": [{"kind": "rate", "rate_dps": 1e-3, "revolutions": 2}]},
     "steps.0.rate: 2 revolution(s) at 0.001 °/s take 7.2e+05 s; a record may last at most "
     "604800 s (7 days)"),
    ({"steps": [{"kind": "rate", "rate_dps": 5e4, "revolutions": 2}]},
     "steps.0.rate.rate_dps: Input should be less than or equal to 10000 (got 50000.0)"),
    ({"imus": [{"name": "IMU-1", "sample_rate_hz": 0.5}]},
     "imus.0.sample_rate_hz: Input should be greater than or equal to 1 (got 0.5)"),
    ({"imus": [{"name": "IMU-1", "sample_rate_hz": 1e6}]},
     "imus.0.sample_rate_hz: Input should be less than or equal to 100000 (got 1000000.0)"),
    ({"imus": [{"name": "IMU-1", "seed": -1}]},
     "imus.0.seed: Input should be greater than or equal to 0 (got -1)"),
    ({"imus": [{"name": "IMU-1", "thermal_time_constant_s": 1e9}]},
     "imus.0.thermal_time_constant_s: Input should be less than or equal to 86400 (got "
     "1000000000.0)"),
    ({"fixture": {"lever_arm_m": [0.0, 10.0, 0.0]}},
     "fixture.lever_arm_m.1: Input should be less than or equal to 5 (got 10.0)"),
    ({"table": {"kind": "single-axis", "feedback_rate_hz": 0.1}},
     "table.feedback_rate_hz: Input should be greater than or equal to 1 (got 0.1)"),
    ({"chamber": {"enabled": True, "min_temperature_degc": 50.0,
                  "max_temperature_degc": 10.0}},
     "chamber: min_temperature_degc (50) must be below max_temperature_degc (10)"),
    ({"chamber": {"enabled": True, "max_temperature_degc": 1e308}},
     "chamber.max_temperature_degc: Input should be less than or equal to 200 (got 1e+308)"),
    ({"chamber": {"enabled": True},
      "steps": [{"kind": "soak", "temperature_degc": 150.0, "duration_s": 60.0}]},
     "steps[0] (soak): temperature_degc 150 is outside the chamber's range [-55, 125] °C"),
    ({"chamber": {"enabled": True},
      "steps": [{"kind": "soak", "temperature_degc": 20.0, "stable_for_s": 3 * DAY}]},
     "steps.0.soak.stable_for_s: Input should be less than or equal to 172800 (got 259200.0)"),
    ({"table": {"kind": "none"}, "centrifuge": {"enabled": True},
      "steps": [{"kind": "centrifuge", "rate_dps": 1000.0, "revolutions": 1}]},
     "steps[0] (centrifuge): rate_dps 1000 exceeds centrifuge.max_rate_dps 720"),
    ({"table": {"kind": "none"},
      "centrifuge": {"enabled": True, "unbalance_c0_m_per_rps_sq": 1.0},
      "steps": [{"kind": "centrifuge", "rate_dps": 100.0, "revolutions": 1}]},
     "centrifuge.unbalance_c0_m_per_rps_sq: Input should be less than or equal to 0.001 "
     "(got 1.0)"),
    ({"imus": [{"name": "IMU-1", "thermal_time_constant_s": 1e-320}]},  # NaN temperatures
     "imus.0.thermal_time_constant_s: Input should be greater than or equal to 1 (got 1e-320)"),
    ({"chamber": {"enabled": True, "air_time_constant_s": 0.5}},
     "chamber.air_time_constant_s: Input should be greater than or equal to 1 (got 0.5)"),
    ({"chamber": {"enabled": True, "max_ramp_degc_per_min": 1e-320}},
     "chamber.max_ramp_degc_per_min: Input should be greater than or equal to 0.01 (got "
     "1e-320)"),
    ({"chunk_s": 1e-320},  # found by the fuzz suite: a denormal chunk never ends a simulation
     "chunk_s: Input should be greater than or equal to 0.1 (got 1e-320)"),
    ({"imus": [{"name": f"IMU-{i}"} for i in range(65)], "fixture": {"kind": "array"}},
     "imus: Tuple should have at most 64 items after validation, not 65"),
])
def test_out_of_bounds_scenarios_are_refused(tmp_path, changes, message):
    refused(tmp_path, changes, message)


def test_builtin_scenarios_are_within_the_bounds():
    for name, make in BUILTIN_SCENARIOS.items():
        assert make().name == name


def test_a_former_format_scenario_loads_with_a_note_per_renamed_field(tmp_path):
    """A soak's `duration_s` and the unbalance names in m·s² are read with today's names."""
    data = copy.deepcopy(BASE)
    data.update({"table": {"kind": "none"},
                 "chamber": {"enabled": True},
                 "centrifuge": {"enabled": True, "unbalance_c0_m_s2": 2e-7,
                                "unbalance_c_per_kg_m_s2_per_kg": 5e-8},
                 "steps": [{"kind": "soak", "temperature_degc": 30.0, "duration_s": 120.0},
                           {"kind": "static", "duration_s": 10.0}]})
    path = tmp_path / "old.toml"
    path.write_text(tomli_w.dumps(data), encoding="utf-8")
    with pytest.warns(ScenarioFormatWarning) as notes:
        sc = load_scenario(path)
    assert [str(n.message).split(": ", 2)[2] for n in notes] == [
        "steps.0 (soak): `duration_s` is now `stable_for_s` (the soak waits until chamber and "
        "IMU temperatures are stable that long); please update the file",
        "centrifuge: `unbalance_c0_m_s2` is now `unbalance_c0_m_per_rps_sq` (the unit is "
        "m/(rad/s)²); please update the file",
        "centrifuge: `unbalance_c_per_kg_m_s2_per_kg` is now `unbalance_c_m_per_rps_sq_per_kg` "
        "(the unit is m/(rad/s)²); please update the file"]
    assert sc.steps[0].stable_for_s == 120.0  # type: ignore[union-attr]
    assert sc.centrifuge.unbalance_c0_m_per_rps_sq == 2e-7
    assert sc.centrifuge.unbalance_c_m_per_rps_sq_per_kg == 5e-8


def test_a_former_and_a_current_name_together_are_refused(tmp_path):
    refused(tmp_path, {"table": {"kind": "none"},
                       "centrifuge": {"enabled": True, "unbalance_c0_m_s2": 1e-7,
                                      "unbalance_c0_m_per_rps_sq": 1e-7}},
            "centrifuge: give `unbalance_c0_m_per_rps_sq` only (`unbalance_c0_m_s2` is its "
            "former name)")
