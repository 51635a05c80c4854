"""From a P2 Recording to the window means of one unit, grouped by temperature point.

One step's valid window of one unit at a time (memory bounded by the longest step, whatever
the number of units):

1. the unit's samples of the window (gyro, accelerometer, counter, internal temperature);
2. its time base from the sample counter (docs/drivers.md, "Time synchronisation practice");
   samples lost in the window beyond :attr:`P2Processing.max_lost_fraction` (or one gap
   longer than :attr:`P2Processing.max_gap_s`) make the window unusable;
3. a static window (role ``p2.static``) is averaged over its samples; a turning one
   (``p2.rate``) over the longest span of whole table revolutions, the table angle of every
   sample interpolated from the feedback
   (:func:`~imucalib.processing.statistics.compute_integer_revolution_window`), and it must hold
   the commanded number of whole revolutions;
4. the noise terms of the first windows of each point from their own Allan variance
   (:func:`~imucalib.processing.statistics.window_noise_fit`), a turning window's taken about
   its mean and once-per-revolution harmonic (what the averaging cancels), and the standard
   error of every mean from the noise model pooled over the point
   (:func:`pooled_standard_errors`);
5. the internal temperature's mean and slope over the window.

Which orientation a window belongs to is read from the data: each pose's static windows say
which body axis reads +g (:func:`~imucalib.procedures.p2.reduction.orientation_of`), so the
analysis needs neither the fixture geometry nor the unit's place on it; the turning windows of
the same pose and point share it.

Contents
--------
:class:`P2Processing`, :class:`P2Window`, :class:`UnitObservations`,
:func:`extract_unit_observations`, :func:`p2_units`.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from imucalib.conventions import ACCEL_COLUMNS, GYRO_COLUMNS, TEMPERATURE_COLUMN
from imucalib.errors import CalibrationError, InvalidInputError, MissingSegmentError, RecordingError
from imucalib.io.reader import Recording, StepRecord, StreamData, StreamInfo
from imucalib.io.streams import DEVICE_IMU, DEVICE_TABLE, axis_columns
from imucalib.models.noise import NoiseModel, compute_theoretical_adev
from imucalib.procedures.common.noise import (
    FLICKER_FACTOR,
    NOISE_RECORD_MIN_S,
    longest_cluster_s,
    with_declared_floor,
)
from imucalib.procedures.common.reference import site_vectors
from imucalib.procedures.common.window_checks import WindowLimits, checked_samples
from imucalib.procedures.common.windows import counter_times, table_angle_at
from imucalib.procedures.p2.reduction import orientation_of
from imucalib.procedures.p2.roles import P2_RATE, P2_STATIC
from imucalib.processing.statistics import (
    compute_integer_revolution_window,
    unwrap_angle,
    window_noise_fit,
)

__all__ = ["P2Processing", "P2Window", "UnitObservations", "declared_noise",
           "extract_unit_observations", "p2_units", "unit_noise", "where"]

_F64 = NDArray[np.float64]
_COLUMNS = (*GYRO_COLUMNS, *ACCEL_COLUMNS)


@dataclass(frozen=True)
class P2Processing(WindowLimits):
    """Processing options of P2's window reduction (module docstring).

    The window limits (:class:`~imucalib.procedures.common.window_checks.WindowLimits`:
    ``max_lost_fraction``, ``max_gap_s``) and:

    Attributes
    ----------
    orientation_tolerance : float
        How far (in g) a static mean may be from ±g on its up axis and from 0 on the others.
    gravity_mps2 : float or None
        Local gravity; None: the normal gravity at the recorded latitude and height.
    noise_windows : int
        Windows of each point whose Allan variance is fitted for the pooled noise model (the
        first ones, turns and static records of the first poses; every window when fewer):
        the pool's median needs a handful, and the fit is most of a window's reduction time.
    """

    orientation_tolerance: float = 0.25
    gravity_mps2: float | None = None
    noise_windows: int = 8


@dataclass(frozen=True)
class P2Window:
    """One window of one unit, reduced (module docstring).

    Attributes
    ----------
    step_index, label : int, str
        The recorded step.
    point : int
        The temperature point (tag ``point=<k>``).
    leg : str
        ``"heating"`` or ``"cooling"``.
    held_out : bool
        The point is held out of the temperature-model fit.
    pose : str
        The fixture pose (tag ``pose=<axis>``; ``""`` when the step has none).
    kind : str
        ``"static"`` or ``"rate"``.
    table_rate_rps : float
        Mean measured table rate over the averaged span (0 for a static window). [rad/s]
    n_revolutions : int
        Whole revolutions averaged (0 static).
    gyro_mean_rps, accel_mean_mps2, gyro_se_rps, accel_se_mps2 : ndarray, shape (3,)
        Means and their standard errors.
    temperature_degc, temperature_rate_degc_ps : float
        Mean internal temperature and its slope over the window. [°C], [°C/s]
    duration_s : float
        Span averaged. [s]
    n_samples, n_lost : int
        Samples averaged; samples lost to dropouts in the window.
    orientation : str
        The body axis up (``"+x"`` …) from the static means of the window's pose and point.
    allan_fit : ndarray, shape (3, 6), or None
        The window's own fitted N̂, Ĉ_B, K̂ per channel (the first windows of each point).
    start_s : float or None
        Start of the averaged span on the recording's clock (None when unknown: then the
        analysis treats the windows as independent). [s]
    """

    step_index: int
    label: str
    point: int
    leg: str
    held_out: bool
    pose: str
    kind: str
    table_rate_rps: float
    n_revolutions: int
    gyro_mean_rps: _F64
    accel_mean_mps2: _F64
    gyro_se_rps: _F64
    accel_se_mps2: _F64
    temperature_degc: float
    temperature_rate_degc_ps: float
    duration_s: float
    n_samples: int
    n_lost: int
    orientation: str = ""
    allan_fit: _F64 | None = None
    start_s: float | None = None


@dataclass(frozen=True)
class UnitObservations:
    """Every usable P2 window of one unit, and what the analysis needs of the site.

    ``failures`` holds, per temperature point, why a window of it could not be used (the point
    is then left out for this unit; other points and units go on). ``noise`` is the unit's
    noise model over the whole sweep (:func:`unit_noise`: ``{"gyro", "accel"}``), whose
    covariance of the window means (docs/test-design.md, Eq. (TD.2)) the analysis carries
    into the temperature models; None: the windows are treated as independent, each with its
    standard error.
    """

    unit: str
    windows: tuple[P2Window, ...]
    gravity_mps2: float
    earth_rate_up_rps: float
    latitude_deg: float
    sample_rate_hz: float
    failures: dict[int, str] = field(default_factory=dict)
    notes: tuple[str, ...] = ()
    noise: dict[str, NoiseModel] | None = None


def p2_units(rec: Recording) -> list[str]:
    """Return the IMU units of a recording, in stream order."""
    return [s.unit for s in rec.streams if s.device == DEVICE_IMU]


def _tag_int(step: StepRecord, key: str) -> int | None:
    value = step.tag_value(key)
    if value is None:
        return None
    try:
        return int(value)
    except ValueError:
        raise RecordingError(f"step {step.index} ({step.label}): tag {key}={value!r} is not an "
                             "integer") from None


def _slope(t: _F64, y: _F64, y_mean: float) -> float:
    """Return the least-squares slope of y on t (0 for fewer than three points).

    `y_mean` is ``float(np.mean(y))`` (the caller has it).
    """
    if t.size < 3:
        return 0.0
    dt = t - t.mean()
    den = float(dt @ dt)
    return float(dt @ (y - y_mean) / den) if den > 0 else 0.0


def where(unit: str, point: int, temperature_degc: float | None, step: StepRecord | None) -> str:
    """Name a unit, a temperature point and a step for an error message."""
    temp = "" if temperature_degc is None or not math.isfinite(temperature_degc) \
        else f" ({temperature_degc:+.1f} °C)"
    at = "" if step is None else f", step {step.index} ({step.label})"
    return f"unit {unit}, temperature point {point}{temp}{at}"


@dataclass(frozen=True)
class _RecordingFacts:
    """What every unit of a recording reads alike: its streams and its site."""

    streams: tuple[StreamInfo, ...]
    latitude_deg: float
    heading_deg: float


#: One :class:`_RecordingFacts` per open Recording: the streams are declared and the root
#: attributes written when a recording is created, so the units of a lot read them once
_FACTS: weakref.WeakKeyDictionary[Recording, _RecordingFacts] = weakref.WeakKeyDictionary()


def _facts_of(rec: Recording) -> _RecordingFacts:
    """Return the streams and site of `rec` (read on its first unit, then remembered)."""
    facts = _FACTS.get(rec)
    if facts is None:
        meta = rec.metadata
        facts = _RecordingFacts(streams=tuple(rec.streams),
                                latitude_deg=float(meta.get("latitude_deg", math.nan)),
                                heading_deg=float(meta.get("heading_deg", 0.0)))
        _FACTS[rec] = facts
    return facts


class _Reducer:
    def __init__(self, rec: Recording, unit: str, opt: P2Processing,
                 streams: tuple[StreamInfo, ...]) -> None:
        self.rec, self.unit, self.opt = rec, unit, opt
        tables = [s for s in streams if s.device == DEVICE_TABLE]
        if not tables:
            raise RecordingError(f"{rec.path} has no table stream: P2 needs the table feedback")
        self.table = tables[0]
        names = [c[len("angle_"):-len("_rad")] for c in self.table.columns
                 if c.startswith("angle_") and c.endswith("_rad")]
        if len(names) != 1:
            raise RecordingError(f"{rec.path}: P2 needs a single-axis table; the table stream "
                                 f"has the axes {names}")
        self.angle_col, self.rate_col = axis_columns(names[0])[:2]
        self.sample_rate_hz = 0.0
        self._fitted: dict[int, int] = {}

    def read(self, step: StepRecord, point: int, data: StreamData
             ) -> tuple[_F64, _F64, _F64, float, int]:
        """Return (counter times, values (n, 6), temperatures, their mean, samples lost)."""
        here = where(self.unit, point, None, step)
        values = checked_samples(here, data, _COLUMNS)
        temp = np.asarray(data.columns[TEMPERATURE_COLUMN], dtype=np.float64)
        if not np.all(np.isfinite(temp)):
            raise InvalidInputError(f"{here}: the window holds NaN or infinite samples")
        temp_mean = float(np.mean(temp))
        # a turn's mean weights samples by the table angle at their own instants: the counter's
        # time base (receive-time jitter removed); a static mean needs no instants
        t, period, lost = counter_times(
            where(self.unit, point, temp_mean, step), data.columns["counter"], data.time_s,
            max_lost_fraction=self.opt.max_lost_fraction, max_gap_s=self.opt.max_gap_s,
            reconstruct=step.role == P2_RATE)
        if self.sample_rate_hz <= 0.0 and period > 0:
            self.sample_rate_hz = 1.0 / period
        return t, values, temp, temp_mean, lost

    def reduce(self, step: StepRecord, point: int, leg: str, held: bool, data: StreamData,
               fb: StreamData | None) -> P2Window:
        """Reduce one window (`data`: the unit's rows; `fb`: the table's, for a turn)."""
        kind = "rate" if step.role == P2_RATE else "static"
        t, values, temp, temp_mean, lost = self.read(step, point, data)
        fs = self.sample_rate_hz
        n_rev, rate = 0, 0.0
        fit: _F64 | None = None
        if kind == "rate":
            assert fb is not None
            if len(fb) < 2:
                raise MissingSegmentError(f"{where(self.unit, point, None, step)}: fewer than 2 "
                                          "table feedback samples in the window")
            angle = table_angle_at(t, fb.time_s, unwrap_angle(fb.columns[self.angle_col]))
            try:
                win = compute_integer_revolution_window(t, values, angle_rad=angle)
            except InvalidInputError as exc:
                raise MissingSegmentError(f"{where(self.unit, point, temp_mean, step)}: {exc}"
                                          ) from None
            wanted = step.commanded.get("revolutions") if isinstance(step.commanded,
                                                                      dict) else None
            n_rev = int(win.n_revolutions)
            if isinstance(wanted, int | float) and n_rev < int(wanted):
                raise MissingSegmentError(
                    f"{where(self.unit, point, temp_mean, step)}: the turn holds "
                    f"{n_rev} whole revolution(s) of the {int(wanted)} commanded (short of an "
                    "integer number of revolutions)")
            sl = slice(win.start_index, win.stop_index)
            mean = np.asarray(win.mean, dtype=np.float64)
            if self.count(point):
                # the noise about the mean and the once-per-revolution harmonic
                a = angle[sl]
                design = np.column_stack([np.ones(a.size), np.sin(a), np.cos(a)])
                coef, *_ = np.linalg.lstsq(design, values[sl], rcond=None)
                fit = window_noise_fit(values[sl] - design @ coef, fs)[1]
            span_t = t[sl]
            rate = float((angle[sl][-1] - angle[sl][0]) / (span_t[-1] - span_t[0]))
            t_used, temp_used = span_t, temp[sl]
            temp_mean_used = float(np.mean(temp_used))
        else:
            if self.count(point):
                mean, fit = window_noise_fit(values, fs)
            else:
                mean = values.mean(axis=0)
            t_used, temp_used, temp_mean_used = t, temp, temp_mean
        # the pooled model (pooled_standard_errors) gives every window its standard error
        se = np.full(6, np.nan)
        return P2Window(
            step_index=step.index, label=step.label, point=point, leg=leg, held_out=held,
            pose=step.tag_value("pose") or "", kind=kind, table_rate_rps=rate,
            n_revolutions=n_rev, gyro_mean_rps=mean[:3], accel_mean_mps2=mean[3:],
            gyro_se_rps=se[:3], accel_se_mps2=se[3:],
            temperature_degc=temp_mean_used,
            temperature_rate_degc_ps=_slope(t_used, temp_used, temp_mean_used),
            duration_s=float(t_used[-1] - t_used[0]), n_samples=int(t_used.size), n_lost=lost,
            allan_fit=fit, start_s=float(t_used[0]))

    def count(self, point: int) -> bool:
        """Whether this window of `point` is one whose noise is fitted (and count it)."""
        done = self._fitted.get(point, 0)
        if done >= self.opt.noise_windows > 0:
            return False
        self._fitted[point] = done + 1
        return True


def extract_unit_observations(rec: Recording, unit: str, *,
                              processing: P2Processing | None = None,
                              progress: Callable[[float], None] | None = None,
                              steps: list[StepRecord] | None = None,
                              table_windows: dict[int, StreamData] | None = None
                              ) -> UnitObservations:
    """Reduce every P2 window of one unit (module docstring).

    A window that cannot be used (dropouts, a short turn, NaN) is recorded in ``failures`` for
    its temperature point, and the point is left out for this unit; the others go on.

    `steps` (the recording's, read once) saves reading the steps table again for each unit;
    `table_windows` (step index → the table's rows in its valid window, filled by the first
    unit that reads them) saves reading the same turns of the table again for each unit.

    Raises
    ------
    RecordingError
        No IMU stream `unit`, no table stream, no latitude, or no step with a P2 role.
    """
    opt = processing or P2Processing()
    facts = _facts_of(rec)
    units = [s.unit for s in facts.streams if s.device == DEVICE_IMU]  # p2_units
    if unit not in units:
        raise RecordingError(f"{rec.path} has no IMU stream {unit!r}; it has {units}")
    lat = facts.latitude_deg
    if not math.isfinite(lat):
        raise RecordingError(f"{rec.path} does not record the latitude (latitude_deg): the "
                             "vertical Earth rate needs it")
    g, earth_t = site_vectors(lat, facts.heading_deg, opt.gravity_mps2)
    steps = [s for s in (rec.steps if steps is None else steps)
             if s.role in (P2_STATIC, P2_RATE) and s.concerns(unit)]
    if not steps:
        raise RecordingError(f"{rec.path}: no step has a P2 role ({P2_STATIC}, {P2_RATE}); "
                             "is it a P2 recording?")
    red = _Reducer(rec, unit, opt, facts.streams)
    windows: list[P2Window] = []
    failures: dict[int, str] = {}
    points = {}
    for step in steps:
        point = _tag_int(step, "point")
        if point is None:
            raise RecordingError(f"step {step.index} ({step.label}) has the role {step.role} "
                                 "but no point=<k> tag")
        points[step.index] = point
    usable = [s for s in steps if s.status == "done" and s.has_valid_window]
    # every window of the unit (and the table's of every turn) in time order, the datasets held
    # open: one decompression per chunk (Recording.iter_windows)
    imu_rows = rec.iter_windows(DEVICE_IMU, unit,
                                [(s.valid_start_s, s.valid_end_s) for s in usable],
                                [*_COLUMNS, "counter", "saturated", TEMPERATURE_COLUMN])
    turns = [s for s in usable if s.role == P2_RATE]
    shared = {} if table_windows is None else table_windows
    missing = [s for s in turns if s.index not in shared]
    shared.update(zip((s.index for s in missing), rec.iter_windows(
        DEVICE_TABLE, red.table.unit, [(s.valid_start_s, s.valid_end_s) for s in missing],
        [red.angle_col, red.rate_col]), strict=True))
    for i, (step, data) in enumerate(zip(usable, imu_rows, strict=True), start=1):
        fb = shared[step.index] if step.role == P2_RATE else None
        point = points[step.index]
        if point not in failures:
            try:
                windows.append(red.reduce(step, point, step.tag_value("leg") or "heating",
                                          "held-out" in step.tags, data, fb))
            except CalibrationError as exc:
                failures[point] = str(exc)
        if progress is not None:
            progress(i / len(usable))
    noise, noise_note = unit_noise(windows, red.sample_rate_hz, declared_noise(rec))
    notes = ["standard errors of the window means from the noise model pooled over each "
             "temperature point's windows (median Allan-fit coefficients, docs/p2.md)"]
    if noise_note:
        notes.append(noise_note)
    return UnitObservations(unit=unit, windows=tuple(pooled_standard_errors(windows)),
                            gravity_mps2=g, earth_rate_up_rps=float(earth_t[2]),
                            latitude_deg=lat, sample_rate_hz=red.sample_rate_hz,
                            failures=failures, notes=tuple(notes), noise=noise)


def _noise_of(fit: _F64) -> dict[str, NoiseModel]:
    """Return the noise models of Allan-fit coefficients N̂, Ĉ_B, K̂ (3, 6), clipped at zero."""
    return {triad: NoiseModel(white_density=np.maximum(fit[0, cols], 0.0),
                              bias_instability=np.sqrt(np.maximum(fit[1, cols], 0.0)
                                                       / FLICKER_FACTOR),
                              random_walk=np.maximum(fit[2, cols], 0.0))
            for triad, cols in (("gyro", slice(0, 3)), ("accel", slice(3, 6)))}


def declared_noise(rec: Recording) -> tuple[dict[str, NoiseModel], str] | None:
    """Return the noise of the unit grade the recording's stored plan states, and the grade.

    :func:`~imucalib.procedures.common.grade.grade_noise` (white terms only for a twin IMU
    with ``noise = "white"``); None when the recording holds no plan or it states no grade.
    """
    from imucalib.errors import ConfigurationError
    from imucalib.plan import parse_plan
    from imucalib.procedures.common.grade import grade_noise, plan_grade

    text = rec.metadata.get("plan_toml")
    if not text:
        return None
    try:
        plan = parse_plan(str(text))
        return grade_noise(plan), plan_grade(plan)
    except ConfigurationError:
        return None


def unit_noise(windows: list[P2Window], sample_rate_hz: float,
               declared: tuple[dict[str, NoiseModel], str] | None
               ) -> tuple[dict[str, NoiseModel] | None, str | None]:
    """Return the unit's noise model over the sweep, and a note when a Type B input entered.

    The white density N is the median of every window's Allan-fit coefficient (as
    :func:`pooled_standard_errors` pools a point's). The flicker B and random walk K follow
    the rule of docs/p1.md, "Noise model of the window means": windows shorter than a noise
    record (:data:`~imucalib.procedures.common.noise.NOISE_RECORD_MIN_S`, P2's are seconds
    long) determine neither, whose corners lie at tens of seconds to hours, so every axis takes
    the declared grade's B and K — a Type B input (JCGM 100:2008 §4.3), none for a grade
    declared white (a white-noise twin); longer ones keep the fit where it reaches
    :data:`~imucalib.procedures.common.noise.FLICKER_CORNERS_MIN` flicker corners of the
    declared noise (:func:`~imucalib.procedures.common.noise.with_declared_floor`). Without a
    declared grade the fitted B and K stay, with a note. None when no window has an Allan fit.
    """
    fits = [np.nan_to_num(w.allan_fit, nan=0.0) for w in windows if w.allan_fit is not None]
    if not fits or sample_rate_hz <= 0.0:
        return None, None
    fitted = _noise_of(np.median(np.array(fits), axis=0))
    longest = max(w.duration_s for w in windows if w.allan_fit is not None)
    if declared is None:
        return fitted, ("noise model: no declared grade (the recording holds no plan stating "
                        f"one): flicker and random walk fitted to windows of {longest:.3g} s, "
                        "which do not determine them")
    if longest >= NOISE_RECORD_MIN_S:
        return with_declared_floor(fitted, declared[0],
                                   longest_cluster_s(longest, sample_rate_hz),
                                   source=f"grade {declared[1]}")
    dec = declared[0]
    out = {t: NoiseModel(white_density=m.white_density,
                         bias_instability=dec[t].bias_instability,
                         random_walk=dec[t].random_walk) for t, m in fitted.items()}
    return out, (f"noise model: the windows ({longest:.3g} s at most) are shorter than a noise "
                 f"record ({NOISE_RECORD_MIN_S:g} s) and determine no flicker or random walk: "
                 f"the grade {declared[1]} bias instability and random walk (Type B) with the "
                 "fitted white noise")


def pooled_standard_errors(windows: list[P2Window]) -> list[P2Window]:
    """Give each window the standard error of a noise model pooled over its point's windows.

    One short window's own Allan fit is heavy-tailed (its SE² is right in the median but 2.5–4
    times too large on average, docs/processing-estimation.md), and every window of one unit
    and temperature point sees the same sensor noise: the median of the windows' white,
    flicker and random-walk coefficients is a noise model (:class:`~imucalib.models.noise.
    NoiseModel`) whose Allan deviation at each window's duration is its standard error
    (:func:`~imucalib.procedures.common.noise.window_mean_se`, for all of them at once).
    """
    by_point: dict[int, list[P2Window]] = {}
    for w in windows:
        by_point.setdefault(w.point, []).append(w)
    every = [np.nan_to_num(w.allan_fit, nan=0.0) for w in windows if w.allan_fit is not None]
    out: dict[int, P2Window] = {}
    for mine in by_point.values():
        fits = [np.nan_to_num(w.allan_fit, nan=0.0) for w in mine if w.allan_fit is not None]
        if len(fits) < 3:  # a point cut short: the unit's windows pooled
            fits = every
        if not fits:
            continue
        noise = _noise_of(np.median(np.array(fits), axis=0))
        gyro, accel = _window_mean_ses(noise, [w.duration_s for w in mine])
        for w, g_se, a_se in zip(mine, gyro, accel, strict=True):
            out[id(w)] = _replaced(w, gyro_se_rps=g_se, accel_se_mps2=a_se)
    return [out.get(id(w), w) for w in windows]


def _window_mean_ses(noise: dict[str, NoiseModel], durations_s: list[float]
                     ) -> tuple[_F64, _F64]:
    """:func:`~imucalib.procedures.common.noise.window_mean_se` of many durations, row by row.

    The model's Allan deviation at τ = each duration (at least 1 ms), floored at 1e-300, in
    one evaluation (:func:`~imucalib.models.noise.compute_theoretical_adev` is element-wise
    in τ: each row equals the one-window call bit for bit). [rad/s], [m/s²], shape (m, 3)
    """
    tau = np.array([max(d, 1e-3) for d in durations_s])
    gyro = compute_theoretical_adev(noise["gyro"], tau)
    accel = compute_theoretical_adev(noise["accel"], tau)
    return np.maximum(gyro, 1e-300), np.maximum(accel, 1e-300)


def _replaced(w: P2Window, **changes: object) -> P2Window:
    """``dataclasses.replace(w, **changes)`` without its pass over the fields' definitions.

    Every field of :class:`P2Window` is an ``__init__`` field held in the instance's
    ``__dict__``: the copy of that dict with `changes` builds the same window.
    """
    fields = dict(w.__dict__)
    fields.update(changes)
    return P2Window(**fields)


def detect_orientations(obs: UnitObservations, opt: P2Processing | None = None
                        ) -> tuple[list[P2Window], dict[int, str]]:
    """Give every window the orientation its pose's static means show (module docstring).

    Returns the windows with ``orientation`` set and, per point, why it cannot be used (a
    pose whose static means show no axis up, or two poses showing the same).
    """
    tol = (opt or P2Processing()).orientation_tolerance
    failures: dict[int, str] = {}
    by_key: dict[tuple[int, str], str] = {}
    for w in obs.windows:
        if w.kind != "static":
            continue
        found = orientation_of(w.accel_mean_mps2.tolist(), obs.gravity_mps2, tolerance=tol)
        key = (w.point, w.pose)
        if found is None:
            failures.setdefault(w.point, (
                f"{where(obs.unit, w.point, w.temperature_degc, None)}, step {w.step_index} "
                f"({w.label}): no body axis reads ±g (static mean "
                f"{np.round(w.accel_mean_mps2, 3).tolist()} m/s²): the unit is not square to "
                "the fixture"))
        elif by_key.setdefault(key, found) != found:
            failures.setdefault(w.point, (
                f"{where(obs.unit, w.point, w.temperature_degc, None)}: the static windows of "
                f"pose {w.pose or '?'} show {by_key[key]} and {found} up"))
    out = []
    for w in obs.windows:
        o = by_key.get((w.point, w.pose), "")
        out.append(_replaced(w, orientation=o))
    return out, failures
