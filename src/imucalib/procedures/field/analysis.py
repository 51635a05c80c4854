"""The field calibration's analysis: a hand-held log → the unit's triad model.

Steps (docs/field.md derives each):

1. The static intervals and the rotations between them (:func:`.observations.find_intervals`:
   Tedaldi's variance detector, k chosen by the smallest gravity-norm χ²/ν unless given).
2. Local g: given, or normal gravity at the given latitude and height (a Type B of 3·10⁻⁵ g for
   the anomaly), or, with neither, normal gravity at 45° with the whole range of the Earth's
   normal gravity as a rectangular Type B (σ = 0.015 m/s²: every scale factor then carries
   1.5·10⁻³) — and a note saying so.
3. The accelerometer (its form and terms chosen by :mod:`imucalib.procedures.field.accel_model`,
   then fitted here): the gravity-norm fit (F.2) over the poses (unknown orientations; at
   least ten poses), or the nominal six-position form (F.10) when the poses were placed on a
   fixture's faces (``accel_form="six-position"``; ``"auto"`` takes it when the poses hold at
   most six distinct directions, each near its own axis direction: a fixture's faces, or the
   twin station's exact remounts; the gravity-norm fit cannot see the non-orthogonality from
   such poses). The gravity-norm form fits the quadratic terms (F.1′) too (with at least 16
   poses, unless told not): a K2 looks like a bias at the poses with an axis up or down and
   differs only at the tilted ones, so the χ² hardly sees it while it moves the biases by
   K2·g² (a tactical 55 µg/g² by 7σ of the plain fit on the twin). The coverage check says which
   directions no pose visited and how many more poses bring each σ under its target.
4. The gyro bias, and its g-sensitivity G when the poses cover every axis direction: the
   static gyro means, less the vertical Earth rate along each pose's measured gravity
   direction (latitude known), fitted by GLS to b + G·f_k (FL.2), the horizontal Earth rate a
   Type B (unknown heading; independent between poses); χ² across the poses flags a
   wandering bias (Birge-scaled).
5. The gyro's M from the rotations between poses (:mod:`imucalib.procedures.field.rotations`,
   fitted by :mod:`imucalib.estimation.gyro_rotations`):
   a full turn flat on the desk (‖θ‖ within 10 % of n·360° and the gravity direction back
   within 5°) is a known-angle observation (Ferraris et al. 1995), every other rotation a
   gravity-referenced one (Tedaldi et al. 2014); ``gyro_form`` chooses "auto" (both),
   "gravity" or "turns" only, or "none".
6. The triad model (FL.1) with the joint covariance; every fit's χ²/ν in the result and, on a
   misfit, the Birge-scaled σ (the project's rule) and a note.
7. *No decision*: a field calibration has no acceptance limits
   (:func:`~imucalib.procedures.field.result.field_decision`, each misfit named in its notes).

Contents
--------
:class:`FieldOptions`, :func:`analyze_field`; :data:`K3_SEPARATION_MAX` is
:mod:`~imucalib.procedures.field.accel_model`'s, named here too.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass, fields
from datetime import UTC, datetime
from typing import Any

import numpy as np
import scipy.stats
from numpy.typing import NDArray

from imucalib import __version__
from imucalib.errors import CalibrationError, InvalidInputError
from imucalib.estimation.linear import solve_weighted_lsq
from imucalib.estimation.term_selection import (
    CRITERIA,
    TermChoice,
    choose_terms,
    parse_terms,
)
from imucalib.models.earth import normal_gravity_mps2
from imucalib.models.fit_quality import FitQuality
from imucalib.models.reported import ReportedParameter
from imucalib.models.result import Provenance
from imucalib.procedures.common.static_intervals import (
    FieldLog,
    StaticPose,
    find_intervals,
    static_poses,
)
from imucalib.procedures.field.accel_model import (
    DRIFT_MIN_POSES,
    K3_SEPARATION_MAX,
    accel_names,
    choose_gravity_norm,
    choose_six_position,
    on_faces,
    pose_noise_floor,
)
from imucalib.procedures.field.result import (
    FieldResult,
    calibration_result,
    field_decision,
    triad_from_field,
)
from imucalib.procedures.field.rotations import fit_gyro, gyro_covariance
from imucalib.units import EARTH_RATE_RPS, UG

__all__ = ["K3_SEPARATION_MAX", "FieldOptions", "analyze_field"]

_F64 = NDArray[np.float64]
#: Normal gravity spans 9.7803 (equator) … 9.8322 m/s² (poles) at sea level.
_G_RANGE_MPS2 = (9.7803, 9.8322)
#: Relative standard uncertainty of normal gravity as local g (anomalies, ~50 mGal).
_ANOMALY_REL = 3e-5
#: The optional model terms the data choose among (docs/field.md, "Model terms"): the
#: accelerometer's K2 (F.1′), its K3 (F.1⁗), its bias drift (F.1″), its scale factors'
#: temperature coefficients (F.1‴, "temp"), the gyro's g-sensitivity G (FL.2).
TERMS = ("k2", "k3", "drift", "g", "temp")
#: Fewest poses with which the gyro's G is a candidate (12 unknowns from 3 per pose).
_G_MIN_POSES = 6
#: A note suggests a pose-noise floor (and its size) when the accelerometer fit's χ² exceeds
#: this quantile of χ²_ν (white noise alone: one session in twenty).
_SUGGEST_FLOOR_QUANTILE = 0.95


@dataclass(frozen=True)
class FieldOptions:
    """Options of :func:`analyze_field` (module docstring; docs/field.md).

    Attributes
    ----------
    accel_form : {"auto", "gravity-norm", "six-position"}
    gyro_form : {"auto", "gravity", "turns", "none"}
    accel_k2 : {"auto", "yes", "no"}
        Fit the accelerometer's quadratic terms (F.1′) ("auto": when the data support them,
        by `term_criterion`).
    accel_drift : {"auto", "yes", "no"}
        Fit a linear drift of the accelerometer's bias over the session (F.1″), gravity-norm
        form only ("auto": by `term_criterion`); the bias is then that at the poses' mean
        time.
    accel_temperature : {"auto", "yes", "no"}
        Fit the accelerometer's scale factors as linear in the IMU's temperature (F.1‴),
        gravity-norm form, when the log has a temperature ("auto": by `term_criterion`); the
        scale factors are then those at the poses' mean temperature.
    terms : str
        Terms forced in or out, ``"+k2,+k3,-drift,+g"`` (of :data:`TERMS`); overrides
        `accel_k2`, `accel_drift` and `gyro_g_sensitivity`.
    term_criterion : {"lrt", "aicc", "bic"}
        How "auto" terms are chosen (:func:`~imucalib.estimation.term_selection.choose_terms`):
        by default the likelihood-ratio test at `term_level` (docs/field.md, "Model terms",
        says why not AICc: with 25 poses and 15 unknowns its small-sample term rejects a K2 of
        Δχ² = 27 on 3 parameters, and the biases then miss by 15σ).
    term_level : float
        The likelihood-ratio test's level α (with ``lrt``).
    accel_instability_mps2, gyro_instability_rps : float
        A datasheet's bias instability, added in quadrature to each pose mean's standard error
        (a flicker floor the poses' white noise does not show: without it the accelerometer's
        σ understate the error by about 1.5 on the twin's grade noise). [m/s²], [rad/s]
    accel_instability_auto : bool
        Estimate the accelerometer's floor from the poses' own scatter instead (Paule–Mandel,
        :func:`~imucalib.estimation.dark_uncertainty.paule_mandel_floor`: the floor that makes
        the accelerometer fit's χ²/ν one); not with `accel_instability_mps2`.
    gyro_g_sensitivity : {"auto", "yes", "no"}
        Fit the gyro's g-sensitivity G from the static poses ("auto": with at least six poses,
        when the data support it, by `term_criterion`).
    gravity_mps2, gravity_std_mps2 : float, optional
        Local g and its standard uncertainty (default: from the latitude). [m/s²]
    latitude_deg, height_m : float, optional
        The site (a Recording's metadata when omitted). [°], [m]
    static_threshold : float, optional
        The detector's k; None: chosen automatically.
    window_s, init_static_s, min_static_s, min_rotation_deg : float
        Detector settings (:func:`~imucalib.processing.static_detector.
        detect_static_and_rotations`).
    noise_block_s : float
        Block length of the pooled white-noise estimate. [s]
    target_accel_bias_mps2, target_scale, target_angle_rad : float
        The σ the coverage check counts poses for.
    """

    accel_form: str = "auto"
    gyro_form: str = "auto"
    gyro_g_sensitivity: str = "auto"
    accel_k2: str = "auto"
    accel_drift: str = "auto"
    accel_temperature: str = "auto"
    terms: str = ""
    term_criterion: str = "lrt"
    term_level: float = 0.05
    accel_instability_mps2: float = 0.0
    gyro_instability_rps: float = 0.0
    accel_instability_auto: bool = False
    gravity_mps2: float | None = None
    gravity_std_mps2: float | None = None
    latitude_deg: float | None = None
    height_m: float | None = None
    static_threshold: float | None = None
    window_s: float = 0.5
    init_static_s: float = 2.0
    min_static_s: float = 1.0
    min_rotation_deg: float = 5.0
    noise_block_s: float = 0.25
    target_accel_bias_mps2: float = 1e-3
    target_scale: float = 1e-4
    target_angle_rad: float = 1e-4

    def __post_init__(self) -> None:
        if self.accel_form not in ("auto", "gravity-norm", "six-position"):
            raise InvalidInputError(f"`accel_form` must be auto, gravity-norm or six-position; "
                                    f"got {self.accel_form!r}")
        if self.accel_drift not in ("auto", "yes", "no"):
            raise InvalidInputError(f"`accel_drift` must be auto, yes or no; got "
                                    f"{self.accel_drift!r}")
        if self.accel_temperature not in ("auto", "yes", "no"):
            raise InvalidInputError(f"`accel_temperature` must be auto, yes or no; got "
                                    f"{self.accel_temperature!r}")
        if self.accel_k2 not in ("auto", "yes", "no"):
            raise InvalidInputError(f"`accel_k2` must be auto, yes or no; got "
                                    f"{self.accel_k2!r}")
        if self.gyro_g_sensitivity not in ("auto", "yes", "no"):
            raise InvalidInputError(f"`gyro_g_sensitivity` must be auto, yes or no; got "
                                    f"{self.gyro_g_sensitivity!r}")
        if self.term_criterion not in CRITERIA:
            raise InvalidInputError(f"`term_criterion` must be one of {', '.join(CRITERIA)}; "
                                    f"got {self.term_criterion!r}")
        if not 0.0 < self.term_level < 1.0:
            raise InvalidInputError(f"`term_level` must be in (0, 1); got {self.term_level!r}")
        parse_terms(self.terms, TERMS)
        if self.gyro_form not in ("auto", "gravity", "turns", "none"):
            raise InvalidInputError(f"`gyro_form` must be auto, gravity, turns or none; got "
                                    f"{self.gyro_form!r}")
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, float) and not math.isfinite(v):
                raise InvalidInputError(f"`{f.name}` must be finite; got {v!r}")
        if self.accel_instability_mps2 < 0 or self.gyro_instability_rps < 0:
            raise InvalidInputError("the bias instabilities must be ≥ 0; got "
                                    f"{self.accel_instability_mps2!r}, "
                                    f"{self.gyro_instability_rps!r}")
        if self.accel_instability_auto and self.accel_instability_mps2 > 0:
            raise InvalidInputError("give the accelerometer's bias instability or ask for it to "
                                    "be estimated (auto), not both")
        if self.latitude_deg is not None and not -90.0 <= self.latitude_deg <= 90.0:
            raise InvalidInputError(f"`latitude_deg` must be in [−90, 90]; got "
                                    f"{self.latitude_deg!r}")


    def forced_terms(self) -> dict[str, bool]:
        """Terms forced in (True) or out (False): `accel_k2` … not "auto", then `terms`."""
        forced = {name: choice == "yes" for name, choice in (
            ("k2", self.accel_k2), ("drift", self.accel_drift), ("g", self.gyro_g_sensitivity),
            ("temp", self.accel_temperature))
            if choice != "auto"}
        forced.update(parse_terms(self.terms, TERMS))
        return forced


#: A note says the session's temperature moved when the poses span more than this. [°C]
_TEMPERATURE_SPAN_NOTE_DEGC = 1.0


def _pose_temperatures(log: FieldLog, poses: list[StaticPose]) -> _F64 | None:
    """Each pose's mean temperature, when the log has a finite one for every pose. [°C]

    A pose's samples are those with start ≤ t ≤ end; the log's time increasing (the detector
    has checked it), they are the index range that two binary searches find, the same values
    in the same order as the boolean mask's without two comparisons of the whole log a pose.
    """
    if log.temperature_degc is None:
        return None
    temps = []
    first = np.searchsorted(log.time_s, [p.start_time_s for p in poses], side="left")
    stop = np.searchsorted(log.time_s, [p.end_time_s for p in poses], side="right")
    for a, b in zip(first, stop, strict=True):
        t = log.temperature_degc[a:b]
        t = t[np.isfinite(t)]
        if not t.size:          # a pose without a reading: no temperature for the fit
            return None
        temps.append(float(np.mean(t)))
    return np.array(temps) if temps else None


def _gyro_names(terms: Collection[str]) -> list[str]:
    """Return the names of the static gyro fit's values (FL.2) for a term set."""
    return [*(f"gyro_bias_{a}" for a in "xyz"),
            *((f"gyro_G_{i}{j}" for i in "xyz" for j in "xyz") if "g" in terms else ()),
            *((f"gyro_bias_rate_{a}" for a in "xyz") if "drift" in terms else ())]


def _model_var(choice: TermChoice, names: Sequence[str]) -> _F64:
    """u²_model of (TS.4) in the order of `names` (0 where the choice added none)."""
    return np.array([choice.model_std.get(n, 0.0) ** 2 for n in names])


def _gravity(opt: FieldOptions, log: FieldLog) -> tuple[float, float, float | None, str]:
    """Return (g, σ_g, latitude or None, note) of step 2."""
    lat = opt.latitude_deg if opt.latitude_deg is not None else log.latitude_deg
    height = opt.height_m if opt.height_m is not None else (log.height_m or 0.0)
    if opt.gravity_mps2 is not None:
        g = float(opt.gravity_mps2)
        sg = float(opt.gravity_std_mps2 or 0.0)
        return g, sg, lat, f"local g given: {g:.6f} ± {sg:.2g} m/s²"
    if lat is not None:
        g = normal_gravity_mps2(lat, height)
        sg = opt.gravity_std_mps2 if opt.gravity_std_mps2 is not None else _ANOMALY_REL * g
        return g, float(sg), lat, (f"local g = normal gravity at {lat:g}°, {height:g} m: "
                                   f"{g:.6f} ± {sg:.2g} m/s²")
    g = normal_gravity_mps2(45.0, 0.0)
    sg = (_G_RANGE_MPS2[1] - _G_RANGE_MPS2[0]) / math.sqrt(12.0)
    return g, sg, None, (f"no latitude or local g given: normal gravity at 45° ({g:.5f} m/s²) "
                         f"with σ = {sg:.3f} m/s² for any latitude; every scale factor "
                         f"carries {sg / g:.1e} of it (give --latitude for 3e-5)")


def _gyro_design(poses: list[StaticPose], up: _F64, force: _F64, lat: float | None,
                 g_sensitivity: bool, times: _F64 | None = None
                 ) -> tuple[list[str], _F64, _F64, _F64]:
    """Return step 4's (names, design, observations, covariance) of (FL.2), every pose at once.

    Pose k's rows: ω_k − Ω·sin φ·u_k = b + G·f_k (+ ḃ·(t_k − t̄)), with C_k = diag(σ_k²) plus
    the horizontal Earth rate's Type B, (Ω·cos φ)²/2·(I − u_k u_kᵀ) (unknown heading; Ω²/3·I
    with no latitude, the whole Earth rate then unknown in direction). The blocks are the
    products a pose-by-pose build makes (``np.kron``'s, ``np.diag``'s), value for value.
    """
    omega = EARTH_RATE_RPS
    names = [f"gyro_bias_{a}" for a in "xyz"]
    if g_sensitivity:
        names += [f"gyro_G_{i}{j}" for i in "xyz" for j in "xyz"]
    if times is not None:
        names += [f"gyro_bias_rate_{a}" for a in "xyz"]
    n = len(poses)
    eye = np.eye(3)
    if lat is None:  # the whole Earth rate unknown in direction
        vertical = np.zeros((n, 3))
        type_b = np.broadcast_to(omega**2 / 3.0 * eye, (n, 3, 3))
    else:
        s, c = math.sin(math.radians(lat)), math.cos(math.radians(lat))
        vertical = omega * s * up
        type_b = (omega * c) ** 2 / 2.0 * (eye - up[:, :, None] * up[:, None, :])
    block = [np.broadcast_to(eye, (n, 3, 3))]
    if g_sensitivity:  # np.kron(I, f_kᵀ): row i holds f_k in columns 3i … 3i + 2
        block.append((eye[None, :, :, None] * force[:, None, None, :]).reshape(n, 3, 9))
    if times is not None:
        block.append((times - times.mean())[:, None, None] * eye)
    design = np.concatenate(block, axis=2).reshape(3 * n, len(names))
    z = (np.array([p.gyro_mean for p in poses]) - vertical).reshape(3 * n)
    noise = np.zeros((n, 3, 3))
    noise[:, [0, 1, 2], [0, 1, 2]] = np.array([p.gyro_se for p in poses]) ** 2
    cov = np.zeros((n, 3, n, 3))
    k = np.arange(n)
    cov[k, :, k, :] = noise + type_b
    return names, design, z, cov.reshape(3 * n, 3 * n)


def _gyro_static(poses: list[StaticPose], up: _F64, force: _F64, lat: float | None,
                 g_sensitivity: bool, times: _F64 | None = None
                 ) -> tuple[_F64, _F64, FitQuality, list[_F64]]:
    """Step 4: bias (and G) from the static gyro means less the known Earth rate (FL.2).

    Returns the values (b, G row-major when fitted, the bias rates ḃ when `times` are given:
    b then holds at the poses' mean time, as the accelerometer's (F.1″)), their covariance
    (Birge-scaled on a misfit), the fit quality and the residual per pose. The poses' 3×3
    covariances (noise and the Earth rate's Type B) make one block-diagonal C
    (:func:`_gyro_design`): GLS by :func:`~imucalib.estimation.linear.solve_weighted_lsq`.
    """
    names, design, z, cov = _gyro_design(poses, up, force, lat, g_sensitivity, times)
    fit = solve_weighted_lsq(design, z, covariance=cov, param_names=names,
                             group="gyro (static poses)", context="static gyro design (FL.2)")
    return (np.array(fit.estimate), np.array(fit.covariance_birge), fit.fit_quality,
            list(fit.residuals.reshape(len(poses), 3)))


def analyze_field(log: FieldLog, options: FieldOptions | None = None, *,
                  progress: Callable[[float], None] | None = None) -> FieldResult:
    """Calibrate the IMU of a hand-held log (module docstring).

    Raises
    ------
    MissingSegmentError
        Too few static intervals.
    InsufficientExcitationError
        Poses or rotations that leave parameters unseen (named).
    InvalidInputError
        Bad options.
    """
    from imucalib.estimation.gravity_norm import (
        correct_accel,
        fit_gravity_norm,
        pose_coverage,
    )
    from imucalib.estimation.six_position import fit_six_position, nominal_directions

    opt = options or FieldOptions()
    report = progress or (lambda _f: None)
    g, sg, lat, g_note = _gravity(opt, log)
    detection = find_intervals(
        log, threshold_factor=opt.static_threshold, window_s=opt.window_s,
        init_static_s=opt.init_static_s, min_static_s=opt.min_static_s,
        min_rotation_deg=opt.min_rotation_deg, gravity_mps2=g)
    report(0.3)
    poses = static_poses(log, detection, block_s=opt.noise_block_s)
    if opt.accel_instability_mps2 > 0 or opt.gyro_instability_rps > 0:
        poses = [dataclasses.replace(
            p, accel_se=np.hypot(p.accel_se, opt.accel_instability_mps2),
            gyro_se=np.hypot(p.gyro_se, opt.gyro_instability_rps)) for p in poses]
    y = np.array([p.accel_mean for p in poses])
    sy = np.array([p.accel_se for p in poses])
    form = opt.accel_form
    if form == "auto":
        form = "six-position" if on_faces(y) else "gravity-norm"
    notes = [g_note]
    six: Any = None
    drift_rows: list[ReportedParameter] = []
    times = np.array([0.5 * (p.start_time_s + p.end_time_s) for p in poses])
    forced = opt.forced_terms()
    temps = _pose_temperatures(log, poses)
    if forced.get("temp") and (form != "gravity-norm" or temps is None):
        raise InvalidInputError(
            "the temperature term (+temp) needs the gravity-norm form and a log with the IMU's "
            f"temperature; got the {form} form and "
            f"{'no temperature column' if temps is None else 'a temperature'}")
    if forced.get("k3") and form != "gravity-norm":
        raise InvalidInputError("K3 (+k3) is a term of the gravity-norm form; got the "
                                f"{form} form")
    separation = math.nan
    if form == "gravity-norm":
        choice_a, separation = choose_gravity_norm(y, sy, g, times, temps, forced,
                                                   criterion=opt.term_criterion,
                                                   level=opt.term_level)
    else:
        choice_a, six = choose_six_position(y, sy, g, sg, forced, criterion=opt.term_criterion,
                                             level=opt.term_level)
    selection = [choice_a]
    k2, k3, drift = choice_a.has("k2"), choice_a.has("k3"), choice_a.has("drift")
    tt = temps if choice_a.has("temp") else None
    notes.append(choice_a.summary())
    floor = None
    if opt.accel_instability_auto:
        floor = pose_noise_floor(y, sy, g, form, k2, times if drift else None, sg, tt, k3)
        poses = [dataclasses.replace(p, accel_se=np.hypot(p.accel_se, floor)) for p in poses]
        sy = np.array([p.accel_se for p in poses])
        notes.append(f"accelerometer pose-noise floor {floor / UG:.3g} µg estimated from the "
                     "poses' scatter (Paule–Mandel: the floor that makes the fit's χ²/ν one), "
                     "added in quadrature to each pose's white-noise σ" if floor > 0 else
                     "accelerometer pose-noise floor: none (auto): the poses scatter no more "
                     "than their white noise says")
    if form == "gravity-norm":
        fit = fit_gravity_norm(y, sy, g, k2=k2, k3=k3, times_s=times if drift else None,
                               temperatures_degc=tt)
        core = fit.values.size - (3 if drift else 0) - (0 if tt is None else 3)
        # g's Type B: refit with g + δ (the norms scale with g)
        dg = 1e-4 * g
        jg = (fit_gravity_norm(y, sy, g + dg, k2=k2, k3=k3, times_s=times if drift else None,
                               temperatures_degc=tt).values - fit.values) / dg
        full_cov = fit.covariance_noise + np.outer(jg, jg) * sg**2
        full_cov = full_cov + np.diag(_model_var(choice_a, accel_names(choice_a.chosen, False)))
        accel_values = fit.values[:core]
        accel_cov_noise = np.asarray(full_cov[:core, :core], dtype=np.float64)
        accel_quality = fit.quality
        residuals = fit.residuals
        if drift:   # the poses' means at t̄, for the gravity directions of the gyro
            rate = fit.values[core:core + 3]
            y = y - np.outer(times - times.mean(), rate)
            drift_rows = [ReportedParameter(f"accel_bias_rate_{a}", float(v), float(math.sqrt(
                full_cov[core + i, core + i] * fit.quality.sigma_scale**2)), "m/s^3",
                float(math.sqrt(full_cov[core + i, core + i])))
                for i, (a, v) in enumerate(zip("xyz", rate, strict=True))]
        if tt is not None:  # (F.1‴)'s coefficients, after the rates, reported as the forward
            # model's dM_ii/dT = −ṡ_T,i/(1 + s_i)² (M_ii = 1/(1 + s_i) − 1 to first order)
            at = core + (3 if drift else 0)
            for i, a in enumerate("xyz"):
                k = 1.0 / (1.0 + float(accel_values[3 + i])) ** 2
                sd = math.sqrt(full_cov[at + i, at + i])
                drift_rows.append(ReportedParameter(
                    f"accel_M_{a}{a}_tc", float(-fit.values[at + i] * k),
                    sd * k * fit.quality.sigma_scale, "1/K", sd * k))
        # each pose's force by the fitted model (with (F.1‴) its scale at the pose's
        # temperature): the gravity directions of the gyro's fit
        corrected = correct_accel(accel_values, y) if tt is None else fit.forces
    else:
        if floor:
            six = fit_six_position(y, sy, nominal_directions(y), g, gravity_std_mps2=sg, k2=k2)
        accel_values = six.values
        accel_cov_noise = np.asarray(six.covariance_noise, dtype=np.float64) + np.diag(
            _model_var(choice_a, accel_names(choice_a.chosen, True)))
        accel_quality = six.quality
        residuals = np.linalg.norm(six.residuals, axis=1)
        corrected = np.asarray(np.linalg.solve(np.eye(3) + six.scale_misalignment,
                                               (y - six.bias).T).T, dtype=np.float64)
    accel_cov = accel_cov_noise * accel_quality.sigma_scale**2
    if (floor is None and opt.accel_instability_mps2 == 0.0 and accel_quality.dof > 0
            and accel_quality.chi2 > scipy.stats.chi2.ppf(_SUGGEST_FLOOR_QUANTILE,
                                                           accel_quality.dof)):
        suggested = pose_noise_floor(y, sy, g, form, k2, times if drift else None, sg, tt, k3)
        notes.append(
            f"the poses scatter more than their white noise (accelerometer χ²/ν = "
            f"{accel_quality.reduced_chi2:.3g}): a bias instability of about "
            f"{suggested / UG:.2g} µg between poses would explain it (Paule–Mandel); if the "
            "datasheet agrees, give it (--accel-instability-ug) or let it be estimated "
            "(--accel-instability-ug auto), else look for a model misfit (docs/field.md)")
    up = corrected / np.linalg.norm(corrected, axis=1, keepdims=True)
    report(0.5)
    missing, needed = pose_coverage(
        y, sy, g, target_std=[opt.target_accel_bias_mps2] * 3 + [opt.target_scale] * 3
        + [opt.target_angle_rad] * 3)
    coverage = {"missing_directions": missing, "poses_needed": needed,
                "targets": {"accel_bias_mps2": opt.target_accel_bias_mps2,
                            "scale": opt.target_scale, "angle_rad": opt.target_angle_rad}}
    if missing:
        notes.append(f"no pose had gravity within 45° of {', '.join(missing)}: add poses "
                     "there (the coverage check in the report counts how many)")
    force = g * up if form == "gravity-norm" else corrected
    forced_g = {k: v for k, v in forced.items() if k in ("g", "drift")}
    if len(poses) < _G_MIN_POSES:
        forced_g.setdefault("g", False)
    choice_g, (static_values, static_cov, bias_quality, bias_resid), _ = choose_terms(
        "gyro (static poses)", ("g", "drift"),
        lambda t: _gyro_static(poses, up, force, lat, "g" in t,
                               times if "drift" in t else None),
        lambda f: (float(f[2].chi2), int(f[2].dof), int(f[0].size)),
        forced=forced_g, ruled={"drift": len(poses) >= DRIFT_MIN_POSES},
        criterion=opt.term_criterion, level=opt.term_level,
        estimates=lambda t, f: (_gyro_names(t), f[0], np.sqrt(np.diag(f[1]))))
    static_cov = static_cov + np.diag(_model_var(choice_g, _gyro_names(choice_g.chosen)))
    selection.append(choice_g)
    notes.append(choice_g.summary())
    fit_g = choice_g.has("g")
    if choice_g.has("drift"):   # the rates go beside the triad, as the accelerometer's
        core = 3 + 9 * fit_g
        drift_rows += [ReportedParameter(
            f"gyro_bias_rate_{a}", float(static_values[core + i]),
            float(math.sqrt(static_cov[core + i, core + i])), "rad/s^2",
            float(math.sqrt(static_cov[core + i, core + i])) / bias_quality.sigma_scale)
            for i, a in enumerate("xyz")]
        static_values, static_cov = static_values[:core], static_cov[:core, :core]
    omitted: list[str] = []
    try:
        # the accelerometer's noise-only covariance: its cross-covariance with the gyro and the
        # gyro block then come from one covariance, so the joint one stays positive
        # semi-definite; each triad's Birge ratio scales its rows afterwards (a scaled C_a
        # here with the unscaled block beside it made the joint covariance indefinite on a
        # misfit accelerometer fit: eigenvalue −0.14 of the correlation on a harsh session)
        gyro = fit_gyro(log, detection, poses, y, up, opt.gyro_form, opt.window_s,
                        accel_values, accel_cov_noise, form,
                         six, static_values[3:].reshape(3, 3) if fit_g else None, lat)
    except CalibrationError as exc:
        if opt.gyro_form != "auto":
            raise
        gyro = None
        omitted.append(f"the gyro triad (scale and misalignment, from the rotations): {exc}")
        notes.append(f"PARTIAL RESULT: the gyro triad was left out ({exc}); the accelerometer "
                     f"triad and the gyro bias{' and G' if fit_g else ''} from the static poses "
                     "are in the result (docs/field.md, \"A partial result\")")
    report(0.9)
    quality: list[FitQuality] = [accel_quality]
    if gyro is not None:
        quality.append(gyro["fit"].quality)
    quality.append(bias_quality)
    for q in quality:
        if q.misfit:
            notes.append(q.summary())
    names, values, cov = triad_from_field(
        form, accel_values, accel_cov_noise, static_values, static_cov,
        None if gyro is None else gyro["fit"].values,
        None if gyro is None else gyro_covariance(gyro["fit"]),
        None if gyro is None else gyro["fit"].cross_covariance)
    if gyro is None and not omitted:
        notes.append("no rotation fitted: the gyro triad is not in the calibration "
                     "(its bias is in the report)")
    if gyro is not None:
        left = [r for r in gyro["rows"] if "left_out" in r]
        if left:
            notes.append(f"{len(left)} of {len(gyro['rows'])} rotations left out of the gyro "
                         "fit: " + "; ".join(f"{r['start_time_s']:.1f}–{r['end_time_s']:.1f} s: "
                                            f"{r['left_out']}" for r in left))
    if form == "gravity-norm":
        notes.append("the accelerometer frame: x along the sensor x axis, y in the sensors' "
                     "x–y plane (a field calibration cannot see the case)")
    span = None if temps is None else (float(temps.min()), float(temps.max()))
    reference_degc = None if temps is None else float(np.mean(temps))
    if tt is not None and span is not None:
        notes.append(
            f"the IMU's temperature moved from {span[0]:.3g} to {span[1]:.3g} °C over the "
            "poses: the accelerometer's scale factors were fitted as linear in it (F.1‴, "
            f"accel_M_xx_tc …); the calibration holds them at {reference_degc:.3g} °C, the "
            "poses' mean (docs/field.md, \"Model terms\")")
    elif span is not None and span[1] - span[0] > _TEMPERATURE_SPAN_NOTE_DEGC:
        notes.append(
            f"the IMU's temperature moved from {span[0]:.3g} to {span[1]:.3g} °C over the poses "
            f"({span[1] - span[0]:.2g} °C): every parameter here is one value for the whole "
            "session, and what moves with temperature (a consumer unit's scale factors by "
            "about 1e-4 per °C) moved by more than its σ may show; calibrate after the unit "
            "has warmed up, or with a chamber (docs/field.md, \"Measured\")")
    prov = Provenance(recording=log.source, software_version=__version__,
                      created_utc=datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
                      details={"accel_form": form, "n_poses": len(poses),
                               "threshold_factor": detection.threshold_factor,
                               "gravity_mps2": g, "gravity_std_mps2": sg})
    cal = calibration_result(log.unit, log.source, names, values, cov, tuple(quality),
                             tuple(notes), prov)
    pose_rows = [{"index": p.index, "start_time_s": p.start_time_s,
                  "end_time_s": p.end_time_s, "accel_mean_mps2": p.accel_mean,
                  "accel_se_mps2": p.accel_se, "gyro_mean_rps": p.gyro_mean,
                  "gyro_se_rps": p.gyro_se, "accel_residual": residuals[k],
                  "gyro_bias_residual_rps": bias_resid[k], "up_direction": up[k]}
                 for k, p in enumerate(poses)]
    report(1.0)
    return FieldResult(
        extra_rows=drift_rows,
        unit=log.unit, source=log.source, result=cal, accel_form=form,
        gyro_form="static only" if gyro is None else gyro["form"],
        gyro_static_names=tuple(f"gyro_bias_{a}" for a in "xyz") + (
            tuple(f"gyro_G_{i}{j}" for i in "xyz" for j in "xyz") if fit_g else ()),
        gyro_static_values=static_values, gyro_static_cov=static_cov, gravity_mps2=g,
        gravity_std_mps2=sg,
        threshold_factor=detection.threshold_factor, poses=pose_rows,
        rotations=[] if gyro is None else gyro["rows"], coverage=coverage,
        quality=tuple(quality), notes=tuple(notes),
        model_selection=tuple(c.to_dict() for c in selection), omitted=tuple(omitted),
        details={"latitude_deg": lat, "n_samples": int(log.time_s.size),
                 "temperature_span_degc": None if span is None else list(span),
                 "reference_temperature_degc": reference_degc,
                 "k3_separation": None if not math.isfinite(separation) else separation,
                 "window_s": opt.window_s, "accel_values": accel_values,
                 "accel_covariance": accel_cov},
        decision=field_decision(tuple(quality)))
