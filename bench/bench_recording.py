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
      .venv/bin/python bench/bench_recording.py --codecs out/p1-run.h5 [--repeat 3]
      (each codec on copies of a closed recording: size, close, plain-h5py read)

``--codecs FILE`` converts copies of a closed Recording (e.g. ``make demo``'s ``out/p1-run.h5``)
with each codec as a closing writer does (:func:`~imucalib.io.recover.compact_recording` from
the uncompressed file: copy, verify, rename), and prints the file size, the time of that
conversion (best of ``--repeat``), the time the filter alone takes (every stream column written
from memory with plain h5py, best of ``--repeat``), the time plain h5py takes to read every
stream column (best of 2 × repeat + 1) and whether a plain h5py without ``hdf5plugin`` reads it
(a subprocess in which ``import hdf5plugin`` fails). ``gzip-4`` and ``lzf+shuffle`` are
variants for comparison, not names the writer accepts.
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
from imucalib.io.compression import COMPRESSIONS, DEFAULT_COMPRESSION
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


_PLAIN_READ = """
import sys
sys.modules["hdf5plugin"] = None  # a plain h5py: no plugin filter
import h5py
with h5py.File(sys.argv[1], "r") as f:
    for base in ("streams", "truth/streams"):
        if base in f:
            f[base].visititems(lambda n, o: o[()] if isinstance(o, h5py.Dataset) else None)
"""

#: The codecs of ``--codecs``: a writer's name, or (label, filter keywords) of a variant.
CODEC_VARIANTS: dict[str, dict[str, object]] = {
    "gzip-4": {"compression": "gzip", "compression_opts": 4, "shuffle": True},
    "lzf+shuffle": {"compression": "lzf", "shuffle": True},
}


def write_columns_h5py(path: Path, columns: dict[str, np.ndarray],
                      filters: dict[str, object]) -> None:
    """Write every column with plain h5py in chunks of the Recording's rows, with `filters`."""
    with h5py.File(path, "w") as f:
        for name, values in columns.items():
            f.create_dataset(name, data=values, maxshape=(None,),
                             chunks=(min(DEFAULT_CHUNK_ROWS, len(values)),), **filters)


def read_columns_h5py(path: Path) -> int:
    """Read every stream column with plain h5py; return the bytes read."""
    total = 0

    def read(_: str, obj: object) -> None:
        nonlocal total
        if isinstance(obj, h5py.Dataset):
            total += obj[()].nbytes

    with h5py.File(path, "r") as f:
        for base in ("streams", "truth/streams"):
            if base in f:
                f[base].visititems(read)
    return total


def run_codecs(source: Path, repeat: int) -> None:
    """Each codec on copies of the closed recording `source` (module docstring)."""
    import shutil
    import subprocess
    import sys
    from unittest import mock

    from imucalib.io import compact_recording
    from imucalib.io import recover as recover_module
    from imucalib.io.compression import column_filter_kwargs, ensure_plugin

    ensure_plugin()  # this process reads and writes every codec
    print(f"codecs on copies of {source} ({source.stat().st_size / 1e6:.1f} MB as given), "
          f"h5py {h5py.__version__} (HDF5 {h5py.version.hdf5_version}); close = "
          f"compact_recording from the uncompressed file (copy, verify, rename), best of "
          f"{repeat}; filter = every stream column written from memory by plain h5py, best of "
          f"{repeat}; read = plain h5py, every stream column, best of {2 * repeat + 1}")
    names: list[str | None] = [None, "gzip", "gzip-4", "lzf", "lzf+shuffle", "blosc-lz4",
                               "blosc-zstd"]
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp) / "base.h5"
        shutil.copyfile(source, base)
        compact_recording(base, None)
        payload = read_columns_h5py(base)
        columns: dict[str, np.ndarray] = {}
        with h5py.File(base, "r") as f:
            for group in ("streams", "truth/streams"):
                if group in f:
                    f[group].visititems(lambda n, o, g=group: columns.__setitem__(
                        f"{g}/{n}", o[()]) if isinstance(o, h5py.Dataset) else None)
        print(f"stream columns: {payload / 1e6:.1f} MB as stored uncompressed "
              f"(file {base.stat().st_size / 1e6:.1f} MB)")
        print(f"{'codec':<13} {'size MB':>8} {'ratio':>6} {'close s':>8} {'filter s':>9} "
              f"{'read s':>7}  plain h5py reads it")
        for name in names:
            path = Path(tmp) / f"{name}.h5"
            t_close = float("inf")
            for _ in range(repeat):
                shutil.copyfile(base, path)
                t0 = time.perf_counter()
                if name in CODEC_VARIANTS:
                    with mock.patch.object(recover_module, "column_filter_kwargs",
                                           lambda _c, kw=CODEC_VARIANTS[name]: dict(kw)):
                        compact_recording(path, "gzip")
                else:
                    compact_recording(path, name)
                t_close = min(t_close, time.perf_counter() - t0)
            kwargs = (CODEC_VARIANTS[name] if name in CODEC_VARIANTS
                      else column_filter_kwargs(name))
            (t_filter,) = best_times([lambda k=kwargs: write_columns_h5py(
                Path(tmp) / "filter.h5", columns, k)], repeat)
            (t_read,) = best_times([lambda p=path: read_columns_h5py(p)], 2 * repeat + 1)
            plain = subprocess.run([sys.executable, "-c", _PLAIN_READ, str(path)],
                                   capture_output=True, text=True, check=False)
            size = path.stat().st_size
            label = (name or "none") + (" (default)" if name == DEFAULT_COMPRESSION else "")
            print(f"{label:<13} {size / 1e6:8.1f} {base.stat().st_size / size:6.2f} "
                  f"{t_close:8.2f} {t_filter:9.2f} {t_read:7.2f}  "
                  f"{'yes' if plain.returncode == 0 else 'no'}")


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
    parser.add_argument("--codecs", type=Path, metavar="FILE",
                        help="each codec on copies of this closed recording (e.g. "
                             "out/p1-run.h5): size, close and plain-h5py read times")
    args = parser.parse_args()
    if args.codecs is not None:
        run_codecs(args.codecs, args.repeat)
        return
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
                label = (comp or "none") + (" (default)" if comp == DEFAULT_COMPRESSION else "")
                print(f"  {label:<16} {payload / t / 1e6:8.1f} MB/s   file "
                      f"{path.stat().st_size / 1e6:8.1f} MB")


if __name__ == "__main__":
    main()
