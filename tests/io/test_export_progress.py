"""export_csv reports its progress: rows written of the rows to write, as increasing fractions."""

from __future__ import annotations

import itertools

from imucalib.exports.streams import export_csv


def test_csv_progress_fractions_increase_to_one(recording, tmp_path):
    path, data = recording
    fractions: list[float] = []
    n = export_csv(path, "imu", "IMU-0001", tmp_path / "imu.csv", chunk_samples=3001,
                   progress=fractions.append)
    assert n == len(data["imu"]["time_s"])
    assert len(fractions) >= n // 3001
    assert all(0.0 <= f <= 1.0 for f in fractions)
    assert all(b > a for a, b in itertools.pairwise(fractions))
    assert fractions[-1] == 1.0


def test_csv_progress_of_an_empty_window_ends_at_one(recording, tmp_path):
    path, _ = recording
    fractions: list[float] = []
    n = export_csv(path, "imu", "IMU-0001", tmp_path / "none.csv", t_start_s=1e9,
                   progress=fractions.append)
    assert n == 0
    assert fractions == [1.0]
