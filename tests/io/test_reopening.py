"""``reopening()``: a file opened again in one task is not checked again, unless it changed."""

from __future__ import annotations

import os
from pathlib import Path

import h5py
import numpy as np
import pytest

from imucalib.errors import RecordingCorruptError
from imucalib.io import opening
from imucalib.io.opening import open_recording, reopening


@pytest.fixture
def probes(monkeypatch) -> list[Path]:
    """Count the probes (and with them the layout and time-base checks) that opening runs."""
    seen: list[Path] = []
    real = opening.run_probe

    def counting(path, work, **kwargs):
        seen.append(path)
        return real(path, work, **kwargs)

    monkeypatch.setattr(opening, "run_probe", counting)
    return seen


def _read_all(path: Path) -> np.ndarray:
    with open_recording(path) as rec:
        return rec.read_stream("imu", "IMU-0001").columns["gyro_x_rps"]


def test_a_second_open_in_the_scope_skips_the_checks_and_reads_the_same(recording, probes):
    path, _ = recording
    first = _read_all(path)
    assert len(probes) == 1
    with reopening():
        a = _read_all(path)
        b = _read_all(path)
        with reopening():  # nested: the same scope
            c = _read_all(path)
    assert len(probes) == 2  # the first open in the scope checks; the others reuse it
    for x in (a, b, c):
        np.testing.assert_array_equal(x, first)
    _read_all(path)
    assert len(probes) == 3  # outside the scope every open checks


def test_a_file_changed_in_the_scope_is_checked_again(recording, probes):
    path, _ = recording
    with reopening():
        _read_all(path)
        with h5py.File(path, "r+") as f:  # a time stamp that goes backwards
            f["streams/imu/IMU-0001/time_s"][5] = -1.0
        st = path.stat()
        os.utime(path, ns=(st.st_atime_ns, st.st_mtime_ns + 1))
        with pytest.raises(RecordingCorruptError, match="time_s"):
            open_recording(path)
    assert len(probes) == 2


def test_a_damaged_file_is_never_remembered(recording, probes):
    path, _ = recording
    with h5py.File(path, "r+") as f:
        f["streams/imu/IMU-0001/time_s"][5] = -1.0
    with reopening():
        for _ in range(2):
            with pytest.raises(RecordingCorruptError):
                open_recording(path)
    assert len(probes) == 2
