"""The columns of a still IMU, for the small recordings the fuzz tests write and damage.

A standalone module (numpy only): the test modules import it, and so do the child processes
they start with ``python -c`` (their scripts put this folder on ``sys.path`` first, as
:data:`CHILD_PATH` does), which write a recording and then crash or edit it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: The line a child script begins with to import this module.
CHILD_PATH = f"import sys; sys.path.insert(0, {str(Path(__file__).parent)!r})\n"


def still_imu_columns(n: int, rate_hz: float = 200.0) -> dict[str, np.ndarray]:
    """Return `n` rows of a still, level IMU stream (small gyro rates, 9.8 m/s² up)."""
    t = np.arange(n) / rate_hz
    cols = {"time_s": t, "device_time_s": t, "counter": np.arange(n),
            "temperature_degc": np.full(n, 25.0), "saturated": np.zeros(n, dtype=bool)}
    for c in ("gyro_x_rps", "gyro_y_rps", "gyro_z_rps", "accel_x_mps2", "accel_y_mps2"):
        cols[c] = np.full(n, 1e-3)
    cols["accel_z_mps2"] = np.full(n, 9.8)
    return cols
