"""Speed of the twin's noise generation and output stage (one gyro triad + one accel triad).

Prints six-channel samples per second for:

- ``full``: NoiseGenerator (white + quantization + flicker + random walk + rate ramp + Markov)
  plus OutputChain (2nd-order Butterworth low-pass, saturation, quantization) for both triads;
- ``noise only`` and ``output chain only``;
- ``full, fast Markov``: the same with a Markov time constant too short for the slow grid
  (T_c = 20 ms at 1 kHz), which runs at the full rate;
- ``reference``: numpy's bare ``Generator.standard_normal`` of the same size (six channels),

and the ratio full / reference. Target of the project: ``full`` ≥ 5 M samples/s per core.

Run:  .venv/bin/python bench/bench_noise.py [--samples 5000000] [--chunk 65536] [--repeat 3]
"""

from __future__ import annotations

import os

# one core: keep BLAS (used by the slow-grid interpolation) single-threaded
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402

import numpy as np  # noqa: E402

from imucalib import units  # noqa: E402
from imucalib.models.noise import NoiseModel  # noqa: E402
from imucalib.models.noise_generator import NoiseGenerator  # noqa: E402
from imucalib.models.sensor import OutputChain, SensorSpec  # noqa: E402

FS_HZ = 1000.0


def gyro_model(markov_time_constant_s: float) -> NoiseModel:
    return NoiseModel.from_datasheet(
        arw_deg_rth=0.125,
        bias_instability_dph=1.0,
        rrw_deg_h_rth=0.5,
        rate_ramp_dph_per_h=[0.5, -0.3, 0.1],
        quantization_arcsec=0.5,
        markov_sigma_dph=0.5,
        markov_time_constant_s=markov_time_constant_s,
    )


def accel_model(markov_time_constant_s: float) -> NoiseModel:
    return NoiseModel.from_datasheet(
        noise_density_ug_rthz=50.0,
        bias_instability_ug=20.0,
        random_walk_ug_rth=10.0,
        rate_ramp_ug_per_h=[1.0, -2.0, 0.5],
        quantization_mps=1e-4,
        markov_sigma_ug=10.0,
        markov_time_constant_s=markov_time_constant_s,
    )


GYRO_SPEC = SensorSpec(range=1000 * units.DEG_PER_S, resolution_bits=20, bandwidth_hz=200.0)
ACCEL_SPEC = SensorSpec(range=16 * units.G0_MPS2, resolution_bits=20, bandwidth_hz=200.0)
GYRO_TRUE = np.array([1e-5, 2e-5, 5e-5])  # Earth-rate-like static input [rad/s]
ACCEL_TRUE = np.array([0.0, 0.0, units.G0_MPS2])  # level, z up [m/s²]


def run_twin(n: int, chunk: int, *, noise: bool, chain: bool, tc_s: float, seed: int) -> None:
    rng = np.random.default_rng(seed)
    gens = (NoiseGenerator(gyro_model(tc_s), 1 / FS_HZ, rng),
            NoiseGenerator(accel_model(tc_s), 1 / FS_HZ, rng))
    chains = (OutputChain(GYRO_SPEC, FS_HZ), OutputChain(ACCEL_SPEC, FS_HZ))
    truth = (GYRO_TRUE, ACCEL_TRUE)
    done = 0
    while done < n:
        c = min(chunk, n - done)
        for gen, out, true in zip(gens, chains, truth, strict=True):
            if noise:
                x = gen.generate(c)
                x += true
            else:
                x = np.broadcast_to(true, (c, 3))
            if chain:
                out.process(x)
        done += c


def run_reference(n: int, chunk: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    done = 0
    while done < n:
        c = min(chunk, n - done)
        rng.standard_normal((c, 6))
        done += c


def best_rate(fn: Callable[[], None], n: int, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return n / best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=5_000_000)
    parser.add_argument("--chunk", type=int, default=1 << 16)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    n, chunk, rep = args.samples, args.chunk, args.repeat
    print(f"numpy {np.__version__}, python {platform.python_version()}, {platform.machine()}")
    print(f"{n:,} six-channel samples at {FS_HZ:g} Hz in chunks of {chunk:,}; best of {rep}")
    slow_tc, fast_tc = 30.0, 0.02
    cases: list[tuple[str, Callable[[], None]]] = [
        ("full (Markov T_c = 30 s)",
         lambda: run_twin(n, chunk, noise=True, chain=True, tc_s=slow_tc, seed=1)),
        ("noise only", lambda: run_twin(n, chunk, noise=True, chain=False, tc_s=slow_tc, seed=1)),
        ("output chain only",
         lambda: run_twin(n, chunk, noise=False, chain=True, tc_s=slow_tc, seed=1)),
        ("full, fast Markov (T_c = 20 ms)",
         lambda: run_twin(n, chunk, noise=True, chain=True, tc_s=fast_tc, seed=1)),
        ("reference: standard_normal((n, 6))", lambda: run_reference(n, chunk, seed=1)),
    ]
    rates = {}
    for label, fn in cases:
        rates[label] = best_rate(fn, n, rep)
        print(f"  {label:36s} {rates[label] / 1e6:7.2f} M samples/s")
    full, fast, ref = rates[cases[0][0]], rates[cases[3][0]], rates[cases[-1][0]]
    print(f"  ratio full / reference               {full / ref:7.2f}")
    print(f"  ratio full, fast Markov / reference  {fast / ref:7.2f}")
    verdict = "met" if min(full, fast) >= 5e6 else "NOT met"
    print(f"  target ≥ 5 M samples/s per core (both full cases): {verdict}")


if __name__ == "__main__":
    main()
