"""P2's predicted uncertainty from a plan, before it runs (docs/test-design.md, "P2").

:func:`predict_p2` walks a P2 plan (:func:`~imucalib.procedures.p2.plan.generate_p2_plan` or
one edited by hand) and builds the windows one unit's run would give: for every calibration
temperature point (the soak's setpoint, its leg) and pose, the static records and the ±ω turns
(whole revolutions), each with its start on the run's clock (the station time of the steps
before it, :func:`~imucalib.plan.budget.plan_run_duration_s`, plus the settle phase). Then, as
the analysis does (:mod:`~imucalib.procedures.p2.analysis`):

1. per point, the weighted least squares of :func:`~imucalib.procedures.p2.reduction.
   least_squares` (the accelerometer's 18 and the gyro's 12 rows of Eqs. (P2.1)–(P2.3),
   docs/p2.md, at the nominal inputs, lever arm estimated about r = 0), weighted as the
   analysis weights them, by each window's standard error σ_j = σ_A(T_j) (the Allan deviation
   of the noise model at the window's length, :func:`~imucalib.procedures.common.noise.
   window_mean_se`): θ_k = Q_k·y_k;
2. per parameter i, the temperature model of the assumed order m (the analysis's highest,
   ``max_order`` = 3, by default; a heating/cooling term when each leg holds two calibration
   points, as ``hysteresis="auto"``) by GLS over the K calibration points, weighted by the
   points' variances V_i = diag(Q_k·diag(σ²)·Q_kᵀ)_ii (Eq. (2) of
   :mod:`~imucalib.estimation.temperature_model`): β_i = W_i·θ_i.

β is linear in the window means, β = G·y, so its covariance under the window means' covariance
C is

    Cov(β) = G·C·Gᵀ                                                              (TD.P1)

    C = C_noise + C_T,   C_noise from (TD.2)                                     (TD.P2)

    C_T[j, l] = σ_T²·(δ_pq − 1/n_p)·Σ_k s_k²·x_k(j)·x_k(l)   (j in pose p, l in pose q of
                                                               one point)         (TD.P3)

(TD.P1) with C = diag(σ_j²) treats the window means as independent, each with the Allan
deviation at its length (what ``calibrate`` reported before issue 30, and still reports for a
recording without a noise model); with the coloured C of (TD.2) (flicker and random walk
correlate windows minutes and hours apart) it is the spread the estimates will have: the
predicted σ, and — with σ_T = 0 and the unit's noise — the σ ``calibrate`` reports, which
carries the same C through the same estimator (docs/p2.md, Eqs. (P2.12)–(P2.13); both build it
with :mod:`~imucalib.procedures.p2.covariance`). (TD.P3) is the chamber's stability: the
unit's temperature differs from pose to pose within the soak's band (σ_T = band/√12, uniform,
``imu_band_degc`` of the soaks; its mean over a point's poses is measured and drops out), and
each output moves with it by the typical temperature slopes s_k of the grade's parameters
(bias, scale factor, misalignments: the swing of :data:`~imucalib.models.imu.THERMAL_GRADES`
over :data:`~imucalib.models.imu.THERMAL_RANGE_DEGC`) times the input x_k of the window.

Names: each parameter of the result at T0 (``gyro_bias_x`` …, the c_0 of its model, as the
result reports it), then every coefficient c_j, j ≥ 1, as ``<name>_c<j>`` (unit the
parameter's per K^j), the hysteresis term as ``<name>_leg``, and ``<name>_range``: the
largest σ of the model's value over the calibration range (Eq. (5) of
:mod:`~imucalib.estimation.temperature_model`). Identifiability: a model of
order m has q = m + 1 (+1 leg) coefficients; the analysis determines it from K calibration
points only when K ≥ q + 2 (AICc, Eq. (6): finite for K − q − 1 > 0; cross-validation K ≥ q + 1,
a fixed order K ≥ q). Otherwise the highest order the points allow is predicted and the
coefficients above it are confounded (named, σ None).

Contents
--------
:func:`predict_p2`, :func:`predict_p2_detail` (→ :class:`P2PredictionDetail`),
:func:`plan_points` (→ :class:`PlannedPoint`, :class:`PlannedWindow`),
:func:`coefficient_names`, :func:`min_points`
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from imucalib import units as u
from imucalib.errors import ConfigurationError
from imucalib.estimation.designs import build_design
from imucalib.estimation.observability import compute_observability
from imucalib.models.noise import NoiseModel
from imucalib.models.result import triad_parameter_unit
from imucalib.plan.budget import (
    MIN_SETTLE_PHASE_S,
    StationFacts,
    _facts_from_plan,
    plan_run_duration_s,
)
from imucalib.plan.schema import Plan, PositionStep, RateStep, SoakStep
from imucalib.procedures.common.grade import grade_noise, plan_grade
from imucalib.procedures.common.noise import window_mean_se
from imucalib.procedures.common.prediction import PredictedParameter, Prediction, PredictionGroup
from imucalib.procedures.common.reference import site_vectors
from imucalib.procedures.p2.covariance import (
    independent_covariance,
    propagate,
    window_covariance,
)
from imucalib.procedures.p2.reduction import ORIENTATIONS, PARAM_NAMES, up_vector
from imucalib.procedures.p2.roles import P2_RATE, P2_SOAK, P2_STATIC

__all__ = ["P2PredictionDetail", "PlannedPoint", "PlannedWindow", "coefficient_names",
           "min_points", "plan_points", "predict_p2", "predict_p2_detail"]

_F64 = NDArray[np.float64]
#: Site of a plan without a twin (the P2 plan's default). [°]
DEFAULT_LATITUDE_DEG = 45.0
#: The assumed order of every temperature model (the analysis's ``max_order``).
DEFAULT_ORDER = 3
#: The reference temperature T0 of the models (the analysis's default). [°C]
DEFAULT_T0_DEGC = 25.0
Criterion = Literal["aicc", "cv", "fixed"]
#: How each order criterion is named in messages.
CRITERION_LABEL: dict[str, str] = {"aicc": "AICc", "cv": "cross-validation",
                                   "fixed": "a fixed order"}
Covariance = Literal["coloured", "analysis"]
_N_GYRO = 21  # gyro parameters: bias, M, G
_N_ACCEL = 15  # accelerometer parameters: bias, M, K2 (the lever arm is a nuisance)


@dataclass(frozen=True)
class PlannedWindow:
    """One window of one unit a run of the plan gives (nominal).

    Attributes
    ----------
    pose : str
        The body axis up (``"+x"`` …: the fixture pose, a unit square to the cube's faces).
    kind : str
        ``"static"`` or ``"rate"``.
    rate_rps : float
        Commanded table rate (0 static). [rad/s]
    start_s, duration_s : float
        Start on the run's clock and length (whole revolutions for a turn). [s]
    """

    pose: str
    kind: str
    rate_rps: float
    start_s: float
    duration_s: float


@dataclass(frozen=True)
class PlannedPoint:
    """One temperature point of the plan: its setpoint, leg, held-out flag and windows."""

    index: int
    temperature_degc: float
    leg: str
    held_out: bool
    windows: tuple[PlannedWindow, ...]


def _tag(tags: Sequence[str], key: str) -> str | None:
    return next((t.split("=", 1)[1] for t in tags if t.startswith(key + "=")), None)


def _facts(plan: Plan) -> StationFacts:
    return StationFacts.of_twin(plan.twin) if plan.twin is not None else _facts_from_plan(plan)


def plan_points(plan: Plan) -> list[PlannedPoint]:
    """Return the plan's temperature points with the windows of one unit (module docstring).

    Each step's start is the station time of the steps before it
    (:func:`~imucalib.plan.budget.plan_run_duration_s`, step by step from the chamber's
    temperature); a point's temperature is its soak's setpoint.

    Raises
    ------
    ConfigurationError
        A P2 step without a ``point=<k>`` tag, or a point without a soak.
    """
    facts = _facts(plan)
    clock, chamber = 0.0, facts.initial_temperature_degc
    temps: dict[int, float] = {}
    info: dict[int, tuple[str, bool]] = {}
    wins: dict[int, list[PlannedWindow]] = {}
    for i, step in enumerate(plan.steps):
        one = plan.model_copy(update={"steps": (step,)})
        duration = plan_run_duration_s(one, dataclasses.replace(
            facts, initial_temperature_degc=chamber))
        role = step.role
        if role in (P2_SOAK, P2_STATIC, P2_RATE):
            value = _tag(step.tags, "point")
            if value is None or not value.lstrip("-").isdigit():
                raise ConfigurationError(f"step {i} ({plan.step_label(i)}) has the role {role} "
                                         "but no point=<k> tag")
            k = int(value)
            info.setdefault(k, (_tag(step.tags, "leg") or "heating", "held-out" in step.tags))
            if role == P2_SOAK and isinstance(step, SoakStep):
                temps[k] = float(step.temperature_degc)
            elif isinstance(step, PositionStep | RateStep):
                pose = _tag(step.tags, "pose") or ""
                start = clock + max(step.settle_s, MIN_SETTLE_PHASE_S)
                if isinstance(step, RateStep) and role == P2_RATE and step.rate_dps != 0.0:
                    turn = 360.0 / abs(step.rate_dps)
                    span = (step.revolutions * turn if step.revolutions is not None
                            else math.floor(float(step.record_s or 0.0) / turn) * turn)
                    wins.setdefault(k, []).append(PlannedWindow(
                        pose, "rate", math.radians(step.rate_dps), start, span))
                elif isinstance(step, PositionStep) and role == P2_STATIC:
                    wins.setdefault(k, []).append(PlannedWindow(
                        pose, "static", 0.0, start, float(step.record_s)))
        if isinstance(step, SoakStep):
            chamber = step.temperature_degc
        clock += duration
    missing = sorted(k for k in wins if k not in temps)
    if missing:
        raise ConfigurationError(f"plan {plan.name!r}: temperature point(s) {missing} have no "
                                 f"soak step (role {P2_SOAK})")
    return [PlannedPoint(k, temps[k], info[k][0], info[k][1], tuple(wins.get(k, ())))
            for k in sorted(temps)]


def min_points(order: int, criterion: Criterion = "aicc", n_extra: int = 0) -> int:
    """Return the least K of calibration points that determine a model of `order`.

    q = order + 1 + n_extra coefficients: K ≥ q + 2 for AICc (Eq. (6) of
    :mod:`~imucalib.estimation.temperature_model` is finite only for K − q − 1 > 0), K ≥ q + 1
    for cross-validation (each fit leaves one point out), K ≥ q for a fixed order.
    """
    q = order + 1 + n_extra
    return q + {"aicc": 2, "cv": 1, "fixed": 0}[criterion]


def coefficient_names(order: int, leg: bool) -> list[tuple[str, str, int]]:
    """Return (name, unit, index in its model) of every predicted coefficient (module docstring).

    The 36 parameters at T0 first (c_0, the result's names), then each parameter's c_1 … c_m
    and its leg term.
    """
    out = [(n, triad_parameter_unit(n), 0) for n in PARAM_NAMES]
    for n in PARAM_NAMES:
        unit = triad_parameter_unit(n)
        for j in range(1, order + 1):
            out.append((f"{n}_c{j}", f"{unit}/K" if j == 1 else f"{unit}/K^{j}", j))
        if leg:
            out.append((f"{n}_leg", unit, order + 1))
    return out


@dataclass(frozen=True)
class _PointFit:
    """One point's estimator θ = Σ Q[:, w, a]·y[w, a] and its variances (analysis weights)."""

    q_gyro: _F64   # (21, n_w, 3)
    q_accel: _F64  # (15, n_w, 3)
    var: _F64      # (36,)
    kappa: tuple[float, float]
    rank: tuple[int, int]


def _rows(point: PlannedPoint) -> dict[str, list[tuple[str, list[int]]]] | str:
    """Group a point's windows by (kind, orientation), or say what is missing."""
    groups: dict[str, list[tuple[str, list[int]]]] = {"static": [], "plus": [], "minus": []}
    for o in ORIENTATIONS:
        mine = [j for j, w in enumerate(point.windows) if w.pose == o]
        got = {"static": [j for j in mine if point.windows[j].kind == "static"],
               "plus": [j for j in mine if point.windows[j].kind == "rate"
                        and point.windows[j].rate_rps > 0],
               "minus": [j for j in mine if point.windows[j].kind == "rate"
                         and point.windows[j].rate_rps < 0]}
        lacking = [k for k, v in got.items() if not v]
        if lacking:
            return f"orientation {o} up has no {' and no '.join(lacking)} window"
        for k, v in got.items():
            groups[k].append((o, v))
    return groups


def _operator(h: _F64, se: _F64, rows: list[list[int]], n_w: int) -> tuple[_F64, _F64, float,
                                                                              int]:
    """Weighted LSQ gain mapped back to the windows: Q (p, n_w, 3), diag covariance, κ, rank.

    `rows` lists each row's windows (averaged, as the analysis's plain mean); `se` (n_w, 3)
    the windows' standard errors; a row's variance is Σ σ²/n² (:func:`~.analysis._combine`).
    """
    n_r = len(rows)
    a = np.zeros((n_r, n_w))
    for r, js in enumerate(rows):
        a[r, js] = 1.0 / len(js)
    row_var = (a**2) @ se**2                                      # (n_r, 3)
    w = 1.0 / row_var.ravel()
    hw = h * w[:, None]
    report = compute_observability(h * np.sqrt(w)[:, None], [f"p{i}" for i in range(h.shape[1])])
    gain = np.linalg.solve(h.T @ hw, hw.T)                        # (p, 3·n_r)
    gain3 = gain.reshape(h.shape[1], n_r, 3)
    q = np.einsum("prc,rw->pwc", gain3, a)                        # (p, n_w, 3)
    var = np.einsum("pwc,wc->p", q**2, se**2)
    return q, var, float(report.condition_number), int(report.rank)


def _point_fit(point: PlannedPoint, groups: dict[str, list[tuple[str, list[int]]]],
               noise: Mapping[str, NoiseModel], g: float, omega_up: float) -> _PointFit:
    """Return the analysis's per-point weighted least squares, Eqs. (P2.1)–(P2.3), r = 0."""
    n_w = len(point.windows)
    se_g = np.zeros((n_w, 3))
    se_a = np.zeros((n_w, 3))
    for j, w in enumerate(point.windows):
        se_g[j], se_a[j] = window_mean_se(noise, w.duration_s)
    ups = np.array([up_vector(o) for o in ORIENTATIONS])

    def mean_rate(kind: str) -> _F64:
        return np.array([np.mean([point.windows[j].rate_rps for j in js])
                         for _, js in groups[kind]])

    w_plus, w_minus = mean_rate("plus"), mean_rate("minus")
    # accelerometer: static, +ω, −ω rows; bias, M, K2 and the lever arm r (about r = 0)
    u_all = np.vstack([ups, ups, ups])
    omega2 = np.concatenate([np.zeros(6), w_plus**2, w_minus**2])
    proj = np.eye(3)[None] - u_all[:, :, None] * u_all[:, None, :]
    base = build_design(g * u_all, ("bias", "scale_misalignment", "k2")).H
    h_a = np.hstack([base, -(omega2[:, None, None] * proj).reshape(-1, 3)])
    rows_a = [js for kind in ("static", "plus", "minus") for _, js in groups[kind]]
    q_a, var_a, k_a, r_a = _operator(h_a, se_a, rows_a, n_w)
    # gyro: the ±ω rows; bias, M, G with f = g·u_o
    u12 = np.vstack([ups, ups])
    x_g = u12 * (np.concatenate([w_plus, w_minus]) + omega_up)[:, None]
    h_g = build_design(x_g, ("bias", "scale_misalignment", "g_sensitivity"),
                       specific_force_b=g * u12).H
    rows_g = [js for kind in ("plus", "minus") for _, js in groups[kind]]
    q_g, var_g, k_g, r_g = _operator(h_g, se_g, rows_g, n_w)
    return _PointFit(q_gyro=q_g, q_accel=q_a[:_N_ACCEL],
                     var=np.concatenate([var_g, var_a[:_N_ACCEL]]), kappa=(k_g, k_a),
                     rank=(r_g, r_a))


def _gls_gain(temps: _F64, legs: _F64 | None, order: int, var: _F64, t0: float
              ) -> tuple[_F64, _F64]:
    """GLS gain W = (AᵀV⁻¹A)⁻¹AᵀV⁻¹ of Eq. (2) (physical units) and the design A."""
    dt = temps - t0
    cols = [dt**j for j in range(order + 1)] + ([legs] if legs is not None else [])
    a = np.column_stack(cols)
    aw = a / var[:, None]
    return np.asarray(np.linalg.solve(a.T @ aw, aw.T), dtype=np.float64), a


def _input_vectors(point: PlannedPoint, g: float, omega_up: float) -> tuple[_F64, _F64]:
    """Each window's nominal input: specific force g·u_o and rate u_o·(ω + Ω_U)."""
    ups = np.array([up_vector(w.pose) for w in point.windows])
    rates = np.array([w.rate_rps for w in point.windows])
    return g * ups, ups * (rates + omega_up)[:, None]


def _thermal_slopes(grade: str) -> dict[str, tuple[float, float, float]]:
    """Typical |dp/dT| of (bias, scale, misalignment) per triad: swing / range. [SI/K]"""
    from imucalib.models.imu import THERMAL_GRADES, THERMAL_RANGE_DEGC

    spec = THERMAL_GRADES[grade]
    span = THERMAL_RANGE_DEGC[1] - THERMAL_RANGE_DEGC[0]
    return {"gyro": (spec.gyro_bias_dph * u.DEG_PER_H / span, spec.gyro_scale_ppm * 1e-6 / span,
                     spec.gyro_misalignment_mrad * 1e-3 / span),
            "accel": (spec.accel_bias_ug * u.UG / span, spec.accel_scale_ppm * 1e-6 / span,
                      spec.accel_misalignment_mrad * 1e-3 / span)}


def _thermal_covariance(point: PlannedPoint, x: _F64, axis: int,
                        slopes: tuple[float, float, float], sigma_t: float) -> _F64:
    """(TD.P3): the covariance the pose-to-pose temperature spread adds to one channel."""
    poses = [w.pose for w in point.windows]
    n_p = len(set(poses))
    same = np.equal.outer(np.array(poses, dtype=object), np.array(poses, dtype=object))
    k = same.astype(float) - 1.0 / n_p
    s_b, s_s, s_m = slopes
    xa = x[:, axis]
    gram = x @ x.T
    inner = s_b**2 + s_s**2 * np.outer(xa, xa) + s_m**2 * (gram - np.outer(xa, xa))
    return np.asarray(sigma_t**2 * k * inner, dtype=np.float64)


@dataclass(frozen=True)
class P2PredictionDetail:
    """:func:`predict_p2_detail`'s answer: the prediction and what the optimiser reads.

    Attributes
    ----------
    prediction : Prediction
        σ per coefficient (the chosen covariance), station time, groups, notes.
    names : tuple of str
        The identified coefficients, in the order of `covariance`.
    covariance, covariance_analysis : ndarray
        Cov(β) of (TD.P1) with the coloured C of (TD.P2) and with C = diag(σ_j²) (the
        independent windows). [SI²]
    range_std : dict of str to float
        Per parameter, the largest σ of its model's value over the calibration range
        (Eq. (5) of :mod:`~imucalib.estimation.temperature_model`, the coloured covariance). [SI]
    order : int
        The order predicted (the assumed one, or the highest the points allow).
    n_points : int
        Calibration points K.
    """

    prediction: Prediction
    names: tuple[str, ...]
    covariance: _F64
    covariance_analysis: _F64
    range_std: dict[str, float]
    order: int
    n_points: int


def predict_p2(plan: Plan, *, noise: Mapping[str, NoiseModel] | None = None,
               order: int = DEFAULT_ORDER, criterion: Criterion = "aicc",
               reference_temperature_degc: float = DEFAULT_T0_DEGC,
               temperature_std_degc: float | None = None,
               covariance: Covariance = "coloured") -> Prediction:
    """Return the predicted σ of every temperature-model coefficient of a P2 plan's result.

    Parameters
    ----------
    plan : Plan
        A P2 plan.
    noise : mapping of str to NoiseModel, optional
        ``{"accel": …, "gyro": …}``; the grade's when omitted
        (:func:`~imucalib.procedures.common.grade.grade_noise`).
    order : int
        The temperature models' order (the analysis chooses it from the data, at most its
        ``max_order``, 3).
    criterion : {"aicc", "cv", "fixed"}
        How the analysis will choose the order (identifiability, :func:`min_points`).
    reference_temperature_degc : float
        T0. [°C]
    temperature_std_degc : float, optional
        σ_T of (TD.P3); the soaks' ``imu_band_degc``/√12 when omitted, 0 to leave it out. [°C]
    covariance : {"coloured", "analysis"}
        The σ of (TD.P1) with the coloured C (the spread, the default) or with diag(σ_j²) and
        no σ_T (the independent windows: what ``calibrate`` reports for a recording without a
        noise model, and reported for every one before issue 30).

    Returns
    -------
    Prediction
        σ per coefficient and per parameter over the range (SI, module docstring's names),
        None where confounded.

    Raises
    ------
    ConfigurationError
        A plan of another procedure, without a grade (and no `noise`), or without P2 steps.
    """
    return predict_p2_detail(plan, noise=noise, order=order, criterion=criterion,
                             reference_temperature_degc=reference_temperature_degc,
                             temperature_std_degc=temperature_std_degc,
                             covariance=covariance).prediction


def _band_std(plan: Plan) -> float:
    bands = [s.imu_band_degc for s in plan.steps if isinstance(s, SoakStep)
             and s.role == P2_SOAK]
    return float(np.median(bands)) / math.sqrt(12.0) if bands else 0.0


def _unidentified(plan: Plan, names: list[tuple[str, str, int]], why: str, station: float,
                  notes: list[str]) -> P2PredictionDetail:
    every = tuple(n for n, _, _ in names)
    pred = Prediction(procedure="p2", station_time_s=station,
                      parameters=tuple(PredictedParameter(n, None, un) for n, un, _ in names)
                      + tuple(PredictedParameter(f"{n}_range", None, triad_parameter_unit(n))
                              for n in PARAM_NAMES),
                      groups=(PredictionGroup(why, len(every), 0, math.inf, every),),
                      notes=(*notes, why))
    return P2PredictionDetail(pred, (), np.zeros((0, 0)), np.zeros((0, 0)), {}, -1, 0)


def predict_p2_detail(plan: Plan, *, noise: Mapping[str, NoiseModel] | None = None,
                      order: int = DEFAULT_ORDER, criterion: Criterion = "aicc",
                      reference_temperature_degc: float = DEFAULT_T0_DEGC,
                      temperature_std_degc: float | None = None,
                      covariance: Covariance = "coloured") -> P2PredictionDetail:
    """Return :func:`predict_p2`'s prediction with the covariances (:class:`P2PredictionDetail`).

    Raises
    ------
    ConfigurationError
        As :func:`predict_p2`; an order outside 0 … 5 or an unknown criterion.
    """
    if plan.procedure and plan.procedure != "p2":
        raise ConfigurationError(f"plan {plan.name!r} is a {plan.procedure} plan, not a p2 plan")
    if not (isinstance(order, int) and 0 <= order <= 5):
        raise ConfigurationError(f"the temperature models' order must be 0 … 5; got {order!r}")
    if criterion not in ("aicc", "cv", "fixed"):
        raise ConfigurationError(f"criterion must be aicc, cv or fixed; got {criterion!r}")
    models = dict(noise) if noise is not None else grade_noise(plan)
    grade = plan_grade(plan) if noise is None else (plan.imu.grade or "consumer")
    sigma_t = _band_std(plan) if temperature_std_degc is None else float(temperature_std_degc)
    if covariance == "analysis":
        sigma_t = 0.0
    station = plan_run_duration_s(plan, _facts(plan))
    points = plan_points(plan)
    cal = [p for p in points if not p.held_out]
    per_leg = [sum(p.leg == leg for p in cal) for leg in ("heating", "cooling")]
    use_leg = min(per_leg) >= 2
    names = coefficient_names(order, use_leg)
    t0 = float(reference_temperature_degc)
    lat = plan.twin.site.latitude_deg if plan.twin is not None else DEFAULT_LATITUDE_DEG
    heading = plan.twin.site.heading_deg if plan.twin is not None else 0.0
    g, earth_t = site_vectors(lat, heading, None)
    omega_up = float(earth_t[2])
    notes = [
        f"noise model ({'given' if noise is not None else 'grade ' + grade}): "
        + ", ".join(f"{k}: N {float(np.ravel(m.white_density)[0]):.3g}, B "
                    f"{float(np.ravel(m.bias_instability)[0]):.3g}, K "
                    f"{float(np.ravel(m.random_walk)[0]):.3g}" for k, m in sorted(models.items()))
        + " (axis x, SI)",
        f"one unit's σ (every unit of the cube alike); {len(cal)} calibration point(s), "
        f"{len(points) - len(cal)} held out (not fitted); models of order {order} about "
        f"T0 = {t0:g} °C" + (" with a heating/cooling term" if use_leg else ""),
    ]
    need = min_points(order, criterion, int(use_leg))
    fits: list[_PointFit] = []
    for p in cal:
        groups = _rows(p)
        if isinstance(groups, str):
            return _unidentified(plan, names, f"point {p.index} ({p.temperature_degc:+g} °C): "
                                 f"{groups}; the analysis cannot calibrate the unit", station,
                                 notes)
        fits.append(_point_fit(p, groups, models, g, omega_up))
    m_eff = order
    while m_eff >= 0 and len(cal) < min_points(m_eff, criterion, int(use_leg)):
        m_eff -= 1
    if len(cal) < 2 or m_eff < 0:
        return _unidentified(plan, names, f"temperature models: {len(cal)} calibration point(s) "
                             f"determine no model (order {order} needs {need}, "
                             f"{CRITERION_LABEL[criterion]})", station, notes)
    temps = np.array([p.temperature_degc for p in cal])
    legs = np.array([1.0 if p.leg == "heating" else -1.0 for p in cal]) if use_leg else None
    q_eff = m_eff + 1 + int(use_leg)
    n_par = len(PARAM_NAMES)
    # G: the coefficients (param-major, q_eff each) from every channel's window means
    offsets = np.cumsum([0] + [len(p.windows) for p in cal])
    n_win = int(offsets[-1])
    gain = np.zeros((6, n_par * q_eff, n_win))     # channel: gyro x, y, z, accel x, y, z
    var = np.array([f.var for f in fits])           # (K, 36)
    for i in range(n_par):
        w_i, _ = _gls_gain(temps, legs, m_eff, var[:, i], t0)   # (q_eff, K)
        for k, f in enumerate(fits):
            gyro = i < _N_GYRO
            qk = f.q_gyro[i] if gyro else f.q_accel[i - _N_GYRO]   # (n_w, 3)
            block = slice(offsets[k], offsets[k + 1])
            for axis in range(3):
                ch = axis if gyro else 3 + axis
                gain[ch, i * q_eff:(i + 1) * q_eff, block] += np.outer(w_i[:, k], qk[:, axis])
    starts = np.array([w.start_s for p in cal for w in p.windows])
    durs = np.array([w.duration_s for p in cal for w in p.windows])
    slopes = _thermal_slopes(grade) if sigma_t > 0 else {}
    se_all = np.array([np.concatenate(window_mean_se(models, d)) for d in durs])   # (n, 6)
    cov_an = propagate(gain, independent_covariance(se_all))
    if covariance == "analysis":
        cov = cov_an
    else:
        c_all = window_covariance(models, starts, durs, reference_time_s=0.0)
        if sigma_t > 0:
            for t_i, triad in enumerate(("gyro", "accel")):
                for k, p in enumerate(cal):
                    xs = _input_vectors(p, g, omega_up)[t_i]
                    block = slice(offsets[k], offsets[k + 1])
                    for axis in range(3):
                        c_all[3 * t_i + axis, block, block] += _thermal_covariance(
                            p, xs, axis, slopes[triad], sigma_t)
        cov = propagate(gain, c_all)
    # names of the identified coefficients, in cov's order (param-major)
    ident = []
    for n in PARAM_NAMES:
        ident += [n] + [f"{n}_c{j}" for j in range(1, m_eff + 1)] + ([f"{n}_leg"] if use_leg
                                                                      else [])
    std = dict(zip(ident, np.sqrt(np.maximum(np.diag(cov), 0.0)).tolist(), strict=True))
    confounded = tuple(n for n, _, _ in names if n not in std)
    grid = np.linspace(float(temps.min()), float(temps.max()), 41)
    range_std = {}
    for i, n in enumerate(PARAM_NAMES):
        blk = cov[i * q_eff:(i + 1) * q_eff, i * q_eff:(i + 1) * q_eff]
        a = np.column_stack([(grid - t0) ** j for j in range(m_eff + 1)]
                            + ([np.zeros_like(grid)] if use_leg else []))
        range_std[n] = float(np.sqrt(np.max(np.einsum("ti,ij,tj->t", a, blk, a))))
    _, a_full = _gls_gain(temps, legs, m_eff, np.ones(temps.size), t0)
    scaled = a_full / np.maximum(np.abs(a_full).max(axis=0), 1e-300)
    tm_report = compute_observability(scaled, [f"c{j}" for j in range(q_eff)])
    groups_out = (
        PredictionGroup("gyro point fit", 21 + 0, min(f.rank[0] for f in fits),
                        max(f.kappa[0] for f in fits)),
        PredictionGroup("accel point fit", 18, min(f.rank[1] for f in fits),
                        max(f.kappa[1] for f in fits)),
        PredictionGroup(f"temperature models (order {order}, {len(cal)} points)",
                        n_par * (order + 1 + int(use_leg)), n_par * tm_report.rank,
                        float(tm_report.condition_number), confounded),
    )
    if m_eff < order:
        notes.append(f"{len(cal)} calibration points determine models up to order {m_eff} "
                     f"({CRITERION_LABEL[criterion]}: order {order} needs {need} points); "
                     f"the σ are those of order {m_eff}, the higher coefficients confounded")
    ratio = np.sqrt(np.diag(cov) / np.maximum(np.diag(cov_an), 1e-300))
    notes.append(
        ("σ of the analysis's estimator under the coloured noise, G·C·Gᵀ (Eqs. (TD.P1), "
         f"(TD.P2)); chamber stability σ_T = {sigma_t:.3g} °C between poses (TD.P3); ratio to "
         "the independent windows' σ (σ_j the Allan deviation at each window's length): "
         f"{float(ratio.min()):.3g} … {float(ratio.max()):.3g}")
        if covariance == "coloured" else
        "σ of independent windows, σ_j the Allan deviation at each window's length (Eq. "
        "(TD.P1) with C = diag(σ_j²); calibrate's for a recording without a noise model); no "
        "σ_T")
    notes.append("a misfit's Birge scaling (an order too low for the unit's curve) and the "
                 "lever arm's second-order terms are not predicted")
    params = tuple(PredictedParameter(n, std.get(n), un) for n, un, _ in names) + tuple(
        PredictedParameter(f"{n}_range", range_std[n], triad_parameter_unit(n))
        for n in PARAM_NAMES)
    pred = Prediction(procedure="p2", station_time_s=station, parameters=params,
                      groups=groups_out, notes=tuple(notes))
    return P2PredictionDetail(pred, tuple(ident), cov, cov_an, range_std, m_eff, len(cal))
