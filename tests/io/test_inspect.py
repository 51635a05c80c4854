"""summarize_recording: durations, rates, counter gaps and time gaps (without jitter alarms)."""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.errors import RecordingError
from imucalib.io import ColumnSpec, RecordingWriter, StreamSpec
from imucalib.io.inspect import summarize_recording

SPEC = StreamSpec("imu", "u", {"gyro_x_rps": ColumnSpec("rad/s"),
                               "counter": ColumnSpec("counts", dtype="i8", quantity="raw")})
PLAIN = StreamSpec("table", "main", {"angle_x_rad": ColumnSpec("rad")})


def write(path, *, jitter_s: float, drop: list[int], time_hole: tuple[int, float] | None):
    rng = np.random.default_rng(1)
    n = 50_000
    k = np.arange(n)
    t = k * 1e-3 + jitter_s * rng.standard_normal(n)
    t = np.maximum.accumulate(t)
    keep = np.ones(n, dtype=bool)
    keep[drop] = False
    table_t = np.arange(1000) * 0.01
    if time_hole is not None:
        at, extra = time_hole
        table_t[at:] += extra
    with RecordingWriter(path, streams=[SPEC, PLAIN]) as w:
        for a in range(0, n, 7919):  # uneven appends, so gaps can straddle chunk borders
            sel = slice(a, a + 7919)
            w.append("imu", "u", {"time_s": t[sel][keep[sel]], "gyro_x_rps": t[sel][keep[sel]],
                                  "counter": k[sel][keep[sel]]})
        w.append("table", "main", {"time_s": table_t, "angle_x_rad": table_t})
        i = w.begin_step("static", "s", 0.0)
        w.update_step(i, t_end_s=10.0, valid_start_s=1.0, valid_end_s=9.0, status="done")


@pytest.mark.parametrize("chunk", [1000, 1 << 18])
def test_counter_and_time_gaps(tmp_path, chunk):
    path = tmp_path / "r.h5"
    write(path, jitter_s=2e-4, drop=[100, 7919, 7920, 7921, 30_000], time_hole=(500, 0.5))
    summary = summarize_recording(path, chunk_samples=chunk)
    imu = next(s for s in summary.streams if s.device == "imu")
    table = next(s for s in summary.streams if s.device == "table")
    assert imu.counter_gaps == 3 and imu.missing_samples == 5
    # 0.2 ms of jitter on 1 ms is not a gap, nor is one lost sample; three in a row are
    assert imu.time_gaps == 1
    assert imu.sample_rate_hz == pytest.approx(1000.0, rel=1e-3)
    assert table.time_gaps == 1 and table.counter_gaps is None
    assert table.duration_s == pytest.approx(9.99 + 0.5)
    assert summary.steps[0].valid_end_s == 9.0


def test_not_a_recording(tmp_path):
    bad = tmp_path / "bad.h5"
    bad.write_bytes(b"not hdf5 at all")
    with pytest.raises(RecordingError):
        summarize_recording(bad)
