"""Rate-table twin runs for the rate-transfer and installation tests, and their truth."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from imucalib.io.opening import open_recording
from imucalib.plan.schema import Plan
from imucalib.station.runner import RunOptions, run_plan
from imucalib.station.sim import SimStation

UNIT = "IMU-0001"


def with_unit(plan: Plan, **update: Any) -> Plan:
    """`plan` with its twin unit's fields changed (white noise by default)."""
    assert plan.twin is not None
    update.setdefault("noise", "white")
    twin = plan.twin.model_copy(update={
        "imus": tuple(i.model_copy(update=update) for i in plan.twin.imus)})
    return plan.model_copy(update={"twin": twin})


def run(plan: Plan, path: Path) -> Path:
    """Run `plan` on its twin into `path` (the truth stored)."""
    assert plan.twin is not None
    station = SimStation(plan.twin)
    summary = run_plan(plan, station, path, options=RunOptions(tick_s=5.0, truth=station.truth))
    assert summary.status == "done", summary.reason
    return path


def gyro_truth(path: Path) -> dict[str, np.ndarray]:
    """The unit's gyro truth: bias, M, G, k2, scale_asymmetry, as arrays."""
    with open_recording(path) as rec:
        gyro = rec.truth["imu_models"][UNIT]["gyro"]
        g = float(rec.metadata.get("latitude_deg", 45.0))
    out = {k: np.asarray(gyro[k], dtype=float)
           for k in ("bias", "scale_misalignment", "g_sensitivity", "k2", "scale_asymmetry",
                     "k3", "koq")}
    out["latitude_deg"] = np.asarray(g)
    return out
