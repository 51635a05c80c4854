"""Shared fixtures of the Recording tests: a small two-stream recording with steps and a log."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType, SimpleNamespace
from typing import Any

import numpy as np
import pytest

from imucalib.io import ColumnSpec, RecordingWriter, StreamSpec

HERE = Path(__file__).parent

IMU_SPEC = StreamSpec("imu", "IMU-0001", {
    "gyro_x_rps": ColumnSpec("rad/s", description="gyro x"),
    "gyro_y_rps": ColumnSpec("rad/s"),
    "accel_z_mps2": ColumnSpec("m/s^2"),
    "temperature_degc": ColumnSpec("degC", dtype="f4"),
    "counter": ColumnSpec("counts", dtype="u4", quantity="raw"),
})
TABLE_SPEC = StreamSpec("table", "main", {"angle_rad": ColumnSpec("rad"),
                                          "rate_rps": ColumnSpec("rad/s")})
TRUTH_SPEC = StreamSpec("imu", "IMU-0001", {"rate_b_rps": ColumnSpec("rad/s")})
METADATA: dict[str, Any] = {
    "plan_toml": 'name = "p1"\n[[steps]]\nkind = "static"\n',
    "station_json": '{"table": "AC-1120", "site": "Lab β"}',
    "environment_json": '{"pressure_hpa": 1013.2}',
    "imu_identity_json": '{"serial": "IMU-0001"}',
    "scenario_json": "{}",
    "n_positions": 12,
    "latitude_deg": 48.137154,
    "dry_run": False,
}
N_IMU = 20_000
IMU_RATE_HZ = 1000.0


def imu_data(n: int = N_IMU, seed: int = 0) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    return {
        "time_s": np.arange(n) / IMU_RATE_HZ,
        "gyro_x_rps": rng.standard_normal(n),
        "gyro_y_rps": rng.standard_normal(n) * 1e-3,
        "accel_z_mps2": 9.81 + rng.standard_normal(n),
        "temperature_degc": (25.0 + rng.standard_normal(n)).astype(np.float32),
        "counter": np.arange(n, dtype=np.uint32),
    }


def table_data(n: int = N_IMU // 10) -> dict[str, np.ndarray]:
    t = np.arange(n) / (IMU_RATE_HZ / 10)
    return {"time_s": t, "angle_rad": np.sin(t), "rate_rps": np.cos(t)}


def write_recording(path: Path, *, n_appends: int = 37, seed: int = 0) -> dict[str, Any]:
    """Write the standard small recording in uneven appends; return what was written."""
    imu = imu_data(seed=seed)
    table = table_data()
    rng = np.random.default_rng(seed + 1)
    with RecordingWriter(path, streams=[IMU_SPEC, TABLE_SPEC], metadata=METADATA,
                         truth={"bias_rps": np.array([1e-4, 2e-4, -3e-4]),
                                "scale_ppm": [100.0, -50.0, 20.0], "model": {"name": "triad"}},
                         truth_streams=[TRUTH_SPEC], chunk_rows=4096) as w:
        for data, spec in ((imu, IMU_SPEC), (table, TABLE_SPEC)):
            n = len(data["time_s"])
            cuts = np.sort(rng.choice(np.arange(1, n), n_appends - 1, replace=False))
            for a, b in zip(np.r_[0, cuts], np.r_[cuts, n], strict=True):
                w.append(spec.device, spec.unit, {k: v[a:b] for k, v in data.items()})
        w.append_truth("imu", "IMU-0001", {"time_s": imu["time_s"],
                                           "rate_b_rps": imu["gyro_x_rps"] * 0.5})
        s0 = w.begin_step("static", "position 1", 0.0, commanded={"angle_deg": [0, 90]})
        w.update_step(s0, t_end_s=8.0, valid_start_s=2.0, valid_end_s=7.5, status="done")
        s1 = w.begin_step("rate", "rate +10 dps", 8.0, commanded='{"rate_dps": 10}',
                          note="ramp 2 s")
        w.update_step(s1, t_end_s=15.0, valid_start_s=10.0, valid_end_s=14.0, status="done")
        w.begin_step("static", "position 2", 15.0)  # still running at close
        w.log_event(0.5, "info", "runner", "started")
        w.log_event(9.0, "warning", "guard", "rate error 0.2 % — continuing")
    return {"imu": imu, "table": table}


@pytest.fixture
def recording(tmp_path: Path) -> tuple[Path, dict[str, Any]]:
    path = tmp_path / "run.h5"
    return path, write_recording(path)


def load_crash_writer() -> ModuleType:
    """Import tests/io/crash_writer.py (also run as a child script) by its path."""
    name = "imucalib_tests_crash_writer"
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, HERE / "crash_writer.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="session")
def helpers() -> SimpleNamespace:
    """The helpers above, for test modules (which cannot import conftest by name)."""
    return SimpleNamespace(
        IMU_SPEC=IMU_SPEC, TABLE_SPEC=TABLE_SPEC, TRUTH_SPEC=TRUTH_SPEC, METADATA=METADATA,
        N_IMU=N_IMU, imu_data=imu_data, table_data=table_data, write_recording=write_recording,
        crash_writer=load_crash_writer(), crash_script=HERE / "crash_writer.py",
    )
