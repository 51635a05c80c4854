"""From a P1 Recording to observations: one mean per static window and per rate point.

Which windows of the recording P1 reduces, and what it makes of them together: each window is
reduced by :class:`~.window_reduction.WindowReducer` (the processing chain, docs/p1.md rules
1–3), in this process or shared with worker processes (:mod:`.parallel`); the standard errors
of the window means come from the noise model fitted to the long static records
(:func:`~imucalib.procedures.common.noise.estimate_noise`), raised to the declared noise where
the records are too short to show its floor (:mod:`.declared_floor`).

Which windows
-------------
The recording's steps say what each window is for (:mod:`.roles`): the six
positions ``p1.accel-position``, the level static record ``p1.gyro-bias``, the calibration rates
``p1.gyro-rate``, and the verification's ``p1.held-out-position`` and ``p1.held-out-rate``. A
step without a role gets the one its tags imply (:func:`~imucalib.io.step_roles.role_from_tags`:
plans written before roles, and version 1 recordings, whose reader does the same). A rate
step's spinning axis and rate come from its ``commanded`` state (``axis``, ``rate_dps``); when
the recording does not give them (an import), from the table feedback: the axis turning
fastest and its measured mean rate. The plan stored in the recording is not read: the
recording's context (:class:`~imucalib.io.context.RecordingContext`: the keys a run writes, or
for an older recording its stored plan read as plain data) gives the procedure that tags imply
roles under, and the IMU specification, equipment accuracies and decision rule that
:func:`~imucalib.procedures.p1.analyze_p1` uses (``P1Options`` or the defaults otherwise).

Contents
--------
:func:`extract_p1_observations`; re-exported: :class:`~.window_reduction.P1Processing`,
:func:`~imucalib.procedures.common.reference.table_rotation`,
:func:`~imucalib.procedures.common.reference.site_vectors`, and the observations' data model,
:class:`~.windows.P1Observations` and :class:`~.windows.WindowObservation` (:mod:`.windows`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence
from typing import Any, TypeVar

from imucalib.errors import InvalidInputError, RecordingError
from imucalib.io.context import RecordingContext
from imucalib.io.reader import Recording, StepRecord
from imucalib.io.step_roles import role_from_tags
from imucalib.io.streams import DEVICE_IMU
from imucalib.models.noise import NoiseModel
from imucalib.plan.schema import AcceptanceConfig, EquipmentConfig, ImuSpecConfig
from imucalib.procedures.common.noise import NOISE_RECORD_MIN_S, estimate_noise, window_mean_se
from imucalib.procedures.common.reference import site_vectors, table_rotation
from imucalib.procedures.common.workers import one_thread
from imucalib.procedures.p1.declared_floor import declared_floor
from imucalib.procedures.p1.parallel import observe_parallel
from imucalib.procedures.p1.roles import ROLES as P1_ROLES
from imucalib.procedures.p1.window_reduction import RATE_ROLES, P1Processing, WindowReducer
from imucalib.procedures.p1.windows import P1Observations, WindowObservation

__all__ = [
    "P1Observations",
    "P1Processing",
    "WindowObservation",
    "estimate_noise",
    "extract_p1_observations",
    "site_vectors",
    "table_rotation",
]


def _step_role(step: StepRecord, procedure: str) -> str:
    """Return the step's P1 role: recorded, else implied by its tags; ``""`` if none."""
    role = step.role or role_from_tags(step.kind, step.tags, procedure)
    return role if role in P1_ROLES else ""


_Config = TypeVar("_Config", EquipmentConfig, ImuSpecConfig, AcceptanceConfig)


def _stated(rec: Recording, what: str, model: type[_Config], table: Mapping[str, Any]
            ) -> _Config | None:
    """Return the configuration the recording's context states (`table`), or None if none."""
    if not table:
        return None
    try:
        return model.model_validate(table)
    except ValueError as exc:
        raise RecordingError(f"{rec.path}: the recorded {what} is not a valid "
                             f"{model.__name__}: {exc}") from exc


def _stated_configs(rec: Recording, context: RecordingContext
                    ) -> tuple[EquipmentConfig | None, ImuSpecConfig | None,
                               AcceptanceConfig | None]:
    """Return the equipment accuracies, IMU specification and decision rule `context` states."""
    rule = {**({"rule": context.acceptance} if context.acceptance else {}),
            **({"guard_band_k": context.guard_band_k}
               if context.guard_band_k is not None else {})}
    return (_stated(rec, "equipment accuracy", EquipmentConfig, context.equipment),
            _stated(rec, "IMU specification", ImuSpecConfig, context.imu_table),
            _stated(rec, "decision rule", AcceptanceConfig, rule))


def extract_p1_observations(rec: Recording, sensor_id: str | None = None, *,
                            processing: P1Processing | None = None,
                            progress: Callable[[float], None] | None = None,
                            workers: int = 1) -> P1Observations:
    """Reduce a P1 Recording to window observations of one IMU (module docstring).

    Parameters
    ----------
    rec : Recording
        An open Recording of a P1 run: its steps' roles (or tags) say which windows calibrate
        and which verify; no plan is needed.
    sensor_id : str, optional
        The IMU; the only one when omitted.
    processing : P1Processing, optional
    progress : callable, optional
        Called after each of the IMU's steps with the fraction of them reduced (increasing;
        the last call is 1.0).
    workers : int
        Processes the windows are reduced in (1: this one; N > 1: this one and N − 1 spawned
        ones, :func:`~.parallel.observe_parallel`). The observations are the same bit for bit.

    Returns
    -------
    P1Observations

    Raises
    ------
    RecordingError
        No step with a P1 role (nor a plan), no table or IMU stream, no latitude, or a window
        without enough data.
    InvalidInputError
        NaN in a window, an alignment error above the limit (LimitExceededError).
    """
    opt = processing or P1Processing()
    imus = [s.unit for s in rec.streams if s.device == DEVICE_IMU]
    if sensor_id is None:
        if len(imus) != 1:
            raise InvalidInputError(f"{rec.path} has {len(imus)} IMU streams {imus}; name one "
                                    "with `sensor_id`")
        sensor_id = imus[0]
    context = RecordingContext.of(rec.metadata)
    steps = [(step, _step_role(step, context.procedure)) for step in rec.steps
             if step.concerns(sensor_id)]
    if not context.has_plan and not any(role for _, role in steps):
        raise RecordingError(f"{rec.path} holds no plan (plan_toml) and none of its steps has a "
                             f"P1 role ({', '.join(P1_ROLES)}) or P1 tags: nothing says which "
                             "windows calibrate and which verify")
    equipment, imu_spec, acceptance = _stated_configs(rec, context)
    ex = WindowReducer(rec, sensor_id, opt)
    skipped: list[str] = []
    todo: list[tuple[StepRecord, str]] = []
    for step, role in steps:
        if step.status != "done" or not step.has_valid_window:
            if step.status in ("invalid", "aborted"):
                skipped.append(f"step {step.index} ({step.label}): {step.status}"
                               + (f" — {step.note}" if step.note else ""))
        elif role:
            todo.append((step, role))
    tick = _Progress(progress, len(steps), len(steps) - len(todo))
    jobs = _with_noise_flags(todo)
    if workers > 1 and len(jobs) > 2:
        windows = observe_parallel(ex, jobs, workers, tick)
    else:
        windows = []
        # one BLAS thread, as every worker runs: the serial result equals the shared one bit
        # for bit whatever OpenBLAS's default threads (docs/performance.md, "Workers")
        with one_thread():
            for job in jobs:
                windows.append(ex.observe(*job))
                tick()
    tick.finish()
    if not windows:
        why = "; ".join(skipped) if skipped else "no step has a P1 measurement role"
        raise RecordingError(f"{rec.path}: no completed calibration or verification window for "
                             f"{sensor_id} ({why})")
    noise = estimate_noise(windows)
    if not noise:  # no noise model after all: every window's own Allan fit gives its SE
        with one_thread():
            windows = [w if w.allan_fit is not None else ex.observe(step, role)
                       for w, (step, role, _) in zip(windows, jobs, strict=True)]
    notes = list(ex.notes)
    if noise:
        noise, floor_note = declared_floor(rec, imu_spec, windows, noise, ex.sample_rate_hz)
        windows = [_with_model_se(w, noise) for w in windows]
        notes.append("standard errors of the window means from the noise model fitted to the "
                     "long static records (white, flicker and random-walk terms)")
        if floor_note:
            notes.append(floor_note)
    else:
        notes.append("no long static record: standard errors from each window's own Allan "
                     "variance (uncertain by about a factor of two)")
    return P1Observations(sensor_id=sensor_id, windows=tuple(windows),
                          gravity_mps2=ex.g, earth_rate_t_rps=ex.earth_t,
                          latitude_deg=ex.latitude_deg, heading_deg=ex.heading_deg,
                          sample_rate_hz=ex.sample_rate_hz, cutoff_hz=ex.cutoff_hz,
                          notes=tuple(notes), skipped=tuple(skipped), noise=noise,
                          equipment=equipment, imu_spec=imu_spec, acceptance=acceptance,
                          context=context)


class _Progress:
    """Report the fraction of a run's steps done; steps with nothing to reduce count as done."""

    def __init__(self, progress: Callable[[float], None] | None, total: int, done: int) -> None:
        self.progress, self.total, self.done = progress, max(total, 1), done
        self.last = 0.0

    def __call__(self, n: int = 1) -> None:
        self.done += n
        self._report(min(self.done / self.total, 1.0))

    def finish(self) -> None:
        self._report(1.0)

    def _report(self, fraction: float) -> None:
        if self.progress is not None and fraction > self.last:
            self.last = fraction
            self.progress(fraction)


def _with_noise_flags(todo: Sequence[tuple[StepRecord, str]]
                      ) -> list[tuple[StepRecord, str, bool]]:
    """Say for each window whether it needs its own Allan fit (``observe``'s `own_noise`).

    When some static window's valid span lasts :data:`~imucalib.procedures.common.noise.
    NOISE_RECORD_MIN_S`, the noise model fitted to the long such records gives every window
    its standard error (:func:`~imucalib.procedures.common.noise.estimate_noise`): only those
    long records need their own fit. Otherwise every window does. (A long record whose
    averaged span turns out shorter than its valid span leaves no model: the windows without
    a fit are reduced again with one, so the result never depends on this guess.)
    """
    def long_static(step: StepRecord, role: str) -> bool:
        return (role not in RATE_ROLES
                and step.valid_end_s - step.valid_start_s >= NOISE_RECORD_MIN_S)

    model = any(long_static(step, role) for step, role in todo)
    return [(step, role, not model or long_static(step, role)) for step, role in todo]


def _with_model_se(w: WindowObservation, noise: Mapping[str, NoiseModel]) -> WindowObservation:
    gyro, accel = window_mean_se(noise, w.duration_s)
    return dataclasses.replace(w, gyro_se_rps=gyro, accel_se_mps2=accel)
