"""A continuous log's static intervals, rotations and poses (the field calibration, segments).

A field log is one IMU's continuous record (a Recording of a guided session, or a user's CSV
read through the import options of docs/import.md). :func:`find_intervals` runs the variance
detector of :mod:`imucalib.processing.static_detector` (Tedaldi et al. 2014): with a given
threshold factor k, or, by default, Tedaldi's search over k for the detection whose
gravity-norm fit has the smallest χ²/ν. :func:`static_poses` reduces each static interval to
its mean outputs with a standard error from the white-noise density pooled over every interval
(block means, :func:`~imucalib.procedures.common.noise.block_variance`): a pose lasts seconds,
too short for its own noise estimate.

The field calibration (docs/field.md) builds its observations from them, and ``imucalib
segments --detector variance`` shows the intervals of any log: both use this one detector.

Contents
--------
:class:`FieldLog`, :func:`log_from_recording`, :func:`log_from_frame`, :class:`StaticPose`,
:func:`static_poses`, :func:`find_intervals`.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from imucalib.conventions import ACCEL_COLUMNS, GYRO_COLUMNS, TEMPERATURE_COLUMN
from imucalib.errors import (
    CalibrationError,
    InsufficientExcitationError,
    InvalidInputError,
    MissingSegmentError,
    RecordingError,
)
from imucalib.procedures.common.noise import block_variance, pooled_white_density
from imucalib.processing.moments import block_means, mean_rows

if TYPE_CHECKING:
    from imucalib.io.reader import Recording
    from imucalib.processing.static_detector import StaticDetection

__all__ = ["FieldLog", "StaticPose", "find_intervals", "log_from_frame", "log_from_recording",
           "static_poses"]

_F64 = NDArray[np.float64]
#: Threshold factors k tried by the automatic choice (Tedaldi et al. 2014 search a range of
#: multiples of the initial variance).
AUTO_THRESHOLDS = (2.0, 3.0, 4.0, 6.0, 8.0, 10.0, 14.0, 20.0)


@dataclass(frozen=True, eq=False)
class FieldLog:
    """One IMU's continuous record, SI.

    Attributes
    ----------
    unit, source : str
        The IMU and where the data came from (a file).
    time_s : ndarray, shape (n,)
    gyro_rps, accel_mps2 : ndarray, shape (n, 3)
    latitude_deg, height_m : float or None
        The site, when the source says it (a Recording's metadata).
    temperature_degc : ndarray, shape (n,), or None
        The IMU's temperature sensor, when the source has it. [°C]
    """

    unit: str
    source: str
    time_s: _F64
    gyro_rps: _F64
    accel_mps2: _F64
    latitude_deg: float | None = None
    height_m: float | None = None
    temperature_degc: _F64 | None = None

    @functools.cached_property
    def period_s(self) -> float:
        """Median sample period (computed once: a median of n values; the log is read-only). [s]"""
        return float(np.median(np.diff(self.time_s)))


def log_from_recording(rec: Recording, unit: str | None = None) -> FieldLog:
    """Read the IMU stream `unit` (the only one when None) of a Recording whole.

    Raises
    ------
    RecordingError
        No IMU stream, or several and none chosen.
    """
    units = [s.unit for s in rec.streams if s.device == "imu"]
    if (unit is not None and unit not in units) or (unit is None and len(units) != 1):
        raise RecordingError(f"{rec.path.name} has the IMU stream(s) {units or 'none'}; "
                             + ("choose one (--imu)" if unit is None else f"not {unit!r}"))
    name = unit or units[0]
    stream = next(s for s in rec.streams if s.device == "imu" and s.unit == name)
    temp = [TEMPERATURE_COLUMN] if TEMPERATURE_COLUMN in stream.columns else []
    data = rec.read_stream("imu", name, columns=[*GYRO_COLUMNS, *ACCEL_COLUMNS, *temp])
    meta = rec.metadata
    lat = meta.get("latitude_deg")
    height = meta.get("height_m")
    return FieldLog(unit=name, source=str(rec.path),
                    time_s=np.asarray(data.time_s, dtype=np.float64),
                    gyro_rps=np.column_stack([data.columns[c] for c in GYRO_COLUMNS]),
                    accel_mps2=np.column_stack([data.columns[c] for c in ACCEL_COLUMNS]),
                    latitude_deg=None if lat is None else float(lat),
                    height_m=None if height is None else float(height),
                    temperature_degc=np.asarray(data.columns[TEMPERATURE_COLUMN],
                                                dtype=np.float64) if temp else None)


def log_from_frame(frame: Any, unit: str, source: str) -> FieldLog:
    """Wrap a DataFrame of :func:`~imucalib.io.import_spec.read_imu_table` (SI, canonical names).

    Raises
    ------
    InvalidInputError
        A gyro or accelerometer column missing (both triads are needed).
    """
    missing = [c for c in (*GYRO_COLUMNS, *ACCEL_COLUMNS) if c not in frame.columns]
    if missing:
        raise InvalidInputError(f"{source}: the field calibration needs the gyro and the "
                                f"accelerometer; columns {missing} are missing (found "
                                f"{list(frame.columns)}; see docs/import.md for --column-map)")
    return FieldLog(unit=unit, source=source,
                    time_s=np.asarray(frame.index, dtype=np.float64),
                    gyro_rps=frame[list(GYRO_COLUMNS)].to_numpy(dtype=np.float64),
                    accel_mps2=frame[list(ACCEL_COLUMNS)].to_numpy(dtype=np.float64),
                    temperature_degc=frame[TEMPERATURE_COLUMN].to_numpy(dtype=np.float64)
                    if TEMPERATURE_COLUMN in frame.columns else None)


@dataclass(frozen=True)
class StaticPose:
    """One static interval reduced to its means.

    Attributes
    ----------
    index : int
        Its place among the intervals (0 the initial rest).
    start_time_s, end_time_s : float
    n_samples : int
    accel_mean, accel_se : ndarray, shape (3,)
        Mean accelerometer output and its standard error. [m/s²]
    gyro_mean, gyro_se : ndarray, shape (3,)
        Mean gyro output and its standard error. [rad/s]
    """

    index: int
    start_time_s: float
    end_time_s: float
    n_samples: int
    accel_mean: _F64
    accel_se: _F64
    gyro_mean: _F64
    gyro_se: _F64

    @property
    def duration_s(self) -> float:
        """Span of its samples. [s]"""
        return self.end_time_s - self.start_time_s


#: One interval's reductions, by (start, stop) index: block variance, accel and gyro means.
_IntervalMemo = dict[tuple[int, int], tuple[tuple[int, _F64], _F64, _F64]]


def static_poses(log: FieldLog, detection: StaticDetection, *, block_s: float = 0.25,
                 memo: _IntervalMemo | None = None) -> list[StaticPose]:
    """Return the static intervals' means with pooled-noise standard errors (module docstring).

    `memo` keeps each interval's block variance and means for further calls on the same log
    and `block_s` (the automatic threshold choice asks for the poses of several detections,
    which share most of their intervals). The means are the detection's own (its intervals'
    :func:`~imucalib.processing.moments.mean_rows`, taken when absent), and the block variance
    is taken of the accelerometer's and the gyro's columns apiece (each column's block means and
    variance are reduced alone, so the values are those of the six columns together, without
    copying them side by side): the per-sample work is one pass of block means.

    Raises
    ------
    InsufficientExcitationError
        No interval long enough for three blocks of `block_s` (no noise estimate).
    """
    period = log.period_s
    slices = [slice(s.start_index, s.stop_index) for s in detection.static]
    memo = {} if memo is None else memo
    for seg, sl in zip(detection.static, slices, strict=True):
        if (sl.start, sl.stop) not in memo:
            memo[sl.start, sl.stop] = (
                _block_variance_pair(log.accel_mps2[sl], log.gyro_rps[sl], period, block_s),
                _segment_mean(seg.mean_specific_force_mps2, log.accel_mps2[sl]),
                _segment_mean(seg.mean_rate_rps, log.gyro_rps[sl]))
    reduced = [memo[sl.start, sl.stop] for sl in slices]
    blocks = [r[0] for r in reduced]
    density = pooled_white_density(blocks)
    if density is None:
        raise InsufficientExcitationError(
            ["noise"], f"no static interval of {log.source} holds three {block_s:g} s blocks: "
                       "the poses' noise cannot be estimated (hold each pose longer)")
    poses = []
    for k, (sl, (_, accel, gyro)) in enumerate(zip(slices, reduced, strict=True)):
        t = log.time_s[sl]
        span = max(float(t[-1] - t[0]) + period, period)
        se = density / math.sqrt(span)
        poses.append(StaticPose(index=k, start_time_s=float(t[0]), end_time_s=float(t[-1]),
                                n_samples=int(t.size), accel_mean=accel.copy(), accel_se=se[:3],
                                gyro_mean=gyro.copy(), gyro_se=se[3:]))
    return poses


def _block_variance_pair(accel: _F64, gyro: _F64, period_s: float, block_s: float
                         ) -> tuple[int, _F64]:
    """Return :func:`~imucalib.procedures.common.noise.block_variance` of [accel | gyro].

    Each column's block means (:func:`~imucalib.processing.moments.block_means`, rows added one
    after the other) and their variance (numpy's reduction along the rows of a C-ordered array
    of two columns or more, also one row after the other) do not depend on the other columns:
    the two triads' block means, side by side, give the six columns' values bit for bit with
    one ``np.var`` instead of two (its fixed cost, per interval) and without stacking the
    samples into a copy.
    """
    per_block = max(round(block_s / period_s), 1)
    k = accel.shape[0] // per_block
    if k < 3 or accel.ndim != 2 or gyro.shape != accel.shape:
        dof, var_a = block_variance(accel, period_s, block_s)
        _, var_g = block_variance(gyro, period_s, block_s)
        return dof, np.concatenate([var_a, var_g])
    means = np.concatenate([block_means(accel, per_block), block_means(gyro, per_block)],
                           axis=1)
    return k - 1, np.asarray(np.var(means, axis=0, ddof=1) * per_block * period_s,
                             dtype=np.float64)


def _segment_mean(found: _F64 | None, rows: _F64) -> _F64:
    """Return the detector's mean of an interval's rows, or ``mean_rows(rows)`` without one.

    The detector's is :func:`~imucalib.processing.moments.mean_rows` of the same rows
    (:func:`~imucalib.processing.static_detector.detect_for_thresholds`), ``mean(axis=0)``.
    """
    return mean_rows(rows) if found is None else found


def _gravity_score(log: FieldLog, detection: StaticDetection, gravity_mps2: float,
                   memo: _IntervalMemo) -> float:
    """χ²/ν of the gravity-norm fit to a detection's poses; inf when the fit fails."""
    from imucalib.estimation.gravity_norm import fit_gravity_norm

    try:
        poses = static_poses(log, detection, memo=memo)
        return float(fit_gravity_norm([p.accel_mean for p in poses],
                                      [p.accel_se for p in poses],
                                      gravity_mps2).quality.reduced_chi2)
    except CalibrationError:
        return math.inf


def find_intervals(log: FieldLog, *, threshold_factor: float | None,
                   window_s: float, init_static_s: float, min_static_s: float,
                   min_rotation_deg: float, gravity_mps2: float,
                   candidates: Sequence[float] = AUTO_THRESHOLDS) -> StaticDetection:
    """Detect the static intervals and rotations, choosing k when not given (module docstring).

    The automatic choice keeps, of the candidate k whose detection gives at least ten poses
    and a full-rank gravity-norm fit, the one with the smallest χ²/ν; when none does (a
    fixture's six faces), the k that finds the most intervals (ties: the nearest to 6).

    Raises
    ------
    MissingSegmentError
        Fewer than two static intervals with the given k, or with every candidate.
    """
    from imucalib.processing.static_detector import detect_for_thresholds

    def detect(ks: Sequence[float]) -> list[StaticDetection]:
        # the moving variances are computed once for all k (docs/performance.md)
        return detect_for_thresholds(
            log.time_s, log.gyro_rps, log.accel_mps2, window_s=window_s,
            init_static_s=init_static_s, threshold_factors=ks, min_static_s=min_static_s,
            min_rotation_deg=min_rotation_deg)

    if threshold_factor is not None:
        (found,) = detect([threshold_factor])
        if len(found.static) < 2:
            raise MissingSegmentError(
                f"{log.source}: {len(found.static)} static interval(s) found with the "
                f"threshold factor {threshold_factor:g} (the log must start at rest for "
                f"{init_static_s:g} s and hold each pose at least {min_static_s:g} s; try "
                "another --static-threshold, or none for the automatic choice)")
        return found
    best: tuple[tuple[float, int, float], StaticDetection] | None = None
    tried = []
    memo: _IntervalMemo = {}  # the candidates' detections share most intervals
    # χ²/ν by the detection's intervals: neighbouring k often find the same ones, whose poses
    # and fit are then the same (the bench's field recording: 6 distinct of 8)
    scores: dict[tuple[tuple[int, int], ...], float] = {}
    for k, found in zip(candidates, detect(candidates), strict=True):
        tried.append(f"k={k:g}: {len(found.static)}")
        if len(found.static) < 2:
            continue
        score = math.inf
        if len(found.static) >= 10:
            intervals = tuple((s.start_index, s.stop_index) for s in found.static)
            if intervals not in scores:
                scores[intervals] = _gravity_score(log, found, gravity_mps2, memo)
            score = scores[intervals]
        key = (score, -len(found.static), abs(k - 6.0))
        if best is None or key < best[0]:
            best = (key, found)
    if best is None:
        raise MissingSegmentError(
            f"{log.source}: no threshold factor finds two static intervals (found: "
            f"{'; '.join(tried)}); the log must start at rest for {init_static_s:g} s, then "
            f"hold each pose at least {min_static_s:g} s")
    return best[1]
