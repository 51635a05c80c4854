"""Reading a large IMU log: whole-file against chunked, with pandas' own read as the floor.

Writes a synthetic log of ``--rows`` rows (default 3·10⁶, about 300 MB: ``time_s`` and the
six gyro and accelerometer columns in °/s and g, ``name [unit]`` headers, as a vendor export
converted to imucalib's layout would be) to a temporary directory, deleted afterwards, then
reads it, each way in a fresh Python process (so that one read's memory does not hide
another's):

- ``pandas``: ``pandas.read_csv`` of the whole file, no checks, no conversion (the floor the
  checks and conversions are measured against; its memory is the parsed file);
- ``read``: :func:`~imucalib.io.import_spec.read_imu_table` (every check, SI conversion, one
  frame);
- ``iter``: :func:`~imucalib.io.import_spec.iter_imu_table` at its default ``chunk_rows``
  (10⁶), each chunk dropped after use (what ``imucalib import`` and ``imucalib apply`` do);
- ``iter 250k``: the same with ``chunk_rows = 250 000``.

Printed per way: seconds, rows/s, peak memory (the process's peak resident set minus its
resident set after the imports, from ``resource.getrusage``), and both as ratios to
``pandas``. Repeated ``--repeat`` times, the fastest time and the smallest peak kept.

Run:  .venv/bin/python bench/bench_import.py [--rows 3000000] [--repeat 1]
"""

from __future__ import annotations

import argparse
import json
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HEADER = ("time_s [s],gyro_x_rps [deg/s],gyro_y_rps [deg/s],gyro_z_rps [deg/s],"
          "accel_x_mps2 [g],accel_y_mps2 [g],accel_z_mps2 [g]")
WAYS = {"pandas": None, "read": None, "iter": 1_000_000, "iter 250k": 250_000}


def write_log(path: Path, n_rows: int, block: int = 500_000) -> None:
    """Write `n_rows` rows of a 200 Hz log: noise on a static IMU, 9 significant digits."""
    rng = np.random.default_rng(0)
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(HEADER + "\n")
        for a in range(0, n_rows, block):
            k = np.arange(a, min(a + block, n_rows))
            data = np.column_stack([k / 200.0, rng.normal(0.0, 0.05, (k.size, 3)),
                                    rng.normal([0.0, 0.0, 1.0], 1e-3, (k.size, 3))])
            np.savetxt(fh, data, fmt=["%.6f"] + ["%.9g"] * 6, delimiter=",")


def _rss_bytes() -> int:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # Linux: KiB


def one(way: str, path: str) -> dict[str, float]:
    """Read `path` one way in this process; return rows, seconds and peak memory [bytes]."""
    import pandas as pd

    from imucalib.io.import_spec import iter_imu_table, read_imu_table

    base = _rss_bytes()
    t0 = time.perf_counter()
    if way == "pandas":
        rows = len(pd.read_csv(path))
    elif way == "read":
        rows = len(read_imu_table(path))
    else:
        rows = 0
        for chunk in iter_imu_table(path, chunk_rows=WAYS[way] or 1_000_000):
            rows += len(chunk)
            del chunk
    seconds = time.perf_counter() - t0
    return {"rows": rows, "seconds": seconds, "peak_bytes": _rss_bytes() - base}


def measure(way: str, path: Path) -> dict[str, float]:
    """Run :func:`one` in a fresh interpreter."""
    out = subprocess.run([sys.executable, __file__, "--one", way, str(path)], check=True,
                         capture_output=True, text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rows", type=int, default=3_000_000)
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--one", nargs=2, metavar=("WAY", "PATH"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        print(json.dumps(one(args.one[0], args.one[1])))
        return
    print(f"# bench_import: {args.rows:,} rows, Python {platform.python_version()}, "
          f"{platform.machine()}")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "log.csv"
        t0 = time.perf_counter()
        write_log(path, args.rows)
        size = path.stat().st_size
        print(f"wrote {size / 1e6:.0f} MB in {time.perf_counter() - t0:.1f} s")
        best: dict[str, dict[str, float]] = {}
        for _ in range(args.repeat):
            for way in WAYS:
                r = measure(way, path)
                assert r["rows"] == args.rows, (way, r)
                old = best.get(way)
                best[way] = r if old is None else {
                    "rows": r["rows"], "seconds": min(r["seconds"], old["seconds"]),
                    "peak_bytes": min(r["peak_bytes"], old["peak_bytes"])}
    floor = best["pandas"]
    print(f"{'way':<10} {'s':>7} {'rows/s':>12} {'× pandas':>9} {'peak MB':>9} "
          f"{'× pandas':>9}")
    for way, r in best.items():
        print(f"{way:<10} {r['seconds']:7.2f} {r['rows'] / r['seconds']:12,.0f} "
              f"{r['seconds'] / floor['seconds']:9.2f} {r['peak_bytes'] / 1e6:9.0f} "
              f"{r['peak_bytes'] / floor['peak_bytes']:9.2f}")
    print("(time × pandas: > 1 is slower; peak: resident memory above the imports)")


if __name__ == "__main__":
    main()
