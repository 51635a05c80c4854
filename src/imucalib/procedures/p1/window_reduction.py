"""One P1 window reduced to a :class:`~.windows.WindowObservation`: the processing chain.

The processing chain of P1 (docs/p1.md, processing rules 1–3), one step's valid window at a
time. A static window longer than :data:`CHUNK_ROWS` IMU rows (the static record) is read in
blocks of that many rows, its table feedback too, so what it holds is bounded by the block
whatever its length (:meth:`WindowReducer.observe_long_static`); shorter windows and the turns
are read whole (a turn's whole-revolution span, filter and harmonic fit take all its samples at
once: its length is its plan's revolutions at its rate):

1. read the IMU samples of the window and the table feedback;
2. rebuild the IMU time base from its sample counter (regression of receive time on counter,
   docs/drivers.md "Time synchronisation practice"), which removes receive-time jitter;
3. reject outliers per channel (by default one pass against a running median with a threshold
   that grows with the window length, :func:`~imucalib.processing.reject_outliers_robust`; P1's
   3σ rule or Grubbs test as options), replacing them by interpolation (or dropping them),
   counts per channel and the times of the first few kept;
4. compute per-channel statistics with a standard error that accounts for correlated noise
   (:func:`~imucalib.processing.statistics.compute_window_statistics`);
5. low-pass the window with a zero-phase Butterworth at 1/4 (1/5–1/3) of the IMU bandwidth;
6. interpolate the filtered IMU onto the table feedback times (the achieved alignment error is
   reported and must stay below 1 ms);
7. average: a static window over its feedback times; a rate point over the longest span of
   whole table revolutions
   (:func:`~imucalib.processing.statistics.compute_integer_revolution_window`).


Reference inputs
----------------
From :mod:`imucalib.procedures.common.reference` (shared with the other procedures; the window
statistics from :mod:`~imucalib.procedures.common.windows`, the noise model of window means from
:mod:`~imucalib.procedures.common.noise`). The table geometry comes from the axis names
(:data:`imucalib.conventions.TABLE_AXIS_VECTORS`: pitch about −y, roll about x, azimuth about z),
outer axis first, with the IMU body frame equal to the platform frame. For measured angles,
rot_tp = Π R_{n_i}(θ_i) and

- static: specific force f_b = rot_tpᵀ·[0, 0, g] (P1: g·[sin θ, sin φ cos θ, cos θ cos φ]) and
  angular rate ω_b = rot_tpᵀ·Ω_t (Earth rate at the site's latitude and heading);
- rate point turning axis i at the measured mean rate ω: the axis in b is a_b = (Π_{j>i}
  R_{n_j}(θ_j))ᵀ·n_i and in t a_t = rot_tp·a_b (constant while it turns); averaged over whole
  revolutions the input is ω_b = (ω + Ω_t·a_t)·a_b (the horizontal Earth rate and gravity cancel,
  their components along the axis stay) and f_b = (g_t·a_t)·a_b.

Contents
--------
:class:`P1Processing`, :class:`WindowReducer`, :data:`CHUNK_ROWS`, :data:`OUTLIER_TIMES_KEPT`
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from imucalib.conventions import ACCEL_COLUMNS, GYRO_COLUMNS
from imucalib.errors import MissingSegmentError, RecordingError
from imucalib.io.reader import Recording, StepRecord
from imucalib.io.streams import DEVICE_IMU, DEVICE_TABLE, axis_columns
from imucalib.procedures.common.reference import axis_vector as _axis_vector
from imucalib.procedures.common.reference import (
    rate_inputs_b,
    site_vectors,
    static_inputs_b,
)
from imucalib.procedures.common.window_checks import WindowLimits, checked_samples
from imucalib.procedures.common.windows import RunningMoments as _Moments
from imucalib.procedures.common.windows import RunningRowMean as _RowMean
from imucalib.procedures.common.windows import counter_times
from imucalib.procedures.common.windows import harmonic_residual_std as _harmonic_residual_std
from imucalib.procedures.common.windows import table_angle_at as _angle_at
from imucalib.procedures.p1.roles import (
    P1_ACCEL_POSITION,
    P1_GYRO_BIAS,
    P1_GYRO_RATE,
    P1_HELD_OUT_POSITION,
    P1_HELD_OUT_RATE,
)
from imucalib.procedures.p1.windows import WindowObservation
from imucalib.processing import (
    compute_integer_revolution_window,
    compute_window_statistics,
    lowpass_zero_phase,
    reject_outliers_3sigma,
    reject_outliers_grubbs,
    reject_outliers_robust,
    synchronize,
)
from imucalib.processing.moments import block_means

__all__ = ["CHUNK_ROWS", "OUTLIER_TIMES_KEPT", "RATE_ROLES", "P1Processing", "WindowReducer"]

_F64 = NDArray[np.float64]
#: The IMU columns a window reads: the samples, the counter of the time base and dropouts, and
#: the saturation flags.
_IMU_READ = (*GYRO_COLUMNS, *ACCEL_COLUMNS, "counter", "saturated")


@dataclass(frozen=True)
class P1Processing(WindowLimits):
    """Settings of the processing chain (docs/p1.md, processing rules 1–3).

    The window limits (:class:`~imucalib.procedures.common.window_checks.WindowLimits`:
    ``max_lost_fraction``, ``max_gap_s``: what a window may lose to dropouts) and:

    Attributes
    ----------
    outlier_test : {"robust", "3sigma", "grubbs", "none"}
        ``"robust"`` (default): one pass against the running median of each sample's
        neighbours, threshold k(n) = Φ⁻¹(1 − α_n/2), α_n = 1 − (1 − α)^{1/n}
        (:func:`~imucalib.processing.reject_outliers_robust`), so that a Gaussian window loses
        any sample with probability `outlier_alpha`. ``"3sigma"`` and ``"grubbs"`` are the
        rules P1 names (docs/p1.md, rule 1): the 3σ rule flags 0.27 % of good Gaussian samples
        per window whatever its length, truncating the distribution and biasing the noise
        figures computed after it; the Grubbs test (α = 0.05) flags a good sample in 5 % of the
        windows.
    outlier_passes : int
        Passes of the 3σ rule (robust centre and scale); three catch clusters that mask each
        other, further passes only erode the Gaussian tails.
    outlier_alpha : float
        α of the robust rule: the probability that a Gaussian window loses any sample.
    outlier_method : {"interpolate", "drop"}
    cutoff_fraction : float or None
        Low-pass cut-off as a fraction of the IMU bandwidth (1/5–1/3); None: no filter.
    max_alignment_error_s : float
        Largest synchronisation error allowed (docs/p1.md, rule 3: 1 ms). [s]
    gravity_mps2 : float or None
        g for the reference specific force; None: the site's normal gravity (P1's 9.80665 is
        the alternative for a site that does not know its g). [m/s²]
    """

    outlier_test: Literal["robust", "3sigma", "grubbs", "none"] = "robust"
    outlier_passes: int = 3
    outlier_alpha: float = 0.01
    outlier_method: Literal["interpolate", "drop"] = "interpolate"
    cutoff_fraction: float | None = 0.25
    max_alignment_error_s: float = 1e-3
    gravity_mps2: float | None = None


#: Rows per block of a long static window (bounded memory).
CHUNK_ROWS = 1 << 18
#: Times of flagged rows a WindowObservation keeps (the first ones).
OUTLIER_TIMES_KEPT = 10


@dataclass
class _Flagged:
    """Outliers of a window, accumulated over its blocks: counts per channel, first times."""

    per_channel: NDArray[np.int64] = field(default_factory=lambda: np.zeros(6, dtype=np.int64))
    times_s: list[float] = field(default_factory=list)
    tested: bool = False

    @property
    def total(self) -> int:
        return int(self.per_channel.sum())

    def add(self, other: _Flagged) -> None:
        self.per_channel = self.per_channel + other.per_channel
        self.times_s = (self.times_s + other.times_s)[:OUTLIER_TIMES_KEPT]
        self.tested = self.tested or other.tested

    def fields(self) -> dict[str, Any]:
        """Return the WindowObservation fields."""
        return {"n_outliers": self.total,
                "outliers_per_channel": (tuple(int(c) for c in self.per_channel)
                                         if self.tested else ()),
                "outlier_times_s": tuple(self.times_s)}
_ALLAN_POINTS = 1 << 19


def _meta_json(rec: Recording, key: str) -> dict[str, Any]:
    text = rec.metadata.get(key)
    if isinstance(text, dict):
        return text
    if not text:
        return {}
    try:
        value = json.loads(str(text))
    except ValueError as exc:
        raise RecordingError(f"{rec.path}: metadata {key} is not JSON: {exc}") from exc
    return value if isinstance(value, dict) else {}


#: The tag the fit selects a window by, implied by its role.
_ROLE_TAGS = {P1_ACCEL_POSITION: "six-position", P1_GYRO_BIAS: "gyro-bias"}
RATE_ROLES = (P1_GYRO_RATE, P1_HELD_OUT_RATE)
_HELD_OUT_ROLES = (P1_HELD_OUT_POSITION, P1_HELD_OUT_RATE)
#: A rate point whose rate the recording does not give is static below this measured rate.
_STATIC_RATE_DPS = 0.01


def _repetition(tags: Sequence[str]) -> int:
    for t in tags:
        if t.startswith("rep") and t[3:].isdigit():
            return int(t[3:])
        if t.startswith("repetition=") and t[len("repetition="):].isdigit():
            return int(t[len("repetition="):])
    return 1


def _window_tags(step: StepRecord, role: str) -> tuple[str, ...]:
    implied = _ROLE_TAGS.get(role)
    return step.tags if implied is None or implied in step.tags else (*step.tags, implied)


def _plan_step(step: StepRecord) -> int:
    cmd = step.commanded if isinstance(step.commanded, dict) else {}
    value = cmd.get("plan_step")
    return value if isinstance(value, int) and not isinstance(value, bool) else step.index


def _commanded_number(step: StepRecord, key: str) -> float | None:
    cmd = step.commanded if isinstance(step.commanded, dict) else {}
    value = cmd.get(key)
    if isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value):
        return float(value)
    return None


class WindowReducer:
    """Reduce the windows of one IMU of a P1 recording, one step at a time (module docstring).

    Holds what every window of the recording shares: the table stream and its axes, the IMU's
    sample rate and bandwidth (the first window's counter gives a rate the recording does not
    state), the site's g and Earth rate, and the low-pass cut-off used.
    """

    def __init__(self, rec: Recording, sensor_id: str, opt: P1Processing) -> None:
        self.rec, self.sensor, self.opt = rec, sensor_id, opt
        meta = rec.metadata
        tables = [s for s in rec.streams if s.device == DEVICE_TABLE]
        if not tables:
            raise RecordingError(f"{rec.path} has no table stream: P1 needs the table feedback")
        self.table = tables[0]
        self.axis_names = tuple(c[len("angle_"):-len("_rad")] for c in self.table.columns
                                if c.startswith("angle_") and c.endswith("_rad"))
        for name in self.axis_names:
            _axis_vector(name)
        if not any(s.device == DEVICE_IMU and s.unit == sensor_id for s in rec.streams):
            have = [s.unit for s in rec.streams if s.device == DEVICE_IMU]
            raise RecordingError(f"{rec.path} has no IMU stream {sensor_id!r}; it has {have}")
        ident = _meta_json(rec, "imu_identity_json").get(sensor_id, {})
        self.sample_rate_hz = float(ident.get("sample_rate_hz") or 0.0)
        self.bandwidth_hz = ident.get("bandwidth_hz")
        lat = float(meta.get("latitude_deg", math.nan))
        heading = float(meta.get("heading_deg", 0.0))
        if not math.isfinite(lat):
            raise RecordingError(f"{rec.path} does not record the latitude (latitude_deg): the "
                                 "Earth-rate projection needs it")
        self.latitude_deg, self.heading_deg = lat, heading
        self.g, self.earth_t = site_vectors(lat, heading, opt.gravity_mps2)
        self.cutoff_hz: float | None = None
        self.notes: list[str] = []

    def imu_window(self, step_index: int) -> tuple[_F64, _F64, _Flagged]:
        """Return (time, values (n, 6): gyro then accel, outliers removed) of a step."""
        # read into the call: clean() releases the rows once it has their samples
        return self.clean(step_index,
                          self.rec.read_step(step_index, DEVICE_IMU, self.sensor, _IMU_READ))

    def clean(self, step_index: int, data: Any) -> tuple[_F64, _F64, _Flagged]:
        """Check one block of IMU rows, give it the counter's time base, reject outliers.

        :meth:`samples` then :meth:`rejected`; `data` is released in between (the rows as read
        are not held while the outliers are tested).
        """
        values, t = self.samples(step_index, data)
        del data
        return self.rejected(values, t)

    def samples(self, step_index: int, data: Any) -> tuple[_F64, _F64]:
        """Return (values (n, 6), times) of one block of IMU rows, checked. [SI], [s]

        The shared window reader's checks (:func:`~imucalib.procedures.common.window_checks.
        checked_samples`: samples, finiteness, saturation; :func:`~imucalib.procedures.common.
        windows.counter_times`: counter and dropouts within the limits); the times are the
        counter's time base.
        """
        where = f"step {step_index}"
        values = checked_samples(where, data, (*GYRO_COLUMNS, *ACCEL_COLUMNS))
        t, period, _ = counter_times(where, data.columns["counter"], data.time_s,
                                     max_lost_fraction=self.opt.max_lost_fraction,
                                     max_gap_s=self.opt.max_gap_s, reconstruct=True)
        if self.sample_rate_hz <= 0:
            self.sample_rate_hz = 1.0 / period
        return values, t

    def rejected(self, values: _F64, t: _F64) -> tuple[_F64, _F64, _Flagged]:
        """Return (time, values, outliers) of a block with its outliers rejected (or not tested).

        The test and method of :class:`P1Processing`; dropped rows leave the times too.
        """
        flagged = _Flagged()
        test, method = self.opt.outlier_test, self.opt.outlier_method
        if test != "none":
            if test == "robust":
                res = reject_outliers_robust(values, alpha=self.opt.outlier_alpha, method=method,
                                             time_s=t)
            elif test == "3sigma":
                res = reject_outliers_3sigma(values, method=method, time_s=t,
                                             max_iterations=self.opt.outlier_passes)
            else:
                res = reject_outliers_grubbs(values, method=method, time_s=t)
            del values
            rows = (np.flatnonzero(res.outlier_mask.any(axis=1))[:OUTLIER_TIMES_KEPT]
                    if res.n_outliers.any() else np.empty(0, dtype=np.intp))
            flagged = _Flagged(per_channel=np.asarray(res.n_outliers, dtype=np.int64),
                               times_s=[float(x) for x in t[rows]], tested=True)
            values = res.values
            if method == "drop":
                t = t[res.kept]
        return t, values, flagged

    def filtered(self, values: _F64) -> _F64:
        """Return `values` low-passed at the cut-off fraction of the IMU bandwidth (or as is)."""
        frac = self.opt.cutoff_fraction
        if frac is None:
            return values
        bw = float(self.bandwidth_hz) if self.bandwidth_hz else 0.45 * self.sample_rate_hz
        res = lowpass_zero_phase(values, self.sample_rate_hz, bandwidth_hz=bw,
                                 cutoff_fraction=frac)
        self.cutoff_hz = res.cutoff_hz
        return res.values

    def observe_long_static(self, step: StepRecord, role: str, tags: tuple[str, ...],
                            step_role: str) -> WindowObservation:
        """Observe a long static window in blocks of :data:`CHUNK_ROWS` rows (bounded memory).

        The mean and the scatter are accumulated exactly over the blocks (each block's time
        base, outliers and low-pass on its own); the Allan fit uses the means of 2^k-sample
        blocks (at most 2^19 of them: the overlapping estimator at the coarser spacing, unbiased);
        the alignment error is that of the first block. The table feedback is read in blocks
        too (:meth:`static_feedback`).
        """
        i0, i1 = self.rec.row_range(DEVICE_IMU, self.sensor, step.valid_start_s,
                                    step.valid_end_s)
        n_total = i1 - i0
        decim = 1 << max(0, math.ceil(math.log2(max(n_total, 1) / _ALLAN_POINTS)))
        acc = _Moments()
        # the 2^k-sample means, in one array (each block leaves out its partial last group)
        means = np.empty((n_total // decim, len(GYRO_COLUMNS) + len(ACCEL_COLUMNS)))
        n_means = 0
        flagged = _Flagged()
        align = math.nan
        t_first = t_last = math.nan
        for block in self.rec.iter_stream(DEVICE_IMU, self.sensor, CHUNK_ROWS, _IMU_READ,
                                          step.valid_start_s, step.valid_end_s):
            if len(block) < 10:
                continue
            values, t = self.samples(step.index, block)
            del block  # one block's arrays at a time: what is read goes once it is copied
            t, raw, out = self.rejected(values, t)
            del values
            flagged.add(out)
            filt = self.filtered(raw)
            acc.add(raw, filt)
            block_mean = block_means(raw, decim)
            means[n_means:n_means + block_mean.shape[0]] = block_mean
            n_means += block_mean.shape[0]
            if math.isnan(align):
                align = float(synchronize(
                    t, filt, self.feedback_times(step, t[0], t[-1]),
                    max_alignment_error_s=self.opt.max_alignment_error_s,
                    signal_bandwidth_hz=self.cutoff_hz).alignment_error_s)
                t_first = float(t[0])
            t_last = float(t[-1])
            del t, raw, filt, block_mean
        stats = compute_window_statistics(means[:n_means], self.sample_rate_hz / decim)
        del means
        mean_angles = self.static_feedback(step)
        rate_b, force_b = static_inputs_b(self.axis_names, mean_angles, self.g, self.earth_t)
        mean = acc.mean
        return WindowObservation(
            step_index=step.index, plan_step=_plan_step(step), kind="static",
            role=role, repetition=_repetition(tags), tags=tags, label=step.label,
            step_role=step_role, gyro_mean_rps=mean[:3], accel_mean_mps2=mean[3:],
            gyro_se_rps=stats.standard_error[:3], accel_se_mps2=stats.standard_error[3:],
            gyro_std_rps=acc.std[:3], accel_std_mps2=acc.std[3:],
            rate_b_rps=rate_b, force_b_mps2=force_b,
            angles_rad=np.asarray(mean_angles, dtype=np.float64), table_rate_rps=0.0,
            axis=None, n_samples=acc.n, **flagged.fields(), n_revolutions=0,
            alignment_error_s=align, duration_s=t_last - t_first, t_start_s=t_first,
            allan_fit=np.vstack([stats.white_density, stats.flicker_variance,
                                 stats.random_walk]))

    def feedback_times(self, step: StepRecord, t0_s: float, t1_s: float) -> _F64:
        """Return the times of the step's table feedback rows with t0_s ≤ time ≤ t1_s. [s]"""
        lo = max(float(t0_s), step.valid_start_s)
        hi = min(float(np.nextafter(t1_s, math.inf)), step.valid_end_s)
        if hi < lo:
            return np.empty(0)
        return np.asarray(self.rec.read_stream(DEVICE_TABLE, self.table.unit, [], lo, hi).time_s,
                          dtype=np.float64)

    def static_feedback(self, step: StepRecord) -> _F64:
        """Return the mean table angles over a step's valid window, read in blocks. [rad]

        numpy's mean of the angles (rows: feedback samples, columns: axes) bit for bit
        (:class:`~imucalib.procedures.common.windows.RunningRowMean`); a one-axis table's single
        column, which numpy sums pairwise, is read whole (8 bytes a feedback sample).

        Raises
        ------
        MissingSegmentError
            No table feedback in the window.
        """
        cols = [axis_columns(a)[0] for a in self.axis_names]
        where = (step.valid_start_s, step.valid_end_s)
        blocks = (self.rec.iter_stream(DEVICE_TABLE, self.table.unit, CHUNK_ROWS, cols, *where)
                  if len(cols) > 1 else
                  [self.rec.read_stream(DEVICE_TABLE, self.table.unit, cols, *where)])
        acc = _RowMean()
        one = None
        for block in blocks:
            angles = np.column_stack([block.columns[c] for c in cols])
            if len(cols) > 1:
                acc.add(angles)
            elif angles.shape[0]:
                one = np.asarray(angles.mean(axis=0), dtype=np.float64)
        if one is None and not acc.n:
            raise MissingSegmentError(f"step {step.index} ({step.label}): no table feedback in "
                                      "its valid window")
        return one if one is not None else acc.mean

    def observe(self, step: StepRecord, step_role: str, own_noise: bool = True
                ) -> WindowObservation:
        """Reduce one step's valid window to a :class:`WindowObservation` (module docstring).

        Without `own_noise` the window's own Allan fit is not made (its standard errors are NaN
        and ``allan_fit`` None): for windows whose standard errors the noise model of the long
        static record replaces (:func:`~.observations.extract_p1_observations`).
        """
        role = "verification" if step_role in _HELD_OUT_ROLES else "calibration"
        tags = _window_tags(step, step_role)
        spins = step_role in RATE_ROLES
        if not spins:
            i0, i1 = self.rec.row_range(DEVICE_IMU, self.sensor, step.valid_start_s,
                                        step.valid_end_s)
            if i1 - i0 > CHUNK_ROWS:
                return self.observe_long_static(step, role, tags, step_role)
        t, raw, flagged = self.imu_window(step.index)
        stats = compute_window_statistics(raw, self.sample_rate_hz) if own_noise else None
        filt = self.filtered(raw)
        fb = self.rec.read_step(step.index, DEVICE_TABLE, self.table.unit)
        inside = (fb.time_s >= t[0]) & (fb.time_s <= t[-1])
        if np.count_nonzero(inside) < 2:
            raise RecordingError(f"step {step.index} ({step.label}): fewer than 2 table feedback "
                                 "samples inside the IMU window")
        fb_t = fb.time_s[inside]
        angles = np.column_stack([fb.columns[axis_columns(a)[0]][inside]
                                  for a in self.axis_names])
        rates = np.column_stack([fb.columns[axis_columns(a)[1]][inside]
                                 for a in self.axis_names])
        # the filtered signal holds nothing above the cut-off: the interpolation bound uses it
        sync = synchronize(t, filt, fb_t, max_alignment_error_s=self.opt.max_alignment_error_s,
                           signal_bandwidth_hz=self.cutoff_hz)
        axis, rate_dps = self.spin(step, rates) if spins else (None, 0.0)
        n_rev = 0
        if axis is not None and rate_dps != 0.0:
            # at constant rate the table angle is linear in time: interpolated onto the IMU
            # times it gives every IMU sample its angle, so the whole-revolution mean uses all
            # samples whatever the feedback rate (the IMU-onto-table interpolation above
            # still bounds the alignment error)
            # IMU samples just outside the feedback span (less than a feedback period at each
            # end) get the angle extrapolated at the rate of the span: without them the span of
            # a valid window that holds exactly N revolutions would hold only N − 1 whole ones
            imu_angle = _angle_at(t, fb_t, np.unwrap(angles[:, axis]))
            win = compute_integer_revolution_window(t, filt, angle_rad=imu_angle)
            mean = win.mean
            in_win = (fb_t >= win.start_time_s) & (fb_t <= win.end_time_s)
            sel = in_win if np.count_nonzero(in_win) >= 2 else np.ones(fb_t.size, dtype=bool)
            n_rev = win.n_revolutions
            t0, span = float(win.start_time_s), float(win.end_time_s - win.start_time_s)
            table_rate = float(np.mean(rates[sel, axis]))
            held = angles[sel].mean(axis=0)
            held[axis] = float(np.interp(win.start_time_s, fb_t, angles[:, axis]))
            rate_b, force_b = rate_inputs_b(self.axis_names, axis, held, table_rate, self.g,
                                            self.earth_t)
            kind, mean_angles = "rate", held
            in_imu = slice(win.start_index, win.stop_index)
            resid_std = _harmonic_residual_std(filt[in_imu], imu_angle[in_imu])
        else:
            mean = sync.values.mean(axis=0)
            mean_angles = angles.mean(axis=0)
            rate_b, force_b = static_inputs_b(self.axis_names, mean_angles, self.g, self.earth_t)
            table_rate, kind = 0.0, "static"
            t0, span = float(fb_t[0]), float(fb_t[-1] - fb_t[0])
            resid_std = filt.std(axis=0, ddof=1)
        se = np.full(6, np.nan) if stats is None else stats.standard_error
        return WindowObservation(
            step_index=step.index, plan_step=_plan_step(step), kind=kind,
            role=role, repetition=_repetition(tags), tags=tags, label=step.label,
            step_role=step_role, gyro_mean_rps=np.asarray(mean[:3], dtype=np.float64),
            accel_mean_mps2=np.asarray(mean[3:], dtype=np.float64),
            gyro_se_rps=se[:3], accel_se_mps2=se[3:],
            gyro_std_rps=resid_std[:3], accel_std_mps2=resid_std[3:],
            rate_b_rps=np.asarray(rate_b, dtype=np.float64),
            force_b_mps2=np.asarray(force_b, dtype=np.float64),
            angles_rad=np.asarray(mean_angles, dtype=np.float64), table_rate_rps=table_rate,
            axis=axis, n_samples=int(t.size), **flagged.fields(), n_revolutions=n_rev,
            alignment_error_s=float(sync.alignment_error_s), duration_s=span, t_start_s=t0,
            allan_fit=None if stats is None else np.vstack([
                stats.white_density, stats.flicker_variance, stats.random_walk]))

    def spin(self, step: StepRecord, rates_rps: _F64) -> tuple[int | None, float]:
        """Return the spinning table axis and commanded rate [°/s] of a rate step.

        From ``commanded`` (``axis``, ``rate_dps``); what it lacks, from the table feedback
        `rates_rps` (n, axes): the axis turning fastest, and its measured mean rate (0 below
        :data:`_STATIC_RATE_DPS`).
        """
        axis_value = _commanded_number(step, "axis")
        rate_dps = _commanded_number(step, "rate_dps")
        mean_dps = np.degrees(np.mean(rates_rps, axis=0))
        if axis_value is None:
            axis = int(np.argmax(np.abs(mean_dps)))
        else:
            axis = int(axis_value)
            if not (axis_value == axis and 0 <= axis < len(self.axis_names)):
                raise RecordingError(
                    f"step {step.index} ({step.label}): commanded axis {axis_value:g} is not "
                    f"one of the table's axes {list(range(len(self.axis_names)))} "
                    f"({', '.join(self.axis_names)})")
        if rate_dps is None:
            measured = float(mean_dps[axis])
            rate_dps = measured if abs(measured) >= _STATIC_RATE_DPS else 0.0
        return axis, rate_dps
