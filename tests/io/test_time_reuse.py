"""The time columns the opening's check reads whole are handed to the reader, not read again.

open_recording checks every committed time base (imucalib.io._validate.check_time_bases); the
columns it reads whole (one block, within imucalib.io.opening.KEEP_TIME_BYTES a file) are kept
for the reader: the first whole read takes the array, a part is copied from it. What the reader
returns is the same as reading the dataset, and no caller shares an array with another.
"""

from __future__ import annotations

import subprocess
import sys

import h5py
import numpy as np
import pytest

import imucalib.io.opening as opening
from imucalib.io import open_recording


class _TimeReads:
    """Counts the reads of any ``.../time_s`` dataset through h5py (slicing or read_direct)."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch) -> None:
        self.count = 0
        getitem, direct = h5py.Dataset.__getitem__, h5py.Dataset.read_direct

        def counted_getitem(ds, *args, **kwargs):
            self.count += ds.name.endswith("/time_s")
            return getitem(ds, *args, **kwargs)

        def counted_direct(ds, *args, **kwargs):
            self.count += ds.name.endswith("/time_s")
            return direct(ds, *args, **kwargs)

        monkeypatch.setattr(h5py.Dataset, "__getitem__", counted_getitem)
        monkeypatch.setattr(h5py.Dataset, "read_direct", counted_direct)


def test_a_whole_stream_reads_its_time_column_once(recording, monkeypatch):
    path, data = recording
    reads = _TimeReads(monkeypatch)
    with open_recording(path, probe=False) as rec:
        opened = reads.count  # the check: the IMU's, the table's and the truth stream's
        info = rec.stream_info("imu", "IMU-0001")
        whole = rec.read_stream("imu", "IMU-0001")
        assert reads.count == opened  # extents and rows from the kept column
        np.testing.assert_array_equal(whole.time_s, data["imu"]["time_s"])
        assert (info.t_first_s, info.t_last_s) == (data["imu"]["time_s"][0],
                                                   data["imu"]["time_s"][-1])
        again = rec.read_stream("imu", "IMU-0001")  # handed over: read from the file now
        assert reads.count == opened + 1
        np.testing.assert_array_equal(again.time_s, whole.time_s)
        assert not np.shares_memory(again.time_s, whole.time_s)


def test_parts_are_copies_and_equal_the_file(recording, monkeypatch):
    path, data = recording
    t = data["table"]["time_s"]
    with open_recording(path, probe=False) as rec:
        part = rec.read_stream("table", "main", t_start_s=t[100], t_end_s=t[400])
        np.testing.assert_array_equal(part.time_s, t[100:400])
        part.time_s[:] = -1.0  # the caller's own array
        other = rec.read_stream("table", "main", t_start_s=t[100], t_end_s=t[400])
        np.testing.assert_array_equal(other.time_s, t[100:400])
        windows = list(rec.iter_windows("table", "main", [(t[10], t[20]), (t[50], t[90])]))
        np.testing.assert_array_equal(windows[1].time_s, t[50:90])
        whole = rec.read_stream("table", "main")
        np.testing.assert_array_equal(whole.time_s, t)


def test_nothing_is_kept_past_the_budget_or_for_a_file_being_written(recording, monkeypatch,
                                                                    helpers, tmp_path):
    path, data = recording
    monkeypatch.setattr(opening, "KEEP_TIME_BYTES", 8 * len(data["table"]["time_s"]))
    reads = _TimeReads(monkeypatch)
    with open_recording(path, probe=False) as rec:
        assert set(rec._times) == {"streams/table/main"}  # the IMU's does not fit
        opened = reads.count
        np.testing.assert_array_equal(rec.read_stream("imu", "IMU-0001").time_s,
                                      data["imu"]["time_s"])
        assert reads.count == opened + 1
    monkeypatch.setattr(opening, "KEEP_TIME_BYTES", 8 * len(data["imu"]["time_s"]))
    with open_recording(path, probe=False) as rec:
        assert set(rec._times) == {"streams/imu/IMU-0001"}  # truth streams never
    live = tmp_path / "live.h5"  # a writer killed after its flushes: left open for write
    out = subprocess.run([sys.executable, str(helpers.crash_script), str(live), "5", "manual",
                          "1"], capture_output=True, text=True, timeout=60, check=False)
    assert out.returncode == -9, out.stderr
    with open_recording(live) as rec:
        assert rec.was_open_for_write and rec._times == {}
        stream = rec.stream_info("imu", "IMU-0001")
        assert stream.n_samples > 0
        with h5py.File(live, "r", swmr=True) as f:
            expected = f["streams/imu/IMU-0001/time_s"][:stream.n_samples]
        np.testing.assert_array_equal(rec.read_stream("imu", "IMU-0001").time_s, expected)
