"""P2 benchmark: batch analysis throughput against the bare HDF5 read, memory, speed-up.

A 16-unit × 6-temperature array recording at 1 kHz is made on the twin (consumer units on the
cube, a fast chamber so the soaks take minutes of virtual time; kept under ``--cache`` and
reused), or given with ``--recording``. Then, each in a child process so that peak memory is
its own:

1. **floor**: reading every P2 window of every unit (gyro, accelerometer, counter and
   temperature columns) with h5py and nothing else;
2. **analysis**: the whole P2 batch on one core (``analyze_p2(workers=1)``);
3. **memory**: the analysis of 4 units and of all 16 in one process (peak RSS);
4. **speed-up**: the batch with ``--workers`` processes against one.

Printed: six-channel samples per second per core (the samples of the analysed windows over the
analysis time), the floor's time and the ratio between them, the peak resident memory for 4
and 16 units, and the parallel speed-up. Aim (issue 12): within 3× of the bare read, and peak
memory independent of the number of units.

Run:  .venv/bin/python bench/bench_p2.py [--recording FILE] [--cache DIR] [--workers 2]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

_CHILD = r"""
import json, sys, time
mode, path = sys.argv[1], sys.argv[2]
t0 = time.perf_counter()
out = {}
if mode == "floor":
    import h5py, numpy as np
    from imucalib.io.opening import open_recording
    with open_recording(path) as rec:
        spans = [(s.valid_start_s, s.valid_end_s) for s in rec.steps
                 if s.role in ("p2.static", "p2.rate") and s.has_valid_window]
        units = [s.unit for s in rec.streams if s.device == "imu"]
    n = 0
    t0 = time.perf_counter()
    with h5py.File(path, "r") as f:
        for unit in units:
            g = f[f"streams/imu/{unit}"]
            t = g["time_s"][:]
            cols = [g[c] for c in ("gyro_x_rps", "gyro_y_rps", "gyro_z_rps", "accel_x_mps2",
                                   "accel_y_mps2", "accel_z_mps2", "counter",
                                   "temperature_degc")]
            for a, b in spans:
                i0, i1 = np.searchsorted(t, [a, b])
                block = [c[i0:i1] for c in cols]
                n += i1 - i0
    out["samples"] = int(n)
else:
    from imucalib.procedures.p2.batch import analyze_p2
    units = None if mode == "all" else json.loads(sys.argv[3])
    workers = int(sys.argv[4]) if len(sys.argv) > 4 else 1
    batch = analyze_p2(path, units=units, workers=workers)
    out["units"] = len(batch.results)
    out["errors"] = [r.error for r in batch.results if r.error]
out["seconds"] = time.perf_counter() - t0
# VmHWM: this process's own peak (ru_maxrss survives fork and exec: it would be the parent's)
with open("/proc/self/status") as fh:
    hwm = [line for line in fh if line.startswith("VmHWM:")]
out["peak_rss_mib"] = int(hwm[0].split()[1]) / 1024 if hwm else float("nan")
print(json.dumps(out))
"""


def _child(*args: str) -> dict[str, object]:
    res = subprocess.run([sys.executable, "-c", _CHILD, *args], capture_output=True, text=True,
                         check=False)
    if res.returncode != 0:
        raise SystemExit(f"child {args[0]} failed:\n{res.stderr[-3000:]}")
    return json.loads(res.stdout.strip().splitlines()[-1])


def make_recording(path: Path) -> None:
    """16 consumer units, 6 temperatures, 1 kHz, on the twin (about ten minutes)."""
    from imucalib.plan.equipment import (
        ChamberConfig,
        FixtureConfig,
        ImuConfig,
        SiteConfig,
        TableConfig,
        TwinEquipment,
    )
    from imucalib.procedures.p2.plan import generate_p2_plan
    from imucalib.station.runner import RunOptions, run_plan
    from imucalib.station.sim import SimStation

    twin = TwinEquipment(
        seed=7, site=SiteConfig(latitude_deg=45.0, ambient_temperature_degc=25.0),
        table=TableConfig(kind="single-axis", grade="lab"),
        chamber=ChamberConfig(enabled=True, initial_temperature_degc=25.0,
                              max_ramp_degc_per_min=20.0, air_time_constant_s=20.0),
        fixture=FixtureConfig(kind="hexahedral", half_edge_m=0.08, spacing_m=0.05),
        imus=tuple(ImuConfig(name=f"IMU-{i + 1:04d}", grade="consumer", sample_rate_hz=1000.0,
                             thermal_time_constant_s=40.0) for i in range(16)))
    plan = generate_p2_plan(temperatures_degc=(-40.0, -15.0, 10.0, 35.0, 60.0, 85.0),
                            held_out_degc=(), rate_dps=90.0, revolutions=1, static_s=5.0,
                            settle_s=2.0, stable_for_s=60.0, resoak_s=5.0,
                            ramp_degc_per_min=20.0, twin=twin)
    station = SimStation(twin)
    t0 = time.perf_counter()
    summary = run_plan(plan, station, path, options=RunOptions(tick_s=5.0))
    if summary.status != "done":
        raise SystemExit(f"the twin run stopped: {summary.reason}")
    print(f"made {path} on the twin in {time.perf_counter() - t0:.0f} s "
          f"({path.stat().st_size / 2**20:.0f} MiB)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--recording", type=Path)
    ap.add_argument("--cache", type=Path, default=Path(tempfile.gettempdir()) / "imucalib-bench")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    path = args.recording
    if path is None:
        args.cache.mkdir(parents=True, exist_ok=True)
        path = args.cache / "p2-16x6-1khz.h5"
        if not path.exists():
            make_recording(path)
    from imucalib.io.opening import open_recording

    with open_recording(path) as rec:
        units = [s.unit for s in rec.streams if s.device == "imu"]
    floor = _child("floor", str(path))
    one = _child("all", str(path), "null", "1")
    some = _child("some", str(path), json.dumps(units[:4]), "1")
    par = _child("all", str(path), "null", str(args.workers))
    samples = int(floor["samples"])  # type: ignore[call-overload]
    t_floor, t_one = float(floor["seconds"]), float(one["seconds"])  # type: ignore[arg-type]
    t_par = float(par["seconds"])  # type: ignore[arg-type]
    print(f"recording: {path} ({path.stat().st_size / 2**20:.0f} MiB), {len(units)} units, "
          f"{samples:,} six-channel samples in the P2 windows; {os.cpu_count()} cores")
    print(f"floor (h5py read of the windows):  {t_floor:8.2f} s   "
          f"{samples / t_floor / 1e6:8.2f} M samples/s")
    print(f"analysis, 1 core:                  {t_one:8.2f} s   "
          f"{samples / t_one / 1e6:8.2f} M samples/s per core")
    print(f"analysis / floor:                  {t_one / t_floor:8.2f}×")
    print(f"peak RSS: 4 units {some['peak_rss_mib']:.0f} MiB, {len(units)} units "
          f"{one['peak_rss_mib']:.0f} MiB (floor child {floor['peak_rss_mib']:.0f} MiB)")
    print(f"speed-up with {args.workers} workers: {t_one / t_par:.2f}× ({t_par:.2f} s)")
    if one["errors"]:
        print(f"units that failed: {one['errors']}")


if __name__ == "__main__":
    main()
