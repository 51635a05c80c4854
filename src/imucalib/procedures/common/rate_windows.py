"""Rate windows: from a rate-table Recording to the whole-revolution gyro means of every turn.

Shared by the rate-transfer and the installation tests (docs/rate-transfer.md, "Observations";
docs/installation.md, "Analysis"): :func:`extract_rate_windows` reduces every turn of one unit to
a :class:`RateWindow`, with the options of :class:`RateProcessing`. One turn's valid window at a
time:

1. the unit's gyro samples, sample counter and saturation flags; a window holding a saturated
   sample is refused (:class:`~imucalib.errors.SaturationError`: a clipped mean biases the scale
   factor), one with dropouts beyond :attr:`RateProcessing.max_lost_fraction` (or one gap longer
   than :attr:`RateProcessing.max_gap_s`) is missing;
2. each sample's table angle interpolated from the encoder feedback on the counter's time base;
   the mean over the longest span of whole revolutions
   (:func:`~imucalib.processing.statistics.compute_integer_revolution_window`, eq. (RT-2) of
   docs/rate-transfer.md): the Earth rate's horizontal part and any once-per-revolution term
   cancel; the span must hold the commanded revolutions, one fewer accepted (a sample short at
   each edge of the station's window) — fewer is a :class:`~imucalib.errors.MissingSegmentError`;
3. the table rate over the span: the encoder angle turned over its time (eq. (RT-3));
4. the standard error of each mean N/√T, N the unit's white-noise density per axis from the
   scatter of 1 s block means about the once-per-revolution harmonic, pooled over all its turns:
   N² = Σ (K_i − 1)·s_i²·τ / Σ (K_i − 1) (eq. (RT-4)).

Contents
--------
:class:`RateProcessing`, :class:`RateWindow`, :func:`extract_rate_windows`, :func:`pooled_se`
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from imucalib.conventions import GYRO_COLUMNS
from imucalib.errors import (
    MissingSegmentError,
    RecordingError,
)
from imucalib.io.reader import Recording, StepRecord, StreamData
from imucalib.io.streams import DEVICE_IMU, DEVICE_TABLE, axis_columns
from imucalib.procedures.common.noise import block_variance
from imucalib.procedures.common.reference import site_vectors
from imucalib.procedures.common.window_checks import (
    BlockNoiseLimits,
    checked_samples,
    pooled_white_se,
)
from imucalib.procedures.common.windows import counter_times, whole_revolutions

__all__ = ["RateProcessing", "RateWindow", "extract_rate_windows", "pooled_se"]

_F64 = NDArray[np.float64]
_AXES = {"x": 0, "y": 1, "z": 2}


@dataclass(frozen=True)
class RateProcessing(BlockNoiseLimits):
    """Options of the turn reduction (module docstring): the window limits, as they are."""


@dataclass(frozen=True)
class RateWindow:
    """One turn of one unit, reduced (module docstring).

    Attributes
    ----------
    step_index, label : int, str
        The recorded step.
    axis : {"x", "y", "z"}
        The body axis up (tag ``axis=``).
    commanded_rate_dps : float
        The plan's rate. [°/s]
    table_rate_rps : float
        Encoder angle over time across the averaged span (eq. (RT-3)). [rad/s]
    n_revolutions : int
        Whole revolutions averaged.
    gyro_mean_rps, gyro_se_rps : ndarray, shape (3,)
        Mean output of the three gyros and its standard error. [rad/s]
    duration_s : float
        Span averaged. [s]
    block_variance : (int, ndarray (3,))
        Degrees of freedom K − 1 and s²·τ from the window's block means. [(rad/s)²·s]
    """

    step_index: int
    label: str
    axis: str
    commanded_rate_dps: float
    table_rate_rps: float
    n_revolutions: int
    gyro_mean_rps: _F64
    gyro_se_rps: _F64
    duration_s: float
    block_variance: tuple[int, _F64]

    @property
    def angle_rad(self) -> _F64:
        """Integrated angle of each gyro over the span, mean × T (eq. (IN-1)). [rad]"""
        return np.asarray(self.gyro_mean_rps * self.duration_s, dtype=np.float64)


def _where(unit: str, step: StepRecord) -> str:
    return f"unit {unit}, step {step.index} ({step.label})"


def _reduce(unit: str, step: StepRecord, data: StreamData, fb: StreamData, angle_col: str,
            opt: RateProcessing) -> RateWindow:
    where = _where(unit, step)
    axis = step.tag_value("axis")
    if axis not in _AXES:
        raise RecordingError(f"{where}: tag axis={axis!r}; expected axis=x, y or z (the body "
                             "axis up)")
    values = checked_samples(where, data, GYRO_COLUMNS, saturation_note=lambda v: (
        f" (largest gyro output {np.degrees(np.max(np.abs(v))):.6g} °/s): a clipped mean "
        "biases the scale factor — keep the rates below the gyro's full scale"))
    t, period, _ = counter_times(where, np.asarray(data.columns["counter"]), data.time_s,
                                 max_lost_fraction=opt.max_lost_fraction,
                                 max_gap_s=opt.max_gap_s, reconstruct=True)
    wanted = step.commanded.get("revolutions") if isinstance(step.commanded, dict) else None
    turn = whole_revolutions(where, t, values, fb.time_s, np.asarray(fb.columns[angle_col]),
                             wanted)
    n_rev, rate, residual, ts = turn.n_revolutions, turn.rate_rps, turn.residual, turn.time_s
    blocks = block_variance(residual, period, opt.noise_block_s)
    commanded = step.commanded.get("rate_dps") if isinstance(step.commanded, dict) else None
    return RateWindow(
        step_index=step.index, label=step.label, axis=str(axis),
        commanded_rate_dps=float(commanded) if isinstance(commanded, int | float)
        else math.degrees(rate),
        table_rate_rps=rate, n_revolutions=n_rev,
        gyro_mean_rps=turn.mean.reshape(3),
        gyro_se_rps=np.full(3, np.nan), duration_s=float(ts[-1] - ts[0]),
        block_variance=blocks)


def pooled_se(windows: Sequence[RateWindow], unit: str = "?") -> list[RateWindow]:
    """Give each window the white-noise standard error N/√T per axis (eq. (RT-4)).

    Raises
    ------
    MissingSegmentError
        No window is long enough for three noise blocks.
    """
    se = pooled_white_se([w.block_variance for w in windows], [w.duration_s for w in windows],
                         unit=unit, what="turn")
    return [dataclasses.replace(w, gyro_se_rps=e) for w, e in zip(windows, se, strict=True)]


def extract_rate_windows(rec: Recording, unit: str | None, roles: Sequence[str], *,
                         processing: RateProcessing | None = None
                         ) -> tuple[str, list[RateWindow], float]:
    """Reduce every turn with one of `roles` of one unit (module docstring).

    Returns
    -------
    unit : str
        The unit analysed (the only IMU stream when `unit` is None).
    windows : list of RateWindow
        Its turns, in recorded order, with pooled standard errors.
    earth_rate_up_rps : float
        The vertical Earth rate Ω_U = Ω_e·sin L of the recorded latitude. [rad/s]

    Raises
    ------
    RecordingError
        No such IMU stream (or several and no `unit`), no single-axis table stream, no latitude,
        no step with one of `roles`.
    MissingSegmentError, SaturationError, InvalidInputError
        A turn that cannot be used (module docstring); a step with a role that did not finish.
    """
    opt = processing or RateProcessing()
    imus = [s.unit for s in rec.streams if s.device == DEVICE_IMU]
    if unit is None:
        if len(imus) != 1:
            raise RecordingError(f"{rec.path} has the IMU streams {imus}; name the unit")
        unit = imus[0]
    if unit not in imus:
        raise RecordingError(f"{rec.path} has no IMU stream {unit!r}; it has {imus}")
    tables = [s for s in rec.streams if s.device == DEVICE_TABLE]
    if not tables:
        raise RecordingError(f"{rec.path} has no table stream: the turns need the encoder")
    names = [c[len("angle_"):-len("_rad")] for c in tables[0].columns
             if c.startswith("angle_") and c.endswith("_rad")]
    if len(names) != 1:
        raise RecordingError(f"{rec.path}: a single-axis table is expected; the table stream "
                             f"has the axes {names}")
    angle_col, rate_col = axis_columns(names[0])[:2]
    lat = float(rec.metadata.get("latitude_deg", math.nan))
    if not math.isfinite(lat):
        raise RecordingError(f"{rec.path} does not record the latitude (latitude_deg): the "
                             "vertical Earth rate needs it")
    _, earth_t = site_vectors(lat, float(rec.metadata.get("heading_deg", 0.0)), None)
    chosen = [s for s in rec.steps if s.role in roles and s.concerns(unit)]
    if not chosen:
        raise RecordingError(f"{rec.path}: no step has the role {', '.join(roles)}")
    for s in chosen:
        if not (s.status == "done" and s.has_valid_window):
            raise MissingSegmentError(f"{_where(unit, s)}: the turn did not complete (status "
                                      f"{s.status!r}); every rate is needed")
    spans = [(s.valid_start_s, s.valid_end_s) for s in chosen]
    imu_rows = rec.iter_windows(DEVICE_IMU, unit, spans, [*GYRO_COLUMNS, "counter", "saturated"])
    fb_rows = rec.iter_windows(DEVICE_TABLE, tables[0].unit, spans, [angle_col, rate_col])
    windows = [_reduce(unit, step, data, fb, angle_col, opt)
               for step, data, fb in zip(chosen, imu_rows, fb_rows, strict=True)]
    return unit, pooled_se(windows, unit), float(earth_t[2])
