"""Cost of opening a Recording (validation and the forked metadata probe) against plain h5py.

Opens and closes the same file repeatedly, interleaved, and prints the median and minimum of
each way of opening, and their ratio to the floor (plain ``h5py.File`` open, reading the root's
attributes, close):

- ``h5py``: the floor;
- ``no probe``: :func:`~imucalib.io.opening.open_recording` with ``probe=False`` (layout, commit
  counts, tables and time bases checked in this process);
- ``probe``: ``open_recording`` as users get it (the metadata checks first run in a forked child
  with a time limit, see ``docs/recording-format.md``);
- ``fork``: a bare ``os.fork`` + ``waitpid`` of this process, the part of the probe no check can
  avoid.

Two files: a small one (three streams, 42 000 rows) and one 7-column IMU stream of ``--rows``
rows (default 10^7, about 560 MB; written once to ``--dir``, default a temporary directory).

Run:  .venv/bin/python bench/bench_open.py [--rows 10000000] [--repeat 20] [--dir DIR]
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import h5py
import numpy as np

from imucalib.io import ColumnSpec, RecordingWriter, StreamSpec, open_recording

COLUMNS = ("gyro_x_rps", "gyro_y_rps", "gyro_z_rps", "accel_x_mps2", "accel_y_mps2",
           "accel_z_mps2")


def write_file(path: Path, n_rows: int, n_streams: int = 1, block: int = 1 << 20) -> None:
    """Write `n_streams` IMU streams of `n_rows` rows, with two steps."""
    cols = {c: ColumnSpec("rad/s" if c.startswith("gyro") else "m/s^2") for c in COLUMNS}
    specs = [StreamSpec("imu", f"IMU-{k:04d}", cols) for k in range(n_streams)]
    rng = np.random.default_rng(0)
    with RecordingWriter(path, streams=specs, metadata={"plan_toml": ""}) as w:
        for spec in specs:
            for a in range(0, n_rows, block):
                b = min(n_rows, a + block)
                d = {"time_s": np.arange(a, b) / 1000.0}
                d.update({c: rng.standard_normal(b - a) for c in COLUMNS})
                w.append(spec.device, spec.unit, d)
        s = w.begin_step("static", "one", 0.0)
        w.update_step(s, t_end_s=n_rows / 1000.0, status="done")


def h5py_floor(path: Path) -> None:
    with h5py.File(path, "r") as f:
        dict(f.attrs)


def no_probe(path: Path) -> None:
    open_recording(path, probe=False).close()


def with_probe(path: Path) -> None:
    open_recording(path).close()


def bare_fork(_: Path) -> None:
    pid = os.fork()
    if pid == 0:
        os._exit(0)
    os.waitpid(pid, 0)


def measure(path: Path, repeat: int) -> dict[str, list[float]]:
    ways: dict[str, Callable[[Path], None]] = {"h5py": h5py_floor, "no probe": no_probe,
                                               "probe": with_probe, "fork": bare_fork}
    times: dict[str, list[float]] = {k: [] for k in ways}
    for fn in ways.values():  # warm the page cache and imports
        fn(path)
    for _ in range(repeat):
        for name, fn in ways.items():
            t0 = time.perf_counter()
            fn(path)
            times[name].append(time.perf_counter() - t0)
    return times


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=10_000_000)
    ap.add_argument("--repeat", type=int, default=20)
    ap.add_argument("--dir", type=Path, default=None)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(dir=args.dir) as d:
        files = {"small (3 x 14 000 rows)": Path(d) / "small.h5",
                 f"large (1 x {args.rows} rows)": Path(d) / "large.h5"}
        write_file(files["small (3 x 14 000 rows)"], 14_000, n_streams=3)
        write_file(files[f"large (1 x {args.rows} rows)"], args.rows)
        print(f"{'file':28s} {'way':9s} {'median ms':>10s} {'min ms':>8s} {'median/h5py':>12s}")
        for label, path in files.items():
            size_mb = path.stat().st_size / 1e6
            t = measure(path, args.repeat)
            floor = statistics.median(t["h5py"])
            for name, v in t.items():
                med = statistics.median(v)
                print(f"{label:28s} {name:9s} {med * 1e3:10.2f} {min(v) * 1e3:8.2f} "
                      f"{med / floor:12.1f}")
            print(f"{'':28s} ({size_mb:.0f} MB)")


if __name__ == "__main__":
    main()
