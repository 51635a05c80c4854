"""SIGKILL a writer mid-recording: every row flushed before the kill must be readable and exact.

The child (tests/io/crash_writer.py) appends deterministic blocks forever and prints, after each
completed flush, how many blocks every stream holds durably. The parent kills it with SIGKILL
while it is still appending, then reads the file (in SWMR mode, transparently) and compares
with the regenerated data; finally recover_recording must give a normally opening file with the
same rows.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import h5py
import numpy as np
import pytest

from imucalib.errors import RecordingOpenForWriteError
from imucalib.io import open_recording, recover_recording

pytestmark = pytest.mark.skipif(not hasattr(signal, "SIGKILL"), reason="needs POSIX signals")


def _run_and_kill(script, path, seed, mode, n_lines, delay_s, *, live_check=None):
    proc = subprocess.Popen([sys.executable, str(script), str(path), str(seed), mode],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        last = None
        for _ in range(n_lines):
            line = proc.stdout.readline()
            if not line:
                proc.wait(timeout=10)
                pytest.fail(f"the writer ended early: {proc.stderr.read()}")
            last = json.loads(line)
        if live_check is not None:
            live_check(last)
        time.sleep(delay_s)
        assert proc.poll() is None, "the writer must still be running when killed"
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=10)
        assert proc.returncode == -signal.SIGKILL
        for line in proc.stdout.read().splitlines():  # flushes reported before it died
            last = json.loads(line)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        proc.stdout.close()
        proc.stderr.close()
    return last


def _check_contents(rec, cw, seed, last):
    assert rec.metadata["plan_toml"] == cw.METADATA["plan_toml"]
    assert rec.metadata["station_json"] == {"site": "lab 1"}
    assert rec.metadata["latitude_deg"] == cw.METADATA["latitude_deg"]
    assert rec.truth["gyro_bias_rps"].tobytes() == cw.TRUTH["gyro_bias_rps"].tobytes()
    infos = {(i.device, i.unit): i for i in rec.streams}
    rows = {}
    for k, (dev, unit, size) in enumerate(cw.STREAMS):
        got = rec.read_stream(dev, unit)  # a live writer may have added rows since `infos`
        n = len(got)
        assert n >= infos[(dev, unit)].n_samples >= last["blocks"] * size, (
            f"{dev}/{unit}: flushed rows are missing")
        assert n % size == 0, f"{dev}/{unit}: a partial append became visible"
        want = cw.expected(seed, k, n // size)
        assert got.time_s.tobytes() == want["time_s"].tobytes()
        for col, values in got.columns.items():
            assert values.dtype == want[col].dtype
            assert values.tobytes() == want[col].tobytes(), f"{dev}/{unit} {col} differs"
        rows[(dev, unit)] = got
    steps = rec.steps
    assert len(steps) >= last["steps"]
    for s in steps:
        assert s.label == f"block {3 * s.index}" and s.commanded == {"b": 3 * s.index}
    assert all(s.status == "done" for s in steps[:-1])
    log = rec.log
    assert len(log) >= last["log"]
    assert [e.message for e in log] == [f"block {b}" for b in range(len(log))]
    return rows


@pytest.mark.parametrize(("mode", "n_lines", "delay_s", "seed"), [
    ("manual", 1, 0.0, 11),
    ("manual", 3, 0.004, 12),
    ("manual", 7, 0.011, 13),
    ("interval", 4, 0.017, 14),
    ("buffer", 9, 0.003, 15),
])
def test_sigkill_keeps_every_flushed_row(tmp_path, helpers, mode, n_lines, delay_s, seed):
    cw = helpers.crash_writer
    path = tmp_path / "killed.h5"
    last = _run_and_kill(helpers.crash_script, path, seed, mode, n_lines, delay_s)
    assert last["blocks"] >= 1

    with pytest.raises(OSError, match="open for write"):  # the failure the reader hides
        h5py.File(path, "r")
    with open_recording(path) as rec:
        assert rec.was_open_for_write
        rows = _check_contents(rec, cw, seed, last)
    with pytest.raises(RecordingOpenForWriteError, match=r"imucalib recover"):
        open_recording(path, strict=True)

    original = path.read_bytes()
    report = recover_recording(path)
    assert path.read_bytes() == original  # never modified
    assert report.output == tmp_path / "killed.recovered.h5"
    assert report.was_open_for_write and report.verified
    with open_recording(report.output, strict=True) as rec:
        assert not rec.was_open_for_write
        assert rec.metadata["recovered_from"] == "killed.h5"
        for (dev, unit), got in rows.items():
            again = rec.read_stream(dev, unit)
            assert again.time_s.tobytes() == got.time_s.tobytes()
            for col in got.columns:
                assert again.columns[col].tobytes() == got.columns[col].tobytes()
        _check_contents(rec, cw, seed, last)
    with h5py.File(report.output, "r") as f:  # plain HDF5 opens it too
        assert "streams" in f


def test_live_reader_sees_flushed_rows_and_step_updates(tmp_path, helpers):
    cw = helpers.crash_writer
    path = tmp_path / "live.h5"
    seen = {}

    def live_check(last):
        with open_recording(path) as rec:  # the writer is alive and appending
            assert rec.was_open_for_write
            seen["rows"] = _check_contents(rec, cw, 21, last)
            seen["steps"] = rec.steps

    last = _run_and_kill(helpers.crash_script, path, 21, "manual", 5, 0.0, live_check=live_check)
    assert len(seen["steps"]) >= 7  # blocks 0..18 began steps 0..6; earlier ones updated to done
    assert seen["steps"][0].status == "done" and seen["steps"][0].valid_end_s == 0.2
    with open_recording(path) as rec:
        _check_contents(rec, cw, 21, last)
        n_after = rec.streams[0].n_samples
    assert n_after >= len(seen["rows"][("imu", "IMU-0001")])
    assert np.isfinite(last["blocks"])
