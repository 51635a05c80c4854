"""Generation speed of the digital twin (whole IMU synthesis), against numpy's own RNG floor.

Measures :meth:`imucalib.sim.rig.TwinRig.generate` in virtual time, one core, for:

- ``static``: one tactical IMU (full noise model: white, quantization, flicker bank, random walk;
  full error model incl. K2, g-sensitivity and lever arms; 200 Hz output low-pass, 24-bit
  quantization, saturation) on a fixed plate, 1 kHz;
- ``table at rest``: the same IMU on a dual-axis table holding a position;
- ``table spinning``: the same IMU on the dual-axis table at 100 °/s about roll (every sample's
  attitude, rate and specific force computed, incl. wobble and non-orthogonality);
- ``8 IMUs, hour``: eight IMUs on an array fixture for an hour at 1 kHz (the issue's yard-stick,
  extrapolated from ``--seconds`` of virtual time),

and prints six-channel samples per second, and the ratio to numpy's bare
``Generator.standard_normal((n, 6))`` of the same size (the floor any synthesis sits above).
Target of the project: ≥ 5 M six-channel samples/s per core with the full noise model.

Run:  .venv/bin/python bench/bench_twin.py [--seconds 300] [--chunk 60] [--repeat 3]
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402

import numpy as np  # noqa: E402

from imucalib import units  # noqa: E402
from imucalib.models.earth import Site  # noqa: E402
from imucalib.models.imu import sample_imu_model  # noqa: E402
from imucalib.sim.fixture import array_fixture, single_imu_fixture  # noqa: E402
from imucalib.sim.rig import TwinRig  # noqa: E402
from imucalib.sim.synth import SimImu  # noqa: E402
from imucalib.sim.table import RateTableSpec, SimRateTable  # noqa: E402

SITE = Site(latitude_deg=45.0)


def make_rig(kind: str, n_imus: int = 1) -> TwinRig:
    names = [f"IMU-{i}" for i in range(n_imus)]
    imus = [SimImu(n, sample_imu_model("tactical", rng=i)) for i, n in enumerate(names)]
    fixture = (single_imu_fixture(name=names[0]) if n_imus == 1
               else array_fixture(np.c_[np.arange(n_imus) * 0.05, np.zeros((n_imus, 2))], names))
    table = None
    if kind != "static":
        table = SimRateTable(RateTableSpec.dual_axis_pitch_roll("high"), rng=1)
        if kind == "spinning":
            table.command_rate(1, 100.0 * units.DEG, 0.0)
        else:
            table.command_position(0, 0.3, 0.0)
    rig = TwinRig(site=SITE, fixture=fixture, imus=imus, table=table, rng=1)
    if table is not None:
        rig.generate(30.0)  # past the move or ramp: measure the steady state
    return rig


def time_generation(rig: TwinRig, seconds: float, chunk_s: float) -> float:
    t0 = rig.now_s
    start = time.perf_counter()
    t = t0
    while t < t0 + seconds:
        t = min(t + chunk_s, t0 + seconds)
        rig.generate(t)
    return time.perf_counter() - start


def best(make: Callable[[], TwinRig], seconds: float, chunk_s: float, repeat: int) -> float:
    return min(time_generation(make(), seconds, chunk_s) for _ in range(repeat))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=300.0, help="virtual seconds per case")
    parser.add_argument("--chunk", type=float, default=60.0, help="virtual seconds per generate")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    fs = 1000.0
    n = int(args.seconds * fs)
    print(f"imucalib twin, numpy {np.__version__}, Python {platform.python_version()}, "
          f"{platform.machine()}; {args.seconds:g} s virtual at {fs:g} Hz per IMU, chunks of "
          f"{args.chunk:g} s; best of {args.repeat}")
    rng = np.random.default_rng(0)
    ref_s = min(_timed(lambda: rng.standard_normal((n, 6))) for _ in range(args.repeat))
    ref_rate = n / ref_s
    cases = [("static", lambda: make_rig("static"), 1),
             ("table at rest", lambda: make_rig("rest"), 1),
             ("table spinning", lambda: make_rig("spinning"), 1),
             ("8 IMUs on a table at rest", lambda: make_rig("rest", 8), 8)]
    print(f"  {'reference: standard_normal((n, 6))':34s} {ref_rate / 1e6:7.2f} M samples/s")
    for label, make, n_imus in cases:
        dt = best(make, args.seconds, args.chunk, args.repeat)
        rate = n * n_imus / dt
        line = (f"  {label:34s} {rate / 1e6:7.2f} M samples/s   ratio to reference "
                f"{rate / ref_rate:5.2f}")
        if n_imus == 8:
            line += f"   an hour for 8 IMUs: {3600.0 * fs * 8 / rate:5.1f} s"
        print(line)
    print("target: ≥ 5 M six-channel samples/s per core with the full noise model")


def _timed(func: Callable[[], object]) -> float:
    start = time.perf_counter()
    func()
    return time.perf_counter() - start


if __name__ == "__main__":
    main()
