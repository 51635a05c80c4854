"""Static intervals and hand rotations of a hand-held IMU log, whatever the gyro bias.

Contents
--------
:func:`detect_static_and_rotations` → :class:`StaticDetection`
    The static intervals (:class:`~imucalib.processing.segmentation.Segment`, kind
    ``"static"``) and the rotations between them (:class:`Rotation`, with the integrated angle
    vector).

Method
------
The static detector of Tedaldi, Pretto & Menegatti (ICRA 2014) [1]_, as imu_tk implements it,
with the gyro added:

1. Over a centred moving window of w samples (`window_s`), the variance of each accelerometer
   axis; ς_a(t) = ‖(var_x, var_y, var_z)‖. Likewise ς_g(t) for the gyro. A variance does not see
   a constant offset, so neither the gyro bias (3.7 °/s of a raw-count consumer gyro) nor the
   accelerometer bias matters.
2. The *initial static interval*: the first `init_static_s` seconds of the record, during which
   the IMU must lie still (refused when its variance exceeds 25 times the 10th percentile of
   ς_a: it was moving) (Tedaldi: T_init, 50 s in their experiments; a few seconds suffice for
   a consumer MEMS IMU). ς_a,init = ‖var_init‖ over that interval (ς_g,init likewise).
3. A sample is static when ς_a(t) < k·ς_a,init and ς_g(t) < k·ς_g,init, k the
   `threshold_factor` (Tedaldi's multiple of the initial variance; default 6, settable: the
   command line's ``--static-threshold``). The gyro test catches a rotation about the vertical,
   which leaves the accelerometer almost unchanged.
4. Runs of static samples shorter than `min_static_s` are dropped. Because every window lies
   inside the interval, an interval starts and ends about w/2 inside the true still period.
5. Between two consecutive static intervals, the gyro bias is taken as the mean of the two
   intervals' mean rates; the bias-free rate is integrated over the gap (from the last sample of
   the first interval to the first of the next), giving the angle vector θ = ∫(ω − b) dt. A
   gap whose ‖θ‖ reaches `min_rotation_deg` is a :class:`Rotation`, whatever its rate profile
   (a hand's rise and fall, a pause mid-way). θ is the rotation vector for a rotation about one
   fixed axis of the body (as a hand rotation about a face normal is); for other motions it is
   the integral of the body rate, not an attitude change.

References
----------
.. [1] D. Tedaldi, A. Pretto and E. Menegatti, "A robust and easy to implement method for IMU
   calibration without external equipments", Proc. IEEE ICRA 2014, pp. 3042–3049.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib._checks import as_array, check_positive
from imucalib.errors import InvalidInputError
from imucalib.processing import _angle_kernel, _variance_kernel
from imucalib.processing._common import as_time
from imucalib.processing.moments import mean_rows
from imucalib.processing.segmentation import (
    Segment,
    _block_means,
    _moving_unsteadiness,
    _runs,
)

__all__ = ["Rotation", "StaticDetection", "detect_for_thresholds", "detect_static_and_rotations"]

_MIN_WINDOW = 5
#: The initial interval is refused when its accelerometer variance exceeds this multiple of the
#: _QUIET_PERCENTILE-th percentile of the windowed variance (it was not at rest).
_NOT_AT_REST = 25.0
_QUIET_PERCENTILE = 10.0


@dataclass(frozen=True, eq=False)
class Rotation:
    """A motion between two static intervals whose bias-free rate integrates to an angle.

    Attributes
    ----------
    start_index, stop_index : int
        Samples ``start_index … stop_index − 1`` (from the last sample of the static interval
        before to the first of the one after).
    start_time_s, end_time_s : float
        Times of the first and last sample. [s]
    angle_rad : ndarray, shape (3,)
        θ = ∫(ω − b) dt per gyro axis, b the mean of the neighbouring static means. [rad]
    bias_rps : ndarray, shape (3,)
        b. [rad/s]
    """

    start_index: int
    stop_index: int
    start_time_s: float
    end_time_s: float
    angle_rad: NDArray[np.float64]
    bias_rps: NDArray[np.float64]

    @property
    def angle_norm_rad(self) -> float:
        """‖θ‖. [rad]"""
        return float(np.linalg.norm(self.angle_rad))

    @property
    def duration_s(self) -> float:
        """Time from the first to the last sample. [s]"""
        return self.end_time_s - self.start_time_s


@dataclass(frozen=True, eq=False)
class StaticDetection:
    """Result of :func:`detect_static_and_rotations`.

    Attributes
    ----------
    static : tuple of Segment
        The static intervals, in time order (kind ``"static"``).
    rotations : tuple of Rotation
        The rotations found between consecutive static intervals.
    is_static : ndarray of bool, shape (n,)
        Per sample, whether it lies in a static interval.
    accel_variance : ndarray, shape (n,)
        ς_a(t) (module docstring). [(m/s²)²]
    gyro_variance : ndarray, shape (n,)
        ς_g(t). [(rad/s)²]
    accel_threshold, gyro_threshold : float
        k·ς_a,init and k·ς_g,init.
    threshold_factor : float
        k.
    window_samples : int
        w.
    """

    static: tuple[Segment, ...]
    rotations: tuple[Rotation, ...]
    is_static: NDArray[np.bool_]
    accel_variance: NDArray[np.float64]
    gyro_variance: NDArray[np.float64]
    accel_threshold: float
    gyro_threshold: float
    threshold_factor: float
    window_samples: int


def _edges(n: int, w: int) -> NDArray[np.bool_]:
    """Mark the samples whose centred window of w samples does not lie inside the record."""
    edge = np.zeros(n, dtype=bool)
    edge[: w // 2] = edge[n - (w - 1 - w // 2):] = True
    return edge


def _variance_norm(x: NDArray[np.float64], w: int, *, backend: str = "auto"
                   ) -> NDArray[np.float64]:
    """‖(var_w of each column)‖ over centred windows of w samples (step 1), n ≥ w.

    Each column's variance is :func:`~imucalib.processing.segmentation._moving_unsteadiness`
    of that column alone (block-wise, exact at any rate). `backend` ``"auto"`` computes all the
    columns in one compiled pass (:mod:`~imucalib.processing._variance_kernel`; the block means
    by the same numpy reduction, one column at a time), equal to the ``"numpy"`` path bit for
    bit (``tests/processing/test_variance_kernel.py``).
    """
    if backend != "numpy" and _variance_kernel.kernel() is not None:
        ref = np.column_stack([_block_means(x[:, i:i + 1], w) for i in range(x.shape[1])])
        return _variance_kernel.moving_variance(x, ref, w, _variance_kernel.NORM)[0]
    per_axis = [_moving_unsteadiness(x[:, i:i + 1], w) for i in range(x.shape[1])]
    return np.asarray(np.sqrt(np.sum(np.square(per_axis), axis=0)), dtype=np.float64)


def detect_static_and_rotations(
    time_s: ArrayLike,
    gyro_rps: ArrayLike,
    accel_mps2: ArrayLike,
    *,
    window_s: float = 0.5,
    init_static_s: float = 2.0,
    threshold_factor: float = 6.0,
    min_static_s: float = 1.0,
    min_rotation_deg: float = 5.0,
) -> StaticDetection:
    """Find the static intervals and the rotations between them (module docstring).

    Parameters
    ----------
    time_s : array_like, shape (n,)
        Increasing sample times (uniform sampling assumed). [s]
    gyro_rps : array_like, shape (n, 3)
        Gyro output, bias included. [rad/s]
    accel_mps2 : array_like, shape (n, 3)
        Accelerometer output. [m/s²]
    window_s : float
        Moving-window length (at least 5 samples). [s]
    init_static_s : float
        The initial static interval from which the variance reference is taken. [s]
    threshold_factor : float
        k: static below k times the initial variance (> 1).
    min_static_s : float
        Shortest static interval kept. [s]
    min_rotation_deg : float
        Smallest ‖θ‖ reported as a rotation. [°]

    Returns
    -------
    StaticDetection
        Static intervals, rotations, the variance curves and thresholds.

    Raises
    ------
    InvalidInputError
        Bad shapes or values, a record shorter than the initial interval plus two windows, an
        initial interval of zero variance (a constant, clipped or synthetic noiseless signal),
        or one not at rest (its accelerometer variance over 25 times the 10th percentile of the
        windowed variance).
    """
    return detect_for_thresholds(time_s, gyro_rps, accel_mps2, window_s=window_s,
                                 init_static_s=init_static_s,
                                 threshold_factors=[threshold_factor],
                                 min_static_s=min_static_s,
                                 min_rotation_deg=min_rotation_deg)[0]


def detect_for_thresholds(
    time_s: ArrayLike,
    gyro_rps: ArrayLike,
    accel_mps2: ArrayLike,
    *,
    threshold_factors: Sequence[float],
    window_s: float = 0.5,
    init_static_s: float = 2.0,
    min_static_s: float = 1.0,
    min_rotation_deg: float = 5.0,
) -> list[StaticDetection]:
    """Run :func:`detect_static_and_rotations` for several threshold factors k at once.

    The moving variances and the initial interval's reference depend on the samples and the
    window, not on k: they are computed once and shared (an automatic choice of k tries eight;
    recomputing them was most of a field calibration's time, docs/performance.md). Each
    detection equals the one :func:`detect_static_and_rotations` gives for its k.

    Raises
    ------
    InvalidInputError
        As :func:`detect_static_and_rotations`, for any k.
    """
    ks = [check_positive(k, "threshold_factor") for k in threshold_factors]
    for k in ks:
        if k <= 1.0:
            raise InvalidInputError(f"`threshold_factor` (--static-threshold) must be > 1; "
                                    f"got {k}")
    t, steps = _checked_time(time_s)
    gyro = _checked_samples(gyro_rps, "gyro_rps", t.size)
    accel = _checked_samples(accel_mps2, "accel_mps2", t.size)
    win = check_positive(window_s, "window_s")
    t_init = check_positive(init_static_s, "init_static_s")
    min_static = check_positive(min_static_s, "min_static_s")
    min_rot = np.deg2rad(check_positive(min_rotation_deg, "min_rotation_deg"))
    if t.size < 2:
        raise InvalidInputError(f"`time_s` must have at least 2 samples; got {t.size}")
    dt = float(np.median(steps))
    if not win / dt < 1e9:
        raise InvalidInputError(f"`window_s` = {win:g} s is longer than the record")
    w = round(win / dt)
    if w < _MIN_WINDOW:
        raise InvalidInputError(f"`window_s` must span at least {_MIN_WINDOW} samples; got {w} "
                                f"({win:g} s at {1.0 / dt:.6g} Hz)")
    n_init = int(np.searchsorted(t, t[0] + t_init, side="right"))
    if n_init < w or t.size < n_init + 2 * w:
        raise InvalidInputError(
            f"the record ({t.size} samples, {t[-1] - t[0]:.6g} s) must hold the initial static "
            f"interval ({t_init:g} s, {n_init} samples, at least one window of {w}) and two "
            "windows more")
    var_a = _variance_norm(accel, w)
    var_g = _variance_norm(gyro, w)
    init_a = float(np.linalg.norm(accel[:n_init].var(axis=0)))
    init_g = float(np.linalg.norm(gyro[:n_init].var(axis=0)))
    if not (init_a > 0.0 and init_g > 0.0):
        raise InvalidInputError(
            f"the initial static interval (first {t_init:g} s) has zero variance (accelerometer "
            f"{init_a:.3g}, gyro {init_g:.3g}): a constant or clipped signal; the detector needs "
            "the sensor noise")
    inside = ~_edges(t.size, w)
    quiet = float(np.percentile(var_a[inside], _QUIET_PERCENTILE))
    if init_a > _NOT_AT_REST * quiet:
        raise InvalidInputError(
            f"the first {t_init:g} s are not at rest: their accelerometer variance "
            f"{init_a:.3g} (m/s²)² is {init_a / quiet:.3g} times that of the quietest windows; "
            "the detector needs the log to begin with the IMU still (Tedaldi's initial static "
            "interval): shorten `init_static_s` (--init-static-s) or trim the log")
    for arr in (var_a, var_g):  # read-only: the detections share the curves
        arr.setflags(write=False)
    means: _Means = {}  # the detections share most of their intervals
    inside.setflags(write=False)
    return [_detect(t, gyro, accel, var_a, var_g, init_a, init_g, inside, w, k, min_static,
                    min_rot, means) for k in ks]


def _usable(value: ArrayLike, ndim: int) -> NDArray[np.float64] | None:
    """`value` itself when it is a C-ordered float64 array of `ndim` dimensions, all finite.

    The detector only reads its inputs, so such an array needs no copy (``as_array`` copies
    each: a field log's three columns, 10 MB at 1 kHz); finiteness is tested through the sum
    (NaN and ±∞ propagate), element by element only when the sum is not finite.
    """
    if not (isinstance(value, np.ndarray) and value.dtype == np.float64 and value.ndim == ndim
            and value.flags.c_contiguous):
        return None
    with np.errstate(over="ignore", invalid="ignore"):  # huge finite values may overflow
        total = value.sum()
    if not np.isfinite(total) and not np.isfinite(value).all():
        return None
    return value


def _checked_time(time_s: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Return ``as_time(time_s, "time_s")`` and its steps, without a copy when it can.

    The same checks and errors as :func:`~imucalib.processing._common.as_time` (which raises
    them when the times are not a finite, strictly increasing float64 vector).
    """
    t = _usable(time_s, 1)
    if t is not None:
        steps = np.diff(t)
        if not (steps <= 0).any():
            return t, steps
    t = as_time(time_s, "time_s")
    return t, np.diff(t)


def _checked_samples(value: ArrayLike, name: str, n: int) -> NDArray[np.float64]:
    """Return ``as_array(value, name, shape=(n, 3))``, without a copy when it can."""
    arr = _usable(value, 2)
    if arr is not None and arr.shape == (n, 3):
        return arr
    return as_array(value, name, shape=(n, 3))


#: An interval's mean rate and mean specific force, by (start, stop) index.
_Means = dict[tuple[int, int], tuple[NDArray[np.float64], NDArray[np.float64]]]


def _interval_means(gyro: NDArray[np.float64], accel: NDArray[np.float64], start: int,
                    stop: int, means: _Means) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Return the mean rate and specific force of samples start … stop − 1 (read-only, kept).

    :func:`~imucalib.processing.moments.mean_rows`: ``mean(axis=0)``'s values, computed once
    per interval for all the thresholds that find it.
    """
    found = means.get((start, stop))
    if found is None:
        rate, force = mean_rows(gyro[start:stop]), mean_rows(accel[start:stop])
        rate.setflags(write=False)
        force.setflags(write=False)
        found = means[start, stop] = (rate, force)
    return found


def _detect(t: NDArray[np.float64], gyro: NDArray[np.float64], accel: NDArray[np.float64],
            var_a: NDArray[np.float64], var_g: NDArray[np.float64], init_a: float,
            init_g: float, inside: NDArray[np.bool_], w: int, k: float, min_static: float,
            min_rot: float, means: _Means) -> StaticDetection:
    """Detect with one threshold factor k: steps 2–4 of the module docstring.

    `inside` marks the samples whose window lies inside the record (``~_edges(n, w)``).
    """
    thr_a, thr_g = k * init_a, k * init_g
    still = var_a < thr_a
    still &= var_g < thr_g
    still &= inside
    static: list[Segment] = []
    for start, stop, lab in _runs(still):
        if lab == 0:
            continue
        if t[stop - 1] - t[start] < min_static:
            still[start:stop] = False
            continue
        rate, force = _interval_means(gyro, accel, start, stop, means)
        static.append(Segment(kind="static", start_index=start, stop_index=stop,
                              start_time_s=float(t[start]), end_time_s=float(t[stop - 1]),
                              mean_rate_rps=rate, mean_specific_force_mps2=force))
    rotations: list[Rotation] = []
    pairs = list(itertools.pairwise(static))
    spans = [(before.stop_index - 1, after.start_index + 1) for before, after in pairs]
    biases = [0.5 * (before.mean_rate_rps + after.mean_rate_rps) for before, after in pairs]
    for (a, b), bias, theta in zip(spans, biases, _gap_angles(t, gyro, spans, biases),
                                   strict=True):
        if np.linalg.norm(theta) >= min_rot:
            theta.setflags(write=False)
            bias.setflags(write=False)
            rotations.append(Rotation(start_index=a, stop_index=b, start_time_s=float(t[a]),
                                      end_time_s=float(t[b - 1]), angle_rad=theta,
                                      bias_rps=bias))
    still.setflags(write=False)
    return StaticDetection(static=tuple(static), rotations=tuple(rotations), is_static=still,
                           accel_variance=var_a, gyro_variance=var_g, accel_threshold=thr_a,
                           gyro_threshold=thr_g, threshold_factor=k, window_samples=w)


def _gap_angles(t: NDArray[np.float64], gyro: NDArray[np.float64],
                spans: Sequence[tuple[int, int]], biases: Sequence[NDArray[np.float64]], *,
                backend: str = "auto") -> list[NDArray[np.float64]]:
    """θ = ∫(ω − b) dt over each gap's samples a … b − 1 by the trapezoid rule (step 5).

    `backend` ``"auto"`` computes every gap in one compiled call
    (:func:`~imucalib.processing._angle_kernel.gap_angles`, numpy's operations in its order:
    the same values bit for bit), ``"numpy"`` one gap at a time.
    """
    if backend != "numpy" and spans and _angle_kernel.kernel() is not None:
        index = np.array(spans, dtype=np.int64)
        found = _angle_kernel.gap_angles(t, gyro, np.ascontiguousarray(index[:, 0]),
                                         np.ascontiguousarray(index[:, 1]), np.array(biases))
        return [row.copy() for row in found]
    thetas = []
    for (a, b), bias in zip(spans, biases, strict=True):
        rate = gyro[a:b] - bias
        step = np.diff(t[a:b])
        thetas.append(np.sum(0.5 * (rate[1:] + rate[:-1]) * step[:, None], axis=0))  # trapezoid
    return thetas
