"""A Recording writer run as a child process by test_crash.py and test_recover.py.

Usage: ``python crash_writer.py PATH SEED MODE [KILL_SELF_AFTER_FLUSHES]``

It appends deterministic blocks (a function of SEED, stream and block number) to three streams
forever, and after every flush it knows to be complete prints one JSON line
``{"blocks": B, "steps": S, "log": L}``: every stream then holds B blocks durably, with S steps
and L log events. The parent kills it with SIGKILL at a moment of its choosing, or, with
KILL_SELF_AFTER_FLUSHES, the child appends one more unflushed block after that many flushes
and kills itself.

MODE:
- ``manual``: ``flush()`` every FLUSH_EVERY blocks;
- ``interval``: automatic flushes (``flush_interval_s`` = 0.02 s, blocks 0.03 s apart);
- ``buffer``: automatic flushes whenever the buffers exceed a (1-byte) limit.
"""

from __future__ import annotations

import json
import math
import os
import signal
import sys
import time

import numpy as np

from imucalib.io.recording import ColumnSpec, RecordingWriter, StreamSpec

STREAMS = (("imu", "IMU-0001", 500), ("imu", "IMU-0002", 500), ("table", "main", 100))
FLUSH_EVERY = 4
CHUNK_ROWS = 1024  # small, so that blocks reach the file between flushes too
METADATA = {"plan_toml": 'name = "crash"\n', "station_json": '{"site": "lab 1"}',
            "operator": "test", "latitude_deg": 48.1}
TRUTH = {"gyro_bias_rps": np.array([1e-5, -2e-5, 3e-5]), "scenario": {"seed": 7}}
ACCEL_LSB_MPS2 = 30 * 9.80665 / 2**23  # accel_z_mps2 is stored as int32 counts of it


def specs() -> list[StreamSpec]:
    imu_cols = {
        "gyro_x_rps": ColumnSpec("rad/s"),
        "accel_z_mps2": ColumnSpec("m/s^2", dtype="i4", scale=ACCEL_LSB_MPS2),
        "counter": ColumnSpec("counts", dtype="u4", quantity="raw"),
    }
    table_cols = {"angle_rad": ColumnSpec("rad"), "rate_rps": ColumnSpec("rad/s", dtype="f4")}
    return [StreamSpec(dev, unit, imu_cols if dev == "imu" else table_cols)
            for dev, unit, _ in STREAMS]


def block(seed: int, stream: int, b: int) -> dict[str, np.ndarray]:
    """Block `b` of stream number `stream`: exactly reproducible from its arguments."""
    dev, _, size = STREAMS[stream]
    rng = np.random.default_rng([seed, stream, b])
    rows = np.arange(b * size, (b + 1) * size)
    time_s = rows / (size * 10.0) + stream * 1e-4
    if dev == "imu":
        gyro = rng.standard_normal(size)
        gyro[rng.integers(0, size)] = np.nan  # NaN is data
        return {"time_s": time_s, "gyro_x_rps": gyro,
                "accel_z_mps2": np.rint((9.8 + rng.standard_normal(size)) / ACCEL_LSB_MPS2)
                * ACCEL_LSB_MPS2,
                "counter": (rows % 2**32).astype(np.uint32)}
    return {"time_s": time_s, "angle_rad": rng.uniform(-np.pi, np.pi, size),
            "rate_rps": rng.standard_normal(size).astype(np.float32)}


def expected(seed: int, stream: int, n_blocks: int) -> dict[str, np.ndarray]:
    parts = [block(seed, stream, b) for b in range(n_blocks)]
    return {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}


def main() -> None:
    path, seed, mode = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    kill_self_after = int(sys.argv[4]) if len(sys.argv) > 4 else None
    options = {
        "manual": {"flush_interval_s": math.inf},
        "interval": {"flush_interval_s": 0.02},
        "buffer": {"flush_interval_s": math.inf, "buffer_limit_bytes": 1},
    }[mode]
    w = RecordingWriter(path, streams=specs(), metadata=METADATA, truth=TRUTH,
                        chunk_rows=CHUNK_ROWS, **options)
    w.flush()
    flushes = 0
    step = -1
    b = 0
    while True:
        if b % 3 == 0:
            if step >= 0:
                w.update_step(step, t_end_s=b / 10.0, valid_start_s=(b - 2) / 10.0,
                              valid_end_s=(b - 1) / 10.0, status="done")
            step = w.begin_step("static", f"block {b}", b / 10.0, commanded={"b": b})
        w.log_event(b / 10.0, "info", "crash_writer", f"block {b}")
        for i, (dev, unit, _) in enumerate(STREAMS):
            w.append(dev, unit, block(seed, i, b))  # "buffer": the last one flushes it all
        b += 1
        if mode == "manual":
            if b % FLUSH_EVERY:
                continue
            w.flush()
        elif mode == "interval":
            time.sleep(0.03)
            w.update_step(step, note=f"after block {b}")  # the interval has passed: flushes
        flushes += 1
        print(json.dumps({"blocks": b, "steps": step + 1, "log": b}), flush=True)
        if kill_self_after is not None and flushes >= kill_self_after:
            for i, (dev, unit, _) in enumerate(STREAMS):
                w.append(dev, unit, block(seed, i, b))  # never flushed
            os.kill(os.getpid(), signal.SIGKILL)

if __name__ == "__main__":
    main()
