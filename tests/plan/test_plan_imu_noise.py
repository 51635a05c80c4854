"""The plan's ``[imu.noise]`` table: the unit's declared noise, carried by value.

docs/test-design.md, "A noise characterisation in place of the grade's": a plan carries the
fitted N, B, K per axis of the unit's noise characterisation with the file's name and SHA-256
(:class:`~imucalib.plan.schema.ImuNoiseConfig`); a plan without it writes the same TOML and JSON
as before the table existed.
"""

from __future__ import annotations

import json
import tomllib

import pytest
import tomli_w

from imucalib.errors import ConfigurationError
from imucalib.plan import load_plan, parse_plan, plan_hash, plan_json_schema, write_plan
from imucalib.plan.io import plan_to_toml
from imucalib.plan.schema import ImuNoiseConfig
from imucalib.procedures import registry
from imucalib.procedures.p1.plan import generate_p1_plan

NOISE = dict(source="unit.noise.json", source_sha256="ab" * 32, record="whole record",
             record_duration_s=2621.4,
             gyro_white_rps_rthz=(3.5e-5, 3.6e-5, 3.7e-5),
             gyro_bias_instability_rps=(4.8e-6, 5e-6, 0.0),
             gyro_random_walk_rps_rts=(4e-8, 0.0, 1e-7),
             accel_white_mps2_rthz=(5e-4, 5.1e-4, 5.2e-4),
             accel_bias_instability_mps2=(2e-4, 2e-4, 3e-4),
             accel_random_walk_mps2_rts=(0.0, 0.0, 1e-6))


def _with_noise():
    plan = generate_p1_plan(repetitions=1, static_s=120.0)
    return plan.model_copy(update={"imu": plan.imu.model_copy(
        update={"noise": ImuNoiseConfig(**NOISE)})})


def test_a_plan_with_declared_noise_round_trips(tmp_path):
    plan = _with_noise()
    text = plan_to_toml(plan)
    assert "[imu.noise]" in text and 'source_sha256 = "' + "ab" * 32 + '"' in text
    back = load_plan(write_plan(plan, tmp_path / "p.toml"))
    assert back == plan and plan_hash(back) == plan_hash(plan)
    assert back.imu.noise is not None
    assert back.imu.noise.gyro_white_rps_rthz == NOISE["gyro_white_rps_rthz"]
    assert json.loads(plan.model_dump_json())["imu"]["noise"]["record"] == "whole record"


@pytest.mark.parametrize("name", list(registry.BUILTIN))
def test_a_plan_without_it_writes_no_trace_of_it(name):
    plan = registry.get(name).generate_plan()
    assert plan.imu.noise is None
    assert "noise" not in plan.model_dump()["imu"]
    assert "noise" not in json.loads(plan.model_dump_json())["imu"]
    assert "[imu.noise]" not in plan_to_toml(plan)
    assert parse_plan(plan_to_toml(plan)) == plan


@pytest.mark.parametrize(("key", "value", "message"), [
    ("gyro_white_rps_rthz", [1e-5, -1e-5, 1e-5], "greater than or equal to 0"),
    ("accel_bias_instability_mps2", [1e-4, 1e-4], "imu.noise.accel_bias_instability_mps2"),
    ("source_sha256", "not-a-hash", "imu.noise.source_sha256"),
    ("gyro_random_walk_rps_rts", [0.0, float("nan"), 0.0], "imu.noise.gyro_random_walk"),
])
def test_bad_values_are_refused_naming_the_field(key, value, message):
    data = tomllib.loads(plan_to_toml(_with_noise()))
    data["imu"]["noise"][key] = value
    text = tomli_w.dumps(data)
    with pytest.raises(ConfigurationError, match=message.replace(".", r"\.")):
        parse_plan(text)


def test_the_schema_describes_the_table():
    schema = plan_json_schema()
    props = schema["$defs"]["ImuNoiseConfig"]["properties"]
    assert {"source", "source_sha256", "gyro_white_rps_rthz",
            "accel_random_walk_mps2_rts"} <= set(props)
