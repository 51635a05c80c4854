"""RecordingWriter.reopen: appending to a closed Recording keeps everything already there."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from imucalib.errors import InvalidInputError, RecordingError, RecordingOpenForWriteError
from imucalib.io import RecordingWriter, open_recording, recover_recording


def test_reopen_appends_after_the_existing_rows(recording, helpers):
    path, _ = recording
    with open_recording(path) as rec:
        before = rec.read_stream("imu", "IMU-0001").columns["gyro_x_rps"]
        t_last = rec.stream_info("imu", "IMU-0001").t_last_s
        n_steps, n_log = len(rec.steps), len(rec.log)
    more = helpers.imu_data(n=1000, seed=3)
    more["time_s"] = more["time_s"] + t_last + 1.0
    with RecordingWriter.reopen(path) as w:
        w.append("imu", "IMU-0001", more)
        w.update_step(2, t_end_s=20.0, status="aborted", note="interrupted; resumed")
        i = w.begin_step("static", "after resume", t_last + 1.0)
        w.update_step(i, t_end_s=t_last + 2.0, valid_start_s=t_last + 1.0,
                      valid_end_s=t_last + 2.0, status="done")
        w.log_event(t_last + 1.0, "info", "runner", "resumed")
        with pytest.raises(InvalidInputError, match="before the previous last time"):
            w.append("imu", "IMU-0001", helpers.imu_data(n=10))
    with open_recording(path) as rec:
        gyro = rec.read_stream("imu", "IMU-0001").columns["gyro_x_rps"]
        np.testing.assert_array_equal(gyro[: before.size], before)
        np.testing.assert_array_equal(gyro[before.size:], more["gyro_x_rps"])
        steps = rec.steps
        assert len(steps) == n_steps + 1
        assert steps[2].status == "aborted" and steps[2].note == "interrupted; resumed"
        assert steps[0].status == "done" and steps[0].commanded == {"angle_deg": [0, 90]}
        assert steps[-1].label == "after resume"
        assert [e.message for e in rec.log][-1] == "resumed" and len(rec.log) == n_log + 1
        assert rec.truth["model"] == {"name": "triad"}
        assert not rec.was_open_for_write


def test_reopen_refuses_a_file_left_open_then_its_recovered_copy_reopens(tmp_path, helpers):
    path = tmp_path / "open.h5"
    out = subprocess.run([sys.executable, str(helpers.crash_script), str(path), "5", "manual",
                          "2"], capture_output=True, text=True, timeout=60, check=False)
    assert out.returncode == -9, out.stderr
    with pytest.raises(RecordingOpenForWriteError, match="recover"):
        RecordingWriter.reopen(path)
    copy = recover_recording(path).output
    with RecordingWriter.reopen(copy) as w:
        w.log_event(1e6, "info", "runner", "resumed after a crash")
    with open_recording(copy) as rec:
        assert rec.log[-1].message == "resumed after a crash"


def test_reopen_missing_file(tmp_path):
    with pytest.raises(RecordingError, match="no such recording"):
        RecordingWriter.reopen(tmp_path / "missing.h5")
