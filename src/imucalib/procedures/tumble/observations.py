"""From a tumble Recording to each position's mean accelerometer outputs and reference gravity.

One step's valid window at a time (memory bounded by the longest record):

1. the unit's accelerometer samples (x, y, z), the sample counter and the saturation flags; a
   window with a saturated sample is refused (:class:`~imucalib.errors.SaturationError`), one
   with dropouts beyond :attr:`TumbleProcessing.max_lost_fraction` is missing;
2. the mean of each accelerometer over the window, and the table's mean measured angles from
   its feedback over the same window;
3. the specific force in the body frame, Eq. (T.10): f_p = rot_tpᵀ·[0, 0, g] at the measured
   angles (:func:`~imucalib.procedures.common.reference.static_inputs_b`), f_b = R_pmᵀ·f_p with
   R_pm the fixture's remount (tags ``mount=``, ``yaw=``;
   :func:`~imucalib.plan.fixture_poses.rot_pm_for_pose`);
4. the standard error of each mean, N/√T per accelerometer: N² = Σ (K_i − 1)·s_i²·τ /
   Σ (K_i − 1) pooled over all the unit's records, s_i² the variance of record i's K_i block
   means of τ = :attr:`TumbleProcessing.noise_block_s` (as P3 does, docs/p3.md). Noise
   correlated over longer times shows in the fit's χ² (Birge).

Contents
--------
:class:`TumbleProcessing`, :class:`TumbleWindow`, :func:`extract_tumble_windows`.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from imucalib.conventions import ACCEL_COLUMNS
from imucalib.errors import (
    InvalidInputError,
    MissingSegmentError,
    RecordingError,
)
from imucalib.io.reader import Recording, StepRecord, StreamData
from imucalib.io.streams import DEVICE_IMU, DEVICE_TABLE, axis_columns
from imucalib.plan.fixture_poses import FIXTURE_AXES, rot_pm_for_pose
from imucalib.procedures.common.noise import block_variance
from imucalib.procedures.common.reference import static_inputs_b
from imucalib.procedures.common.window_checks import (
    BlockNoiseLimits,
    checked_samples,
    pooled_white_se,
)
from imucalib.procedures.tumble.roles import TUMBLE_DRIFT, TUMBLE_POSITION

__all__ = ["TumbleProcessing", "TumbleWindow", "extract_tumble_windows"]

_F64 = NDArray[np.float64]
#: Roles whose windows the analysis reduces.
WINDOW_ROLES = (TUMBLE_POSITION, TUMBLE_DRIFT)


@dataclass(frozen=True)
class TumbleProcessing(BlockNoiseLimits):
    """Options of the window reduction (module docstring).

    The window limits (:class:`~imucalib.procedures.common.window_checks.BlockNoiseLimits`; a
    static record's dropouts are limited by their fraction, not by the longest gap), with
    `max_lost_fraction` in [0, 1).
    """

    def __post_init__(self) -> None:
        super().__post_init__()
        if not 0 <= self.max_lost_fraction < 1:
            raise InvalidInputError(f"`max_lost_fraction` must be in [0, 1); got "
                                    f"{self.max_lost_fraction!r}")


@dataclass(frozen=True)
class TumbleWindow:
    """One record, reduced (module docstring).

    Attributes
    ----------
    step_index, label, role : int, str, str
        The recorded step.
    axis : str
        The body axis along the head axis (tag ``axis=``).
    angle_deg : float
        The head angle θ_k commanded (tag ``angle=``). [°]
    n_positions : int
        N of its sequence (tag ``positions=``).
    direction : str
        ``cw``, ``ccw`` or ``""`` (tag ``pass=``).
    table_angles_rad : ndarray, shape (2,)
        Mean measured (pitch, roll). [rad]
    force_b : ndarray, shape (3,)
        The specific force in the body frame at the measured angles, (T.10). [m/s²]
    force_nominal_b : ndarray, shape (3,)
        The same at the commanded angles (the DFT form's equally spaced positions). [m/s²]
    mean, se : ndarray, shape (3,)
        Mean output of the x, y, z accelerometers and their standard errors. [m/s²]
    duration_s : float
    time_s : float
        Middle of the window (station time). [s]
    block_variance : (int, ndarray)
        Degrees of freedom K − 1 and s²·τ per accelerometer. [(m/s²)²·s]
    """

    step_index: int
    label: str
    role: str
    axis: str
    angle_deg: float
    n_positions: int
    direction: str
    table_angles_rad: _F64
    force_b: _F64
    force_nominal_b: _F64
    mean: _F64
    se: _F64
    duration_s: float
    time_s: float
    block_variance: tuple[int, _F64]


def _tag(step: StepRecord, key: str, default: str | None = None) -> str:
    """Return tag `key`'s value, or `default`; a required tag missing is a RecordingError."""
    value = step.tag_value(key)
    if value is not None:
        return value
    if default is None:
        raise RecordingError(f"step {step.index} ({step.label}): a tumble record needs the tag "
                             f"{key}=; its tags are {list(step.tags)}")
    return default


def _number(step: StepRecord, key: str, default: str | None = None) -> float:
    value = _tag(step, key, default)
    try:
        return float(value)
    except ValueError:
        raise RecordingError(f"step {step.index} ({step.label}): tag {key}={value!r} is not a "
                             "number") from None


class _Reducer:
    def __init__(self, unit: str, opt: TumbleProcessing, axis_names: tuple[str, ...],
                 gravity_mps2: float, earth_t: _F64) -> None:
        self.unit, self.opt, self.axis_names = unit, opt, axis_names
        self.g, self.earth_t = gravity_mps2, earth_t

    def reduce(self, step: StepRecord, data: StreamData, fb: StreamData) -> TumbleWindow:
        where = f"unit {self.unit}, step {step.index} ({step.label})"
        if len(data) < 10 or len(fb) < 1:
            raise MissingSegmentError(f"{where}: only {len(data)} samples and {len(fb)} table "
                                      "feedback samples in its valid window")
        values = checked_samples(where, data, ACCEL_COLUMNS,
                                 saturation_note=lambda _: " (the output reached its range)")
        counter = np.asarray(data.columns["counter"], dtype=np.int64)
        steps = np.diff(counter)
        if np.any(steps <= 0):
            raise InvalidInputError(f"{where}: the sample counter repeats or goes backwards")
        t = np.asarray(data.time_s, dtype=np.float64)
        period = float(t[-1] - t[0]) / float(counter[-1] - counter[0])
        lost = int(np.sum(steps - 1))
        if lost > self.opt.max_lost_fraction * (len(data) + lost):
            raise MissingSegmentError(f"{where}: {lost} of {len(data) + lost} samples lost to "
                                      f"dropouts (at most {self.opt.max_lost_fraction:.0%})")
        angles = np.array([float(np.mean(fb.columns[axis_columns(a)[0]]))
                           for a in self.axis_names])
        pose = _tag(step, "mount", "+z")
        if pose not in FIXTURE_AXES:
            raise RecordingError(f"{where}: tag mount={pose!r} is not a pose of "
                                 f"{list(FIXTURE_AXES)}")
        yaw = _number(step, "yaw", "0")
        rot_pm = rot_pm_for_pose(pose, yaw)
        _, force_p = static_inputs_b(self.axis_names, angles, self.g, self.earth_t)
        cmd = step.commanded.get("angles_deg") if isinstance(step.commanded, dict) else None
        nominal = (np.radians(np.asarray(cmd, dtype=np.float64))
                   if isinstance(cmd, list) and len(cmd) == len(angles) else angles)
        _, nominal_p = static_inputs_b(self.axis_names, nominal, self.g, self.earth_t)
        blocks = block_variance(values, period, self.opt.noise_block_s)
        return TumbleWindow(
            step_index=step.index, label=step.label, role=step.role,
            axis=_tag(step, "axis"), angle_deg=_number(step, "angle"),
            n_positions=int(_number(step, "positions", "0")), direction=_tag(step, "pass", ""),
            table_angles_rad=angles, force_b=np.asarray(rot_pm.T @ force_p, dtype=np.float64),
            force_nominal_b=np.asarray(rot_pm.T @ nominal_p, dtype=np.float64),
            mean=values.mean(axis=0), se=np.full(3, math.nan), duration_s=float(t[-1] - t[0]),
            time_s=float(0.5 * (t[0] + t[-1])), block_variance=blocks)


def _pooled(unit: str, windows: list[TumbleWindow]) -> list[TumbleWindow]:
    """Give each window the white-noise standard errors N/√T of the unit (module docstring)."""
    se = pooled_white_se([w.block_variance for w in windows], [w.duration_s for w in windows],
                         unit=unit, what="record")
    return [dataclasses.replace(w, se=e) for w, e in zip(windows, se, strict=True)]


def extract_tumble_windows(rec: Recording, unit: str, gravity_mps2: float, earth_rate_t_rps: _F64,
                           *, processing: TumbleProcessing | None = None,
                           steps: Sequence[StepRecord] | None = None,
                           progress: Callable[[float], None] | None = None
                           ) -> list[TumbleWindow]:
    """Reduce every tumble record of one unit (module docstring).

    Raises
    ------
    RecordingError
        No IMU stream `unit`, no table stream, no step with a tumble role, a record's tags
        missing.
    MissingSegmentError
        A record with too many dropouts or too short for the noise estimate.
    SaturationError
        A record with saturated samples.
    """
    opt = processing or TumbleProcessing()
    imus = [s.unit for s in rec.streams if s.device == DEVICE_IMU]
    if unit not in imus:
        raise RecordingError(f"{rec.path} has no IMU stream {unit!r}; it has {imus}")
    chosen = [s for s in (rec.steps if steps is None else steps)
              if s.role in WINDOW_ROLES and s.concerns(unit)]
    if not chosen:
        raise RecordingError(f"{rec.path}: no step has a tumble role ({', '.join(WINDOW_ROLES)})"
                             "; is it a tumble recording?")
    tables = [s for s in rec.streams if s.device == DEVICE_TABLE]
    if not tables:
        raise RecordingError(f"{rec.path} has no table stream: the tumble needs the dividing "
                             "head's measured angles")
    axis_names = tuple(c[len("angle_"):-len("_rad")] for c in tables[0].columns
                       if c.startswith("angle_") and c.endswith("_rad"))
    usable = [s for s in chosen if s.status == "done" and s.has_valid_window]
    red = _Reducer(unit, opt, axis_names, gravity_mps2, earth_rate_t_rps)
    spans = [(s.valid_start_s, s.valid_end_s) for s in usable]
    imu_rows = rec.iter_windows(DEVICE_IMU, unit, spans, [*ACCEL_COLUMNS, "counter", "saturated"])
    fb_rows = rec.iter_windows(DEVICE_TABLE, tables[0].unit, spans,
                               [axis_columns(a)[0] for a in axis_names])
    windows = []
    for i, (step, data, fb) in enumerate(zip(usable, imu_rows, fb_rows, strict=True), start=1):
        windows.append(red.reduce(step, data, fb))
        if progress is not None:
            progress(i / len(usable))
    if not windows:
        raise MissingSegmentError(f"{rec.path}: no tumble record of unit {unit} completed")
    return _pooled(unit, windows)
