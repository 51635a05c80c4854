"""Automatic static / rotating segmentation of a bare IMU stream (no step records).

Contents
--------
:class:`Segment`
    One detected interval: kind, sample range, times, mean angular-rate vector.
:class:`SegmentationResult`, :func:`detect_segments`
    All segments, per-sample labels and the thresholds used.

Method
------
In the spirit of the static detector of Tedaldi, Pretto & Menegatti (ICRA 2014) [1]_, extended
to constant-rate rotation. With a centred moving window of w samples (`window_s`), for each
sample:

- the windowed mean rate ω̄ (per axis) and the *unsteadiness* ζ_g = Σ_axes var_w(ω), the
  variance of the gyro about its window mean (noise, plus a²w_s²/12 during an acceleration a;
  accumulated block-wise so that it stays exact at any rate); with an accelerometer, ζ_a likewise
  for the specific force;
- the noise floor ζ_g,0 (ζ_a,0) is the 10th percentile of ζ_g (ζ_a) over the record — the
  record must be at least 10 % steady — as Tedaldi's threshold is k·‖var_init‖ from an initial
  static period, but without needing one;
- a sample is **steady** when √ζ_g ≤ max(k_σ·√ζ_g,0, `rate_stability_rps`): k_σ
  (`threshold_factor`, default 3) times the noise in standard deviation, or the table's rate
  stability (docs/p1.md, step 3: 0.1 °/s), whichever is larger — so table rate ripple at high
  rates does not break a constant-rate step of a quiet (navigation-grade) IMU, while a table
  acceleration a makes √ζ_g ≈ a·w_s/√12 (2.9 °/s for 10 °/s² over 1 s) and is rejected;
- a steady sample is **static** when ‖ω̄‖ < `static_rate_threshold_rps` (default 2.5 °/s, above
  the bias of a consumer MEMS gyro and below the slowest rate of imucalib's plans, 5 °/s) and,
  with an accelerometer, √ζ_a ≤ k_σ·√ζ_a,0 (no handling or vibration); it is **rotating** when
  ‖ω̄‖ ≥ the threshold.

Runs of equal labels shorter than `min_static_s` / `min_rotating_s` are dropped (labelled
transition), and a rotating run is split where its windowed mean rate leaves a band of
±max(`rate_stability_rps`, 3·√ζ_g,0) around the run's median rate. Because every window must lie
inside the steady interval, segments start and end about w/2 inside the true steady interval
(plus the table's settling): no transition sample enters a segment. The IMU's sampling is
assumed uniform (its median interval is used).

References
----------
.. [1] D. Tedaldi, A. Pretto and E. Menegatti, "A robust and easy to implement method for IMU
   calibration without external equipments", Proc. IEEE ICRA 2014, pp. 3042–3049.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib import units
from imucalib._checks import as_array, check_positive
from imucalib.errors import InvalidInputError
from imucalib.processing import _variance_kernel
from imucalib.processing._common import as_time

__all__ = ["SEGMENT_LABELS", "Segment", "SegmentKind", "SegmentationResult", "detect_segments"]

SegmentKind = Literal["static", "rotating"]
#: Values of :attr:`SegmentationResult.labels`.
SEGMENT_LABELS: dict[int, str] = {0: "transition", 1: "static", 2: "rotating"}
_FLOOR_PERCENTILE = 10.0
_MIN_WINDOW = 5


@dataclass(frozen=True, eq=False)
class Segment:
    """One detected steady interval.

    Attributes
    ----------
    kind : {"static", "rotating"}
        What the IMU did.
    start_index, stop_index : int
        Samples ``start_index … stop_index − 1``.
    start_time_s, end_time_s : float
        Times of the first and last sample. [s]
    mean_rate_rps : ndarray, shape (3,)
        Mean gyro output over the segment (the bias, plus Earth rate, for a static one). [rad/s]
    mean_specific_force_mps2 : ndarray, shape (3,) or None
        Mean accelerometer output, when an accelerometer was given. [m/s²]
    """

    kind: SegmentKind
    start_index: int
    stop_index: int
    start_time_s: float
    end_time_s: float
    mean_rate_rps: NDArray[np.float64]
    mean_specific_force_mps2: NDArray[np.float64] | None

    @property
    def duration_s(self) -> float:
        """Time from the first to the last sample. [s]"""
        return self.end_time_s - self.start_time_s

    @property
    def n_samples(self) -> int:
        """Samples in the segment."""
        return self.stop_index - self.start_index


@dataclass(frozen=True, eq=False)
class SegmentationResult:
    """Result of :func:`detect_segments`.

    Attributes
    ----------
    segments : tuple of Segment
        In time order.
    labels : ndarray of int8, shape (n,)
        Per sample: 0 transition, 1 static, 2 rotating (:data:`SEGMENT_LABELS`).
    gyro_noise_floor_rps : float
        √ζ_g,0 (module docstring). [rad/s]
    steady_threshold_rps : float
        The steadiness threshold on √ζ_g. [rad/s]
    static_rate_threshold_rps : float
        The rate-norm threshold between static and rotating. [rad/s]
    window_samples : int
        w.
    """

    segments: tuple[Segment, ...]
    labels: NDArray[np.int8]
    gyro_noise_floor_rps: float
    steady_threshold_rps: float
    static_rate_threshold_rps: float
    window_samples: int

    @property
    def static(self) -> tuple[Segment, ...]:
        """The static segments."""
        return tuple(s for s in self.segments if s.kind == "static")

    @property
    def rotating(self) -> tuple[Segment, ...]:
        """The rotating segments."""
        return tuple(s for s in self.segments if s.kind == "rotating")


def detect_segments(
    time_s: ArrayLike,
    gyro_rps: ArrayLike,
    *,
    accel_mps2: ArrayLike | None = None,
    window_s: float = 1.0,
    threshold_factor: float = 3.0,
    static_rate_threshold_rps: float = 2.5 * units.DEG_PER_S,
    rate_stability_rps: float = 0.1 * units.DEG_PER_S,
    min_static_s: float = 2.0,
    min_rotating_s: float = 2.0,
) -> SegmentationResult:
    """Detect static and constant-rate rotating intervals of an IMU stream (module docstring).

    Parameters
    ----------
    time_s : array_like, shape (n,)
        Strictly increasing sample times (uniform sampling assumed). [s]
    gyro_rps : array_like, shape (n, 3)
        Gyro output. [rad/s]
    accel_mps2 : array_like, shape (n, 3), optional
        Accelerometer output; tightens the static test (Tedaldi's detector). [m/s²]
    window_s : float
        Moving-window length (at least 5 samples). [s]
    threshold_factor : float
        k_σ, the steadiness threshold in multiples of the noise floor (standard deviation), > 1.
    static_rate_threshold_rps : float
        Rate-norm boundary between static and rotating. [rad/s]
    rate_stability_rps : float
        Smallest steadiness threshold and rotating-rate band (table rate stability). [rad/s]
    min_static_s, min_rotating_s : float
        Shortest segments kept. [s]

    Returns
    -------
    SegmentationResult
        Segments, labels and thresholds.

    Raises
    ------
    InvalidInputError
        If shapes disagree, values are not finite, time does not increase, the record is shorter
        than three windows, or a parameter is out of range.
    """
    t = as_time(time_s, "time_s")
    gyro = as_array(gyro_rps, "gyro_rps", shape=(t.size, 3))
    accel = None if accel_mps2 is None else as_array(accel_mps2, "accel_mps2", shape=(t.size, 3))
    win = check_positive(window_s, "window_s")
    k_sigma = check_positive(threshold_factor, "threshold_factor")
    if k_sigma <= 1.0:
        raise InvalidInputError(f"`threshold_factor` must be > 1; got {k_sigma}")
    rate_thr = check_positive(static_rate_threshold_rps, "static_rate_threshold_rps")
    stab = check_positive(rate_stability_rps, "rate_stability_rps")
    min_static = check_positive(min_static_s, "min_static_s")
    min_rot = check_positive(min_rotating_s, "min_rotating_s")
    if t.size < 2:
        raise InvalidInputError(f"`time_s` must have at least 2 samples; got {t.size}")
    dt = float(np.median(np.diff(t)))
    if not win / dt < 1e15:  # before round(): an infinite ratio cannot be rounded
        raise InvalidInputError(f"the record must be at least three windows long; got "
                                f"{t.size} samples, {t[-1] - t[0]:.6g} s, for `window_s` = "
                                f"{win:g} s")
    w = round(win / dt)
    if w < _MIN_WINDOW:
        raise InvalidInputError(f"`window_s` must span at least {_MIN_WINDOW} samples; got {w} "
                                f"({win} s at {1.0 / dt:.6g} Hz)")
    if t.size < 3 * w:
        raise InvalidInputError(f"the record must be at least three windows ({3 * w} samples) "
                                f"long; got {t.size}")

    mean_g, zeta_g = _moving_mean_and_unsteadiness(gyro, w)
    floor_g = float(np.percentile(zeta_g, _FLOOR_PERCENTILE))
    noise_g = float(np.sqrt(floor_g))
    thr_g = max(k_sigma * noise_g, stab)
    steady = np.sqrt(zeta_g) <= thr_g
    rate_norm = np.linalg.norm(mean_g, axis=1)
    quiet_a = np.ones(t.size, dtype=bool)
    if accel is not None:
        _, zeta_a = _moving_mean_and_unsteadiness(accel, w)
        floor_a = float(np.percentile(zeta_a, _FLOOR_PERCENTILE))
        quiet_a = np.sqrt(zeta_a) <= k_sigma * np.sqrt(floor_a)
    # the window must lie inside the record
    edge = np.zeros(t.size, dtype=bool)
    edge[: w // 2] = edge[t.size - (w - 1 - w // 2):] = True
    labels = np.zeros(t.size, dtype=np.int8)
    labels[steady & (rate_norm < rate_thr) & quiet_a & ~edge] = 1
    labels[steady & (rate_norm >= rate_thr) & ~edge] = 2
    band = max(stab, 3.0 * noise_g)
    _split_rotating_runs(labels, mean_g, band)
    segments = []
    min_len = {1: min_static, 2: min_rot}
    for start, stop, lab in _runs(labels):
        if lab == 0:
            continue
        if t[stop - 1] - t[start] < min_len[lab]:
            labels[start:stop] = 0
            continue
        seg_accel = None if accel is None else accel[start:stop].mean(axis=0)
        if seg_accel is not None:
            seg_accel.setflags(write=False)
        seg_rate = gyro[start:stop].mean(axis=0)
        seg_rate.setflags(write=False)
        segments.append(Segment(kind="static" if lab == 1 else "rotating", start_index=start,
                                stop_index=stop, start_time_s=float(t[start]),
                                end_time_s=float(t[stop - 1]), mean_rate_rps=seg_rate,
                                mean_specific_force_mps2=seg_accel))
    labels.setflags(write=False)
    return SegmentationResult(segments=tuple(segments), labels=labels,
                              gyro_noise_floor_rps=noise_g, steady_threshold_rps=thr_g,
                              static_rate_threshold_rps=rate_thr, window_samples=w)


def _moving_mean_and_unsteadiness(x: NDArray[np.float64], w: int, *, backend: str = "auto"
                                  ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Centred moving mean (n, 3) and Σ_axes moving variance (n,) over windows of w samples.

    Window j covers samples j − ⌊w/2⌋ … j − ⌊w/2⌋ + w − 1 (clipped at the record's ends). The
    sums are accumulated block-wise: the windows starting in block b (w samples) are summed
    over blocks b and b + 1 after subtracting block b's mean, so no running sum grows beyond 2w
    terms and the variance is exact however large the rate (no cancellation of Σx² − (Σx)²/w).
    `backend` ``"auto"`` takes the compiled pass (:mod:`._variance_kernel`, the same values
    bit for bit) when numba is there, ``"numpy"`` the numpy path (n ≥ w).
    """
    if backend != "numpy" and _variance_kernel.kernel() is not None:
        zeta, mean = _variance_kernel.moving_variance(x, _block_means(x, w), w,
                                                      _variance_kernel.SUM)
        assert mean is not None
        return mean, zeta
    ref, s1, s2 = _window_moments(x, w)
    n, k = x.shape
    n_start = n - w + 1
    mean_s = (ref[:, None, :] + s1).reshape(-1, k)[:n_start]
    start = _window_starts(n, w)
    return mean_s[start], _variance_sum(s1, s2, n_start)[start]


def _moving_unsteadiness(x: NDArray[np.float64], w: int) -> NDArray[np.float64]:
    """Return the Σ_axes moving variance of :func:`_moving_mean_and_unsteadiness` alone (numpy).

    The static detector's numpy path, one column at a time (:func:`~imucalib.processing.
    static_detector._variance_norm`).
    """
    _, s1, s2 = _window_moments(x, w)
    n = x.shape[0]
    return _variance_sum(s1, s2, n - w + 1)[_window_starts(n, w)]


def _block_means(x: NDArray[np.float64], w: int) -> NDArray[np.float64]:
    """Return the block means of :func:`_window_moments` (nb, k), the same numpy reduction.

    The blocks b < nb lie inside the record (nb·w ≤ n), so no padding: the rows are copied to
    a C-ordered array of the padded one's layout, and reduced over the same (nb, w, k) shape
    (pairwise for one column, row after row for several), so the means are the same bits.
    """
    n, k = x.shape
    nb = -(-(n - w + 1) // w)
    blocks = np.ascontiguousarray(x[:nb * w], dtype=np.float64).reshape(nb, w, k)
    return np.asarray(blocks.mean(axis=1), dtype=np.float64)


def _window_moments(x: NDArray[np.float64], w: int
                    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Block means (nb, k) and the windows' mean and mean square about them (nb, w, k)."""
    n, k = x.shape
    n_start = n - w + 1
    nb = -(-n_start // w)
    padded = np.empty(((nb + 1) * w, k))
    padded[:n] = x
    padded[n:] = x[-1]  # only feeds windows past the end, which are discarded
    blocks = padded.reshape(nb + 1, w, k)
    ref = blocks[:nb].mean(axis=1)
    pair = np.concatenate([blocks[:nb], blocks[1:]], axis=1) - ref[:, None, :]
    zero = np.zeros((nb, 1, k))
    c1 = np.concatenate([zero, np.cumsum(pair, axis=1)], axis=1)
    c2 = np.concatenate([zero, np.cumsum(pair * pair, axis=1)], axis=1)
    s1 = (c1[:, w:2 * w] - c1[:, :w]) / w
    s2 = (c2[:, w:2 * w] - c2[:, :w]) / w
    return ref, s1, s2


def _variance_sum(s1: NDArray[np.float64], s2: NDArray[np.float64], n_start: int
                  ) -> NDArray[np.float64]:
    """Σ over the columns of each window's variance, windows 0 … n_start − 1."""
    k = s1.shape[2]
    return np.asarray(np.maximum(s2 - s1 * s1, 0.0).reshape(-1, k)[:n_start].sum(axis=1),
                      dtype=np.float64)


def _window_starts(n: int, w: int) -> NDArray[np.intp]:
    """Return the window of each sample: its centred one, clipped at the record's ends."""
    return np.clip(np.arange(n) - w // 2, 0, n - w)


def _runs(labels: NDArray[np.int8] | NDArray[np.bool_]) -> list[tuple[int, int, int]]:
    """(start, stop, label) of each run of equal labels (int8, or bool: labels 0 and 1).

    The changes are found on a boolean mask (``np.flatnonzero`` of an int8 difference takes
    several times as long).
    """
    change = np.flatnonzero(labels[1:] != labels[:-1]) + 1
    starts = np.concatenate([[0], change])
    stops = np.concatenate([change, [labels.size]])
    return [(int(a), int(b), int(labels[a])) for a, b in zip(starts, stops, strict=True)]


def _split_rotating_runs(labels: NDArray[np.int8], mean_rate: NDArray[np.float64],
                         band: float) -> None:
    """Mark rotating samples whose windowed rate leaves ±band of their run's median (in place)."""
    for start, stop, lab in _runs(labels):
        if lab != 2:
            continue
        med = np.median(mean_rate[start:stop], axis=0)
        off = np.linalg.norm(mean_rate[start:stop] - med, axis=1) > band
        labels[start:stop][off] = 0
