"""The rate transfer's predicted σ from a plan, before it runs (docs/rate-transfer.md, TD.R4).

:func:`predict_rate_transfer` builds, per body axis tested, the turns a run of the plan would
give: input x_j = ω_j + Ω_U (RT-1, Ω_U the vertical Earth rate of the twin's site), the span of
whole revolutions T_j = n_j·360°/|ω_j| (RT-2) and its start on the run's clock (the station
time of the steps before it, :func:`~imucalib.plan.budget.estimate_plan_recording`, plus the
settle phase). The covariance C of gyro k's means is that of the grade's noise model, the
random walk from the run's start
(:func:`~imucalib.estimation.compute_window_mean_covariance`, Eq. (TD.2): white N²/T_j on the
diagonal, flicker and random walk correlating the turns).

The analysis fits both models by generalized least squares with the same C (RT-4c: the white
density it fits, the declared grade's flicker and random walk), so its estimator is
θ̂ = P·y with P = (AᵀC⁻¹A)⁻¹AᵀC⁻¹, for the line A = [1, x] (RT-5) and the second fit
A = [1, x, |x|, x²] (RT-7); the predicted covariance is

    (TD.R4)  Cov(θ̂) = P·C·Pᵀ = (AᵀC⁻¹A)⁻¹,

the Cramér–Rao bound (:func:`~imucalib.estimation.crlb.compute_crlb`, Eq. (TD.3)); what
calibrate reports as ``std_noise``. The notes give its largest ratio to the white-noise bound
(AᵀWA)⁻¹, W = diag(T_j/N²): how much flicker and random walk add. Derived quantities as the
result computes them: the asymmetry 2A/E′ (RT-8) with E′ = 1, A = 0 gives σ = 2σ_A; the
nonlinearity's σ (RT-6a) depends on which mean deviates most, so the largest over the turns of
σ(r_j)/max|x| (r the line's residuals, Cov(r) = R·C·Rᵀ, R = I − A·P) is given, an upper value.

Identifiability as the analysis decides it: fewer than two distinct rates on an axis confound
all its parameters; fewer than three commanded magnitudes, or one sign only, confound the
second fit's (``gyro_bias_up_k``, ``gyro_asymmetry_k``, ``gyro_E2_k``; ``gyro_M_kk`` then
comes from the line, as the result does). The magnitudes are the commanded ones: the analysis
counts those of x_j, which the vertical Earth rate splits (|ω + Ω_U| ≠ |−ω + Ω_U|), so it may
fit (RT-7) to two commanded magnitudes, its terms then separated by Ω_U alone (σ ~ 10⁴ times
larger).

Contents
--------
:func:`predict_rate_transfer`, :func:`parameter_names`
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from imucalib.errors import ConfigurationError
from imucalib.estimation.crlb import compute_crlb
from imucalib.estimation.noise_covariance import compute_window_mean_covariance
from imucalib.estimation.observability import compute_observability
from imucalib.models.noise import NoiseModel
from imucalib.plan.budget import MIN_SETTLE_PHASE_S, estimate_plan_recording
from imucalib.plan.schema import Plan, RateStep
from imucalib.procedures.common.prediction import PredictedParameter, Prediction, PredictionGroup
from imucalib.procedures.common.reference import site_vectors
from imucalib.procedures.rate_transfer.design import station_time_s
from imucalib.procedures.rate_transfer.roles import RATE_TRANSFER_RATE

__all__ = ["parameter_names", "predict_rate_transfer"]

_F64 = NDArray[np.float64]
_INDEX = {"x": 0, "y": 1, "z": 2}
#: Site of a plan without a twin. [°]
DEFAULT_LATITUDE_DEG = 45.0


def parameter_names(axis: str) -> tuple[tuple[str, str], ...]:
    """Return (name, unit) of one axis' rows, in the result's order (``parameter_rows``)."""
    k = axis
    return ((f"gyro_scale_factor_{k}", "1"), (f"gyro_bias_line_{k}", "rad/s"),
            (f"gyro_nonlinearity_{k}", "1"), (f"gyro_M_{k}{k}", "1"),
            (f"gyro_bias_up_{k}", "rad/s"), (f"gyro_asymmetry_{k}", "1"),
            (f"gyro_E2_{k}", "s/rad"))


@dataclass(frozen=True)
class _Turn:
    axis: str
    rate_rps: float
    start_s: float
    duration_s: float


def _turns(plan: Plan) -> list[_Turn]:
    """Return the plan's turns with their nominal windows (module docstring)."""
    out: list[_Turn] = []
    for i, step in enumerate(plan.steps):
        if not (isinstance(step, RateStep) and step.role == RATE_TRANSFER_RATE):
            continue
        axis = next((t.split("=", 1)[1] for t in step.tags if t.startswith("axis=")), None)
        if axis not in _INDEX:
            raise ConfigurationError(f"step {i} ({plan.step_label(i)}): tag axis={axis!r}; a "
                                     "rate-transfer turn needs axis=x, y or z")
        if step.rate_dps == 0.0:
            raise ConfigurationError(f"step {i} ({plan.step_label(i)}) turns at 0 °/s: a "
                                     "rate-transfer turn needs whole revolutions")
        turn_s = 360.0 / abs(step.rate_dps)
        span = (step.revolutions * turn_s if step.revolutions is not None
                else math.floor(float(step.record_s or 0.0) / turn_s) * turn_s)
        if span <= 0.0:
            raise ConfigurationError(f"step {i} ({plan.step_label(i)}) records less than one "
                                     "revolution")
        before = estimate_plan_recording(
            plan.model_copy(update={"steps": plan.steps[:i]})).duration_s if i else 0.0
        out.append(_Turn(str(axis), math.radians(step.rate_dps),
                         before + max(step.settle_s, MIN_SETTLE_PHASE_S), span))
    if not out:
        raise ConfigurationError(f"plan {plan.name!r} has no rate-transfer turn (role "
                                 f"{RATE_TRANSFER_RATE}): nothing to predict")
    return out


def _gls(a: _F64, cov: _F64) -> tuple[_F64, _F64]:
    """Return P = (AᵀC⁻¹A)⁻¹AᵀC⁻¹ (the analysis's GLS operator) and P·C·Pᵀ (TD.R4)."""
    aw = np.linalg.solve(cov, a)
    p = np.asarray(np.linalg.solve(a.T @ aw, aw.T), dtype=np.float64)
    return p, np.asarray(p @ cov @ p.T, dtype=np.float64)


def _group(name: str, names: tuple[str, ...], a: _F64, cov: _F64,
           confounded: tuple[str, ...]) -> PredictionGroup:
    whitened = a / np.sqrt(np.diag(cov))[:, None]
    report = compute_observability(whitened, names)
    return PredictionGroup(name, len(names), report.rank, report.condition_number, confounded)


def predict_rate_transfer(plan: Plan, noise: NoiseModel | None = None) -> Prediction:
    """Return the predicted σ of every row of a rate-transfer plan's result (module docstring).

    Parameters
    ----------
    plan : Plan
        A rate-transfer plan (:func:`~.plan.generate_rate_transfer_plan` or edited).
    noise : NoiseModel, optional
        The gyro's noise; the plan grade's (:func:`~imucalib.procedures.common.grade.grade_noise`,
        white terms only when its twin says ``noise = "white"``) when omitted.

    Returns
    -------
    Prediction
        σ per parameter, SI, the result's names and units (``parameter_rows``); None for a
        parameter the rates cannot identify, named in the groups' ``confounded``.

    Raises
    ------
    ConfigurationError
        A plan of another procedure, one without turns, or without a grade (and no `noise`).
    """
    from imucalib.procedures.common.grade import grade_noise, plan_grade

    if plan.procedure and plan.procedure != "rate-transfer":
        raise ConfigurationError(f"plan {plan.name!r} is a {plan.procedure} plan, not a "
                                 "rate-transfer plan")
    model = noise if noise is not None else grade_noise(plan)["gyro"]
    lat = plan.twin.site.latitude_deg if plan.twin is not None else DEFAULT_LATITUDE_DEG
    heading = plan.twin.site.heading_deg if plan.twin is not None else 0.0
    earth_up = float(site_vectors(lat, heading, None)[1][2])
    turns = _turns(plan)
    params: list[PredictedParameter] = []
    groups: list[PredictionGroup] = []
    worst_ratio = 1.0
    for axis in sorted({t.axis for t in turns}, key=list(_INDEX).index):
        k = _INDEX[axis]
        mine = [t for t in turns if t.axis == axis]
        rows = parameter_names(axis)
        std: dict[str, float | None] = dict.fromkeys(n for n, _ in rows)
        x = np.array([t.rate_rps + earth_up for t in mine])
        cov = compute_window_mean_covariance(
            model, [t.start_s for t in mine], [t.duration_s for t in mine],
            reference_time_s=0.0)[k]  # the random walk from the run's start, as the analysis
        white = float(np.asarray(model.white_density).ravel()[k]) ** 2 / np.array(
            [t.duration_s for t in mine])
        line_names = tuple(n for n, _ in rows[:2])
        second_names = tuple(n for n, _ in rows[3:])
        a1 = np.column_stack([np.ones_like(x), x])
        if np.unique(np.round(x, 9)).size < 2:
            groups.append(_group(f"gyro {axis} line", line_names, a1, cov,
                                 tuple(n for n, _ in rows)))
            params += [PredictedParameter(n, None, u) for n, u in rows]
            continue
        p1, c1 = _gls(a1, cov)
        crlb = compute_crlb(a1, np.diag(white), param_names=line_names)
        worst_ratio = max(worst_ratio, float(np.max(np.sqrt(np.diag(c1)) / crlb.std)))
        std[line_names[0]] = float(math.sqrt(c1[1, 1]))
        std[line_names[1]] = float(math.sqrt(c1[0, 0]))
        resid = np.eye(x.size) - a1 @ p1  # (RT-6a): the line's residuals r = R·y
        std[rows[2][0]] = float(np.sqrt(np.max(np.diag(resid @ cov @ resid.T)))
                                / np.max(np.abs(x)))
        groups.append(_group(f"gyro {axis} line", line_names, a1, cov, ()))
        a2 = np.column_stack([np.ones_like(x), x, np.abs(x), x * x])
        # magnitudes as commanded: Ω_U splits ±ω into two |x| the analysis would count, yet
        # the terms of (RT-7) stay confounded but for Ω_U (a condition number ~ 10⁵)
        mags = np.unique(np.round(np.abs([t.rate_rps for t in mine]), 9))
        if mags.size < 3 or not (np.any(x > 0) and np.any(x < 0)):
            # (RT-7) not determined: gyro_M_kk from the line, as the result gives it
            std[f"gyro_M_{axis}{axis}"] = std[line_names[0]]
            confounded = tuple(n for n in second_names if n != f"gyro_M_{axis}{axis}")
            groups.append(_group(f"gyro {axis} second fit", second_names, a2, cov, confounded))
        else:
            _, c2 = _gls(a2, cov)
            s2 = np.sqrt(np.diag(c2))
            std[f"gyro_M_{axis}{axis}"] = float(s2[1])
            std[f"gyro_bias_up_{axis}"] = float(s2[0])
            std[f"gyro_asymmetry_{axis}"] = float(2.0 * s2[2])  # (RT-8) at E′ = 1, A = 0
            std[f"gyro_E2_{axis}"] = float(s2[3])
            groups.append(_group(f"gyro {axis} second fit", second_names, a2, cov, ()))
        params += [PredictedParameter(n, std[n], u) for n, u in rows]
    notes = [
        f"noise model ({'given' if noise is not None else 'grade ' + plan_grade(plan)}): N "
        f"{float(np.ravel(model.white_density)[0]):.3g}, B "
        f"{float(np.ravel(model.bias_instability)[0]):.3g}, K "
        f"{float(np.ravel(model.random_walk)[0]):.3g} (axis x, SI); turns' means correlated by "
        "flicker and random walk (Eq. (TD.2))",
        "σ of the analysis's generalized least squares with that covariance, (AᵀC⁻¹A)⁻¹ "
        "(Eq. (TD.R4)), what calibrate reports as std_noise (RT-4c); largest ratio to the "
        f"white-noise bound: {worst_ratio:.3g}",
        "nonlinearity σ: the largest over the turns of σ(residual)/max|x| (RT-6a), an upper "
        "value; reported σ are Birge-scaled on a misfit, not predicted",
    ]
    return Prediction(procedure="rate-transfer",
                      station_time_s=station_time_s(plan),
                      parameters=tuple(params), groups=tuple(groups), notes=tuple(notes))
