"""Twin runs of the P4 static procedures (g-sensitivity, Earth-rate bias, random drift)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from imucalib.io.opening import open_recording
from imucalib.plan.schema import Plan
from imucalib.station.runner import RunOptions, run_plan
from imucalib.station.sim import SimStation


def run_twin(plan: Plan, path: Path) -> Path:
    """Run `plan` on its twin into `path` (truth stored)."""
    assert plan.twin is not None
    station = SimStation(plan.twin)
    summary = run_plan(plan, station, path, options=RunOptions(tick_s=5.0, truth=station.truth))
    assert summary.status == "done", summary.reason
    return path


def gyro_truth(path: Path, unit: str = "IMU-0001") -> dict[str, Any]:
    """The unit's gyro truth model (bias, scale_misalignment, g_sensitivity as arrays)."""
    with open_recording(path) as rec:
        model = rec.truth["imu_models"][unit]["gyro"]
    return {k: np.asarray(model[k], dtype=float) for k in
            ("bias", "scale_misalignment", "g_sensitivity")}


def accel_truth(path: Path, unit: str = "IMU-0001") -> dict[str, Any]:
    """The unit's accelerometer truth model (bias, scale_misalignment as arrays)."""
    with open_recording(path) as rec:
        model = rec.truth["imu_models"][unit]["accel"]
    return {k: np.asarray(model[k], dtype=float) for k in ("bias", "scale_misalignment")}


def fail_step(path: Path, role: str, nth: int = 0) -> None:
    """Mark the `nth` recorded step with `role` as failed (a position not recorded)."""
    import h5py

    with h5py.File(path, "r+") as f:
        roles = [r.decode() if isinstance(r, bytes) else r for r in f["steps"]["role"][()]]
        k = [i for i, r in enumerate(roles) if r == role][nth]
        f["steps"]["status"][k] = b"failed"
