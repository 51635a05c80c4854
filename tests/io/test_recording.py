"""Tests of RecordingWriter: exact round trips, metadata/truth/steps/log, and every bad input."""

from __future__ import annotations

import json
import math
import tempfile
from pathlib import Path

import h5py
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from imucalib import __version__
from imucalib.errors import InvalidInputError, RecordingError, UnitError
from imucalib.io import ColumnSpec, RecordingWriter, StreamSpec, open_recording
from imucalib.io._schema import FORMAT_VERSION_PLAIN
from imucalib.io.recording import FORMAT_NAME, FORMAT_VERSION, STEP_FIELDS

SPEC = StreamSpec("imu", "IMU-0001", {"gyro_x_rps": ColumnSpec("rad/s"),
                                      "counter": ColumnSpec("counts", dtype="i8", quantity="raw")})


def _one(n: int = 10, t0: float = 0.0) -> dict[str, np.ndarray]:
    return {"time_s": t0 + np.arange(n) * 0.01, "gyro_x_rps": np.linspace(0, 1, n),
            "counter": np.arange(n)}


# --- round trips ---------------------------------------------------------------------------
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(sizes=st.lists(st.integers(0, 700), min_size=1, max_size=25),
       chunk_rows=st.sampled_from([1, 7, 256, 65536]),
       dtype=st.sampled_from(["f8", "f4", "i2", "u8"]),
       seed=st.integers(0, 2**32 - 1))
def test_many_appends_read_back_bitwise(sizes, chunk_rows, dtype, seed):
    rng = np.random.default_rng(seed)
    n = sum(sizes)
    t = np.cumsum(rng.integers(0, 3, n)) * 1e-3  # repeated times allowed (non-decreasing)
    if np.dtype(dtype).kind == "f":
        x = rng.standard_normal(n).astype(dtype)
        x[rng.random(n) < 0.05] = np.nan
    else:
        info = np.iinfo(dtype)
        x = rng.integers(info.min, info.max, n, dtype=dtype, endpoint=True)
    y = rng.standard_normal(n)
    spec = StreamSpec("imu", "u1", {"x": ColumnSpec("1", dtype=dtype), "y": ColumnSpec("rad/s")})
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "r.h5"
        with RecordingWriter(path, streams=[spec], chunk_rows=chunk_rows,
                             flush_interval_s=math.inf) as w:
            a = 0
            for k, size in enumerate(sizes):
                w.append("imu", "u1", {"time_s": t[a:a + size], "x": x[a:a + size],
                                       "y": y[a:a + size]})
                a += size
                if k % 7 == 3:
                    w.flush()
        with open_recording(path) as rec:
            (info,) = rec.streams
            assert info.n_samples == n
            d = rec.read_stream("imu", "u1")
            assert d.time_s.tobytes() == t.tobytes()
            assert d.columns["x"].dtype == np.dtype(dtype)
            assert d.columns["x"].tobytes() == x.tobytes()
            assert d.columns["y"].tobytes() == y.tobytes()
            chunks = list(rec.iter_stream("imu", "u1", chunk_samples=333))
            assert all(len(c) <= 333 for c in chunks)
            joined = np.concatenate([c.columns["x"] for c in chunks]) if chunks else x[:0]
            assert joined.tobytes() == x.tobytes()


def test_recording_layout_and_attributes(recording):
    path, _ = recording
    with h5py.File(path, "r") as f:
        assert f.attrs["format"] == FORMAT_NAME
        # float64 columns closed with the default gzip: nothing that needs version 3
        assert f.attrs["format_version"] == FORMAT_VERSION_PLAIN == FORMAT_VERSION - 1
        assert f.attrs["software_version"] == __version__
        ds = f["streams/imu/IMU-0001/gyro_x_rps"]
        assert ds.maxshape == (None,)
        assert ds.chunks == (4096,)
        assert ds.attrs["unit"] == "rad/s"
        assert ds.attrs["quantity"] == "si"
        assert f["streams/imu/IMU-0001/counter"].attrs["quantity"] == "raw"
        assert f["streams/imu/IMU-0001/time_s"].attrs["unit"] == "s"
        assert set(f["steps"]) == set(STEP_FIELDS)
        assert set(f["log"]) == {"time_s", "level", "source", "message"}
        assert "truth/streams/imu/IMU-0001/rate_b_rps" in f


def test_metadata_truth_steps_log_round_trip(recording, helpers):
    path, _ = recording
    with open_recording(path) as rec:
        meta = rec.metadata
        for key, value in helpers.METADATA.items():
            if key.endswith("_json"):
                assert meta[key] == json.loads(value)
            else:
                assert meta[key] == value and type(meta[key]) is type(value)
        assert meta["format"] == FORMAT_NAME and rec.format_version == FORMAT_VERSION_PLAIN
        assert meta["created_utc"].endswith("Z")
        truth = rec.truth
        assert truth["bias_rps"].tobytes() == np.array([1e-4, 2e-4, -3e-4]).tobytes()
        assert truth["scale_ppm"] == [100.0, -50.0, 20.0]
        assert truth["model"] == {"name": "triad"}
        steps = rec.steps
        assert [s.index for s in steps] == [0, 1, 2]
        assert steps[0].commanded == {"angle_deg": [0, 90]}
        assert (steps[0].valid_start_s, steps[0].valid_end_s, steps[0].status) == (2.0, 7.5, "done")
        assert steps[1].note == "ramp 2 s" and steps[1].commanded == {"rate_dps": 10}
        assert steps[2].status == "running" and math.isnan(steps[2].t_end_s)
        assert not steps[2].has_valid_window and steps[2].commanded is None
        assert [(e.level, e.source) for e in rec.log] == [("info", "runner"), ("warning", "guard")]
        assert rec.log[1].message == "rate error 0.2 % — continuing"


def test_step_updates_overwrite_rows_across_flushes(tmp_path):
    path = tmp_path / "s.h5"
    with RecordingWriter(path, streams=[SPEC], flush_interval_s=math.inf) as w:
        for k in range(100):  # several chunks of the steps table
            w.begin_step("static", f"p{k}", float(k))
        w.flush()
        w.update_step(3, status="invalid", note="table drift")
        w.flush()
        w.update_step(3, t_end_s=4.0, valid_start_s=3.2, valid_end_s=3.9)
        w.update_step(99, status="skipped")
    with open_recording(path) as rec:
        steps = rec.steps
    assert len(steps) == 100
    assert (steps[3].status, steps[3].note, steps[3].valid_end_s) == ("invalid", "table drift", 3.9)
    assert steps[99].status == "skipped" and steps[98].status == "running"


def test_nan_data_kept_and_empty_append_is_noop(tmp_path):
    path = tmp_path / "n.h5"
    d = _one()
    d["gyro_x_rps"][[0, 5]] = [np.nan, np.inf]
    with RecordingWriter(path, streams=[SPEC]) as w:
        w.append("imu", "IMU-0001", {"time_s": [], "gyro_x_rps": [], "counter": []})
        w.append("imu", "IMU-0001", d)
    with open_recording(path) as rec:
        got = rec.read_stream("imu", "IMU-0001").columns["gyro_x_rps"]
    assert got.tobytes() == d["gyro_x_rps"].tobytes()


def test_failed_append_keeps_earlier_data(tmp_path):
    path = tmp_path / "f.h5"
    with RecordingWriter(path, streams=[SPEC]) as w:
        w.append("imu", "IMU-0001", _one())
        bad = _one(t0=1.0)
        bad["counter"] = bad["counter"][:-1]
        with pytest.raises(InvalidInputError):
            w.append("imu", "IMU-0001", bad)
        w.append("imu", "IMU-0001", _one(t0=1.0))
    with open_recording(path) as rec:
        assert rec.streams[0].n_samples == 20


def test_stream_without_data_is_empty(tmp_path):
    path = tmp_path / "e.h5"
    with RecordingWriter(path, streams=[SPEC]):
        pass
    with open_recording(path) as rec:
        (info,) = rec.streams
        assert info.n_samples == 0 and math.isnan(info.t_first_s)
        assert len(rec.read_stream("imu", "IMU-0001")) == 0
        assert rec.steps == [] and rec.log == [] and rec.truth == {}


def test_closed_file_opens_normally(recording):
    path, _ = recording
    with h5py.File(path, "r") as f:  # no SWMR flag left behind
        assert "streams" in f


# --- bad input -----------------------------------------------------------------------------
@pytest.mark.parametrize("unit", ["furlongs", "", "rad/ss"])
def test_unknown_unit_names_stream_and_column(unit):
    with pytest.raises(UnitError, match=r"stream imu/IMU-0001, column 'gyro_x_rps'.*unit"):
        StreamSpec("imu", "IMU-0001", {"gyro_x_rps": ColumnSpec(unit)})


@pytest.mark.parametrize(("column", "match"), [
    (ColumnSpec("rad/s", dtype="U4"), r"'c': dtype must be numeric"),
    (ColumnSpec("rad/s", dtype="nope"), r"'c': unknown dtype"),
    (ColumnSpec("rad/s", quantity="cooked"), r"'c': quantity must be one of"),
    ("rad/s", r"'c': expected a ColumnSpec"),
])
def test_bad_column_spec(column, match):
    with pytest.raises(InvalidInputError, match=match):
        StreamSpec("imu", "A", {"c": column})


@pytest.mark.parametrize(("device", "unit", "column"), [
    ("imu/x", "A", "c"), ("imu", "", "c"), ("imu", "A", "1c"), ("imu", "A", "c-d")])
def test_bad_names(device, unit, column):
    with pytest.raises(InvalidInputError, match="must match"):
        StreamSpec(device, unit, {column: ColumnSpec("1")})


def test_time_column_must_be_float_seconds():
    with pytest.raises(InvalidInputError, match="time_s must be float64 in 's'"):
        StreamSpec("imu", "A", {"time_s": ColumnSpec("ms")})


@pytest.fixture
def writer(tmp_path):
    w = RecordingWriter(tmp_path / "w.h5", streams=[SPEC])
    yield w
    w.close()


def test_non_monotonic_time_within_append(writer):
    d = _one()
    d["time_s"][4] = 0.0
    with pytest.raises(InvalidInputError,
                       match=r"stream imu/IMU-0001, column time_s: must be non-decreasing; row 4"):
        writer.append("imu", "IMU-0001", d)


def test_non_monotonic_time_across_appends(writer):
    writer.append("imu", "IMU-0001", _one(t0=5.0))
    with pytest.raises(InvalidInputError, match=r"non-decreasing across appends; this append "
                                                r"starts at 4\.0 s"):
        writer.append("imu", "IMU-0001", _one(t0=4.0))


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_non_finite_time(writer, bad):
    d = _one()
    d["time_s"][2] = bad
    with pytest.raises(InvalidInputError, match=r"column time_s: must be finite; row 2"):
        writer.append("imu", "IMU-0001", d)


def test_missing_and_unknown_columns(writer):
    d = _one()
    del d["counter"]
    with pytest.raises(InvalidInputError, match=r"stream imu/IMU-0001: missing column\(s\) "
                                                r"\['counter'\]"):
        writer.append("imu", "IMU-0001", d)
    d = {**_one(), "gyro_z_rps": np.zeros(10)}
    with pytest.raises(InvalidInputError, match=r"unknown column\(s\) \['gyro_z_rps'\]"):
        writer.append("imu", "IMU-0001", d)


def test_wrong_lengths_and_shapes(writer):
    d = _one()
    d["gyro_x_rps"] = d["gyro_x_rps"][:7]
    with pytest.raises(InvalidInputError, match=r"column 'gyro_x_rps': length 7 differs from "
                                                r"time_s length 10"):
        writer.append("imu", "IMU-0001", d)
    d = _one()
    d["gyro_x_rps"] = np.zeros((10, 1))
    with pytest.raises(InvalidInputError, match=r"'gyro_x_rps' must be 1-D; got shape \(10, 1\)"):
        writer.append("imu", "IMU-0001", d)


def test_lossy_integer_conversion_refused(writer):
    d = _one()
    d["counter"] = d["counter"] + 0.5
    with pytest.raises(InvalidInputError, match=r"'counter' is an integer column"):
        writer.append("imu", "IMU-0001", d)


def test_unknown_stream(writer):
    with pytest.raises(InvalidInputError, match=r"unknown stream imu/IMU-9; declared: "
                                                r"imu/IMU-0001"):
        writer.append("imu", "IMU-9", _one())
    with pytest.raises(InvalidInputError, match=r"unknown truth stream"):
        writer.append_truth("imu", "IMU-0001", _one())


def test_step_field_too_long_is_refused_not_truncated(writer):
    with pytest.raises(InvalidInputError, match=r"step 0 `label` is 300 bytes in UTF-8; the field "
                                                r"holds at most 256"):
        writer.begin_step("static", "x" * 300, 0.0)
    i = writer.begin_step("static", "ok", 0.0)
    with pytest.raises(InvalidInputError, match=r"`note` is 4000 bytes.*at most 2048"):
        writer.update_step(i, note="é" * 2000)
    with pytest.raises(InvalidInputError, match=r"`message` is 5000 bytes"):
        writer.log_event(0.0, "info", "x", "m" * 5000)


def test_bad_step_updates(writer):
    i = writer.begin_step("static", "ok", 1.0)
    with pytest.raises(InvalidInputError, match=r"`status` must be one of"):
        writer.update_step(i, status="finished")
    with pytest.raises(InvalidInputError, match=r"cannot update step field\(s\) \['index'\]"):
        writer.update_step(i, index=4)
    with pytest.raises(InvalidInputError, match=r"`t_end_s` \(0.5 s\) is before `t_start_s`"):
        writer.update_step(i, t_end_s=0.5)
    with pytest.raises(InvalidInputError, match=r"no step with index 7"):
        writer.update_step(7, status="done")
    with pytest.raises(InvalidInputError, match=r"`commanded` must be JSON text"):
        writer.begin_step("static", "x", 0.0, commanded="{not json")
    with pytest.raises(InvalidInputError, match=r"`level` must be one of"):
        writer.log_event(0.0, "loud", "x", "y")


def test_append_after_close(tmp_path):
    w = RecordingWriter(tmp_path / "c.h5", streams=[SPEC])
    w.close()
    w.close()  # idempotent
    with pytest.raises(RecordingError, match=r"cannot append to imu/IMU-0001: the writer of .* "
                                             r"is closed"):
        w.append("imu", "IMU-0001", _one())
    with pytest.raises(RecordingError, match="is closed"):
        w.begin_step("static", "x", 0.0)


def test_existing_file_needs_overwrite(tmp_path):
    path = tmp_path / "x.h5"
    path.write_bytes(b"keep me")
    with pytest.raises(RecordingError, match="exists; pass overwrite=True"):
        RecordingWriter(path, streams=[SPEC])
    assert path.read_bytes() == b"keep me"
    RecordingWriter(path, streams=[SPEC], overwrite=True).close()
    with open_recording(path) as rec:
        assert rec.streams[0].name == "imu/IMU-0001"


@pytest.mark.parametrize(("metadata", "match"), [
    ({"format": "x"}, "reserved"),
    ({"plan json": "{}"}, "metadata key must match"),
    ({"station_json": "{oops"}, r"metadata\['station_json'\] must hold JSON text"),
    ({"station_json": 3}, r"must be JSON text \(a str\)"),
    ({"limits": [1, 2]}, r"must be str, int, float or bool; got list"),
    ({"note": "a\x00b"}, "NUL"),
])
def test_bad_metadata_creates_no_file(tmp_path, metadata, match):
    path = tmp_path / "m.h5"
    with pytest.raises(InvalidInputError, match=match):
        RecordingWriter(path, streams=[SPEC], metadata=metadata)
    assert not path.exists()


def test_bad_specs_and_options(tmp_path):
    path = tmp_path / "o.h5"
    with pytest.raises(InvalidInputError, match="declares stream imu/IMU-0001 twice"):
        RecordingWriter(path, streams=[SPEC, SPEC])
    with pytest.raises(InvalidInputError, match="`flush_interval_s` must be ≥ 0"):
        RecordingWriter(path, streams=[SPEC], flush_interval_s=-1.0)
    with pytest.raises(InvalidInputError, match="`compression` must be one of"):
        RecordingWriter(path, streams=[SPEC], compression="zstd")
    with pytest.raises(InvalidInputError, match=r"truth\['f'\]: cannot be stored as JSON"):
        RecordingWriter(path, streams=[SPEC], truth={"f": object()})
    assert not path.exists()


def test_compressed_recording_round_trips(tmp_path):
    path = tmp_path / "z.h5"
    d = _one(5000)
    with RecordingWriter(path, streams=[SPEC], compression="lzf") as w:
        w.append("imu", "IMU-0001", d)
    with open_recording(path) as rec:
        got = rec.read_stream("imu", "IMU-0001")
    assert got.columns["counter"].tobytes() == d["counter"].tobytes()
