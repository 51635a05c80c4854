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
from imucalib.models.noise import NoiseModel
from imucalib.models.noise_generator import simulate_noise
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


def best_of(fn: Callable[[], object], repeat: int = 3) -> float:
    out = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return min(out)


def _ref_time_base(counter: np.ndarray, host: np.ndarray) -> np.ndarray:
    """reconstruct_time_base as it was: np.polyfit fits, medians recomputed, checked copies."""
    c = np.array(counter, dtype=np.float64)
    assert np.all(np.isfinite(c)) and not np.any(c != np.round(c))
    t = np.array(host, dtype=np.float64)
    x = c - c[0]
    y = t - t[0]
    keep = np.ones(c.size, dtype=bool)
    coef = np.polyfit(x, y, 1)
    for _ in range(2):
        resid = y - np.polyval(coef, x)
        mad = 1.4826 * float(np.median(np.abs(resid[keep] - np.median(resid[keep]))))
        new_keep = np.abs(resid - np.median(resid[keep])) <= 5.0 * mad if mad > 0 else keep
        if new_keep.sum() < 3 or np.array_equal(new_keep, keep):
            break
        keep = new_keep
        coef = np.polyfit(x[keep], y[keep], 1)
    return t[0] + coef[1] + coef[0] * x


def _ref_jitter(t: np.ndarray) -> float:
    t = np.array(t, dtype=np.float64)
    d = np.diff(t)
    k = np.concatenate([[0.0], np.cumsum(np.maximum(np.round(d / np.median(d)), 1.0))])
    assert np.unique(k).size >= 3
    coef = np.polyfit(k, t - t[0], 1)
    return float(np.sqrt(np.sum(((t - t[0]) - np.polyval(coef, k)) ** 2) / (t.size - 2)))


def _fixed_costs_at(n: int, rng: np.random.Generator) -> None:
    from scipy import signal

    from imucalib.processing import estimate_timestamp_jitter_s, reconstruct_time_base

    k = np.arange(n)
    host = 10.0 + k / 1000.0 + rng.exponential(3e-4, n)
    host[n // 3] += 0.05
    stamps = np.sort(host) + k * 1e-9
    x = rng.normal(size=(n, 6))
    rows = [
        ("reconstruct_time_base", lambda: reconstruct_time_base(k, host),
         lambda: _ref_time_base(k, host)),
        ("estimate_timestamp_jitter_s", lambda: estimate_timestamp_jitter_s(stamps),
         lambda: _ref_jitter(stamps)),
        ("lowpass_zero_phase (6 columns)",
         lambda: lowpass_zero_phase(x, 1000.0, bandwidth_hz=200.0),
         lambda: signal.sosfiltfilt(signal.butter(4, 50.0, output="sos", fs=1000.0),
                                    np.array(x), axis=0)),
    ]
    for name, new, ref in rows:
        t_new, t_ref = best_of(new), best_of(ref)
        print(f"{name:<40}  {n:>7}  {1e3 * t_new:8.3f}  {1e3 * t_ref:8.3f}  {t_new / t_ref:6.2f}")
    t_ws = best_of(lambda: compute_window_statistics(x, 1000.0))
    print(f"{'compute_window_statistics (allan-fit)':<40}  {n:>7}  {1e3 * t_ws:8.3f}  "
          f"{'—':>8}  {'—':>6}")


def fixed_costs() -> None:
    """Per-window fixed costs: each function against the way it was computed before."""
    from imucalib.models.noise import compute_theoretical_adev

    rng = np.random.default_rng(1)
    model = NoiseModel(white_density=1e-3, bias_instability=1e-4, random_walk=1e-5)
    print(f"{'per-window function (best of 3)':<40}  {'n':>7}  {'new ms':>8}  {'ref ms':>8}  "
          f"{'ratio':>6}")
    for n in (600_000, 6_000):
        _fixed_costs_at(n, rng)
    tau = np.array([6.0])
    t_adev = best_of(lambda: [compute_theoretical_adev(model, tau) for _ in range(1000)])
    print(f"{'compute_theoretical_adev, 1 τ (µs/call)':<40}  {1:>7}  {t_adev * 1e3:8.2f}")
    print("references: np.polyfit line fits with the medians recomputed, a fresh butter design "
          "+ sosfiltfilt; compute_window_statistics and compute_theoretical_adev: see "
          "docs/performance.md (timed against the previous code)")


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
    import sys

    if "--fixed-costs" in sys.argv:
        fixed_costs()
    else:
        main()
