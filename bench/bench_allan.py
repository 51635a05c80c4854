"""Speed of imucalib's overlapping Allan deviation against allantools, in one process.

Run ``.venv/bin/python bench/bench_allan.py`` (add ``--streamed-samples 1e9`` for the day-scale
streamed run, which takes minutes and writes an 8 GB scratch file).

What it prints
--------------
1. For 10^6, 10^7 (and 10^8 when there is memory for allantools' copies) white-noise rate
   samples at 1 kHz, octave τ (``taus="octave"``): the best-of-N wall time of
   ``allantools.oadev(y, rate, data_type="freq", taus="octave")`` and of
   ``imucalib.analysis.compute_oadev(y, rate, identify_noise=False)`` on the same array (both
   include the rate → phase integration), their ratio, samples/s, the largest relative difference
   of the two results, and imucalib's time with its per-τ noise identification (the default).
2. A streamed run (:func:`imucalib.analysis.compute_deviations_streaming`, scratch file) in a
   child process: samples, wall time, samples/s, and peak memory (``tracemalloc`` peak of the
   Python/numpy allocations and the child's peak RSS).

Speed is measured here, never asserted by a test.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
import tracemalloc

import numpy as np

RATE_HZ = 1000.0


def peak_rss_mb() -> float:
    """Peak resident set of this process [MiB]: VmHWM (Linux, reset by exec), else ru_maxrss.

    ru_maxrss of a child started by fork + exec can still hold the parent's size at the fork.
    """
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def best_time(fn, repeats: int) -> tuple[float, object]:
    best, out = float("inf"), None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def mem_available_gb() -> float:
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) / 2**20
    except OSError:
        pass
    return float("nan")


def in_memory(sizes: list[int], repeats: int) -> None:
    import allantools

    from imucalib.analysis import compute_oadev, kernel_backend

    rng = np.random.default_rng(1)
    compute_oadev(rng.standard_normal(10_000), RATE_HZ)  # compile / load the kernels
    print(f"kernels: {kernel_backend()}; allantools {allantools.__version__}; "
          f"numpy {np.__version__}")
    threads = os.cpu_count() or 1
    print(f"{'samples':>11} {'taus':>4} {'allantools':>11} {'imucalib':>10} {'ratio':>6} "
          f"{'Msamples/s':>10} {'max rel diff':>12} {'with noise-id':>13} "
          f"{'1 thread':>9} {'ratio':>6}")
    for n in sizes:
        y = rng.standard_normal(n)
        reps = repeats if n <= 10**7 else 1
        t_at, (tau_at, dev_at, _, _) = best_time(
            lambda y=y: allantools.oadev(y, rate=RATE_HZ, data_type="freq", taus="octave"),
            max(1, reps - 1))
        t_us, res = best_time(lambda y=y: compute_oadev(y, RATE_HZ, identify_noise=False), reps)
        t_id, _ = best_time(lambda y=y: compute_oadev(y, RATE_HZ), 1)
        os.environ["IMUCALIB_THREADS"] = "1"
        try:
            t_one, res_one = best_time(
                lambda y=y: compute_oadev(y, RATE_HZ, identify_noise=False), reps)
        finally:
            del os.environ["IMUCALIB_THREADS"]
        assert np.array_equal(res_one.deviation, res.deviation)  # threads change nothing
        common = np.isin(tau_at, res.taus_s)
        diff = float(np.max(np.abs(res.deviation / dev_at[common] - 1)))
        print(f"{n:>11.0e} {res.taus_s.size:>4} {t_at:>10.3f}s {t_us:>9.4f}s "
              f"{t_at / t_us:>5.1f}x {n / t_us / 1e6:>10.1f} {diff:>12.1e} {t_id:>12.4f}s "
              f"{t_one:>8.4f}s {t_at / t_one:>5.1f}x", flush=True)
        del y
    print(f"(imucalib shares the τ values between {threads} thread(s), IMUCALIB_THREADS "
          "overrides; results are bit-identical for any thread count; allantools is one numpy "
          "thread)")


def streamed_child(n: int, chunk: int) -> None:
    """Run in a fresh process: feed n samples in chunks, compute octave OADEV, report."""
    from imucalib.analysis import AllanStream, compute_oadev

    rng = np.random.default_rng(2)
    compute_oadev(rng.standard_normal(10_000), RATE_HZ)  # load the kernels before timing
    base_rss = peak_rss_mb()
    tracemalloc.start()
    t_gen = 0.0
    t0 = time.perf_counter()
    with AllanStream(RATE_HZ, scratch_dir=tempfile.gettempdir()) as stream:
        done = 0
        while done < n:
            k = min(chunk, n - done)
            g0 = time.perf_counter()
            y = rng.standard_normal(k)
            t_gen += time.perf_counter() - g0
            stream.append(y)
            done += k
        t_fed = time.perf_counter()
        res = stream.compute(["oadev"], identify_noise=False)["oadev"]
        t_end = time.perf_counter()
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    rss = peak_rss_mb()
    print(json.dumps({"n": n, "taus": int(res.taus_s.size), "wall_s": t_end - t0,
                      "generate_s": t_gen, "feed_s": t_fed - t0 - t_gen,
                      "compute_s": t_end - t_fed, "tracemalloc_peak_mb": peak / 2**20,
                      "peak_rss_mb": rss, "base_rss_mb": base_rss,
                      "adev_tau0": float(res.deviation[0])}))


def streamed(n: int) -> None:
    out = subprocess.run([sys.executable, __file__, "--_child", str(n)], capture_output=True,
                         text=True, check=True)
    r = json.loads(out.stdout.strip().splitlines()[-1])
    work = r["wall_s"] - r["generate_s"]
    print(f"streamed {r['n']:.0e} samples ({r['taus']} octave τ, scratch file): "
          f"{r['wall_s']:.1f} s wall = {r['generate_s']:.1f} s generating + {r['feed_s']:.1f} s "
          f"appending + {r['compute_s']:.1f} s computing; {r['n'] / work / 1e6:.1f} Msamples/s "
          f"without generation; peak memory: tracemalloc {r['tracemalloc_peak_mb']:.0f} MiB, "
          f"RSS {r['peak_rss_mb']:.0f} MiB ({r['base_rss_mb']:.0f} MiB after importing and "
          f"loading the kernels); ADEV(1 ms) = {r['adev_tau0']:.6f} (white noise: ≈ 1)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--streamed-samples", type=float, default=1e8,
                    help="samples of the streamed run (1e9 for the day-scale check; minutes)")
    ap.add_argument("--skip-1e8", action="store_true", help="do not run 1e8 in memory")
    ap.add_argument("--sizes", type=float, nargs="+", default=None,
                    help="in-memory sizes to run instead of 1e6 1e7 (1e8)")
    ap.add_argument("--streamed-only", action="store_true", help="only the streamed run")
    ap.add_argument("--_child", type=float, default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args._child is not None:
        streamed_child(int(args._child), 1 << 20)
        return
    if args.streamed_only:
        streamed(int(args.streamed_samples))
        return
    sizes = [10**6, 10**7]
    avail = mem_available_gb()
    if args.sizes:
        sizes = [int(v) for v in args.sizes]
    elif args.skip_1e8:
        print("1e8 in memory: skipped (--skip-1e8)")
    elif avail >= 10:
        sizes.append(10**8)
    else:
        print(f"1e8 in memory: skipped, {avail:.1f} GiB available (allantools needs about 5 GiB "
              "of copies, imucalib 1.6 GiB)")
    print(f"machine: {os.cpu_count()} CPU(s)")
    in_memory(sizes, args.repeats)
    streamed(int(args.streamed_samples))
    if args.streamed_samples < 1e9:
        print("(the 1e9-sample streamed run is opt-in: --streamed-samples 1e9)")


if __name__ == "__main__":
    main()
