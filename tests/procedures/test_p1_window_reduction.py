"""P1's long static window read in blocks: what it holds is bounded by the block, not its length.

A window longer than :data:`~imucalib.procedures.p1.window_reduction.CHUNK_ROWS` rows is reduced
block by block, its table feedback too; made small here, the 20 s static record of the version
1 test recording (2000 rows) takes that path in many blocks.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from imucalib.io import open_recording
from imucalib.io.streams import DEVICE_IMU, DEVICE_TABLE
from imucalib.procedures.p1 import window_reduction
from imucalib.procedures.p1.window_reduction import P1Processing, WindowReducer

V1_FILE = Path(__file__).parents[1] / "data" / "p1_v1.h5"
STATIC_STEP = 9  # "rep1 level static (gyro bias)": 20 s at 100 Hz
BLOCK = 256


class _Counting:
    """Wrap a Recording's readers: the largest number of rows one read returned, per device."""

    def __init__(self, rec: Any) -> None:
        self.rec, self.most = rec, {DEVICE_IMU: 0, DEVICE_TABLE: 0}
        read_stream, iter_stream = rec.read_stream, rec.iter_stream

        def counted_read(device: str, *args: Any, **kw: Any) -> Any:
            data = read_stream(device, *args, **kw)
            self.most[device] = max(self.most[device], len(data))
            return data

        def counted_iter(device: str, *args: Any, **kw: Any) -> Iterator[Any]:
            for data in iter_stream(device, *args, **kw):
                self.most[device] = max(self.most[device], len(data))
                yield data

        rec.read_stream, rec.iter_stream = counted_read, counted_iter


@pytest.fixture
def small_blocks(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(window_reduction, "CHUNK_ROWS", BLOCK)


def test_long_static_reads_no_more_than_a_block(small_blocks: None) -> None:
    with open_recording(V1_FILE) as rec:
        step = rec.step(STATIC_STEP)
        i0, i1 = rec.row_range(DEVICE_IMU, "IMU-0001", step.valid_start_s, step.valid_end_s)
        assert i1 - i0 > 4 * BLOCK  # the window is many blocks long
        counting = _Counting(rec)
        w = WindowReducer(rec, "IMU-0001", P1Processing()).observe(step, step.role)
    assert w.n_samples == i1 - i0
    assert 0 < counting.most[DEVICE_IMU] <= BLOCK
    assert 0 < counting.most[DEVICE_TABLE] <= BLOCK


def test_long_static_feedback_mean_is_the_whole_windows_bit_for_bit(small_blocks: None) -> None:
    with open_recording(V1_FILE) as rec:
        step = rec.step(STATIC_STEP)
        ex = WindowReducer(rec, "IMU-0001", P1Processing())
        whole = rec.read_step(STATIC_STEP, DEVICE_TABLE, ex.table.unit)
        cols = [f"angle_{a}_rad" for a in ex.axis_names]
        assert len(cols) == 2 and len(whole) > BLOCK  # two axes, several feedback blocks
        expected = np.column_stack([whole.columns[c] for c in cols]).mean(axis=0)
        assert np.array_equal(ex.static_feedback(step), expected)
        w = ex.observe(step, step.role)
        assert np.array_equal(w.angles_rad, expected)
        ex.axis_names = ex.axis_names[:1]  # a one-axis table: its single column read whole
        assert np.array_equal(ex.static_feedback(step),
                              np.column_stack([whole.columns[cols[0]]]).mean(axis=0))


def test_long_static_mean_matches_the_whole_window(small_blocks: None) -> None:
    # without outlier test the blocks change only the order of the mean's additions
    plain = P1Processing(outlier_test="none")
    with open_recording(V1_FILE) as rec:
        step = rec.step(STATIC_STEP)
        w = WindowReducer(rec, "IMU-0001", plain).observe(step, step.role)
        data = rec.read_step(STATIC_STEP, DEVICE_IMU, "IMU-0001")
    cols = ("gyro_x_rps", "gyro_y_rps", "gyro_z_rps", "accel_x_mps2", "accel_y_mps2",
            "accel_z_mps2")
    values = np.column_stack([data.columns[c] for c in cols])
    mean = np.concatenate([w.gyro_mean_rps, w.accel_mean_mps2])
    assert w.n_samples == values.shape[0]
    np.testing.assert_allclose(mean, values.mean(axis=0), rtol=1e-12, atol=0.0)
