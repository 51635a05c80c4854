"""Compact recordings against the former layout: the cases of ``bench_recording.py --sizes``.

"Before" is the layout of every recording up to format version 2: each column float64 (the
counter int64, the flag bool), no compression (``compression=None``). "After" is the compact
layout as it was measured for ``docs/recording-format.md`` (*Size and compression*, "Before and
after"): the IMU's gyro, accelerometer and temperature as int32 counts with their LSB as
``scale`` (the twin delivers exact multiples of its LSB), every column Blosc LZ4 after a
bit-shuffle (``compression="blosc-lz4"``, the default then; the default is now gzip, which
``bench_recording.py --codecs`` compares with it on a closed recording). Both files hold the
same values: the bench checks that reading either returns the same values (SHA-256 of every
column, with -0.0 counted as 0.0: a count of zero reads back as +0.0, which ``np.array_equal``
and every comparison treat as equal).
"""

from __future__ import annotations

import json
import math
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

from imucalib.io import ColumnSpec, RecordingWriter, StreamSpec, open_recording
from imucalib.io.streams import imu_stream_spec

_Data = dict[tuple[str, str], dict[str, np.ndarray]]


def float64_spec(spec: StreamSpec) -> StreamSpec:
    """The former layout of `spec`: scaled columns as float64, every other column as is."""
    cols = {name: ColumnSpec(c.unit, "f8" if c.scale is not None else c.dtype, c.quantity,
                             c.description) for name, c in spec.columns.items()}
    return StreamSpec(spec.device, spec.unit, cols)


def _payload(data: _Data) -> int:
    """Bytes of the data as float64 columns (the counter and the flag as stored before)."""
    return sum(v.nbytes for cols in data.values() for v in cols.values())


def _mb_s(n_bytes: int, seconds: float) -> str:
    return f"{n_bytes / seconds / 1e6:7.0f} MB/s"


# --------------------------------------------------------------------------------------- P1
def make_p1(path: Path, repetitions: int, static_s: float) -> float:
    """Run the P1 plan at 1 kHz on the twin through the station runner; return its seconds."""
    from imucalib.procedures import generate_p1_plan
    from imucalib.station.runner import RunOptions, run_plan
    from imucalib.station.sim import SimStation

    plan = generate_p1_plan(grade="tactical", sample_rate_hz=1000.0, repetitions=repetitions,
                            static_s=static_s, warm_up_s=600.0)
    assert plan.twin is not None
    start = time.perf_counter()
    run_plan(plan, SimStation(plan.twin), path, overwrite=True, options=RunOptions(tick_s=2.0))
    return time.perf_counter() - start


def load(path: Path) -> tuple[list[StreamSpec], _Data, dict[str, Any], list[Any], list[Any]]:
    """Read a recording's stream specs, streams, metadata, steps and log into memory."""
    with open_recording(path) as rec:
        specs = [StreamSpec(i.device, i.unit, {c: s for c, s in i.columns.items()})
                 for i in rec.streams]
        data: _Data = {}
        for info in rec.streams:
            got = rec.read_stream(info.device, info.unit)
            data[(info.device, info.unit)] = {"time_s": got.time_s, **got.columns}
        meta = {k: (json.dumps(v) if k.endswith("_json") and not isinstance(v, str) else v)
                for k, v in rec.metadata.items()
                if k not in {"format", "format_version", "created_utc", "software_version"}}
        return specs, data, meta, rec.steps, rec.log


def write_copy(path: Path, specs: list[StreamSpec], data: _Data, meta: dict[str, Any],
               steps: list[Any], log: list[Any], compression: str | None) -> float:
    """Write the loaded recording in 60 000-row appends; return the seconds it took."""
    start = time.perf_counter()
    with RecordingWriter(path, streams=specs, metadata=meta, overwrite=True,
                         compression=compression) as w:
        for spec in specs:
            cols = data[(spec.device, spec.unit)]
            n = len(cols["time_s"])
            for a in range(0, n, 60_000):
                w.append(spec.device, spec.unit, {c: v[a:a + 60_000] for c, v in cols.items()})
        for s in steps:
            i = w.begin_step(s.kind, s.label, s.t_start_s, commanded=s.commanded, note=s.note,
                             role=s.role, tags=s.tags, units=s.units, status=s.status)
            w.update_step(i, t_end_s=s.t_end_s, valid_start_s=s.valid_start_s,
                          valid_end_s=s.valid_end_s)
        for e in log:
            w.log_event(e.time_s, e.level, e.source, e.message)
    return time.perf_counter() - start


def read_all(path: Path, chunk: int = 1 << 18) -> tuple[float, dict[tuple[str, str], str]]:
    """Read every stream in pieces; return the seconds and a digest per stream."""
    import hashlib

    digests: dict[tuple[str, str], str] = {}
    start = time.perf_counter()
    with open_recording(path) as rec:
        for info in rec.streams:
            h = hashlib.sha256()
            for piece in rec.iter_stream(info.device, info.unit, chunk_samples=chunk):
                h.update(piece.time_s.tobytes())
                for v in piece.columns.values():  # + 0.0: -0.0 reads back as 0.0 (equal)
                    h.update(np.ascontiguousarray(v + 0.0 if v.dtype.kind == "f" else v).tobytes())
            digests[(info.device, info.unit)] = h.hexdigest()
    return time.perf_counter() - start, digests


def analyse(path: Path) -> float:
    """Calibrate the P1 recording; return the seconds."""
    from imucalib.procedures.p1.analysis import P1Options, analyze_p1

    start = time.perf_counter()
    analyze_p1(path, options=P1Options(hash_recording=False))
    return time.perf_counter() - start


def best(funcs: list[Callable[[], float]], repeat: int) -> list[float]:
    """Best time of each function over `repeat` interleaved rounds."""
    out = [math.inf] * len(funcs)
    for _ in range(repeat):
        for k, f in enumerate(funcs):
            out[k] = min(out[k], f())
    return out


def p1_case(tmp: Path, repetitions: int, static_s: float, repeat: int) -> None:
    made = tmp / "p1-station.h5"
    seconds = make_p1(made, repetitions, static_s)
    specs, data, meta, steps, log = load(made)
    n_imu = sum(len(c["time_s"]) for (dev, _), c in data.items() if dev == "imu")
    print(f"\nP1 at 1 kHz ({repetitions} repetition(s), {static_s:g} s static records): "
          f"{n_imu:,} IMU samples, station run on the twin in {seconds:.0f} s "
          f"(file as the station wrote it: {made.stat().st_size / 1e6:,.1f} MB)")
    made.unlink()
    before, after = tmp / "p1-before.h5", tmp / "p1-after.h5"
    old = [float64_spec(s) for s in specs]
    payload = _payload(data)
    w_before, w_after = best([
        lambda: write_copy(before, old, data, meta, steps, log, None),
        lambda: write_copy(after, specs, data, meta, steps, log, "blosc-lz4")], repeat)
    data.clear()  # free the arrays before reading and analysing
    _report(before, after, payload, w_before, w_after, repeat)
    a_before, a_after = best([lambda: analyse(before), lambda: analyse(after)], repeat)
    print(f"  P1 analysis (analyze_p1)   before {a_before:7.2f} s    after {a_after:7.2f} s    "
          f"after/before {a_after / a_before:5.2f}")
    before.unlink()
    after.unlink()


def _report(before: Path, after: Path, payload: int, w_before: float, w_after: float,
            repeat: int) -> None:
    (r_before, d_before), (r_after, d_after) = (read_all(before), read_all(after))
    for _ in range(repeat - 1):
        r_before = min(r_before, read_all(before)[0])
        r_after = min(r_after, read_all(after)[0])
    assert d_before == d_after, "the two layouts must read back the same values"
    s_before, s_after = before.stat().st_size, after.stat().st_size
    print(f"  file size                  before {s_before / 1e6:9,.1f} MB  after "
          f"{s_after / 1e6:9,.1f} MB  ratio {s_before / s_after:5.2f}")
    print(f"  write (payload {payload / 1e6:,.0f} MB)     before {_mb_s(payload, w_before)}  "
          f"after {_mb_s(payload, w_after)}  after/before {w_before / w_after:5.2f}")
    print(f"  read, 2^18-row pieces      before {_mb_s(payload, r_before)}  "
          f"after {_mb_s(payload, r_after)}  after/before {r_before / r_after:5.2f}")
    print("  values read back: equal in both files (SHA-256 of every column, -0.0 as 0.0)")


# ------------------------------------------------------------------------------------ Allan
def allan_blocks(hours: float, block_s: float = 60.0
                 ) -> Iterator[tuple[dict[str, np.ndarray], float, float, float]]:
    """Blocks of a static tactical twin IMU at 1 kHz, with the LSBs of its outputs."""
    from imucalib.models import sample_imu_model
    from imucalib.sim import Site, TwinRig, single_imu_fixture
    from imucalib.sim.synth import SimImu

    model = sample_imu_model("tactical", rng=5)
    imu = SimImu("IMU-0001", model)
    rig = TwinRig(site=Site(latitude_deg=45.0), fixture=single_imu_fixture(name="IMU-0001"),
                  imus=[imu], rng=5)
    g, a = model.gyro_output.effective_lsb, model.accel_output.effective_lsb
    assert g is not None and a is not None
    t = 0.0
    while t < hours * 3600.0 - 1e-9:
        t = min(t + block_s, hours * 3600.0)
        s = rig.generate(t).imu["IMU-0001"]
        cols = {"time_s": s.time_s, "device_time_s": s.device_time_s, "counter": s.counter,
                "temperature_degc": s.temperature_degc, "saturated": s.saturated}
        for j, axis in enumerate("xyz"):
            cols[f"gyro_{axis}_rps"] = s.gyro_rps[:, j]
            cols[f"accel_{axis}_mps2"] = s.accel_mps2[:, j]
        yield cols, g, a, imu.temperature_resolution_degc


def allan_case(tmp: Path, hours: float, flush_every_s: float | None) -> None:
    """Append the same generated blocks to both layouts, timing only the writers' calls."""
    before, after = tmp / "allan-before.h5", tmp / "allan-after.h5"
    writers: dict[str, RecordingWriter] = {}
    spent = {"before": 0.0, "after": 0.0}
    payload = 0
    n = 0
    interval = math.inf if flush_every_s is not None else 1.0
    for cols, g, a, t_lsb in allan_blocks(hours, flush_every_s or 60.0):
        if not writers:
            new = imu_stream_spec("IMU-0001", gyro_lsb_rps=g, accel_lsb_mps2=a,
                                  temperature_lsb_degc=t_lsb)
            t0 = time.perf_counter()
            writers["before"] = RecordingWriter(before, streams=[float64_spec(new)],
                                                overwrite=True, compression=None,
                                                flush_interval_s=interval)
            spent["before"] += time.perf_counter() - t0
            t0 = time.perf_counter()
            writers["after"] = RecordingWriter(after, streams=[new], overwrite=True,
                                               flush_interval_s=interval,
                                               compression="blosc-lz4")
            spent["after"] += time.perf_counter() - t0
        payload += sum(v.nbytes for v in cols.values())
        n += len(cols["time_s"])
        for name, w in writers.items():
            t0 = time.perf_counter()
            w.append("imu", "IMU-0001", cols)
            if flush_every_s is not None:
                w.flush()
            spent[name] += time.perf_counter() - t0
    for name, w in writers.items():
        t0 = time.perf_counter()
        w.close()
        spent[name] += time.perf_counter() - t0
    how = (f"flushed every {flush_every_s:g} s of data, as a real-time station does"
           if flush_every_s is not None else "appended in 60 s blocks")
    print(f"\nAllan record, {hours:g} h at 1 kHz ({n:,} samples, one IMU, {how}):")
    _report(before, after, payload, spent["before"], spent["after"], 1)
    before.unlink()
    after.unlink()


def run_sizes(p1_repetitions: int, p1_static_s: float, allan_hours: float, repeat: int) -> None:
    """Print the before/after tables of the P1 and Allan cases."""
    import platform

    import h5py
    import hdf5plugin

    print(f"compact recordings: h5py {h5py.__version__} (HDF5 {h5py.version.hdf5_version}), "
          f"hdf5plugin {hdf5plugin.version}, numpy {np.__version__}, Python "
          f"{platform.python_version()}, {platform.machine()}")
    print("before: float64 columns, uncompressed (format 2); after: int32 counts × LSB for "
          "gyro/accel/temperature, Blosc LZ4 + bit-shuffle (the defaults when the docs' table "
          "was measured; gzip is the default now: bench_recording.py --codecs)")
    with tempfile.TemporaryDirectory(dir="/tmp") as name:
        tmp = Path(name)
        if p1_repetitions > 0:
            p1_case(tmp, p1_repetitions, p1_static_s, repeat)
        if allan_hours > 0:
            allan_case(tmp, allan_hours, None)
            allan_case(tmp, min(allan_hours, 1.0), 1.0)


# ------------------------------------------------------------------------- filters per column
def column_filters(n_rows: int = 150_000) -> None:
    """Print, per column of a tactical twin IMU at 1 kHz, each filter's ratio and speed.

    The data: 60 s at rest, then turning at 50 °/s about the table's pitch axis. Ratios are
    against the column's own stored bytes (float64 values, or the int32 counts of the ``_i32``
    rows, which are half as many bytes to begin with), written as one 65 536-row-chunk dataset;
    speeds are MB/s of the stored bytes, in this process.
    """
    import h5py
    import hdf5plugin as hp

    from imucalib.models import sample_imu_model
    from imucalib.sim import Site, TwinRig, single_imu_fixture
    from imucalib.sim.synth import SimImu
    from imucalib.sim.table import RateTableSpec, SimRateTable

    model = sample_imu_model("tactical", rng=1)
    table = SimRateTable(RateTableSpec.dual_axis_pitch_roll("ideal"))
    rig = TwinRig(site=Site(latitude_deg=45.0), fixture=single_imu_fixture(name="u"),
                  imus=[SimImu("u", model)], table=table, rng=1)
    rest_s = min(60.0, n_rows / 2000.0)
    parts = [rig.generate(rest_s).imu["u"]]
    table.command_rate(0, math.radians(50.0), rest_s)
    parts.append(rig.generate(n_rows / 1000.0).imu["u"])

    def cat(name: str) -> np.ndarray:
        return np.concatenate([getattr(p, name) for p in parts])

    gyro, accel = cat("gyro_rps"), cat("accel_mps2")
    glsb, alsb = model.gyro_output.effective_lsb, model.accel_output.effective_lsb
    assert glsb is not None and alsb is not None
    cols: dict[str, np.ndarray] = {
        "time_s": cat("time_s"), "device_time_s": cat("device_time_s"),
        "counter_i64": cat("counter").astype(np.int64), "gyro_x": gyro[:, 0],
        "gyro_y (turning)": gyro[:, 1], "accel_z": accel[:, 2],
        "temperature": cat("temperature_degc"), "saturated": cat("saturated")}
    cols["gyro_x_i32"] = np.rint(cols["gyro_x"] / glsb).astype(np.int32)
    cols["gyro_y_i32"] = np.rint(cols["gyro_y (turning)"] / glsb).astype(np.int32)
    cols["accel_z_i32"] = np.rint(cols["accel_z"] / alsb).astype(np.int32)
    cols["temperature_i32"] = np.rint(cols["temperature"] * 256).astype(np.int32)
    cols["counter_i32"] = cols["counter_i64"].astype(np.int32)
    filters: dict[str, dict[str, Any]] = {
        "gzip1": {"compression": "gzip", "compression_opts": 1},
        "gzip4": {"compression": "gzip", "compression_opts": 4},
        "shuf+gzip1": {"compression": "gzip", "compression_opts": 1, "shuffle": True},
        "shuf+gzip4": {"compression": "gzip", "compression_opts": 4, "shuffle": True},
        "lzf": {"compression": "lzf"},
        "shuf+lzf": {"compression": "lzf", "shuffle": True},
        "zstd1": dict(hp.Zstd(clevel=1)),
        "shuf+zstd1": {"shuffle": True, **hp.Zstd(clevel=1)},
        "blosc-lz4-shuf": dict(hp.Blosc(cname="lz4", clevel=5, shuffle=hp.Blosc.SHUFFLE)),
        "blosc-lz4-bit": dict(hp.Blosc(cname="lz4", clevel=5, shuffle=hp.Blosc.BITSHUFFLE)),
        "blosc-zstd1-shuf": dict(hp.Blosc(cname="zstd", clevel=1, shuffle=hp.Blosc.SHUFFLE)),
        "blosc-zstd1-bit": dict(hp.Blosc(cname="zstd", clevel=1, shuffle=hp.Blosc.BITSHUFFLE)),
    }
    n = len(cols["time_s"])
    print(f"\nper-column filters, tactical twin IMU at 1 kHz, {n:,} rows, 65 536-row chunks: "
          "ratio (stored bytes / compressed bytes)  write/read MB/s")
    print(f"{'column':<17}" + "".join(f"{f:>19}" for f in filters))
    with tempfile.TemporaryDirectory(dir="/tmp") as name:
        path = Path(name) / "f.h5"
        for c, v in cols.items():
            row = []
            for kw in filters.values():
                with h5py.File(path, "w", libver="latest") as f:
                    t0 = time.perf_counter()
                    ds = f.create_dataset("x", data=v, chunks=(1 << 16,), maxshape=(None,), **kw)
                    f.flush()
                    tw = time.perf_counter() - t0
                    size = ds.id.get_storage_size()
                with h5py.File(path, "r") as f:
                    t0 = time.perf_counter()
                    f["x"][:]
                    tr = time.perf_counter() - t0
                row.append(f"{v.nbytes / size:7.2f} {v.nbytes / tw / 1e6:4.0f}/"
                           f"{v.nbytes / tr / 1e6:4.0f}")
            print(f"{c:<17}" + "".join(f"{r:>19}" for r in row))
