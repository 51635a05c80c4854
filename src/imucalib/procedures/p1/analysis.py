"""Procedure P1 end to end: a Recording → calibrated parameters, checks and a decision.

:func:`analyze_p1` runs the chain of P1 (docs/p1.md): observations (:mod:`.observations`), the
fit of the chosen model (:mod:`.fit`), then the verification of
:mod:`imucalib.analysis.verification`:

- residuals of the calibration windows against P1's limits (docs/p1.md, rule 5: 0.002 g,
  0.1 °/s) and a χ² test of their means (rule 5: a too-simple model fails it);
- accuracy at the held-out positions and rates after compensation (rule 7: the IMU
  specification the recording states, :class:`~imucalib.io.context.RecordingContext`; 0.01 g
  and 0.5 °/s by default);
- repeatability over the repetitions (rule 6: CV ≤ 1 % for scale factors, spread within 3σ for
  parameters near zero);
- the Kalman refinement of the same observations (P1 step 4), reported with its largest
  difference from least squares in standard deviations;
- the Cramér–Rao bound of the design with the same observation covariance
  (docs/processing-estimation.md);
- with the plan the recording holds, each parameter's predicted σ (the plan's, with the grade's
  noise and with the noise the analysis fitted) beside the achieved σ, and a note when the
  achieved σ is worse than predicted (:mod:`.achieved`, docs/test-design.md, "Predicted
  against achieved");
- the optional model terms (the accelerometer's K2, the gyro's G) chosen per triad by the data
  (:func:`~imucalib.procedures.p1.fit.choose_triad_terms`, docs/p1.md "Model terms"), each
  choice a note and, with every candidate's χ², ν and criterion, the report's
  ``model_selection``;

and one decision under :data:`~imucalib.analysis.verification.DECISION_RULE`. The calibration
itself (:class:`~imucalib.models.result.CalibrationResult`) is the fit of every repetition's
calibration windows together; each repetition is also fitted alone for the repeatability.

Earth rate: the gyro references include the Earth-rate projection at the recorded latitude and
table heading, so the gyro bias excludes it (stated in the result's notes).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from datetime import UTC, datetime
from pathlib import Path
from types import MappingProxyType
from typing import Any, Final, Literal

import numpy as np

from imucalib import __version__, units
from imucalib.analysis.verification import (
    check_accuracy,
    check_repeatability,
    check_residuals,
    check_specification,
    decide,
    decision_rule_text,
)
from imucalib.errors import ConfigurationError, InvalidInputError
from imucalib.estimation import compute_crlb, refine_with_kalman
from imucalib.estimation.term_selection import CRITERIA, parse_terms
from imucalib.io.hashing import file_sha256
from imucalib.io.opening import open_recording
from imucalib.models.decision import Check, Decision
from imucalib.models.fit_quality import FitQuality, assess_fit
from imucalib.models.procedure_result import ResultDefaults, TriadParameters
from imucalib.models.result import (
    CalibrationResult,
    Provenance,
    ResidualStats,
    triad_parameter_unit,
)
from imucalib.models.triad import correct_triad
from imucalib.plan.schema import AcceptanceConfig, EquipmentConfig, ImuSpecConfig, Plan
from imucalib.procedures.common.spec_decision import spec_field
from imucalib.procedures.p1.achieved import PredictionCheck, compare_with_prediction
from imucalib.procedures.p1.fit import (
    TERMS,
    P1Fit,
    TriadFit,
    _stack_covariance,
    fit_p1,
    gyro_windows,
    observation_covariance,
    predict_outputs,
)
from imucalib.procedures.p1.observations import (
    P1Observations,
    P1Processing,
    WindowObservation,
    extract_p1_observations,
)

__all__ = ["P1Analysis", "P1Options", "analyze_p1", "analyze_p1_observations"]


@dataclass(frozen=True)
class P1Options:
    """How to analyse a P1 recording.

    Attributes
    ----------
    model : {"triad", "per-axis"}
        The full triad model or the procedure's per-axis model (docs/p1.md).
    g_sensitivity : bool or None
        Triad model: estimate the gyro g-sensitivity G (True: always, the behaviour before the
        data chose; False: never) or let the data choose (None, the default; docs/p1.md,
        "Model terms"). ``terms`` overrides it.
    terms : str
        Terms forced in or out, ``"+k2,-g"`` (of :data:`~imucalib.procedures.p1.fit.TERMS`:
        the accelerometer's K2, the gyro's G); the others are chosen by the data.
    term_criterion : {"lrt", "aicc", "bic"}
        How the data choose (:func:`~imucalib.estimation.term_selection.choose_terms`): the
        likelihood-ratio test at `term_level` by default, as the field calibration's
        (docs/p1.md, "Model terms", says why).
    term_level : float
        The likelihood-ratio test's level α, in (0, 1).
    processing : P1Processing
        Outliers, low-pass, synchronisation, gravity.
    correlated : bool
        Weight with the full covariance of the window means (recommended).
    residual_accel_g, residual_gyro_dps : float
        Residual limits of P1 rule 5 (docs/p1.md, verification).
    significance : float
        p-value of the χ² test below which the model is too simple.
    accel_accuracy_g, gyro_accuracy_dps : float or None
        Held-out limits; None: the recording's IMU specification (its context,
        :class:`~imucalib.io.context.RecordingContext`: the plan's ``[imu]`` as the run wrote
        it), or without one the defaults of :class:`~imucalib.plan.schema.ImuSpecConfig`
        (0.01 g, 0.5 °/s).
    repeatability_cv : float
        CV limit of scale factors (P1 rule 6: 1 %; docs/p1.md).
    repeatability_k : float
        Spread limit of other parameters, in their typical standard uncertainty.
    hash_recording : bool
        Put the recording's SHA-256 into the provenance (reads the whole file once).
    type_b : bool
        Add the equipment accuracy (table position accuracy and axis perpendicularity, uniform
        distributions) to the misalignment variances (GUM Type B).
    table_position_accuracy_arcsec, table_orthogonality_arcsec : float or None
        The equipment accuracy for `type_b`; None: the recording's (its context: the plan's
        ``[equipment]``, or an import's step file), or without one the defaults of
        :class:`~imucalib.plan.schema.EquipmentConfig` (10″, 5″). [″]
    acceptance : {"simple", "guarded"} or None
        The decision rule; None: the recording's (its context: the plan's ``[acceptance]``),
        simple without one.
    guard_band_k : float or None
        k of a guarded rule; None: the recording's, else 2.
    workers : int
        Processes the windows are reduced in (1: this one); the result is the same bit for bit
        (:func:`~imucalib.procedures.p1.observations.extract_p1_observations`).
    """

    model: Literal["triad", "per-axis"] = "triad"
    g_sensitivity: bool | None = None
    terms: str = ""
    term_criterion: Literal["lrt", "aicc", "bic"] = "lrt"
    term_level: float = 0.05
    processing: P1Processing = field(default_factory=P1Processing)
    correlated: bool = True
    residual_accel_g: float = 0.002
    residual_gyro_dps: float = 0.1
    significance: float = 1e-3
    accel_accuracy_g: float | None = None
    gyro_accuracy_dps: float | None = None
    repeatability_cv: float = 0.01
    repeatability_k: float = 3.0
    hash_recording: bool = True
    type_b: bool = True
    table_position_accuracy_arcsec: float | None = None
    table_orthogonality_arcsec: float | None = None
    acceptance: Literal["simple", "guarded"] | None = None
    guard_band_k: float | None = None
    workers: int = 1

    def __post_init__(self) -> None:
        if self.term_criterion not in CRITERIA:
            raise InvalidInputError(f"`term_criterion` must be one of {', '.join(CRITERIA)}; "
                                    f"got {self.term_criterion!r}")
        if not (isinstance(self.term_level, int | float)
                and 0.0 < float(self.term_level) < 1.0):
            raise InvalidInputError(f"`term_level` must be in (0, 1); got {self.term_level!r}")
        parse_terms(self.terms, TERMS)

    def forced_terms(self) -> dict[str, bool]:
        """Terms forced in (True) or out (False): `g_sensitivity` when given, then `terms`."""
        forced = {} if self.g_sensitivity is None else {"g": bool(self.g_sensitivity)}
        forced.update(parse_terms(self.terms, TERMS))
        return forced


@dataclass(frozen=True, eq=False)
class P1Analysis(ResultDefaults):
    """Everything a P1 analysis produced.

    A :class:`~imucalib.models.procedure_result.ProcedureResult` (docs/procedures.md, "The
    result contract"): ``calibration`` is the fit of every repetition (:attr:`result`), whose
    parameters are the :meth:`~imucalib.models.procedure_result.ResultDefaults.parameter_rows`
    (σ Birge-scaled per triad whose fit is a misfit, docs/processing-estimation.md Eq. (3)) and
    whose covariance as reported the :meth:`triad_parameters`; ``model_selection`` each
    triad's choice of optional terms with every candidate's χ², ν, χ²/ν and criterion
    (:meth:`~imucalib.estimation.term_selection.TermChoice.to_dict`; docs/p1.md, "Model
    terms"; empty for the per-axis model); ``prediction`` the plan's predicted σ beside the
    achieved σ (:class:`~imucalib.procedures.p1.achieved.PredictionCheck`; None without the
    plan, which the notes then say); ``decision`` is the one of
    :data:`~imucalib.analysis.verification.DECISION_RULE` over :attr:`checks` (docs/p1.md,
    rules 5–7); ``passed`` is its verdict.
    """

    result: CalibrationResult
    per_repetition: dict[int, CalibrationResult]
    checks: tuple[Check, ...]
    decision: Decision
    kalman_max_difference_sigma: float
    crlb_ratio: dict[str, float]
    observations: P1Observations
    model_selection: tuple[dict[str, Any], ...] = ()
    prediction: PredictionCheck | None = None

    @property
    def procedure(self) -> str:
        """``"p1"``."""
        return "p1"

    @property
    def unit(self) -> str:
        """The calibrated IMU."""
        return self.result.sensor_id

    @property
    def calibration(self) -> CalibrationResult:
        """The calibration: the fit of every repetition's calibration windows (:attr:`result`)."""
        return self.result

    @property
    def notes(self) -> tuple[str, ...]:
        """The calibration's notes (Earth rate, gravity, weights, Type B, a misfit)."""
        return tuple(self.result.notes)

    @property
    def fit_quality(self) -> tuple[FitQuality, ...]:
        """Each triad fit's χ²/ν and misfit verdict (the calibration's)."""
        return tuple(self.result.fit_quality)

    def triad_parameters(self) -> TriadParameters:
        """Return the calibration's parameters with their covariance as reported (Birge-scaled)."""
        cal = self.result
        return list(cal.param_names), cal.values.copy(), cal.covariance_scaled.copy()

    def to_dict(self) -> dict[str, Any]:
        """Return a JSON-able report: the result, the checks and the decision."""
        return {
            "result": self.result.to_dict(),
            "per_repetition": {str(k): v.to_dict() for k, v in self.per_repetition.items()},
            "checks": [{"name": c.name, "passed": c.passed, "summary": c.summary,
                        "rows": [r.__dict__ for r in c.rows]} for c in self.checks],
            "decision": {"passed": self.decision.passed, "rule": self.decision.rule,
                         "failed": list(self.decision.failed),
                         "notes": list(self.decision.notes),
                         "not_assessed": list(self.decision.not_assessed),
                         "summary": self.decision.summary()},
            "kalman_max_difference_sigma": self.kalman_max_difference_sigma,
            "crlb_ratio": self.crlb_ratio,
            "fit_quality": [{"group": q.group, "chi2": q.chi2, "dof": q.dof,
                             "reduced_chi2": q.reduced_chi2, "expected_low": q.expected_low,
                             "expected_high": q.expected_high, "misfit": q.misfit,
                             "birge_ratio": q.birge_ratio, "summary": q.summary()}
                            for q in self.result.fit_quality],
            "std_scaled": self.result.std(scaled=True),
            "model_selection": list(self.model_selection),
            "prediction": None if self.prediction is None else self.prediction.to_dict(),
        }


def _residual_groups(fit: P1Fit, windows: list[WindowObservation], triad: str
                     ) -> list[tuple[str, np.ndarray, np.ndarray]]:
    out = []
    for w in windows:
        gyro, accel = predict_outputs(fit, w)
        if triad == "accel":
            out.append((w.label, w.accel_mean_mps2 - accel, w.accel_std_mps2))
        else:
            out.append((w.label, w.gyro_mean_rps - gyro, w.gyro_std_rps))
    return out


def _chi2(groups: list[tuple[str, np.ndarray, np.ndarray]], se: list[np.ndarray],
          obs_cov: np.ndarray | None, n_params: int) -> tuple[float, int]:
    """χ² = rᵀC⁻¹r of every residual mean (all axes, all windows), and its degrees of freedom.

    Every axis counts, also those a per-axis model ignores (cross-axis outputs), so a model
    without cross-coupling fails it when the sensor has some.
    """
    r = np.concatenate([g[1] for g in groups])
    cov = _stack_covariance(obs_cov) if obs_cov is not None else np.diag(
        np.concatenate(se) ** 2)
    chi2 = float(r @ np.linalg.solve(cov, r))
    return chi2, max(r.size - n_params, 0)


def _result(fit: P1Fit, obs: P1Observations, opt: P1Options, provenance: Provenance,
            residuals: dict[str, ResidualStats], extra_notes: list[str],
            fit_quality: tuple[FitQuality, ...] = ()) -> CalibrationResult:
    notes = [
        f"gyro bias excludes Earth rate: its projection at latitude {obs.latitude_deg:g}° and "
        f"table heading {obs.heading_deg:g}° (15.041 °/h) was subtracted",
        f"reference specific force with g = {obs.gravity_mps2:.6f} m/s^2"
        + (" (normal gravity at the site)" if opt.processing.gravity_mps2 is None else ""),
        f"model: {fit.model}; weights: "
        + ("full covariance of the window means (noise model from the static record)"
           if opt.correlated and obs.noise else "standard error of each window mean"),
        *obs.notes, *extra_notes,
    ]
    cov = fit.covariance
    if opt.type_b:
        cov, text = _add_type_b(fit.param_names, cov, obs, opt)
        notes.append(text)
    return CalibrationResult(
        sensor_id=obs.sensor_id, procedure="p1", model=fit.model,
        param_names=fit.param_names, values=fit.estimate, covariance=cov,
        units={n: triad_parameter_unit(n) for n in fit.param_names}, residuals=residuals,
        provenance=provenance, notes=tuple(notes), fit_quality=fit_quality)


def _equipment(obs: P1Observations, opt: P1Options) -> tuple[float, float, str]:
    """Return the table position accuracy and perpendicularity [″], and where they come from."""
    eq = obs.equipment or EquipmentConfig()
    pos, perp = opt.table_position_accuracy_arcsec, opt.table_orthogonality_arcsec
    source = ("P1Options" if pos is not None and perp is not None
              else "the plan's [equipment]" if obs.context.has_plan
              else "the recording's equipment_json" if obs.equipment is not None
              else "defaults: the recording holds no plan")
    return (eq.table_position_accuracy_arcsec if pos is None else pos,
            eq.table_orthogonality_arcsec if perp is None else perp, source)


def _imu_spec(obs: P1Observations) -> ImuSpecConfig:
    """Return the IMU specification the recording states, or the defaults."""
    return obs.imu_spec or ImuSpecConfig()


def _acceptance(obs: P1Observations, opt: P1Options) -> tuple[str, float]:
    """Return the decision rule and guard-band k: the options', else the recording's."""
    stated = obs.acceptance or AcceptanceConfig()
    return (opt.acceptance or stated.rule,
            opt.guard_band_k if opt.guard_band_k is not None else stated.guard_band_k)


#: Terms held in by rule, not chosen by the data (docs/p1.md, "Model terms"): the gyro's G,
#: always — P1's plan is made to determine it, a specification that limits it needs its estimate
#: (a tactical unit's 1 °/h/g is near what the windows resolve, so the data would often leave it
#: out and the limit go unchecked), and a rule that depended on the plan's limits would give a
#: recording analysed without its plan (a CSV with a step file, a v1 file) another model.
RULED_TERMS: Final = MappingProxyType({"g": True})
#: Why the gyro's G is in the model by rule (:data:`RULED_TERMS`), said after the choice's note.
_G_RULE_NOTE = (" — G by rule: P1's rate points and statics are planned to determine it, the "
                "specification's check needs its estimate, and a recording calibrates to the "
                "same model with or without its plan (terms=-g forces it out)")


def _specification_rows(result: CalibrationResult, obs: P1Observations, spec: ImuSpecConfig
                        ) -> list[tuple[str, float, float, float | None, str]]:
    """Each specified quantity in its display unit: (label, value, u, limit, unit)."""
    lim = spec.limits
    std = result.std(scaled=True)  # honest under misfit (docs/processing-estimation.md)
    rows: list[tuple[str, float, float, float | None, str]] = []
    for name in result.param_names:
        spec_of = spec_field(name)  # the limit that bounds it (procedures/common/spec_decision)
        if spec_of is None:
            continue
        unit, scale, field_name = spec_of
        value = result.value(name) - (1.0 if name.split("_")[1] == "K" else 0.0)
        rows.append((name, value / scale, std[name] / scale, getattr(lim, field_name), unit))
    for triad, field_name, scale, unit in (
            ("gyro", "gyro_arw_deg_rth", units.DEG_PER_RTH, "°/√h"),
            ("accel", "accel_vrw_ug_rthz", units.UG_PER_RTHZ, "µg/√Hz")):
        model = obs.noise.get(triad)
        if model is not None:
            for axis, n in zip("xyz", np.asarray(model.white_density), strict=True):
                rows.append((f"{triad}_white_noise_{axis}", float(n) / scale, 0.0,
                             getattr(lim, field_name), unit))
    return rows


def _add_type_b(names: tuple[str, ...], cov: np.ndarray, obs: P1Observations,
                opt: P1Options) -> tuple[np.ndarray, str]:
    """Add the equipment's Type B variances to the misalignments (uniform, u = a/√3)."""
    pos_arcsec, perp_arcsec, source = _equipment(obs, opt)
    u_pos = pos_arcsec * units.ARCSEC / math.sqrt(3.0)
    u_perp = perp_arcsec * units.ARCSEC / math.sqrt(3.0)
    out = cov.copy()
    for i, name in enumerate(names):
        parts = name.split("_")
        if len(parts) == 3 and parts[1] == "M" and parts[2][0] != parts[2][1]:
            out[i, i] += (u_pos if parts[0] == "accel" else u_perp) ** 2
    text = (f"Type B (GUM): table position accuracy {pos_arcsec:g}″ and "
            f"axis perpendicularity {perp_arcsec:g}″ (uniform) added to the "
            "accelerometer and gyro misalignment variances")
    if not obs.context.has_plan or source == "P1Options":
        text += f" ({source})"
    return out, text


def _kalman_difference(tf: TriadFit, obs_cov: np.ndarray | None) -> float:
    """Largest |x_KF − x_LSQ|/σ_LSQ of the sequential refinement (triad model)."""
    if tf.H.size == 0:
        return math.nan
    n = tf.H.shape[0] // 3
    if obs_cov is not None:
        full = _stack_covariance(obs_cov)
        blocks_r = [full]
        blocks_h, blocks_z = [tf.H], [tf.z]
    else:
        blocks_h = [tf.H[3 * k:3 * k + 3] for k in range(n)]
        blocks_z = [tf.z[3 * k:3 * k + 3] for k in range(n)]
        blocks_r = [np.diag(tf.sigma[3 * k:3 * k + 3] ** 2) for k in range(n)]
    kf = refine_with_kalman(blocks_h, blocks_z, blocks_r, param_names=tf.param_names)
    sd = np.sqrt(np.diag(tf.covariance))
    return float(np.max(np.abs(kf.estimate - tf.estimate) / sd))


def _crlb_ratio(tf: TriadFit, obs_cov: np.ndarray | None) -> float:
    """Largest reported σ over the Cramér–Rao σ of the same design (1 for an efficient fit)."""
    if tf.H.size == 0:
        return math.nan
    cov = _stack_covariance(obs_cov) if obs_cov is not None else np.diag(tf.sigma**2)
    bound = compute_crlb(tf.H, cov, param_names=tf.param_names)
    return float(np.max(np.sqrt(np.diag(tf.covariance)) / bound.std))


def _held_out(result: CalibrationResult, obs: P1Observations
              ) -> tuple[list[tuple[str, np.ndarray]], list[tuple[str, np.ndarray]]]:
    accel_model = result.triad_model("accel")
    gyro_model = result.triad_model("gyro")
    accel_err, gyro_err = [], []
    for w in obs.select(role="verification"):
        zeros = np.zeros(3)
        f_hat = correct_triad(accel_model, w.accel_mean_mps2, rate_b_rps=zeros,
                              angular_accel_b_rps2=zeros)
        if w.kind == "static":
            accel_err.append((w.label, f_hat - w.force_b_mps2))
        else:
            w_hat = correct_triad(gyro_model, w.gyro_mean_rps, specific_force_b_mps2=f_hat)
            gyro_err.append((w.label, w_hat - w.rate_b_rps))
    return accel_err, gyro_err


#: The note of a recording without its plan: nothing to compare the achieved σ with.
NO_PREDICTION_NOTE = ("predicted σ not compared: the recording holds no plan to predict it from "
                      "(docs/test-design.md, \"Predicted against achieved\")")


def _prediction(plan: Plan | None, obs: P1Observations, result: CalibrationResult
                ) -> tuple[PredictionCheck | None, list[str]]:
    """Return the plan's predicted σ beside the achieved σ and its notes, (PA.1)–(PA.4).

    No plan, or one the prediction cannot use (no grade, another model's parameters): no
    check, one note saying why. A run worse than predicted: the warning as a note.
    """
    if plan is None:
        return None, [NO_PREDICTION_NOTE]
    try:
        check = compare_with_prediction(plan, obs, result.param_names,
                                        result.std(scaled=True), result.units)
    except ConfigurationError as exc:
        return None, [f"predicted σ not compared: {exc}"]
    warning = check.warning()
    return check, [warning] if warning else []


def analyze_p1_observations(obs: P1Observations, options: P1Options | None = None, *,
                            provenance: Provenance | None = None,
                            plan: Plan | None = None) -> P1Analysis:
    """Fit, verify and decide from extracted observations (see :func:`analyze_p1`).

    `plan`, the plan the recording ran, gives each parameter's predicted σ beside the achieved
    σ (:mod:`.achieved`); without it the notes say there is none.
    """
    opt = options or P1Options()
    forced = opt.forced_terms()
    spec = _imu_spec(obs)
    fit = fit_p1(obs, model=opt.model, g_sensitivity=forced.get("g"), k2=forced.get("k2"),
                 correlated=opt.correlated, criterion=opt.term_criterion,
                 level=opt.term_level, ruled=RULED_TERMS)
    accel_w = fit.accel.windows
    gyro_w = list(fit.gyro.windows)
    accel_groups = _residual_groups(fit, list(accel_w), "accel")
    gyro_groups = _residual_groups(fit, gyro_w, "gyro")
    residuals = {f"accel: {lab}": ResidualStats(tuple(m), tuple(s), 0, "m/s^2")
                 for lab, m, s in accel_groups}
    residuals.update({f"gyro: {lab}": ResidualStats(tuple(m), tuple(s), 0, "rad/s")
                      for lab, m, s in gyro_groups})
    cov_a = observation_covariance(accel_w, obs.noise.get("accel")) if opt.correlated else None
    cov_g = observation_covariance(gyro_w, obs.noise.get("gyro")) if opt.correlated else None
    chi2_a, dof_a = _chi2(accel_groups, [w.accel_se_mps2 for w in accel_w], cov_a,
                          fit.accel.estimate.size)
    chi2_g, dof_g = _chi2(gyro_groups, [w.gyro_se_rps for w in gyro_w], cov_g,
                          fit.gyro.estimate.size)
    checks = [
        check_residuals("accelerometer residuals", accel_groups,
                        mean_limit=opt.residual_accel_g, std_limit=opt.residual_accel_g,
                        unit="g", scale=units.G0_MPS2, chi2=chi2_a, dof=dof_a,
                        significance=opt.significance),
        check_residuals("gyro residuals", gyro_groups, mean_limit=opt.residual_gyro_dps,
                        std_limit=opt.residual_gyro_dps, unit="°/s", scale=units.DEG,
                        chi2=chi2_g, dof=dof_g, significance=opt.significance),
    ]
    kalman = max(_kalman_difference(fit.accel, cov_a), _kalman_difference(fit.gyro, cov_g)) \
        if fit.model == "triad" else math.nan
    crlb = ({"accel": _crlb_ratio(fit.accel, cov_a), "gyro": _crlb_ratio(fit.gyro, cov_g)}
            if fit.model == "triad" else {})
    prov = provenance or Provenance(software_version=__version__,
                                    created_utc=datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ"))
    quality = (assess_fit("accel", chi2_a, dof_a), assess_fit("gyro", chi2_g, dof_g))
    result = _result(fit, obs, opt, prov, residuals,
                     [c.summary() + (_G_RULE_NOTE if c.ruled.get("g") else "")
                      for c in fit.selection]
                     + [q.summary() for q in quality if q.misfit], quality)
    prediction, prediction_notes = _prediction(plan, obs, result)
    if prediction_notes:
        result = replace(result, notes=(*result.notes, *prediction_notes))
    accel_err, gyro_err = _held_out(result, obs)
    checks.append(check_accuracy("held-out accelerometer accuracy", accel_err,
                                 limit=opt.accel_accuracy_g or spec.accel_accuracy_g, unit="g",
                                 scale=units.G0_MPS2))
    checks.append(check_accuracy("held-out gyro accuracy", gyro_err,
                                 limit=opt.gyro_accuracy_dps or spec.gyro_accuracy_dps,
                                 unit="°/s", scale=units.DEG))
    rule, guard_k = _acceptance(obs, opt)
    checks.append(check_specification("specification", _specification_rows(result, obs, spec),
                                      rule=rule, guard_band_k=guard_k))
    per_rep: dict[int, CalibrationResult] = {}
    reps = obs.repetitions
    if len(reps) > 1:
        # each repetition with the terms the whole fit chose: the same parameters to compare
        chosen = {t: any(c.has(t) for c in fit.selection) for t in TERMS}
        for rep in reps:
            rep_fit = fit_p1(obs, model=opt.model, g_sensitivity=chosen["g"],
                             k2=chosen["k2"], repetitions=[rep], correlated=opt.correlated)
            per_rep[rep] = _result(rep_fit, obs, opt, prov, {}, [f"repetition {rep} alone"])
    names = result.param_names
    estimates = {n: [r.value(n) for r in per_rep.values()] for n in names}
    sigmas = {n: [r.sigma(n) for r in per_rep.values()] for n in names}
    scale_names = [n for n in names if "_K_" in n]
    if fit.model == "triad":  # 1 + M_ii is the scale factor: judge M_ii by its spread in CV
        scale_names = [n for n in names if n.split("_")[1] == "M" and n[-1] == n[-2]]
        estimates = {n: [v + 1.0 for v in vals] if n in scale_names else vals
                     for n, vals in estimates.items()}
    if per_rep:
        checks.append(check_repeatability(
            "repeatability", estimates, sigmas, result.units, scale_names=scale_names,
            cv_limit=opt.repeatability_cv, spread_k=opt.repeatability_k))
    else:
        checks.append(Check("repeatability", None, f"{len(reps)} repetition in the recording: "
                            "repeatability needs at least 2 (P1 rule 6 asks for 3, docs/p1.md)"))
    return P1Analysis(result=result, per_repetition=per_rep, checks=tuple(checks),
                      decision=decide(checks, notes=[q.summary() for q in quality
                                                     if q.misfit],
                                      rule=decision_rule_text(rule, guard_k)),
                      kalman_max_difference_sigma=kalman,
                      crlb_ratio=crlb, observations=obs,
                      model_selection=tuple(c.to_dict() for c in fit.selection),
                      prediction=prediction)


def analyze_p1(path: str | Path, sensor_id: str | None = None,
               options: P1Options | None = None, *,
               progress: Callable[[float], None] | None = None) -> P1Analysis:
    """Analyse a P1 Recording: observations, fit, verification and decision.

    Parameters
    ----------
    path : str or Path
        The Recording of a P1 plan run (``imucalib run``).
    sensor_id : str, optional
        The IMU (the only one when omitted).
    options : P1Options, optional
    progress : callable, optional
        Called with the fraction of the steps reduced to observations (the long part; see
        :func:`~imucalib.procedures.p1.observations.extract_p1_observations`).

    Raises
    ------
    RecordingError
        Missing plan, streams, latitude or data (the message names what is missing).
    InsufficientExcitationError
        A design that cannot determine some parameters (a missing position, no rate about an
        axis), naming them.
    """
    opt = options or P1Options()
    p = Path(path)
    with open_recording(p) as rec:
        obs = extract_p1_observations(rec, sensor_id, processing=opt.processing,
                                      progress=progress, workers=opt.workers)
        plan = _stored_plan(rec.metadata)
    gyro_w = gyro_windows(obs, "calibration", None)
    spec = _imu_spec(obs)
    rule, guard_k = _acceptance(obs, opt)
    prov = Provenance(
        plan_hash=obs.context.plan_hash,
        recording_sha256=file_sha256(p) if opt.hash_recording else "",
        recording=str(p.name), software_version=__version__,
        created_utc=datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
        details={"repetitions": list(obs.repetitions), "n_windows": len(obs.windows),
                 "n_gyro_windows": len(gyro_w), "cutoff_hz": obs.cutoff_hz,
                 "max_alignment_error_s": max(w.alignment_error_s for w in obs.windows),
                 "outliers_removed": int(sum(w.n_outliers for w in obs.windows)),
                 "outliers": [{"step_index": w.step_index,
                               "per_channel": list(w.outliers_per_channel),
                               "first_times_s": list(w.outlier_times_s)}
                              for w in obs.windows if w.n_outliers],
                 "processing": json.loads(json.dumps(opt.processing.__dict__)),
                 "skipped_steps": list(obs.skipped),
                 "unit": {"serial": spec.serial or obs.sensor_id, "model": spec.model,
                          "maker": spec.maker, "grade": spec.grade},
                 "specification": {**spec.limits.model_dump(exclude_none=True),
                                   "accel_accuracy_g": spec.accel_accuracy_g,
                                   "gyro_accuracy_dps": spec.gyro_accuracy_dps},
                 "acceptance": {"rule": rule, "guard_band_k": guard_k}})
    return analyze_p1_observations(obs, opt, provenance=prov, plan=plan)


def _stored_plan(metadata: Any) -> Plan | None:
    """Return the plan a recording stores (``plan_toml``), or None without a valid one."""
    from imucalib.plan import parse_plan

    text = metadata.get("plan_toml")
    if not text:
        return None
    try:
        return parse_plan(str(text))
    except ConfigurationError:
        return None
