"""Write and read throughput of the Recording against plain h5py, in the same process.

Writes the same arrays (``--streams`` IMU streams × 7 columns: time_s + 3 gyro + 3 accel,
``--rows`` rows each, float64) appended in blocks of ``--block`` rows, stream after stream, as a
station would:

- ``imucalib``: :class:`~imucalib.io.recording.RecordingWriter` (SWMR, automatic flush every
  second, row counts committed on each flush);
- ``h5py``: plain h5py, the same chunked resizable datasets (same chunk size, libver latest), each
  block written with ``resize`` + slice assignment, one flush at the end;

then reads each stream whole (``read_stream`` vs ``ds[:]`` per column) and in pieces of 2^18 rows
(``iter_stream`` vs slicing). Prints MB/s (payload bytes, 10^6 B/s) and the ratio
imucalib / h5py (target for writing: within 1.5×, i.e. ratio ≥ 0.67). Both sides write
uncompressed float64 here (``compression=None``): this part measures the library's overhead.
Optionally compares the writer's compression settings on these random floats (``--compression``).

``--sizes`` measures instead compact recordings against the former layout (float64 columns, no
compression), in the same process, on twin data (:mod:`bench.compact_cases`, shown below):

- **P1 at 1 kHz**: :func:`~imucalib.procedures.p1.plan.generate_p1_plan` (tactical,
  ``sample_rate_hz=1000``) run on the twin through the station runner, which writes the new
  defaults; its streams, steps and metadata are then written again through
  :class:`~imucalib.io.recording.RecordingWriter` in both layouts (same data, same process),
  read back, and calibrated (:func:`~imucalib.procedures.p1.analysis.analyze_p1`);
- **Allan, 8 h at 1 kHz**: a static tactical twin IMU generated block by block and appended to
  both writers (only the append and close calls are timed), then read back in 2^18-row pieces.

Printed per case: file size before/after and their ratio, write and read speed (MB/s of
float64 payload, 10^6 B/s: the same bytes for both), and for P1 the analysis time.

Reads come from the page cache right after writing (both sides alike): they measure the library
overhead, not the disk, and they are noisy (memory allocation and page faults of the returned
arrays dominate), so they are repeated 2 × repeat + 1 times, interleaved, and the best is kept.

Run:  .venv/bin/python bench/bench_recording.py [--streams 8] [--rows 400000] [--block 1000]
      [--repeat 3] [--compression]     (the station-size case: --rows 3600000)
      .venv/bin/python bench/bench_recording.py --sizes [--p1-repetitions 3]
      [--p1-static-s 3600] [--allan-hours 8]     (compact recordings, before/after)
      .venv/bin/python bench/bench_recording.py --filters   (each filter, per column)
"""

from __future__ import annotations

import argparse
import platform
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import h5py
import numpy as np

from imucalib.io import ColumnSpec, RecordingWriter, StreamSpec, open_recording
from imucalib.io.compression import COMPRESSIONS
from imucalib.io.recording import DEFAULT_CHUNK_ROWS

COLUMNS = ("gyro_x_rps", "gyro_y_rps", "gyro_z_rps", "accel_x_mps2", "accel_y_mps2",
           "accel_z_mps2")
UNITS = {"gyro": "rad/s", "accel": "m/s^2"}


def make_data(n_streams: int, n_rows: int) -> list[dict[str, np.ndarray]]:
    rng = np.random.default_rng(0)
    out = []
    for k in range(n_streams):
        d = {"time_s": np.arange(n_rows) / 1000.0 + k * 1e-5}
        for c in COLUMNS:
            d[c] = rng.standard_normal(n_rows)
        out.append(d)
    return out


def specs(n_streams: int) -> list[StreamSpec]:
    cols = {c: ColumnSpec(UNITS[c.split("_")[0]]) for c in COLUMNS}
    return [StreamSpec("imu", f"IMU-{k:04d}", cols) for k in range(n_streams)]


def write_imucalib(path: Path, data: list[dict[str, np.ndarray]], block: int,
                   compression: str | None = None) -> None:
    """Write through RecordingWriter (uncompressed unless asked: the library's overhead)."""
    n = len(data[0]["time_s"])
    with RecordingWriter(path, streams=specs(len(data)), overwrite=True,
                         compression=compression) as w:
        for a in range(0, n, block):
            for k, d in enumerate(data):
                w.append("imu", f"IMU-{k:04d}", {c: v[a:a + block] for c, v in d.items()})


def write_h5py(path: Path, data: list[dict[str, np.ndarray]], block: int) -> None:
    n = len(data[0]["time_s"])
    with h5py.File(path, "w", libver="latest") as f:
        dsets = []
        for k, d in enumerate(data):
            g = f.create_group(f"streams/imu/IMU-{k:04d}")
            dsets.append({c: g.create_dataset(c, shape=(0,), maxshape=(None,), dtype="f8",
                                              chunks=(DEFAULT_CHUNK_ROWS,)) for c in d})
        for a in range(0, n, block):
            for d, ds in zip(data, dsets, strict=True):
                for c, v in d.items():
                    blk = v[a:a + block]
                    dset = ds[c]
                    dset.resize((a + len(blk),))
                    dset[a:a + len(blk)] = blk
        f.flush()


def read_imucalib(path: Path, n_streams: int) -> int:
    total = 0
    with open_recording(path) as rec:
        for k in range(n_streams):
            d = rec.read_stream("imu", f"IMU-{k:04d}")
            total += d.time_s.nbytes + sum(v.nbytes for v in d.columns.values())
    return total


def iter_imucalib(path: Path, n_streams: int, chunk: int) -> int:
    total = 0
    with open_recording(path) as rec:
        for k in range(n_streams):
            for d in rec.iter_stream("imu", f"IMU-{k:04d}", chunk_samples=chunk):
                total += d.time_s.nbytes + sum(v.nbytes for v in d.columns.values())
    return total


def read_h5py(path: Path, n_streams: int) -> int:
    total = 0
    with h5py.File(path, "r") as f:
        for k in range(n_streams):
            g = f[f"streams/imu/IMU-{k:04d}"]
            arrays = {c: g[c][:] for c in g}  # a stream's columns held together, as read_stream
            total += sum(a.nbytes for a in arrays.values())
    return total


def iter_h5py(path: Path, n_streams: int, chunk: int) -> int:
    total = 0
    with h5py.File(path, "r") as f:
        for k in range(n_streams):
            g = f[f"streams/imu/IMU-{k:04d}"]
            dsets = [g[c] for c in g]
            n = dsets[0].shape[0]
            for a in range(0, n, chunk):
                arrays = [ds[a:a + chunk] for ds in dsets]
                total += sum(x.nbytes for x in arrays)
    return total


def best_times(funcs: list[Callable[[], object]], repeat: int) -> list[float]:
    """Best wall time of each function, running them in turn `repeat` times (interleaved, so
    that drifts of the page cache and the allocator affect all alike)."""
    best = [float("inf")] * len(funcs)
    for _ in range(repeat):
        for i, func in enumerate(funcs):
            t0 = time.perf_counter()
            func()
            best[i] = min(best[i], time.perf_counter() - t0)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--streams", type=int, default=8)
    parser.add_argument("--rows", type=int, default=400_000, help="rows per stream")
    parser.add_argument("--block", type=int, default=1000, help="rows per append")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--compression", action="store_true",
                        help="also time the writer's compressions and report file sizes")
    parser.add_argument("--sizes", action="store_true",
                        help="compact recordings vs float64 uncompressed on twin data (P1, Allan)")
    parser.add_argument("--p1-repetitions", type=int, default=3)
    parser.add_argument("--p1-static-s", type=float, default=3600.0)
    parser.add_argument("--allan-hours", type=float, default=8.0)
    parser.add_argument("--filters", action="store_true",
                        help="each filter's ratio and speed per column of twin IMU data")
    args = parser.parse_args()
    if args.filters:
        from compact_cases import column_filters  # bench/compact_cases.py

        column_filters()
        return
    if args.sizes:
        from compact_cases import run_sizes  # bench/compact_cases.py

        run_sizes(args.p1_repetitions, args.p1_static_s, args.allan_hours, args.repeat)
        return

    data = make_data(args.streams, args.rows)
    payload = sum(v.nbytes for d in data for v in d.values())
    print(f"imucalib Recording vs plain h5py {h5py.__version__} (HDF5 {h5py.version.hdf5_version}),"
          f" numpy {np.__version__}, Python {platform.python_version()}, {platform.machine()}")
    print(f"{args.streams} streams x 7 columns x {args.rows:,} rows float64 = "
          f"{payload / 1e6:,.1f} MB, appended {args.block} rows at a time; best of {args.repeat}")
    with tempfile.TemporaryDirectory() as tmp:
        ours, plain = Path(tmp) / "ours.h5", Path(tmp) / "plain.h5"
        t_ours, t_plain = best_times([lambda: write_imucalib(ours, data, args.block),
                                      lambda: write_h5py(plain, data, args.block)], args.repeat)
        print(f"\nwrite  imucalib {payload / t_ours / 1e6:8.1f} MB/s   h5py "
              f"{payload / t_plain / 1e6:8.1f} MB/s   ratio {t_plain / t_ours:5.2f}  "
              f"(imucalib speed / h5py speed; target ≥ 0.67)")
        print(f"       file size imucalib {ours.stat().st_size / 1e6:,.1f} MB, "
              f"h5py {plain.stat().st_size / 1e6:,.1f} MB")

        chunk = 1 << 18
        cases = [
            ("read whole", lambda: read_imucalib(ours, args.streams),
             lambda: read_h5py(plain, args.streams)),
            (f"iterate {chunk}", lambda: iter_imucalib(ours, args.streams, chunk),
             lambda: iter_h5py(plain, args.streams, chunk)),
        ]
        for name, f_ours, f_plain in cases:
            assert f_ours() == f_plain() == payload
            r_ours, r_plain = best_times([f_ours, f_plain], 2 * args.repeat + 1)
            print(f"{name:<15} imucalib {payload / r_ours / 1e6:8.1f} MB/s   h5py "
                  f"{payload / r_plain / 1e6:8.1f} MB/s   ratio {r_plain / r_ours:5.2f}")

        if args.compression:
            print("\nwriter compression (same data; random normal floats compress poorly, real "
                  "IMU data with quantised low bits compresses better):")
            for comp in COMPRESSIONS:
                path = Path(tmp) / f"c_{comp}.h5"
                (t,) = best_times([lambda c=comp, p=path: write_imucalib(p, data, args.block, c)],
                                  args.repeat)
                print(f"  {comp or 'none':<5} {payload / t / 1e6:8.1f} MB/s   file "
                      f"{path.stat().st_size / 1e6:8.1f} MB")


if __name__ == "__main__":
    main()
