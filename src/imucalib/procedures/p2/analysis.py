"""P2's analysis of one unit: points, temperature models, the result at T0, the decision.

:func:`analyze_unit` turns one unit's windows (:mod:`~imucalib.procedures.p2.observations`)
into

1. per temperature point, the parameters by the full least squares and by the patent's closed
   form (:mod:`~imucalib.procedures.p2.reduction`), which must agree (the largest difference
   in σ of the least-squares estimate is reported; above ``AGREEMENT_LIMIT`` the unit
   fails), and the naive closed form that ignores the lever arm, whose difference shows the
   error a lever-arm-blind analysis would make;
2. the covariance Θ of every calibration point's estimates with every other's (docs/p2.md,
   Eq. (P2.13)): each point's least-squares gain carries the covariance of the window means
   into them, under the unit's coloured noise (:attr:`~imucalib.procedures.p2.observations.
   UnitObservations.noise`: white, flicker, random walk; Eq. (TD.2) of docs/test-design.md
   between every pair of windows of the sweep, :mod:`~imucalib.procedures.p2.covariance`),
   each point's block scaled by the Birge ratio of its fit judged under that covariance
   (Eq. (P2.14)); without a noise model, the windows as independent;
3. per parameter, a temperature model (:func:`~imucalib.estimation.fit_temperature_model`:
   polynomial in T − T0 of the order AICc or cross-validation picks, at most
   :attr:`P2Options.max_order`; a hysteresis term when both legs were run; a dT/dt term on
   request): the weighted least squares of the calibration points with their own σ
   (Birge-scaled where a point's fit is a misfit), its covariance the sandwich under Θ and its
   χ² the GLS χ² under Θ (Eqs. (2b)–(3b) there), which choose the order and flag a misfit
   (Birge scaling); checked at the held-out points;
4. the CalibrationResult: every parameter at T0 (the models' c_0) with the joint covariance of
   those c_0 across parameters (each model's weights applied to Θ, docs/p2.md Eq. (P2.12)),
   the per-point fit quality, and the temperature models;
5. the unit's result (:class:`~imucalib.procedures.p2.result.P2UnitResult`, with its decision
   under :data:`~imucalib.procedures.p2.result.DECISION_RULE`: docs/p2.md, "The decision").

The unit's result is a :class:`~imucalib.models.procedure_result.ProcedureResult`
(docs/procedures.md, "The result contract"): its parameters are the calibration's at T0 with
the σ of Eq. (P2.12) and, beside them, the same σ before any Birge scaling (its
``std_noise``: Eq. (P2.12) with s = 1 and the noise-only Θ).

Contents
--------
:class:`P2Options`, :func:`analyze_unit`, :func:`assemble_point`, :func:`failed_unit`; the
result types are :mod:`~imucalib.procedures.p2.result`'s.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from imucalib import __version__
from imucalib import units as u
from imucalib.errors import CalibrationError, InvalidInputError, MissingSegmentError
from imucalib.estimation.temperature_forms import to_parameter_record
from imucalib.estimation.temperature_model import (
    DEFAULT_MAX_ORDER,
    HeldOutCheck,
    TemperatureModelFit,
    check_held_out,
    fit_temperature_model,
    gls_weights,
    predict_temperature_model,
)
from imucalib.models.fit_quality import FitQuality, assess_fit
from imucalib.models.result import CalibrationResult, Provenance, triad_parameter_unit
from imucalib.procedures.p2.covariance import (
    N_CHANNELS,
    independent_covariance,
    means_operator,
    propagate,
    window_covariance,
)
from imucalib.procedures.p2.observations import (
    P2Processing,
    P2Window,
    UnitObservations,
    detect_orientations,
    where,
)
from imucalib.procedures.p2.reduction import (
    LEVER_ARM_MODES,
    ORIENTATIONS,
    PARAM_NAMES,
    LeverArmMode,
    PointEstimate,
    PointWindows,
    closed_form,
    least_squares,
)
from imucalib.procedures.p2.result import (
    AGREEMENT_LIMIT,
    HELD_OUT_ALPHA,
    HELD_OUT_Z_LIMIT,
    P2UnitResult,
    PointResult,
)

__all__ = ["P2Options", "analyze_unit", "assemble_point", "failed_unit"]

_F64 = NDArray[np.float64]

@dataclass(frozen=True)
class P2Options:
    """Options of P2's analysis (docs/p2.md, "Options").

    Attributes
    ----------
    lever_arm : {"estimate", "cancel", "ignore"}
        How the centripetal term is treated
        (:data:`~imucalib.procedures.p2.reduction.LEVER_ARM_MODES`).
    max_order : int
        The highest polynomial order of a temperature model.
    order : int or None
        A fixed order for every model (None: chosen by `criterion`).
    criterion : {"aicc", "cv"}
        How the order is chosen.
    rate_term : bool
        Add a dT/dt term to every temperature model.
    hysteresis : {"auto", "on", "off"}
        A heating/cooling term: ``auto`` when each leg holds two calibration points or more.
    reference_temperature_degc : float
        T0 of the models and of the result's values. [°C]
    accel_accuracy_g, gyro_accuracy_dps : float or None
        The accuracy the compensated model must keep; None: the stored plan's (else the
        consumer grade's 0.01 g and 0.5 °/s).
    processing : P2Processing
    """

    lever_arm: LeverArmMode = "estimate"
    max_order: int = DEFAULT_MAX_ORDER
    order: int | None = None
    criterion: Literal["aicc", "cv"] = "aicc"
    rate_term: bool = False
    hysteresis: Literal["auto", "on", "off"] = "auto"
    reference_temperature_degc: float = 25.0
    accel_accuracy_g: float | None = None
    gyro_accuracy_dps: float | None = None
    processing: P2Processing = field(default_factory=P2Processing)

    def __post_init__(self) -> None:
        checks = (("lever_arm", self.lever_arm in LEVER_ARM_MODES, f"one of {LEVER_ARM_MODES}"),
                  ("criterion", self.criterion in ("aicc", "cv"), "'aicc' or 'cv'"),
                  ("hysteresis", self.hysteresis in ("auto", "on", "off"),
                   "'auto', 'on' or 'off'"),
                  ("max_order", isinstance(self.max_order, int) and 0 <= self.max_order <= 5,
                   "an integer 0 … 5"),
                  ("order", self.order is None or (isinstance(self.order, int)
                                                   and 0 <= self.order <= 5),
                   "None or an integer 0 … 5"),
                  ("reference_temperature_degc",
                   math.isfinite(float(self.reference_temperature_degc)), "a finite number"))
        for name, ok, want in checks:
            if not ok:
                raise InvalidInputError(f"P2 option {name} (--{name.replace('_', '-')}) must be "
                                        f"{want}; got {getattr(self, name)!r}")


# ---------------------------------------------------------------------------------------------
# one point


def _combine(means: Sequence[_F64], ses: Sequence[_F64]) -> tuple[_F64, _F64]:
    """Return the plain mean of windows and its standard error (independent windows)."""
    m = np.mean(np.array(means), axis=0)
    se = np.sqrt(np.sum(np.array(ses) ** 2, axis=0)) / len(ses)
    return m, se


def _combine_each(groups: Sequence[Sequence[P2Window]], attr: str, se_attr: str
                  ) -> tuple[_F64, _F64]:
    """:func:`_combine` of each orientation's group of windows, shape (6, 3) each.

    Groups of one size (a station's plan: two static windows and one turn each way per
    orientation) are combined in one reduction along the group axis, which numpy sums window
    by window as it does the group alone (tests/procedures/test_p2_pooled_se.py).
    """
    sizes = {len(g) for g in groups}
    if len(sizes) == 1:
        size = sizes.pop()
        means = np.array([[getattr(w, attr) for w in g] for g in groups])      # (6, size, 3)
        ses = np.array([[getattr(w, se_attr) for w in g] for g in groups])
        return np.mean(means, axis=1), np.sqrt(np.sum(ses**2, axis=1)) / size
    each = [_combine([getattr(w, attr) for w in g], [getattr(w, se_attr) for w in g])
            for g in groups]
    return np.array([m for m, _ in each]), np.array([se for _, se in each])


def assemble_point(unit: str, point: int, windows: Sequence[P2Window], gravity_mps2: float,
                   earth_rate_up_rps: float) -> PointWindows:
    """Group one point's windows by orientation into :class:`PointWindows`.

    Raises
    ------
    MissingSegmentError
        An orientation without a static window, or without a turn in either direction; it
        names the unit, the point and the orientation.
    """
    temp = float(np.mean([w.temperature_degc for w in windows])) if windows else math.nan
    by_orientation: dict[str, list[P2Window]] = {o: [] for o in ORIENTATIONS}
    for w in windows:
        if w.orientation in by_orientation:
            by_orientation[w.orientation].append(w)
    statics, pluses, minuses = [], [], []
    for o in ORIENTATIONS:
        mine = by_orientation[o]
        static = [w for w in mine if w.kind == "static"]
        plus = [w for w in mine if w.kind == "rate" and w.table_rate_rps > 0]
        minus = [w for w in mine if w.kind == "rate" and w.table_rate_rps < 0]
        missing = [name for name, got in (("static", static), ("+ω turn", plus),
                                          ("−ω turn", minus)) if not got]
        if missing:
            have = sorted({w.orientation for w in windows if w.orientation})
            raise MissingSegmentError(
                f"{where(unit, point, temp, None)}: orientation {o} up has no "
                f"{' and no '.join(missing)} (orientations seen: {have}); P2 needs every body "
                "axis up and down, each static and turning both ways")
        statics.append(static)
        pluses.append(plus)
        minuses.append(minus)
    s_a, s_ase = _combine_each(statics, "accel_mean_mps2", "accel_se_mps2")
    p_g, p_gse = _combine_each(pluses, "gyro_mean_rps", "gyro_se_rps")
    m_g, m_gse = _combine_each(minuses, "gyro_mean_rps", "gyro_se_rps")
    p_a, p_ase = _combine_each(pluses, "accel_mean_mps2", "accel_se_mps2")
    m_a, m_ase = _combine_each(minuses, "accel_mean_mps2", "accel_se_mps2")
    return PointWindows(
        static_accel_mps2=s_a, static_accel_se_mps2=s_ase,
        plus_gyro_rps=p_g, plus_gyro_se_rps=p_gse, minus_gyro_rps=m_g, minus_gyro_se_rps=m_gse,
        plus_accel_mps2=p_a, plus_accel_se_mps2=p_ase,
        minus_accel_mps2=m_a, minus_accel_se_mps2=m_ase,
        plus_rate_rps=np.array([np.mean([w.table_rate_rps for w in g]) for g in pluses]),
        minus_rate_rps=np.array([np.mean([w.table_rate_rps for w in g]) for g in minuses]),
        gravity_mps2=gravity_mps2, earth_rate_up_rps=earth_rate_up_rps)


def _point(obs: UnitObservations, point: int, windows: Sequence[P2Window],
           lever_arm: LeverArmMode) -> PointResult:
    pw = assemble_point(obs.unit, point, windows, obs.gravity_mps2, obs.earth_rate_up_rps)
    ls = least_squares(pw, lever_arm=lever_arm)
    cf = closed_form(pw, lever_arm=lever_arm)
    naive = closed_form(pw, lever_arm="ignore")
    n = len(PARAM_NAMES) + (3 if lever_arm != "ignore" else 0)
    std = np.sqrt(np.diag(ls.covariance_scaled()))[:n]
    agree = float(np.max(np.abs(cf.values[:n] - ls.values[:n]) / np.where(std > 0, std, np.inf)))
    return PointResult(
        point=point, leg=windows[0].leg, held_out=windows[0].held_out,
        temperature_degc=float(np.mean([w.temperature_degc for w in windows])),
        temperature_rate_degc_ps=float(np.mean([w.temperature_rate_degc_ps for w in windows])),
        least_squares=ls, closed_form=cf, naive=naive, agreement_sigma=agree)


# ---------------------------------------------------------------------------------------------
# temperature models and the result


def _leg_value(leg: str) -> float:
    return 1.0 if leg == "heating" else -1.0


def analyze_unit(obs: UnitObservations, options: P2Options | None = None, *,
                 source: str = "", recording_sha256: str = "") -> P2UnitResult:
    """Analyse one unit's P2 windows (module docstring).

    Raises
    ------
    MissingSegmentError
        A point that cannot be used (its first defect, naming unit, temperature and step), or
        fewer than two calibration points.
    InsufficientExcitationError
        A design that cannot resolve the parameters.
    """
    opt = options or P2Options()
    if obs.failures:
        first = min(obs.failures)
        raise MissingSegmentError(obs.failures[first])
    windows, failures = detect_orientations(obs, opt.processing)
    if failures:
        raise MissingSegmentError(failures[min(failures)])
    by_point: dict[int, list[P2Window]] = {}
    for w in windows:
        by_point.setdefault(w.point, []).append(w)
    points = tuple(_point(obs, k, by_point[k], opt.lever_arm) for k in sorted(by_point))
    cal = [p for p in points if not p.held_out]
    if len(cal) < 2:
        raise MissingSegmentError(f"unit {obs.unit}: {len(cal)} usable calibration temperature "
                                  "point(s); a temperature model needs at least 2")
    per_leg = [sum(p.leg == leg for p in cal) for leg in ("heating", "cooling")]
    use_leg = opt.hysteresis == "on" or (opt.hysteresis == "auto" and min(per_leg) >= 2)
    temps = np.array([p.temperature_degc for p in cal])
    rates = np.array([p.temperature_rate_degc_ps for p in cal])
    legs = np.array([_leg_value(p.leg) for p in cal])
    n_par = len(PARAM_NAMES)
    # the covariance of every point estimate with every other, across the sweep (Eq. (P2.13)),
    # point-major (point k's parameter i at k·n_par + i), noise only and with the points' Birge
    # ratios
    theta_noise, point_scale, coloured = _point_covariance(obs, cal, by_point)
    theta_cov = theta_noise * np.outer(point_scale, point_scale)
    models: dict[str, TemperatureModelFit] = {}
    weights: list[_F64] = []
    scales: list[float] = []
    for i, name in enumerate(PARAM_NAMES):
        values = np.array([p.least_squares.values[i] for p in cal])
        var = np.array([p.least_squares.covariance_scaled()[i, i] for p in cal])
        idx = np.arange(len(cal)) * n_par + i
        fit = fit_temperature_model(
            temps, values, theta_cov[np.ix_(idx, idx)], weights=var, name=name,
            order=opt.order, max_order=opt.max_order, criterion=opt.criterion,
            reference_temperature_degc=opt.reference_temperature_degc,
            temperature_rate_degc_ps=rates if opt.rate_term else None,
            leg=legs if use_leg else None, compute_cv=opt.criterion == "cv")
        models[name] = fit
        weights.append(gls_weights(fit, temps, var, rates if opt.rate_term else None,
                                   legs if use_leg else None)[0])
        scales.append(fit.quality.birge_ratio if fit.quality.misfit else 1.0)
    # joint covariance of the c_0 (Eq. (P2.12)): Cov(c0_i, c0_j) = Σ_kl W_ik W_jl Θ_kl[i, j]
    w_full = np.zeros((n_par, n_par * len(cal)))               # c_0 = w_full·θ
    for i, w_i in enumerate(weights):
        w_full[i, np.arange(len(cal)) * n_par + i] = w_i
    s = np.array(scales)
    cov0 = (w_full @ theta_cov @ w_full.T) * np.outer(s, s)
    # the same σ before any Birge scaling: s = 1 and the noise-only Θ, the same W
    var0_noise = np.einsum("ij,jk,ik->i", w_full, theta_noise, w_full)
    values0 = np.array([models[n].model.coefficients[0] for n in PARAM_NAMES])
    # held-out checks and the compensated error
    held = [p for p in points if p.held_out]
    checks: dict[str, HeldOutCheck] = {}
    if held:
        t_h = np.array([p.temperature_degc for p in held])
        r_h = np.array([p.temperature_rate_degc_ps for p in held])
        l_h = np.array([_leg_value(p.leg) for p in held])
        var_h = [np.diag(p.least_squares.covariance_scaled()).tolist() for p in held]
        for i, name in enumerate(PARAM_NAMES):
            checks[name] = check_held_out(
                models[name], t_h, [p.least_squares.values[i] for p in held],
                [math.sqrt(v[i]) for v in var_h],
                temperature_rate_degc_ps=r_h if opt.rate_term else None,
                leg=l_h if use_leg else None, limit=HELD_OUT_Z_LIMIT, alpha=HELD_OUT_ALPHA)
    judged = held or cal
    errors = _compensated_error(models, judged, obs, opt, use_leg)
    accel_lim, gyro_lim = _limits(opt)
    reasons = []
    if errors["accel_mps2"] > accel_lim * u.G0_MPS2:
        reasons.append(f"accelerometer error after compensation "
                       f"{errors['accel_mps2'] / u.G0_MPS2:.3g} g exceeds {accel_lim:g} g at "
                       f"the {'held-out' if held else 'calibration'} points")
    if errors["gyro_rps"] > gyro_lim * u.DEG:
        reasons.append(f"gyro error after compensation {errors['gyro_rps'] / u.DEG:.3g} °/s "
                       f"exceeds {gyro_lim:g} °/s at the {'held-out' if held else 'calibration'} "
                       "points")
    t_range = (float(temps.min()), float(temps.max()))
    worst = max(points, key=lambda p: p.agreement_sigma)
    if worst.agreement_sigma > AGREEMENT_LIMIT:
        reasons.append(f"closed form and least squares differ by {worst.agreement_sigma:.2g} σ "
                       f"at point {worst.point} ({worst.temperature_degc:+.1f} °C)")
    notes = [
        f"{len(cal)} calibration and {len(held)} held-out temperature point(s); lever arm "
        f"{opt.lever_arm}; temperature models chosen by {opt.criterion.upper()} up to order "
        f"{opt.max_order}" + ("; heating/cooling hysteresis term" if use_leg else ""),
        "static gyro means are not used (their horizontal Earth-rate projection depends on the "
        "unit's heading on the fixture); gyro parameters come from the ±ω turns",
        ("the σ carry the covariance of the window means across the sweep (the unit's white, "
         "flicker and random-walk noise, Eq. (TD.2)) through the point fits into the "
         "temperature models (Eqs. (P2.12)–(P2.13), docs/p2.md)") if coloured else
        ("no noise model of the unit (no window with an Allan fit): the σ treat the windows "
         "as independent, each with its standard error; a bias wandering over the sweep "
         "(flicker, random walk) is not in them"),
        *(n for n in obs.notes if n.startswith("noise model")),
    ]
    misfits = [n for n, m in models.items() if m.quality.misfit]
    if misfits:
        orders = sorted({models[n].order for n in misfits})
        notes.append(
            f"the temperature models of {len(misfits)} parameter(s) do not fit their points "
            f"within the noise ({', '.join(misfits[:6])}{', …' if len(misfits) > 6 else ''}; "
            f"order {'/'.join(map(str, orders))}): their σ are Birge-scaled by √(χ²/ν); "
            + (f"with {len(cal)} calibration points AICc (Eq. (6)) allows no higher order: add "
               "temperature points" if len(cal) <= 3 and opt.criterion == "aicc" and
               opt.order is None else "add temperature points or raise --max-order"))
    inconsistent = [n for n, c in checks.items() if not c.consistent]
    if inconsistent:
        notes.append(f"held-out check: the models of {', '.join(inconsistent)} do not predict "
                     "the held-out points within their uncertainty")
    # no fit_quality in the result: its covariance already holds the Birge ratios of misfit
    # point fits and models (Eq. (P2.12)); a fit quality would scale the σ a second time
    # (CalibrationResult.std(scaled=True)). Each point's χ²/ν is in the unit's report.
    result = CalibrationResult(
        sensor_id=obs.unit, procedure="p2", model="triad", param_names=PARAM_NAMES,
        values=values0, covariance=0.5 * (cov0 + cov0.T),
        units={n: triad_parameter_unit(n) for n in PARAM_NAMES},
        provenance=Provenance(recording=Path(source).name if source else "",
                              recording_sha256=recording_sha256, software_version=__version__,
                              created_utc=datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
                              details={"reference_temperature_degc":
                                       opt.reference_temperature_degc,
                                       "lever_arm_m": _mean_lever_arm(cal)}),
        notes=(f"parameters at T0 = {opt.reference_temperature_degc:g} °C, the c_0 of each "
               "temperature model; `imucalib apply` corrects each sample at the unit's "
               "internal temperature with the models (docs/p2.md)",
               "the covariance holds the Birge ratios of misfit point fits and temperature "
               "models already (Eq. (P2.12))"),
        temperature_models=tuple(
            to_parameter_record(models[n], temperature_range_degc=t_range,
                                held_out=checks.get(n)) for n in PARAM_NAMES),
    )
    return P2UnitResult(unit=obs.unit, passed=not reasons, points=points, models=models,
                        held_out=checks, result=result, compensated_error=errors,
                        error_limits={"accel_mps2": accel_lim * u.G0_MPS2,
                                      "gyro_rps": gyro_lim * u.DEG},
                        reasons=tuple(reasons), notes=tuple(notes),
                        std_noise={n: float(np.sqrt(v)) for n, v in zip(PARAM_NAMES, var0_noise,
                                                                         strict=True)})


def _point_scales(qualities: Sequence[FitQuality]) -> _F64:
    """Each parameter's Birge ratio in its point's fit (1 for a good fit), shape (36,)."""
    out = np.ones(len(PARAM_NAMES))
    for q in qualities:
        if q.misfit:
            out[[i for i, n in enumerate(PARAM_NAMES) if n.startswith(q.group + "_")]] = \
                q.birge_ratio
    return out


#: Each triad's parameters in a point's estimate (the lever arm with the accelerometer).
_TRIAD_PARAMS = {"gyro": np.arange(0, 21), "accel": np.arange(21, 39)}


def _coloured_quality(est: PointEstimate, rows_cov: _F64) -> tuple[FitQuality, ...]:
    """χ²/ν of each triad's point fit under the covariance of its means (Eq. (P2.14)).

    χ² = rᵀ·M·r, M = C⁻¹ − C⁻¹H(HᵀC⁻¹H)⁻¹HᵀC⁻¹ (the GLS χ², whatever weights the fit used:
    Eq. (3b) of :mod:`~imucalib.estimation.temperature_model`) with r the fit's residuals, H
    its design at the solution and C the 90 combined means' covariance; ν = rows − parameters.
    """
    assert est.jacobian is not None and est.residuals is not None
    out = []
    for group, params in _TRIAD_PARAMS.items():
        h_all = est.jacobian[:, params]
        rows = np.flatnonzero(np.any(h_all != 0.0, axis=1))
        cols = np.flatnonzero(np.any(h_all[rows] != 0.0, axis=0))
        h = h_all[np.ix_(rows, cols)]
        chol = np.linalg.cholesky(rows_cov[np.ix_(rows, rows)])
        hw = np.linalg.solve(chol, h)
        rw = np.linalg.solve(chol, est.residuals[rows])
        q, _ = np.linalg.qr(hw)
        chi2 = float(rw @ rw - np.sum((q.T @ rw) ** 2))
        out.append(assess_fit(group, chi2, rows.size - cols.size))
    return tuple(out)


def _point_covariance(obs: UnitObservations, cal: Sequence[PointResult],
                      by_point: Mapping[int, Sequence[P2Window]]
                      ) -> tuple[_F64, _F64, bool]:
    """Θ: the noise-only covariance of the calibration points' estimates (Eq. (P2.13)).

    θ_k = Q_k·y_k with Q_k the gain of point k's least squares on its 90 combined means
    (:attr:`~imucalib.procedures.p2.reduction.PointEstimate.gain`) times the averaging of its
    windows into them (:func:`~imucalib.procedures.p2.covariance.means_operator`), so
    Θ = Σ_ch Q_ch·C_ch·Q_chᵀ (Eq. (TD.P1)) with C the covariance of every window mean: Eq.
    (TD.2) of the unit's noise model (:attr:`UnitObservations.noise`) from the windows' start
    times and lengths when it is known (then True), else diag(σ_j²) of the windows' standard
    errors (each point's own noise-only covariance, no correlation between points). Shape
    (36K, 36K), point-major. Also each parameter's Birge ratio in its point's fit (36K,):
    under the coloured covariance, from the point fit's χ² under it (:func:`_coloured_quality`,
    a bias wandering within a point is in that covariance, not a misfit); else the fit's own.
    """
    n_par = len(PARAM_NAMES)
    wins = [w for p in cal for w in by_point[p.point]]
    n_win = len(wins)
    starts = [w.start_s for w in wins]
    coloured = obs.noise is not None and all(t is not None for t in starts)
    if coloured:
        assert obs.noise is not None
        cov = window_covariance(obs.noise, np.array(starts, dtype=np.float64),
                                [w.duration_s for w in wins])
    else:
        cov = independent_covariance([np.concatenate([w.gyro_se_rps, w.accel_se_mps2])
                                      for w in wins])
    gain = np.zeros((N_CHANNELS, n_par * len(cal), n_win))
    scales = []
    col = 0
    for k, p in enumerate(cal):
        mine = by_point[p.point]
        est = p.least_squares
        assert est.gain is not None  # the least squares gives it
        op, channel = means_operator([w.orientation for w in mine], [w.kind for w in mine],
                                     [w.table_rate_rps for w in mine])
        block = slice(col, col + len(mine))
        rows_cov = np.zeros((90, 90))
        for ch in range(N_CHANNELS):
            rows = channel == ch
            gain[ch, k * n_par:(k + 1) * n_par, block] = est.gain[:n_par, rows] @ op[rows]
            rows_cov[np.ix_(rows, rows)] = op[rows] @ cov[ch, block, block] @ op[rows].T
        scales.append(_point_scales(_coloured_quality(est, rows_cov) if coloured
                                    else est.fit_quality))
        col += len(mine)
    return propagate(gain, cov), np.concatenate(scales), coloured


def _mean_lever_arm(points: Sequence[PointResult]) -> list[float]:
    return [float(np.mean([p.least_squares.values[-3 + j] for p in points])) for j in range(3)]


def _limits(opt: P2Options) -> tuple[float, float]:
    return (opt.accel_accuracy_g if opt.accel_accuracy_g is not None else 0.01,
            opt.gyro_accuracy_dps if opt.gyro_accuracy_dps is not None else 0.5)


def _compensated_error(models: Mapping[str, TemperatureModelFit], points: Sequence[PointResult],
                       obs: UnitObservations, opt: P2Options, use_leg: bool) -> dict[str, float]:
    """Return the largest output error left after compensation (docs/p2.md, "The decision").

    At each point, the difference δ between the point's estimates and the models' prediction
    gives the error of the compensated output of sensor i for an input along axis j:
    |δb_i| + |δM_ij|·x_ref (+ |δG_ij|·g for a gyro on a 1 g bench, + |δK2_i|·g² for an
    accelerometer); the largest over i and j, with x_ref = g for the accelerometer and the
    turns' |ω| for the gyro.
    """
    rate_ref = float(np.mean([abs(w.table_rate_rps) for w in obs.windows if w.kind == "rate"]
                             or [0.0]))
    g = obs.gravity_mps2
    worst = {"accel_mps2": 0.0, "gyro_rps": 0.0}
    for p in points:
        pred = np.array([float(predict_temperature_model(
            models[n], [p.temperature_degc],
            temperature_rate_degc_ps=[p.temperature_rate_degc_ps] if opt.rate_term else None,
            leg=[_leg_value(p.leg)] if use_leg else None).value[0]) for n in PARAM_NAMES])
        d = np.abs(p.least_squares.values[:len(PARAM_NAMES)] - pred)
        gyro = d[0:3] + d[3:12].reshape(3, 3).max(axis=1) * rate_ref \
            + d[12:21].reshape(3, 3).max(axis=1) * g
        accel = d[21:24] + d[24:33].reshape(3, 3).max(axis=1) * g + d[33:36] * g**2
        worst["gyro_rps"] = max(worst["gyro_rps"], float(gyro.max()))
        worst["accel_mps2"] = max(worst["accel_mps2"], float(accel.max()))
    return worst


def failed_unit(unit: str, exc: CalibrationError) -> P2UnitResult:
    """Return the result of a unit that could not be calibrated (its typed error)."""
    return P2UnitResult(unit=unit, passed=False, error=str(exc), error_type=type(exc).__name__,
                        reasons=(str(exc),))

