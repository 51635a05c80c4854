"""The one pipeline (imucalib.calibration.calibrate): procedure → result → files → records, the
same for `imucalib calibrate`, `imucalib allan` and the demo (docs/architecture.md)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from imucalib.calibration import calibrate, procedure_of
from imucalib.cli import app
from imucalib.errors import InvalidInputError
from imucalib.procedures import registry
from imucalib.records.api import open_records

from .cli.test_allan_command import _canonical
from .conftest import run_twin


@pytest.fixture(scope="module")
def tumble_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    plan = registry.get("tumble").generate_plan(n_positions=8, axes=("z",), record_s=5.0,
                                                settle_s=2.0, sample_rate_hz=50.0)
    return run_twin(plan, tmp_path_factory.mktemp("tumble") / "t.h5")


def test_calibrate_analyses_writes_and_records(tumble_run, tmp_path):
    db = str(tmp_path / "records.db")
    done = calibrate(tumble_run, out=tmp_path / "out", db=db, operator="tester")
    assert done.procedure.name == "tumble" and done.result.procedure == "tumble"
    names = sorted(p.name for p in done.written)
    assert names == ["t.IMU-0001.tumble.parameters.csv", "t.IMU-0001.tumble.report.json",
                     "t.IMU-0001.tumble.result.json"]
    assert all(p.is_file() for p in done.written)
    assert done.record is not None and done.record.startswith("recorded run ")
    assert done.record_error is None
    records = open_records(db)
    try:
        [entry] = records.history("IMU-0001")
    finally:
        records.close()
    assert entry.procedure == "tumble"
    recorded = {r.name: (r.value, r.std) for r in entry.parameters}
    rows = done.result.parameter_rows()  # type: ignore[attr-defined]
    assert recorded == {r.name: (r.value, r.std) for r in rows} and "K1_x_head_z" in recorded


def test_record_false_writes_files_only_and_formats_may_depend_on_the_result(tumble_run,
                                                                              tmp_path):
    db = tmp_path / "none.db"
    done = calibrate(tumble_run, out=tmp_path, db=str(db), record=False,
                     formats=lambda result: ["report-json"] if result.passed is None else [])
    assert done.record is None and [p.name for p in done.written] == [
        "t.IMU-0001.tumble.report.json"]
    assert not db.exists()


def test_several_recordings_only_for_a_lot(tumble_run, tmp_path):
    with pytest.raises(InvalidInputError, match="several recordings are calibrated together "
                                                "only by a procedure that calibrates a lot"):
        calibrate(tumble_run, more=[tumble_run], out=tmp_path, record=False)


def test_a_log_needs_its_procedure(tmp_path):
    log = _canonical(tmp_path)
    with pytest.raises(InvalidInputError, match="is not a Recording: name the procedure"):
        procedure_of(log)
    with pytest.raises(InvalidInputError, match="procedure tumble analyses a Recording"):
        procedure_of(log, "tumble")
    assert procedure_of(log, "allan").name == "allan"


def test_allan_of_a_bare_log_is_recorded_like_any_calibration(tmp_path):
    db = str(tmp_path / "records.db")
    res = CliRunner().invoke(app, ["allan", str(_canonical(tmp_path)), "--gyro-unit", "deg/s",
                                   "--out", str(tmp_path / "o"), "--db", db])
    assert res.exit_code == 0, res.output
    assert "recorded run 1, result(s) 1" in " ".join(res.output.split())
    records = open_records(db)
    try:
        [entry] = records.history("imu")
    finally:
        records.close()
    assert entry.procedure == "allan" and entry.passed is None
    rows = {r.name: r for r in entry.parameters}
    doc = json.loads((tmp_path / "o" / "canon.imu.allan.json").read_text(encoding="utf-8"))
    fits = {c["channel"]: c["fit"] for c in doc["segments"][0]["channels"]}
    white = next(t for t in fits["gyro_x_rps"]["terms"] if t["name"] == "white")
    assert rows["gyro_x_white"].value == pytest.approx(white["value_si"], rel=1e-12)
    assert rows["gyro_x_white"].std == pytest.approx(white["std_si"], rel=1e-12)
    assert rows["gyro_x_white"].unit == white["unit_si"]
    res = CliRunner().invoke(app, ["allan", str(tmp_path / "canon.csv"), "--gyro-unit",
                                   "deg/s", "--out", str(tmp_path / "p"), "--no-record"])
    assert res.exit_code == 0 and "recorded run" not in res.output
