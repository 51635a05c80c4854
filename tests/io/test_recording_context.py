"""One reader of a recording's calibration facts (io/context.py): a run writes them as keys of
their own; an older recording has them only in its stored plan, and reads the same."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from imucalib.calibration import calibrate
from imucalib.io.context import (
    EQUIPMENT_KEYS,
    IMU_NOISE_KEYS,
    IMU_SPEC_KEYS,
    IMU_UNIT_KEYS,
    SPEC_LIMIT_KEYS,
    RecordingContext,
)
from imucalib.io.opening import open_recording
from imucalib.plan.schema import (
    AcceptanceConfig,
    EquipmentConfig,
    ImuNoiseConfig,
    ImuSpecConfig,
    SpecLimits,
)
from imucalib.procedures import registry
from imucalib.records.api import open_records

from ..conftest import run_twin


@pytest.fixture(scope="module")
def tumble_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    plan = registry.get("tumble").generate_plan(n_positions=8, axes=("z",), record_s=5.0,
                                                settle_s=2.0, sample_rate_hz=50.0,
                                                name="short-tumble")
    return run_twin(plan, tmp_path_factory.mktemp("ctx") / "t.h5")


def test_a_run_writes_the_facts_and_the_stored_plan_says_the_same(tumble_run):
    with open_recording(tumble_run) as rec:
        meta = dict(rec.metadata)
    assert meta["procedure"] == "tumble" and meta["plan_name"] == "short-tumble"
    ctx = RecordingContext.of(meta)
    assert ctx.procedure == "tumble" and ctx.plan_name == "short-tumble"
    assert ctx.plan_hash == meta["plan_hash"] and ctx.acceptance == "simple"
    assert set(ctx.equipment) == {"table_position_accuracy_arcsec",
                                  "table_orthogonality_arcsec"}
    assert {"accel_accuracy_g", "gyro_accuracy_dps"} <= set(ctx.imu_spec)
    # a recording made before the runner wrote the keys: the same facts from its plan
    older = {k: v for k, v in meta.items()
             if k not in ("procedure", "plan_name", "acceptance", "guard_band_k",
                          "equipment_json", "imu_spec_json")}
    assert RecordingContext.of(older) == ctx
    assert RecordingContext.of({}) == RecordingContext()
    assert RecordingContext.of({"plan_toml": "not [toml"}) == RecordingContext()


def test_the_records_get_the_plan_name(tumble_run, tmp_path):
    db = str(tmp_path / "r.db")
    done = calibrate(tumble_run, out=tmp_path, db=db)
    assert done.record is not None and done.record_error is None
    records = open_records(db)
    try:
        [run] = records.runs_of_plan("short-tumble")
    finally:
        records.close()
    assert run.procedure == "tumble"


#: The keys a run writes of its plan's facts besides the plan and its hash.
CONTEXT_KEYS = ("procedure", "plan_name", "acceptance", "guard_band_k", "equipment_json",
                "imu_spec_json")


def test_the_keys_are_the_plan_tables_fields():
    """The context carries every field P1 builds its models from (io cannot import plan)."""
    assert set(SPEC_LIMIT_KEYS) == set(SpecLimits.model_fields)
    assert set(ImuSpecConfig.model_fields) == {*IMU_SPEC_KEYS, *IMU_UNIT_KEYS, "limits",
                                               "noise"}
    assert set(IMU_NOISE_KEYS) == set(ImuNoiseConfig.model_fields)
    assert set(EQUIPMENT_KEYS) <= set(EquipmentConfig.model_fields)
    assert set(AcceptanceConfig.model_fields) == {"rule", "guard_band_k"}


def test_a_p1_run_writes_the_specification_and_the_rule(consumer_run):
    """The unit, its limits and the guard band are keys of their own; without them (an older
    recording) the stored plan gives the same facts, fact by fact."""
    with open_recording(consumer_run) as rec:
        meta = dict(rec.metadata)
    assert meta["guard_band_k"] == 2.0 and meta["acceptance"] == "simple"
    imu = meta["imu_spec_json"]  # decoded by the reader
    assert imu["grade"] == "consumer" and imu["limits"]["accel_bias_ug"] == 160000.0
    ctx = RecordingContext.of(meta)
    assert ctx.imu_unit == {"grade": "consumer"}  # no serial: the plan names none
    assert ctx.spec_limits == imu["limits"] and set(ctx.spec_limits) == set(SPEC_LIMIT_KEYS)
    assert ctx.guard_band_k == 2.0 and ctx.imu_table == imu
    assert RecordingContext.of({k: v for k, v in meta.items() if k not in CONTEXT_KEYS}) == ctx
    # a run from before the unit and the limits were keys: only they come from the plan
    between = {**meta, "imu_spec_json": {k: imu[k] for k in IMU_SPEC_KEYS if k in imu}}
    del between["guard_band_k"]
    assert RecordingContext.of(between) == ctx
    # the keys alone, without the plan's TOML
    assert RecordingContext.of({k: v for k, v in meta.items() if k != "plan_toml"}) == ctx


def test_the_metadata_round_trips_as_json_text_or_decoded():
    ctx = RecordingContext(procedure="p1", plan_name="n", plan_hash="h",
                           equipment={"table_position_accuracy_arcsec": 3.0},
                           imu_spec={"accel_accuracy_g": 0.001}, imu_unit={"serial": "S"},
                           spec_limits={"gyro_bias_dph": 4.0}, acceptance="guarded",
                           guard_band_k=3.0)
    meta = ctx.metadata()
    assert RecordingContext.of(meta) == ctx
    decoded = {k: json.loads(v) if k.endswith("_json") else v for k, v in meta.items()}
    assert RecordingContext.of(decoded) == ctx
    assert RecordingContext().metadata() == {}
    # text, booleans and non-finite numbers give no fact
    assert RecordingContext.of({"guard_band_k": "2", "equipment_json": {
        "table_position_accuracy_arcsec": True, "table_orthogonality_arcsec": float("nan")},
        "imu_spec_json": {"serial": 7, "limits": {"gyro_bias_dph": "x"}}}) == RecordingContext()


def test_the_declared_noise_is_a_fact_of_its_own():
    """A plan's [imu.noise] (a noise characterisation's terms) travels in imu_spec_json."""
    from imucalib.plan import parse_plan
    from imucalib.plan.io import plan_hash, plan_to_toml
    from imucalib.procedures.p1.plan import generate_p1_plan

    plan = generate_p1_plan(repetitions=1, static_s=120.0)
    noise = ImuNoiseConfig(source="unit.noise.json", source_sha256="ab" * 32, record="whole",
                           record_duration_s=2621.0,
                           gyro_white_rps_rthz=(3.5e-5, 3.6e-5, 3.7e-5),
                           gyro_bias_instability_rps=(4.8e-6, 5e-6, 0.0),
                           gyro_random_walk_rps_rts=(4e-8, 0.0, 1e-7),
                           accel_white_mps2_rthz=(5e-4, 5.1e-4, 5.2e-4),
                           accel_bias_instability_mps2=(2e-4, 2e-4, 3e-4),
                           accel_random_walk_mps2_rts=(0.0, 0.0, 1e-6))
    plan = parse_plan(plan_to_toml(plan.model_copy(
        update={"imu": plan.imu.model_copy(update={"noise": noise})})))
    ctx = RecordingContext.of_plan(plan.model_dump(mode="json"), plan_hash(plan))
    assert ImuSpecConfig.model_validate(ctx.imu_table).noise == noise
    # its own key (imu_spec_json) gives it without the stored plan
    again = RecordingContext.of({k: v for k, v in ctx.metadata().items()})
    assert again.imu_noise == ctx.imu_noise and ImuSpecConfig.model_validate(
        again.imu_table).noise == noise
    # a plan without it carries none
    bare = RecordingContext.of_plan(generate_p1_plan().model_dump(mode="json"))
    assert bare.imu_noise == {} and "noise" not in bare.imu_table
