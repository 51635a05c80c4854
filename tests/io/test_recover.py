"""Tests of recover_recording: crashed files, uncommitted and misaligned tails, the report."""

from __future__ import annotations

import json
import subprocess
import sys

import h5py
import numpy as np
import pytest

from imucalib.errors import InvalidInputError, RecordingError, RecordingFormatError
from imucalib.io import open_recording, recover_recording


@pytest.fixture(scope="module")
def crashed(tmp_path_factory, helpers):
    """A file whose writer flushed 3 times, appended one more block, then SIGKILLed itself."""
    path = tmp_path_factory.mktemp("crash") / "run.h5"
    out = subprocess.run([sys.executable, str(helpers.crash_script), str(path), "5", "manual",
                          "3"], capture_output=True, text=True, timeout=60, check=False)
    assert out.returncode == -9, out.stderr
    last = json.loads(out.stdout.splitlines()[-1])
    return path, last


def test_recover_crashed_file(crashed, helpers, tmp_path):
    path, last = crashed
    cw = helpers.crash_writer
    original = path.read_bytes()
    report = recover_recording(path, tmp_path / "fixed.h5")
    assert path.read_bytes() == original
    assert report.source == path and report.output == tmp_path / "fixed.h5"
    assert report.was_open_for_write and report.verified
    by_name = {t.name: t for t in report.tables}
    for dev, unit, size in cw.STREAMS:
        assert by_name[f"streams/{dev}/{unit}"].rows_copied == last["blocks"] * size
    assert by_name["steps"].rows_copied == last["steps"]
    assert by_name["log"].rows_copied == last["log"]
    assert report.unfinished_steps == (last["steps"] - 1,)
    assert [t.name for t in report.streams] == [f"streams/{d}/{u}" for d, u, _ in cw.STREAMS]
    text = report.summary()
    assert f"recovered {path} -> {tmp_path / 'fixed.h5'}" in text
    assert "left open by its writer" in text
    assert f"streams/imu/IMU-0001  {last['blocks'] * 500:>12,} rows copied" in text
    assert f"still running when the writer stopped: {last['steps'] - 1}" in text
    assert "verified" in text
    with open_recording(report.output, strict=True) as rec:
        assert rec.metadata["operator"] == "test"
        assert rec.truth["scenario"] == {"seed": 7}
        got = rec.read_stream("table", "main")
        want = cw.expected(5, 2, last["blocks"])
        assert got.columns["rate_rps"].tobytes() == want["rate_rps"].tobytes()
        assert len(rec.steps) == last["steps"] and len(rec.log) == last["log"]
        assert rec.committed_rows()["streams/table/main"] == last["blocks"] * 100
    assert not list(tmp_path.glob(".*partial"))


def test_default_output_name_and_existing_output(crashed, tmp_path):
    path, _ = crashed
    src = tmp_path / "copy.h5"
    src.write_bytes(path.read_bytes())
    report = recover_recording(src)
    assert report.output == tmp_path / "copy.recovered.h5"
    with pytest.raises(RecordingError, match=r"copy.recovered.h5 exists; choose another output"):
        recover_recording(src)
    again = recover_recording(src, overwrite=True)
    assert again.verified
    with pytest.raises(InvalidInputError, match="must differ from the original"):
        recover_recording(src, src)


def test_uncommitted_and_misaligned_tails_are_dropped(recording, tmp_path):
    path, data = recording
    with h5py.File(path, "r+") as f:
        entries = json.loads(f["commit"].attrs["entries_json"])
        rows = f["commit/rows"][()]
        rows[entries.index("streams/imu/IMU-0001")] = 15_000  # 5000 rows never committed
        f["commit/rows"][...] = rows
        ds = f["streams/table/main/angle_rad"]  # one column longer than the others
        ds.resize((ds.shape[0] + 7,))
    report = recover_recording(path, tmp_path / "out.h5")
    t = {x.name: x for x in report.tables}
    assert (t["streams/imu/IMU-0001"].rows_copied, t["streams/imu/IMU-0001"].rows_dropped) == (
        15_000, 5_000)
    assert t["streams/imu/IMU-0001"].note == "rows after the last flush"
    assert t["streams/table/main"].rows_copied == len(data["table"]["time_s"])
    assert t["streams/table/main"].rows_dropped == 7
    assert not report.was_open_for_write and report.rows_dropped == 5_007
    assert "5,000 dropped" in report.summary() and "closed cleanly" in report.summary()
    with open_recording(report.output) as rec:
        got = rec.read_stream("imu", "IMU-0001")
        assert np.array_equal(got.columns["counter"], data["imu"]["counter"][:15_000])
        assert rec.truth["model"] == {"name": "triad"}
        assert rec.read_truth_stream("imu", "IMU-0001").time_s.shape == (20_000,)
        assert [s.label for s in rec.steps] == ["position 1", "rate +10 dps", "position 2"]


def test_foreign_file_is_not_recovered(tmp_path):
    path = tmp_path / "foreign.h5"
    with h5py.File(path, "w") as f:
        f["x"] = np.arange(3)
    with pytest.raises(RecordingFormatError, match="not an imucalib recording"):
        recover_recording(path)
    assert not (tmp_path / "foreign.recovered.h5").exists()
