"""Tests of open_recording / Recording: windows, steps, iteration, DataFrames, bad files."""

from __future__ import annotations

import math
import os

import h5py
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imucalib.errors import (
    InvalidInputError,
    RecordingCorruptError,
    RecordingError,
    RecordingFormatError,
)
from imucalib.io import FORMAT_VERSION, ColumnSpec, RecordingWriter, StreamSpec, open_recording


def _mask(data, t0, t1):
    t = data["time_s"]
    keep = np.ones(t.shape, bool)
    if t0 is not None:
        keep &= t >= t0
    if t1 is not None:
        keep &= t < t1
    return keep


def test_streams_describe_themselves(recording, helpers):
    path, data = recording
    with open_recording(path) as rec:
        assert not rec.was_open_for_write
        infos = {i.name: i for i in rec.streams}
        assert list(infos) == ["imu/IMU-0001", "table/main"]
        imu = infos["imu/IMU-0001"]
        assert imu.n_samples == helpers.N_IMU
        assert list(imu.columns) == list(helpers.IMU_SPEC.columns)  # time_s first
        assert next(iter(imu.columns)) == "time_s"
        assert imu.columns == dict(helpers.IMU_SPEC.columns)
        assert imu.columns["gyro_x_rps"] == ColumnSpec("rad/s", description="gyro x")
        assert imu.t_first_s == 0.0 and imu.t_last_s == data["imu"]["time_s"][-1]
        assert [i.name for i in rec.truth_streams] == ["imu/IMU-0001"]


def test_read_whole_stream_bitwise(recording):
    path, data = recording
    with open_recording(path) as rec:
        d = rec.read_stream("imu", "IMU-0001")
        assert d.units == {"time_s": "s", "gyro_x_rps": "rad/s", "gyro_y_rps": "rad/s",
                           "accel_z_mps2": "m/s^2", "temperature_degc": "degC",
                           "counter": "counts"}
        assert "time_s" not in d.columns
        for k, v in data["imu"].items():
            got = d.time_s if k == "time_s" else d.columns[k]
            assert got.dtype == v.dtype and got.tobytes() == v.tobytes()
        sub = rec.read_stream("imu", "IMU-0001", columns=["counter", "time_s"])
        assert list(sub.columns) == ["counter"]
        truth = rec.read_truth_stream("imu", "IMU-0001", t_start_s=1.0, t_end_s=1.01)
        assert np.array_equal(truth.columns["rate_b_rps"], data["imu"]["gyro_x_rps"][1000:1010] / 2)


@pytest.fixture(scope="module")
def shared_path(helpers, tmp_path_factory):
    path = tmp_path_factory.mktemp("shared") / "run.h5"
    helpers.write_recording(path)
    return path


@settings(max_examples=40, deadline=None)
@given(a=st.one_of(st.none(), st.floats(-1.0, 21.0)), b=st.one_of(st.none(), st.floats(-1.0, 21.0)))
def test_time_window_matches_mask(helpers, shared_path, a, b):
    path = shared_path
    if a is not None and b is not None and b < a:
        a, b = b, a
    data = helpers.imu_data()
    keep = _mask(data, a, b)
    with open_recording(path) as rec:
        d = rec.read_stream("imu", "IMU-0001", ["gyro_x_rps"], t_start_s=a, t_end_s=b)
    assert np.array_equal(d.time_s, data["time_s"][keep])
    assert np.array_equal(d.columns["gyro_x_rps"], data["gyro_x_rps"][keep])


def test_bisection_on_long_stream_with_repeated_times(tmp_path, monkeypatch):
    import imucalib.io._search as search_module

    monkeypatch.setattr(search_module, "_SEARCH_BLOCK", 64)
    rng = np.random.default_rng(3)
    t = np.cumsum(rng.integers(0, 2, 50_000)) * 0.5  # many repeated values
    spec = StreamSpec("chamber", "main", {"temperature_degc": ColumnSpec("degC")})
    path = tmp_path / "b.h5"
    with RecordingWriter(path, streams=[spec], chunk_rows=1000) as w:
        w.append("chamber", "main", {"time_s": t, "temperature_degc": t * 2})
    with open_recording(path) as rec:
        for t0, t1 in [(0.0, 0.5), (t[12345], t[40000]), (-5.0, 1e9), (t[-1], None),
                       (None, t[0]), (100.25, 100.25), (t[777], t[777])]:
            d = rec.read_stream("chamber", "main", t_start_s=t0, t_end_s=t1)
            keep = _mask({"time_s": t}, t0, t1)
            assert np.array_equal(d.time_s, t[keep]), (t0, t1)
            i0, i1 = rec.row_range("chamber", "main", t0, t1)
            assert i1 - i0 == keep.sum()
            if keep.any():
                assert i0 == int(np.argmax(keep))


@pytest.mark.parametrize("group_rows", [40, 1 << 18])  # nearby windows read alone, together
@pytest.mark.parametrize("scan_from", [1, 10**9])  # one pass over the column, or searches
def test_iter_windows_reads_what_read_stream_reads(tmp_path, monkeypatch, scan_from,
                                                   group_rows):
    import imucalib.io._search as search_module
    import imucalib.io.reader as reader_module

    monkeypatch.setattr(search_module, "_SCAN_BLOCK", 97)  # many blocks, windows across them
    monkeypatch.setattr(reader_module, "_SCAN_WINDOWS", scan_from)
    monkeypatch.setattr(reader_module, "_GROUP_ROWS", group_rows)
    rng = np.random.default_rng(5)
    t = np.cumsum(rng.integers(0, 2, 5_000)) * 0.5  # repeated values
    spec = StreamSpec("chamber", "main", {"temperature_degc": ColumnSpec("degC")})
    path = tmp_path / "w.h5"
    with RecordingWriter(path, streams=[spec], chunk_rows=300) as w:
        w.append("chamber", "main", {"time_s": t, "temperature_degc": t * 2})
    windows = [(t[10], t[900]), (-5.0, 0.5), (t[2000], t[2000]), (t[4000], 1e9),
               (t[1500], t[1600]), (100.25, 100.25), (t[-1], t[-1] + 1.0),
               *((t[a], t[a + 25]) for a in range(2100, 2900, 60)),  # near one another
               (t[2200], t[2400]), (t[2300], t[2350])]  # overlapping, inside
    with open_recording(path) as rec:
        got = list(rec.iter_windows("chamber", "main", windows, ["temperature_degc"]))
        for d in got:  # each window's arrays are its own
            d.columns["temperature_degc"][:] = -1.0
        for (t0, t1), d in zip(windows, got, strict=True):
            want = rec.read_stream("chamber", "main", ["temperature_degc"], t0, t1)
            assert np.array_equal(d.time_s, want.time_s), (t0, t1)
            assert np.all(d.columns["temperature_degc"] == -1.0)
        got = list(rec.iter_windows("chamber", "main", windows, ["temperature_degc"]))
        for (t0, t1), d in zip(windows, got, strict=True):
            want = rec.read_stream("chamber", "main", ["temperature_degc"], t0, t1)
            assert np.array_equal(d.columns["temperature_degc"],
                                  want.columns["temperature_degc"])
        with pytest.raises(InvalidInputError, match="before"):
            list(rec.iter_windows("chamber", "main", [(2.0, 1.0)]))


@pytest.mark.parametrize("chunk", [7, 999, 4096, 1 << 18])
def test_iter_stream_concatenates_to_read_stream(recording, chunk):
    path, _ = recording
    with open_recording(path) as rec:
        whole = rec.read_stream("imu", "IMU-0001", t_start_s=1.5, t_end_s=9.25)
        parts = list(rec.iter_stream("imu", "IMU-0001", chunk_samples=chunk, t_start_s=1.5,
                                     t_end_s=9.25))
    assert all(len(p) <= chunk for p in parts)
    assert sum(len(p) for p in parts) == len(whole)
    assert np.array_equal(np.concatenate([p.time_s for p in parts]), whole.time_s)
    for c in whole.columns:
        assert np.array_equal(np.concatenate([p.columns[c] for p in parts]), whole.columns[c])


def test_read_step_valid_window_and_whole_step(recording):
    path, data = recording
    t = data["imu"]["time_s"]
    with open_recording(path) as rec:
        d = rec.read_step(0, "imu", "IMU-0001")
        assert np.array_equal(d.time_s, t[(t >= 2.0) & (t < 7.5)])
        d = rec.read_step(1, "table", "main", columns=["rate_rps"], valid_only=False)
        tt = data["table"]["time_s"]
        assert np.array_equal(d.time_s, tt[(tt >= 8.0) & (tt < 15.0)])
        d = rec.read_step(2, "imu", "IMU-0001", valid_only=False)  # running: to the end
        assert np.array_equal(d.time_s, t[t >= 15.0])
        with pytest.raises(InvalidInputError, match=r"step 2 \('position 2', status 'running'\) "
                                                    r"has no valid window"):
            rec.read_step(2, "imu", "IMU-0001")
        with pytest.raises(InvalidInputError, match=r"no step 9 in run.h5; it has 3 step\(s\)"):
            rec.read_step(9, "imu", "IMU-0001")


def test_to_dataframe(recording):
    path, data = recording
    with open_recording(path) as rec:
        df = rec.to_dataframe("imu", "IMU-0001", columns=["gyro_x_rps", "counter"],
                              t_start_s=1.0, t_end_s=2.0)
        dfs = rec.to_dataframe("imu", "IMU-0001", step=0)
    assert df.index.name == "time_s" and list(df.columns) == ["gyro_x_rps", "counter"]
    assert np.array_equal(df["counter"].to_numpy(), data["imu"]["counter"][1000:2000])
    assert df.attrs["units"]["gyro_x_rps"] == "rad/s"
    assert dfs.index[0] == 2.0 and dfs.index[-1] < 7.5


def test_unknown_stream_column_and_bad_windows(recording):
    path, _ = recording
    with open_recording(path) as rec:
        with pytest.raises(InvalidInputError, match=r"no stream imu/IMU-0009 in run.h5; streams: "
                                                    r"imu/IMU-0001, table/main"):
            rec.read_stream("imu", "IMU-0009")
        with pytest.raises(InvalidInputError, match=r"no stream imu/IMU-0001/gyro_x_rps in"):
            rec.read_stream("imu", "IMU-0001/gyro_x_rps")
        with pytest.raises(InvalidInputError, match=r"stream imu/IMU-0001 has no column\(s\) "
                                                    r"\['gyro_q'\]"):
            rec.read_stream("imu", "IMU-0001", columns=["gyro_q"])
        with pytest.raises(InvalidInputError, match=r"`t_end_s` \(1.0\) is before `t_start_s`"):
            rec.read_stream("imu", "IMU-0001", t_start_s=2.0, t_end_s=1.0)
        with pytest.raises(InvalidInputError, match=r"`t_start_s` must be a number"):
            rec.read_stream("imu", "IMU-0001", t_start_s=math.nan)
        with pytest.raises(InvalidInputError, match=r"`chunk_samples` must be a positive int"):
            rec.iter_stream("imu", "IMU-0001", chunk_samples=0)


def test_close_is_idempotent(recording):
    path, _ = recording
    rec = open_recording(path)
    rec.close()
    rec.close()


# --- bad files -----------------------------------------------------------------------------
def test_missing_file(tmp_path):
    with pytest.raises(RecordingError, match="no such recording"):
        open_recording(tmp_path / "nope.h5")


def test_foreign_hdf5_file(tmp_path):
    path = tmp_path / "foreign.h5"
    with h5py.File(path, "w") as f:
        f.create_dataset("accel", data=np.zeros(3))
        f.attrs["creator"] = "someone else"
    with pytest.raises(RecordingFormatError, match=r"not an imucalib recording: its root has no "
                                                   r"`format` attribute \(found attributes "
                                                   r"\['creator'\] and objects \['accel'\]\)"):
        open_recording(path)


def test_other_format_name(tmp_path):
    path = tmp_path / "other.h5"
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "nexus"
    with pytest.raises(RecordingFormatError, match=r"`format` attribute is 'nexus', expected "
                                                   r"'imucalib-recording'"):
        open_recording(path)


def test_newer_format_version(recording):
    path, _ = recording
    with h5py.File(path, "r+") as f:
        f.attrs["format_version"] = FORMAT_VERSION + 1
    with pytest.raises(RecordingFormatError,
                       match=rf"format_version {FORMAT_VERSION + 1}, newer than imucalib .* "
                             rf"reads \(up to {FORMAT_VERSION}\); upgrade imucalib"):
        open_recording(path)


def test_truncated_file(recording):
    path, _ = recording
    size = path.stat().st_size
    with open(path, "r+b") as fh:
        fh.truncate(size // 2)
    with pytest.raises(RecordingCorruptError, match=rf"is truncated: {size // 2} of its {size} "
                                                    r"bytes are present"):
        open_recording(path)


def test_garbage_file(tmp_path):
    path = tmp_path / "garbage.h5"
    path.write_bytes(os.urandom(4096))
    with pytest.raises(RecordingCorruptError, match=r"is not an HDF5 file \(no HDF5 signature"):
        open_recording(path)


def test_damaged_superblock(recording):
    path, _ = recording
    raw = bytearray(path.read_bytes())
    raw[40:60] = b"\xff" * 20  # inside the superblock: its checksum no longer matches
    path.write_bytes(bytes(raw))
    with pytest.raises(RecordingCorruptError, match="cannot be opened by HDF5"):
        open_recording(path)


def test_read_groups_join_nearby_spans_in_order_within_the_limit():
    from imucalib.io.reader import _read_groups

    spans = [(0, 10), (15, 30), (200, 210), (205, 220), (100, 120), (120, 120), (500, 9000)]
    groups = list(_read_groups(spans, chunk_rows=50, max_rows=1000))
    assert groups == [(0, 30, [(0, 10), (15, 30)]), (200, 220, [(200, 210), (205, 220)]),
                      (100, 120, [(100, 120), (120, 120)]), (500, 9000, [(500, 9000)])]
    assert [s for _, _, m in groups for s in m] == spans  # every span once, in order
    assert list(_read_groups([(0, 10), (15, 30)], chunk_rows=50, max_rows=20)) == [
        (0, 10, [(0, 10)]), (15, 30, [(15, 30)])]
