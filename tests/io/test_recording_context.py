"""One reader of a recording's calibration facts (io/context.py): a run writes them as keys of
their own; an older recording has them only in its stored plan, and reads the same."""

from __future__ import annotations

from pathlib import Path

import pytest

from imucalib.calibration import calibrate
from imucalib.io.context import RecordingContext
from imucalib.io.reader import open_recording
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
             if k not in ("procedure", "plan_name", "acceptance", "equipment_json",
                          "imu_spec_json")}
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
