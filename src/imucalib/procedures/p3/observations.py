"""From a P3 Recording to the mean output of each accelerometer in each record.

One step's valid window of one unit at a time (memory bounded by the longest step):

1. the unit's samples of the window: its input-axis accelerometer (``accel_x`` by default,
   :attr:`P3Processing.input_axis`), the sample counter and the saturation flags; a window
   with a saturated sample is refused (:class:`~imucalib.errors.SaturationError`: a clipped
   mean would bias K2 silently), one with dropouts beyond :attr:`P3Processing.max_lost_fraction`
   (or a gap longer than :attr:`P3Processing.max_gap_s`) is missing;
2. a record at rest (roles ``p3.rest``, ``p3.tumble``) is averaged over its samples;
3. a spinning record (``p3.rate``) over the longest span of whole revolutions of the arm,
   each sample's arm angle interpolated from the centrifuge's encoder feedback on the
   counter's time base (:func:`~imucalib.processing.statistics.compute_integer_revolution_window`);
   the span must hold the commanded revolutions (one fewer when a sample at each edge falls
   outside the station's window), and its mean rate is the encoder's angle
   over the span's time (what the record's x = (ω + Ω_U)² − Ω_U² uses: IEEE Std 836 wants
   the rate counted over whole revolutions);
4. the standard error of each mean, N/√T: T the record's length, N the unit's white-noise
   density from the scatter of its 1 s block means (:attr:`P3Processing.noise_block_s`),
   pooled over all its records (a spinning one's about its once-per-revolution harmonic):
   N² = Σ (K_i − 1)·s_i²·τ / Σ (K_i − 1), s_i² the variance of record i's K_i block means of
   length τ. Blocks much longer than the output filter's memory keep N free of its bias (an
   Allan fit over the short τ of a one-minute record saw the filtered noise and came out 5 %
   low; its flicker and random-walk terms were biased up — σ of K2 1.5 times the spread on
   the twin). Noise correlated over longer times (bias instability, random walk) is not in N:
   it shows in the series' χ², whose Birge ratios scale the σ (docs/p3.md).

Contents
--------
:class:`P3Processing`, :class:`P3Window`, :func:`extract_p3_windows`, :func:`p3_unit_names`.
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
    RecordingError,
)
from imucalib.io.reader import Recording, StepRecord, StreamData
from imucalib.io.streams import DEVICE_CENTRIFUGE, DEVICE_IMU, axis_columns
from imucalib.procedures.common.noise import block_variance
from imucalib.procedures.common.window_checks import (
    BlockNoiseLimits,
    checked_samples,
    pooled_white_se,
)
from imucalib.procedures.common.windows import counter_times, whole_revolutions
from imucalib.procedures.p3.roles import P3_MOUNT, P3_RATE, P3_REST, P3_TUMBLE

__all__ = ["P3Processing", "P3Window", "extract_p3_windows", "p3_unit_names"]

_F64 = NDArray[np.float64]
_AXES = {"x": 0, "y": 1, "z": 2}
#: Roles whose windows the analysis reduces.
WINDOW_ROLES = (P3_TUMBLE, P3_REST, P3_RATE)


@dataclass(frozen=True)
class P3Processing(BlockNoiseLimits):
    """Processing options of P3's window reduction (module docstring).

    The window limits (:class:`~imucalib.procedures.common.window_checks.BlockNoiseLimits`) and

    Attributes
    ----------
    input_axis : {"x", "y", "z"}
        The accelerometer of each unit that is the instrument (its input axis radial,
        pointing towards the spin axis).
    """

    input_axis: str = "x"

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.input_axis not in _AXES:
            raise InvalidInputError(f"`input_axis` must be 'x', 'y' or 'z'; got "
                                    f"{self.input_axis!r}")


@dataclass(frozen=True)
class P3Window:
    """One record of one unit, reduced (module docstring).

    Attributes
    ----------
    step_index, label, role : int, str, str
        The recorded step.
    unit : str
        The unit (its IMU stream).
    config : int
        The configuration (tag ``config=<k>``; 0 for a tumble record).
    pose : str
        A tumble record's fixture axis up (tag ``pose=``); ``""`` otherwise.
    arm_deg : float
        A rest record's arm position (tag ``arm=``); NaN otherwise. [°]
    phase : str
        A rest record's ``before`` or ``after`` the rates.
    rate_rps : float
        Mean measured rate over the averaged revolutions (0 at rest). [rad/s]
    n_revolutions : int
        Whole revolutions averaged (0 at rest).
    mean, se : float
        Mean output of the input axis and its standard error. [m/s²]
    duration_s : float
        Span averaged. [s]
    n_samples, n_lost : int
        Samples averaged; samples lost to dropouts in the window.
    time_s : float
        Middle of the span averaged (station time). [s]
    block_variance : (int, float)
        Degrees of freedom K − 1 and the estimate s²·τ of N² from the record's block means.
        [(m/s²)²·s]
    """

    step_index: int
    label: str
    role: str
    unit: str
    config: int
    pose: str
    arm_deg: float
    phase: str
    rate_rps: float
    n_revolutions: int
    mean: float
    se: float
    duration_s: float
    n_samples: int
    n_lost: int
    time_s: float = math.nan
    block_variance: tuple[int, float] = (0, math.nan)


def p3_unit_names(rec: Recording, steps: Sequence[StepRecord] | None = None
                  ) -> dict[str, str]:
    """Return the units the first ``p3.mount`` check names: ``ref-a``, ``ref-b``, ``test``.

    Empty when no such check names them (an import: the analysis is then told the names).
    """
    for step in (rec.steps if steps is None else steps):
        if step.role == P3_MOUNT:
            found = {k: v for k in ("ref-a", "ref-b", "test")
                     if (v := step.tag_value(k)) is not None}
            if found:
                return found
    return {}


def _where(unit: str, step: StepRecord) -> str:
    return f"unit {unit}, step {step.index} ({step.label})"


def _tag_int(step: StepRecord, key: str) -> int:
    value = step.tag_value(key)
    try:
        return int(value) if value is not None else 0
    except ValueError:
        raise RecordingError(f"step {step.index} ({step.label}): tag {key}={value!r} is not an "
                             "integer") from None


def _tag_float(step: StepRecord, key: str) -> float:
    value = step.tag_value(key)
    try:
        return float(value) if value is not None else math.nan
    except ValueError:
        raise RecordingError(f"step {step.index} ({step.label}): tag {key}={value!r} is not a "
                             "number") from None


class _Reducer:
    def __init__(self, unit: str, opt: P3Processing, angle_col: str) -> None:
        self.unit, self.opt, self.angle_col = unit, opt, angle_col
        self.column = ACCEL_COLUMNS[_AXES[opt.input_axis]]

    def reduce(self, step: StepRecord, data: StreamData, fb: StreamData | None) -> P3Window:
        where = _where(self.unit, step)
        values = checked_samples(where, data, (self.column,), saturation_note=lambda v: (
            f" (the output reached its range, e.g. {np.max(np.abs(v)):.6g} m/s² on "
            f"{self.column}); a clipped mean would bias K2 — lower the top rate or use "
            "an accelerometer of a larger range"))[:, 0]
        spinning = step.role == P3_RATE
        t, period, lost = counter_times(
            where, np.asarray(data.columns["counter"]), data.time_s,
            max_lost_fraction=self.opt.max_lost_fraction, max_gap_s=self.opt.max_gap_s,
            reconstruct=spinning)
        rate, n_rev = 0.0, 0
        residual = values
        if spinning:
            assert fb is not None
            wanted = step.commanded.get("revolutions") if isinstance(step.commanded,
                                                                      dict) else None
            turn = whole_revolutions(where, t, values, fb.time_s, fb.columns[self.angle_col],
                                     wanted)
            t, rate, n_rev = turn.time_s, turn.rate_rps, turn.n_revolutions
            mean, residual, n = float(turn.mean[0]), turn.residual, turn.time_s.size
        else:
            mean = float(values.mean())
            n = values.size
        dof, var = block_variance(residual, period, self.opt.noise_block_s)
        blocks = (dof, float(var[0]))
        return P3Window(
            step_index=step.index, label=step.label, role=step.role, unit=self.unit,
            config=_tag_int(step, "config"), pose=step.tag_value("pose") or "",
            arm_deg=_tag_float(step, "arm"), phase=step.tag_value("phase") or "",
            rate_rps=rate, n_revolutions=n_rev, mean=mean, se=math.nan,
            duration_s=float(t[-1] - t[0]), n_samples=int(n), n_lost=lost,
            time_s=float(0.5 * (t[0] + t[-1])), block_variance=blocks)


def _pooled(windows: list[P3Window]) -> list[P3Window]:
    """Give each window the white-noise standard error N/√T of the unit (module docstring)."""
    unit = windows[0].unit if windows else "?"
    se = pooled_white_se([(w.block_variance[0], np.array([w.block_variance[1]]))
                          for w in windows], [w.duration_s for w in windows], unit=unit,
                         what="record")
    return [dataclasses.replace(w, se=float(e[0])) for w, e in zip(windows, se, strict=True)]


def extract_p3_windows(rec: Recording, unit: str, *, processing: P3Processing | None = None,
                       steps: Sequence[StepRecord] | None = None,
                       progress: Callable[[float], None] | None = None) -> list[P3Window]:
    """Reduce every P3 record (tumble, rest, rate) of one unit (module docstring).

    Raises
    ------
    RecordingError
        No IMU stream `unit`, no centrifuge stream, no step with a P3 role.
    MissingSegmentError
        A record with too many dropouts, fewer whole revolutions than commanded.
    SaturationError
        A record with saturated samples.
    InvalidInputError
        NaN samples, a counter going backwards.
    """
    opt = processing or P3Processing()
    imus = [s.unit for s in rec.streams if s.device == DEVICE_IMU]
    if unit not in imus:
        raise RecordingError(f"{rec.path} has no IMU stream {unit!r}; it has {imus}")
    fuges = [s for s in rec.streams if s.device == DEVICE_CENTRIFUGE]
    if not fuges:
        raise RecordingError(f"{rec.path} has no centrifuge stream: P3 needs the centrifuge's "
                             "encoder feedback")
    names = [c[len("angle_"):-len("_rad")] for c in fuges[0].columns
             if c.startswith("angle_") and c.endswith("_rad")]
    if len(names) != 1:
        raise RecordingError(f"{rec.path}: the centrifuge stream must have one axis; it has "
                             f"{names}")
    angle_col, rate_col = axis_columns(names[0])
    chosen = [s for s in (rec.steps if steps is None else steps)
              if s.role in WINDOW_ROLES and s.concerns(unit)]
    if not chosen:
        raise RecordingError(f"{rec.path}: no step has a P3 role ({', '.join(WINDOW_ROLES)}); "
                             "is it a P3 recording?")
    usable = [s for s in chosen if s.status == "done" and s.has_valid_window]
    red = _Reducer(unit, opt, angle_col)
    imu_rows = rec.iter_windows(DEVICE_IMU, unit,
                                [(s.valid_start_s, s.valid_end_s) for s in usable],
                                [*ACCEL_COLUMNS, "counter", "saturated"])
    fb_rows = rec.iter_windows(DEVICE_CENTRIFUGE, fuges[0].unit,
                               [(s.valid_start_s, s.valid_end_s) for s in usable
                                if s.role == P3_RATE], [angle_col, rate_col])
    windows = []
    for i, (step, data) in enumerate(zip(usable, imu_rows, strict=True), start=1):
        fb = next(fb_rows) if step.role == P3_RATE else None
        windows.append(red.reduce(step, data, fb))
        if progress is not None:
            progress(i / len(usable))
    return _pooled(windows)
