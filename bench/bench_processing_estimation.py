"""Timings of the processing and estimation layers, with in-process reference points.

Run: ``.venv/bin/python bench/bench_processing_estimation.py``. Prints the median of a few runs of
each operation and, where there is one, the ratio to a plain numpy/scipy reference computed in
the same process (a ratio, not an absolute time, is what compares across machines).
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np
from scipy import stats

from imucalib import units
from imucalib.estimation import build_triad_design, refine_with_kalman, solve_weighted_lsq
from imucalib.models.noise import NoiseModel, simulate_noise
from imucalib.processing import (
    compute_window_statistics,
    detect_segments,
    lowpass_zero_phase,
    reject_outliers_3sigma,
    reject_outliers_grubbs,
    synchronize,
)


def timed(fn: Callable[[], object], repeat: int = 5) -> float:
    out = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return float(np.median(out))


def naive_grubbs(x: np.ndarray, alpha: float) -> int:
    """Textbook iterated Grubbs: recompute mean and s over all kept samples at every step."""
    x = x.copy()
    n_out = 0
    while x.size > 2:
        n = x.size
        dev = np.abs(x - x.mean())
        g = dev.max() / x.std(ddof=1)
        t = stats.t.isf(alpha / (2 * n), n - 2)
        if g <= (n - 1) / np.sqrt(n) * np.sqrt(t**2 / (n - 2 + t**2)):
            break
        x = np.delete(x, np.argmax(dev))
        n_out += 1
    return n_out


def main() -> None:
    rng = np.random.default_rng(0)
    fs = 100.0
    n = 360_000  # one hour at 100 Hz (docs/p1.md, step 2)
    x = rng.normal(0.0, 1.0, (n, 3))
    x[rng.integers(0, n, 200)] += 20.0
    rows = []
    t_3s = timed(lambda: reject_outliers_3sigma(x))
    rows.append(("3σ robust, 1 h × 3 axes", t_3s, None))
    col = x[:, 0].copy()
    t_g = timed(lambda: reject_outliers_grubbs(col, alpha=0.05))
    t_naive = timed(lambda: naive_grubbs(col, 0.05), repeat=1)
    rows.append(("Grubbs (sorted sums), 1 h, ~70 outliers", t_g, t_naive))
    t_lp = timed(lambda: lowpass_zero_phase(x, fs, bandwidth_hz=40.0))
    rows.append(("zero-phase Butterworth, 1 h × 3", t_lp, None))
    t_src = np.arange(n) / fs
    t_tgt = np.arange(1.0, n / fs - 1.0, 0.01)
    t_sync = timed(lambda: synchronize(t_src, x, t_tgt, signal_bandwidth_hz=10.0))
    t_interp = timed(lambda: [np.interp(t_tgt, t_src, x[:, j]) for j in range(3)])
    rows.append(("synchronize 1 h onto 100 Hz targets", t_sync, t_interp))
    noise = simulate_noise(NoiseModel(white_density=0.3 * units.DEG_PER_RTH,
                                      bias_instability=8.0 * units.DEG_PER_H,
                                      random_walk=30.0 * units.DEG_PER_H_RTH), n, 1 / fs, rng)
    rows.append(("window statistics, allan-fit, 1 h × 3", timed(
        lambda: compute_window_statistics(noise, fs)), None))
    gyro = noise.copy()
    gyro[n // 3: 2 * n // 3, 2] += 50.0 * units.DEG
    rows.append(("detect_segments, 1 h × 3", timed(
        lambda: detect_segments(t_src, gyro, window_s=1.0)), None))
    up = rng.normal(size=(20_000, 3))
    up /= np.linalg.norm(up, axis=1, keepdims=True)
    d = build_triad_design(units.G0_MPS2 * up)
    z = rng.normal(0.0, 1e-3, d.H.shape[0])
    t_lsq = timed(lambda: solve_weighted_lsq(d.H, z, param_names=d.param_names, sigma=1e-3))
    t_np = timed(lambda: np.linalg.lstsq(d.H, z, rcond=None))
    rows.append(("WLS 60 000 × 12 (QR+SVD, checks, residuals)", t_lsq, t_np))
    blocks = [d.H[3 * k: 3 * k + 3] for k in range(500)]
    zb = [z[3 * k: 3 * k + 3] for k in range(500)]
    t_kf = timed(lambda: refine_with_kalman(blocks, zb, [1e-6] * 500,
                                            param_names=d.param_names), repeat=3)
    rows.append(("Kalman refinement, 500 blocks of 3", t_kf, None))
    width = max(len(r[0]) for r in rows)
    print(f"{'operation':<{width}}  {'median s':>9}  {'ratio to reference':>18}")
    for name, t, ref in rows:
        ratio = f"{t / ref:18.2f}" if ref else f"{'—':>18}"
        print(f"{name:<{width}}  {t:9.4f}  {ratio}")
    print("references: naive Grubbs (recompute every step), np.interp per column, "
          "np.linalg.lstsq")


if __name__ == "__main__":
    main()
