"""P1's predicted uncertainty from a plan, before it runs (docs/test-design.md).

:func:`predict_p1` walks a P1 plan (:func:`~imucalib.procedures.p1.plan.generate_p1_plan`
or one edited by hand) and builds the windows its run would give: for each calibration step
(roles ``p1.accel-position``, ``p1.gyro-bias``, ``p1.gyro-rate``) the nominal reference inputs
in the body frame (:func:`~imucalib.procedures.common.reference.static_inputs_b`,
:func:`~imucalib.procedures.common.reference.rate_inputs_b`), its length (``record_s``, the
static's ``duration_s``, or whole revolutions) and its start on the run's clock (the station
time of the steps before it, :func:`~imucalib.plan.budget.plan_step_starts_s`, plus its
settle phase). The windows are then selected, weighted and fitted as the analysis does
(:func:`~imucalib.procedures.p1.fit.fit_p1`): the accelerometer's six positions, the gyro's
rate points and statics (:func:`~imucalib.procedures.p1.fit.gyro_windows`), the coloured-noise
covariance of their means (:func:`~imucalib.procedures.p1.fit.observation_covariance`,
Eq. (TD.2)), the triad design (:func:`~imucalib.estimation.designs.build_design`, with the
gyro's G, which the analysis's rule holds in) and its
Cramér–Rao bound (:func:`~imucalib.estimation.crlb.compute_crlb`, Eqs. (TD.1), (TD.3)). The
equipment's Type B terms are added as the analysis adds them (docs/p1.md, "Equipment
uncertainty"; Eq. (TD.4)).

The noise model is the one the plan declares
(:func:`~imucalib.procedures.common.grade.declared_noise`): its ``[imu.noise]`` (a noise
characterisation of the unit, docs/test-design.md, "A noise characterisation in place of the
grade's"), else the unit's grade's (:func:`~imucalib.models.imu.sample_imu_model`'s
coefficients: white, bias instability, rate random walk; its white terms only when the plan's
twin says ``noise = "white"``); :func:`predict_p1` takes another one (a fitted Allan model).
The notes name the source.

Not predicted: the accelerometer's K2 (chosen by the data; none by default, ``accel_k2=True``
predicts the model with it) and the model choice's uncertainty (TS.4), which depend on the
data.

Contents
--------
:func:`predict_p1`, :func:`predict_p1_covariance`, :func:`nominal_observations` (the declared
noise: :func:`~imucalib.procedures.common.grade.declared_noise`)
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from imucalib.errors import ConfigurationError, InsufficientExcitationError
from imucalib.estimation._common import make_whitener
from imucalib.estimation.crlb import compute_crlb
from imucalib.estimation.designs import build_design
from imucalib.estimation.observability import compute_observability
from imucalib.models.noise import NoiseModel
from imucalib.models.result import triad_parameter_names, triad_parameter_unit
from imucalib.plan.budget import (
    MIN_SETTLE_PHASE_S,
    estimate_plan_recording,
    plan_facts,
    plan_step_starts_s,
)
from imucalib.plan.schema import PositionStep, RateStep, StaticStep
from imucalib.procedures.common.grade import declared_noise
from imucalib.procedures.common.prediction import PredictedParameter, Prediction, PredictionGroup
from imucalib.procedures.common.reference import rate_inputs_b, site_vectors, static_inputs_b
from imucalib.procedures.p1.fit import (
    _check_excitation,
    _stack_covariance,
    gyro_windows,
    observation_covariance,
)
from imucalib.procedures.p1.roles import P1_ACCEL_POSITION, P1_GYRO_BIAS, P1_GYRO_RATE
from imucalib.procedures.p1.windows import P1Observations, WindowObservation

if TYPE_CHECKING:
    from imucalib.plan.schema import Plan

__all__ = ["nominal_observations", "predict_p1", "predict_p1_covariance"]

#: The axes of P1's dual-axis table (outer first), as the twin's and a P1 recording's.
TABLE_AXES = ("pitch", "roll")
#: Site of a plan without a twin (the P1 plan's default). [°]
DEFAULT_LATITUDE_DEG = 45.0
#: The tag the analysis implies for each calibration role (observations' window tags).
_ROLE_TAGS = {P1_ACCEL_POSITION: "six-position", P1_GYRO_BIAS: "gyro-bias",
              P1_GYRO_RATE: "rate"}
_Z3 = np.zeros(3)


def _window(step_index: int, kind: str, role: str, tags: tuple[str, ...], label: str,
            rate_b: np.ndarray, force_b: np.ndarray, t_start_s: float, duration_s: float,
            axis: int | None, table_rate_rps: float) -> WindowObservation:
    return WindowObservation(
        step_index=step_index, plan_step=step_index, kind=kind, role="calibration",
        repetition=1, tags=tags, label=label, gyro_mean_rps=rate_b, accel_mean_mps2=force_b,
        gyro_se_rps=_Z3, accel_se_mps2=_Z3, gyro_std_rps=_Z3, accel_std_mps2=_Z3,
        rate_b_rps=rate_b, force_b_mps2=force_b, angles_rad=np.zeros(len(TABLE_AXES)),
        table_rate_rps=table_rate_rps, axis=axis, n_samples=0, n_outliers=0, n_revolutions=0,
        alignment_error_s=0.0, duration_s=duration_s, t_start_s=t_start_s, step_role=role)


def _rate_span_s(step: RateStep) -> float:
    """Length of a rate step's whole-revolution window (its record at 0 °/s). [s]"""
    if step.rate_dps == 0.0:
        return float(step.record_s or 0.0)
    turn = 360.0 / abs(step.rate_dps)
    if step.revolutions is not None:
        return step.revolutions * turn
    return math.floor(float(step.record_s or 0.0) / turn) * turn


def nominal_observations(plan: Plan, noise: Mapping[str, NoiseModel]) -> P1Observations:
    """Return the calibration windows a run of `plan` would give, without their means' noise.

    Each window's means are its reference inputs (a perfect unit); its start is the station time
    of the steps before it plus the step's settle phase (module docstring).

    Raises
    ------
    ConfigurationError
        A calibration step whose angles are not the dual-axis table's (pitch, roll).
    """
    lat = plan.twin.site.latitude_deg if plan.twin is not None else DEFAULT_LATITUDE_DEG
    heading = plan.twin.site.heading_deg if plan.twin is not None else 0.0
    g, earth_t = site_vectors(lat, heading, None)
    angles = np.zeros(len(TABLE_AXES))
    windows: list[WindowObservation] = []
    starts_s = plan_step_starts_s(plan, plan_facts(plan))  # each step's start, one pass
    for i, step in enumerate(plan.steps):
        if isinstance(step, PositionStep):
            if len(step.angles_deg) != len(TABLE_AXES):
                raise ConfigurationError(
                    f"step {i} ({plan.step_label(i)}) commands {len(step.angles_deg)} axes; a P1 "
                    f"plan runs on a dual-axis table ({', '.join(TABLE_AXES)})")
            angles = np.radians(np.asarray(step.angles_deg, dtype=float))
        role = step.role
        if role not in _ROLE_TAGS or not isinstance(step, PositionStep | StaticStep | RateStep):
            continue
        tags = step.tags if _ROLE_TAGS[role] in step.tags else (*step.tags, _ROLE_TAGS[role])
        before = starts_s[i]
        label = plan.step_label(i)
        if isinstance(step, StaticStep):
            rate_b, force_b = static_inputs_b(TABLE_AXES, angles, g, earth_t)
            windows.append(_window(i, "static", role, tags, label, rate_b, force_b, before,
                                   step.duration_s, None, 0.0))
            continue
        start = before + max(step.settle_s, MIN_SETTLE_PHASE_S)
        if isinstance(step, PositionStep) or step.rate_dps == 0.0:
            span = step.record_s if isinstance(step, PositionStep) else _rate_span_s(step)
            rate_b, force_b = static_inputs_b(TABLE_AXES, angles, g, earth_t)
            windows.append(_window(i, "static", role, tags, label, rate_b, force_b, start,
                                   float(span or 0.0), None, 0.0))
            continue
        rate = math.radians(step.rate_dps)
        rate_b, force_b = rate_inputs_b(TABLE_AXES, step.axis, angles, rate, g, earth_t)
        windows.append(_window(i, "rate", role, tags, label, rate_b, force_b, start,
                               _rate_span_s(step), step.axis, rate))
    return P1Observations(
        sensor_id=plan.imu.serial or "unit", windows=tuple(windows), gravity_mps2=g,
        earth_rate_t_rps=earth_t, latitude_deg=lat, heading_deg=heading,
        sample_rate_hz=plan.equipment.acquisition_rate_min_hz, cutoff_hz=None,
        noise=dict(noise), equipment=plan.equipment, imu_spec=plan.imu)


def _group(triad: str, windows: list[WindowObservation], noise: NoiseModel, g_term: bool,
           k2_term: bool = False
           ) -> tuple[PredictionGroup, dict[str, float | None], np.ndarray | None]:
    """One triad's design, identifiability and bound (Eqs. (TD.1)–(TD.3))."""
    accel = triad == "accel"
    terms = (["bias", "scale_misalignment"] + (["g_sensitivity"] if g_term else [])
             + (["k2"] if k2_term else []))
    if not windows:
        all_names = triad_parameter_names(triad, "triad")
        return (PredictionGroup(triad, len(all_names), 0, math.inf, all_names),
                dict.fromkeys(all_names), None)
    x = np.array([w.force_b_mps2 if accel else w.rate_b_rps for w in windows])
    f = np.array([w.force_b_mps2 for w in windows])
    design = build_design(x, terms, specific_force_b=f if g_term else None)
    names = tuple(f"{triad}_{n}" for n in design.param_names)
    cov = observation_covariance(windows, noise)
    assert cov is not None  # windows and a noise model
    full = _stack_covariance(cov)
    whitener, _ = make_whitener(design.H.shape[0], covariance=full)
    report = compute_observability(whitener.whiten(design.H), names)
    confounded: tuple[str, ...] = ()
    try:
        if accel and len(windows) < 6:
            raise InsufficientExcitationError(triad_parameter_names("accel", "triad"))
        _check_excitation(triad, "triad", x)
        bound = compute_crlb(design.H, full, param_names=names)
    except InsufficientExcitationError as exc:
        confounded = tuple(exc.unobservable)
        return (PredictionGroup(triad, len(names), report.rank, report.condition_number,
                                confounded), dict.fromkeys(names), None)
    return (PredictionGroup(triad, len(names), report.rank, report.condition_number),
            dict(bound.std_dict()), np.asarray(bound.covariance))


def predict_p1(plan: Plan, *, noise: Mapping[str, NoiseModel] | None = None,
               accel_k2: bool = False) -> Prediction:
    """Return the predicted σ of every parameter of a P1 plan's result (module docstring).

    Parameters
    ----------
    plan : Plan
        A P1 plan.
    noise : mapping of str to NoiseModel, optional
        ``{"accel": …, "gyro": …}``; when omitted, the plan's declared noise: its
        ``[imu.noise]``, else the grade's
        (:func:`~imucalib.procedures.common.grade.declared_noise`).
    accel_k2 : bool
        Predict the accelerometer with its K2 (P1.K2) in the model, as a calibration with
        ``terms="+k2"`` fits it (the six positions identify it); by default it is left out,
        as the analysis leaves it unless the data choose it.

    Returns
    -------
    Prediction
        σ per parameter (SI, the result's names and units; None for a triad the plan cannot
        identify), each triad's rank and condition number, the confounded parameters, and the
        station time with moves and settling.

    Raises
    ------
    ConfigurationError
        A plan of another procedure, without a grade or ``[imu.noise]`` (and no `noise`), or
        off the dual-axis table.
    """
    return predict_p1_covariance(plan, noise=noise, accel_k2=accel_k2)[0]


def predict_p1_covariance(plan: Plan, *, noise: Mapping[str, NoiseModel] | None = None,
                          accel_k2: bool = False
                          ) -> tuple[Prediction, dict[str, tuple[tuple[str, ...], np.ndarray]]]:
    """Return :func:`predict_p1`'s prediction and each identified triad's covariance.

    The covariance is the bound (TD.3) with the Type B of (TD.4) added, SI, as
    ``{triad: (names, covariance)}``; a triad the plan cannot identify is absent. The
    optimiser's D and A criteria use it (docs/test-design.md, Eqs. (TD.5), (TD.6)).

    Raises
    ------
    ConfigurationError
        As :func:`predict_p1`.
    """
    # the analysis's own rules, reused: G held in by rule, the Type B of (TD.4)
    from imucalib.procedures.p1.analysis import RULED_TERMS, P1Options, _add_type_b

    if plan.procedure and plan.procedure != "p1":
        raise ConfigurationError(f"plan {plan.name!r} is a {plan.procedure} plan, not a p1 plan")
    models, source = ((dict(noise), "given") if noise is not None else declared_noise(plan))
    obs = nominal_observations(plan, models)
    g_term = bool(RULED_TERMS.get("g"))
    accel_w = obs.select(kind="static", role="calibration", tag="six-position")
    gyro_w = gyro_windows(obs, "calibration", None)
    groups, std = [], {}
    covariances: dict[str, tuple[tuple[str, ...], np.ndarray]] = {}
    for triad, wins, g in (("accel", accel_w, False), ("gyro", gyro_w, g_term)):
        group, s, cov = _group(triad, wins, models[triad], g, accel_k2 and triad == "accel")
        groups.append(group)
        if cov is not None:  # (TD.4): the equipment's Type B on the misalignments
            names = tuple(s)
            cov, _ = _add_type_b(names, cov, obs, P1Options())
            s = dict(zip(names, np.sqrt(np.diag(cov)).tolist(), strict=True))
            covariances[triad] = (names, np.asarray(cov))
        std.update(s)
    params = tuple(PredictedParameter(n, v, triad_parameter_unit(n)) for n, v in std.items())
    kinds = ", ".join(f"{k}: {_describe(m)}" for k, m in sorted(models.items()))
    notes = [
        f"noise model ({source}): {kinds}; "
        "window means correlated by flicker and random walk (Eq. (TD.2))",
        f"gyro G {'held in by rule' if g_term else 'not in'}; "
        + ("the accelerometer's K2 in the model (P1.K2); the model choice's uncertainty "
           "(TS.4) is not predicted" if accel_k2 else
           "the accelerometer's K2 and the model choice's uncertainty (TS.4) are not "
           "predicted"),
        f"Type B (GUM): table position accuracy {plan.equipment.table_position_accuracy_arcsec:g}"
        f"″ and axis perpendicularity {plan.equipment.table_orthogonality_arcsec:g}″ on the "
        "misalignments (Eq. (TD.4))",
    ]
    return (Prediction(procedure="p1", station_time_s=estimate_plan_recording(plan).duration_s,
                       parameters=params, groups=tuple(groups), notes=tuple(notes)),
            covariances)


def _describe(m: NoiseModel) -> str:
    """White, bias-instability and random-walk coefficients of axis x, SI."""
    return (f"N {float(m.white_density[0]):.3g}, B {float(m.bias_instability[0]):.3g}, "
            f"K {float(m.random_walk[0]):.3g}")
