"""P3's analysis: from the records of a run to K2 of the test accelerometer (docs/p3.md).

1. Every record of the three units reduced (:mod:`~imucalib.procedures.p3.observations`).
2. K1 and K0 of each accelerometer from its 1 g tumble (the records with the input axis up and
   down: K1 = (V₊ − V₋)/2g, K0 = (V₊ + V₋)/2, Eq. (P3.5)), or given as inputs with their
   uncertainty (:attr:`P3Options.k1`); local g from the recorded latitude (normal gravity,
   with a Type B relative σ :attr:`P3Options.gravity_rel_std`) unless given.
3. Each series (one accelerometer in one configuration): the rest records of each phase
   (before and after the rates) averaged over the arm positions — every position must be
   there, their mean is what cancels the gravity a tilted spin axis leaks into the radial
   input — and the rate records, fitted by :func:`~imucalib.procedures.p3.roundrobin.fit_series`.
4. The round-robin (:func:`~imucalib.procedures.p3.roundrobin.solve_round_robin`): K2 of A, B and
   the test accelerometer, c and c′ with their covariance; the naive K2_T beside it.
5. The decision: the test accelerometer's K2 passes when its expanded uncertainty (k = 2,
   Birge-scaled on a misfit) is within :attr:`P3Options.k2_target_g_per_g2`
   (:attr:`P3Result.decision`).

The result satisfies the result contract (:class:`~imucalib.models.procedure_result.
ProcedureResult`, docs/procedures.md): part of a triad model (K2 of the test accelerometer's
input axis; no ``calibration``).

Contents
--------
:class:`P3Options`, :class:`AccelerometerScale`, :class:`P3Result`, :func:`analyze_p3`,
:func:`tumble_scale`, :func:`build_series`.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from imucalib import units
from imucalib.errors import InvalidInputError, MissingSegmentError, RecordingError
from imucalib.io.opening import open_recording
from imucalib.io.reader import Recording
from imucalib.models.decision import Check, CheckRow, Decision
from imucalib.models.earth import Site
from imucalib.models.fit_quality import FitQuality
from imucalib.models.procedure_result import ResultDefaults, TriadParameters
from imucalib.models.reported import ReportedParameter
from imucalib.procedures.p3.observations import (
    P3Processing,
    P3Window,
    extract_p3_windows,
    p3_unit_names,
)
from imucalib.procedures.p3.roles import P3_RATE, P3_REST, P3_TUMBLE
from imucalib.procedures.p3.roundrobin import (
    PARAMETERS,
    SERIES_NAMES,
    RoundRobinEstimate,
    Series,
    fit_series,
    scale_for_misfit,
    solve_round_robin,
)

__all__ = ["DECISION_RULE", "K2_CHECK", "AccelerometerScale", "P3Options", "P3Result",
           "analyze_p3", "build_series", "tumble_scale"]

#: Which unit role and configuration each series of (P3.3) comes from.
SERIES_SOURCES: dict[str, tuple[str, int]] = {
    "A1": ("ref-a", 1), "B1": ("ref-b", 1), "A2": ("ref-a", 2), "B2": ("ref-b", 2),
    "A3": ("ref-a", 3), "B3": ("ref-b", 3), "T3": ("test", 3)}
_ROLES = ("ref-a", "ref-b", "test")
_G_PER_G2 = units.G0_MPS2  # K2 [1/(m/s²)] × g0 = K2 [g/g²]
#: The name of P3's one check (:attr:`P3Result.decision`).
K2_CHECK = "expanded uncertainty of K2 (test accelerometer)"
#: P3's decision rule (docs/p3.md, "Decision").
DECISION_RULE = ("the test accelerometer passes when the expanded uncertainty of its K2, "
                 "U = 2σ (k = 2; σ Birge-scaled on a misfit), is within the target "
                 "k2_target_g_per_g2 (docs/p3.md)")


@dataclass(frozen=True)
class P3Options:
    """Options of :func:`analyze_p3`.

    Attributes
    ----------
    reference_a, reference_b, test : str, optional
        The units (IMU streams) of reference A, reference B and the test accelerometer;
        default: the names the recording's first mounting check gives.
    k1 : mapping of str to (float, float)
        K1 (output per m/s²) and its standard uncertainty per unit, instead of the tumble's.
    k0 : mapping of str to (float, float)
        K0 (output) and its uncertainty per unit, reported with the result (K0 does not enter
        K2: the rest records are fitted).
    gravity_mps2 : float, optional
        Local gravity for the tumble; default the normal gravity at the recorded latitude.
    gravity_rel_std : float, optional
        Its relative standard uncertainty; default 2e-5 for normal gravity (the anomalies of a
        laboratory site), 0 for a given value.
    radii : {"fitted", "nominal"}
        The radius of each series in (P3.3): its own effective radius (the x coefficient) or
        the nominal ones (:attr:`nominal_radii_m`).
    nominal_radii_m : (float, float)
        Reference and test radii for ``radii="nominal"``. [m]
    k2_target_g_per_g2 : float
        The expanded uncertainty (k = 2) the test accelerometer's K2 must reach. [g/g²]
    processing : P3Processing
        The window reduction's options (input axis, dropouts, noise windows).
    """

    reference_a: str | None = None
    reference_b: str | None = None
    test: str | None = None
    k1: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    k0: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    gravity_mps2: float | None = None
    gravity_rel_std: float | None = None
    radii: str = "fitted"
    nominal_radii_m: tuple[float, float] | None = None
    k2_target_g_per_g2: float = 1e-7
    drift: bool = False
    processing: P3Processing = field(default_factory=P3Processing)

    def __post_init__(self) -> None:
        if self.radii not in ("fitted", "nominal"):
            raise InvalidInputError(f"`radii` must be 'fitted' or 'nominal'; got {self.radii!r}")
        if self.radii == "nominal" and self.nominal_radii_m is None:
            raise InvalidInputError("`radii='nominal'` needs `nominal_radii_m` (reference, test)")
        if not (math.isfinite(self.k2_target_g_per_g2) and self.k2_target_g_per_g2 > 0):
            raise InvalidInputError(f"`k2_target_g_per_g2` must be positive; got "
                                    f"{self.k2_target_g_per_g2!r}")
        for what, given in (("k1", self.k1), ("k0", self.k0)):
            for unit, pair in given.items():
                ok = (isinstance(pair, Sequence) and len(pair) == 2
                      and all(isinstance(v, int | float) and math.isfinite(v) for v in pair)
                      and pair[1] >= 0 and (what == "k0" or pair[0] > 0))
                if not ok:
                    raise InvalidInputError(
                        f"`{what}` of unit {unit!r} must be (value, standard uncertainty) with a "
                        f"{'positive value and ' if what == 'k1' else ''}σ ≥ 0; got {pair!r}")


@dataclass(frozen=True)
class AccelerometerScale:
    """K1 and K0 of one accelerometer with their standard uncertainties.

    ``source`` is ``"tumble"`` (Eq. (P3.5)) or ``"input"``. K1 [output per m/s²], K0 [output].
    """

    unit: str
    k1: float
    k1_std: float
    k0: float
    k0_std: float
    source: str

    def to_dict(self) -> dict[str, Any]:
        """Return the JSON-able fields."""
        return {"unit": self.unit, "k1": self.k1, "k1_std": self.k1_std, "k0": self.k0,
                "k0_std": self.k0_std, "source": self.source}


def tumble_scale(unit: str, windows: Sequence[P3Window], gravity_mps2: float,
                 gravity_rel_std: float) -> AccelerometerScale:
    """K1 = (V₊ − V₋)/2g and K0 = (V₊ + V₋)/2 from the tumble records, Eq. (P3.5).

    V₊ is the mean of the records whose output is above zero (input axis up), V₋ of those below.

    Raises
    ------
    MissingSegmentError
        No record with the axis up, or none with it down.
    """
    tumble = [w for w in windows if w.role == P3_TUMBLE]
    up = [w for w in tumble if w.mean > 0.5 * gravity_mps2]
    down = [w for w in tumble if w.mean < -0.5 * gravity_mps2]
    if not up or not down:
        found = [round(w.mean / gravity_mps2, 3) for w in tumble]
        raise MissingSegmentError(
            f"unit {unit}: the 1 g tumble needs a record with the input axis up (+1 g) and one "
            f"with it down (−1 g); the tumble records read {found} g — give K1 as an input "
            "(k1) instead")

    def mean(ws: list[P3Window]) -> tuple[float, float]:
        return (float(np.mean([w.mean for w in ws])),
                float(np.sqrt(np.sum([w.se**2 for w in ws]))) / len(ws))

    vp, sp = mean(up)
    vm, sm = mean(down)
    k1 = (vp - vm) / (2.0 * gravity_mps2)
    k1_std = math.hypot(math.hypot(sp, sm) / (2.0 * gravity_mps2), k1 * gravity_rel_std)
    return AccelerometerScale(unit=unit, k1=k1, k1_std=k1_std, k0=(vp + vm) / 2.0,
                              k0_std=math.hypot(sp, sm) / 2.0, source="tumble")


def _rest_points(unit: str, config: int, rests: list[P3Window], arms: Sequence[float]
                 ) -> tuple[list[float], list[float], list[float]]:
    """One rest point per complete phase: the mean over the arm positions (module docstring).

    `arms` are the unit's arm positions (every rest record's, all configurations): a phase must
    hold each of them, and they must cancel a once-per-revolution term (|mean of e^{iφ}| below
    0.01: 0°, 90°, 180°, 270° or any evenly spread set, one of them up to about 2° off), else a
    tilted spin axis' gravity leaks in (docs/p3.md, "Sensitivity").
    """
    phasor = abs(np.mean(np.exp(1j * np.radians(np.asarray(arms, dtype=float)))))
    if phasor > 1e-2:
        raise MissingSegmentError(
            f"unit {unit}: the arm positions at rest {sorted(arms)} do not cancel a tilted "
            f"spin axis' gravity leak (|mean e^(iφ)| = {phasor:.3g}); they must be spread "
            "evenly around the circle (0°, 90°, 180°, 270°)")
    means, stds, times = [], [], []
    incomplete = []
    for phase in sorted({w.phase for w in rests}):
        mine = [w for w in rests if w.phase == phase]
        got = sorted({w.arm_deg for w in mine})
        if got != sorted(arms):
            incomplete.append(f"{phase or 'rest'}: arm positions {got} of {sorted(arms)}")
            continue
        by_arm = [np.mean([w.mean for w in mine if w.arm_deg == a]) for a in arms]
        se = [math.sqrt(np.mean([w.se**2 for w in mine if w.arm_deg == a])) for a in arms]
        means.append(float(np.mean(by_arm)))
        stds.append(float(np.sqrt(np.sum(np.square(se)))) / len(arms))
        times.append(float(np.mean([w.time_s for w in mine])))
    if not means:
        raise MissingSegmentError(
            f"unit {unit}, configuration {config}: no complete set of rest records at the arm "
            f"positions ({'; '.join(incomplete) or 'none recorded'}); their mean over the "
            "positions is what the spinning outputs are measured from")
    return means, stds, times


def build_series(windows: Mapping[str, Sequence[P3Window]], roles: Mapping[str, str],
                 scales: Mapping[str, AccelerometerScale], earth_rate_up_rps: float, *,
                 drift: bool = False) -> dict[str, Series]:
    """Fit the seven series of (P3.3) from the reduced records (module docstring, step 3).

    Raises
    ------
    MissingSegmentError
        A configuration without records of a unit (the swap or the test load not run).
    InsufficientExcitationError
        A series with fewer than four rates.
    """
    out = {}
    for name, (role, config) in SERIES_SOURCES.items():
        unit = roles[role]
        mine = [w for w in windows[unit] if w.config == config]
        rates = [w for w in mine if w.role == P3_RATE]
        rests = [w for w in mine if w.role == P3_REST]
        if not rates and not rests:
            what = {1: "before the swap", 2: "after the swap of A and B",
                    3: "with the test load"}[config]
            raise MissingSegmentError(
                f"series {name}: unit {unit} has no records in configuration {config} ({what})"
                "; the round-robin needs all three configurations")
        arms = sorted({w.arm_deg for w in windows[unit] if w.role == P3_REST})
        rest_v, rest_s, rest_t = _rest_points(unit, config, rests, arms)
        w = np.array([0.0] * len(rest_v) + [r.rate_rps for r in rates])
        v = np.array(rest_v + [r.mean for r in rates])
        s = np.array(rest_s + [r.se for r in rates])
        sc = scales[unit]
        t = np.array(rest_t + [r.time_s for r in rates])
        out[name] = fit_series(w, v, s, k1=sc.k1, k1_std=sc.k1_std,
                               earth_rate_up_rps=earth_rate_up_rps, time_s=t if drift else None,
                               name=f"{name} ({unit}, configuration {config})")
    return out


@dataclass(frozen=True)
class P3Result(ResultDefaults):
    """The result of P3 for one test accelerometer (docs/p3.md).

    It satisfies :class:`~imucalib.models.procedure_result.ProcedureResult`: no
    ``calibration`` (K2 of the test accelerometer's input axis, :meth:`triad_parameters`),
    ``decision`` on U(K2) against the target (:attr:`decision`).

    Attributes
    ----------
    unit : str
        The test accelerometer's unit.
    roles : mapping of str to str
        ``ref-a``, ``ref-b``, ``test`` → unit.
    estimate : RoundRobinEstimate
        K2_A, K2_B, c, c′, K2_T with covariance; the naive K2_T.
    series : mapping of str to Series
    scales : mapping of str to AccelerometerScale
    windows : tuple of P3Window
    k2_target_g_per_g2 : float
    series_fit : FitQuality or None
        The χ² pooled over the seven series (:func:`~imucalib.procedures.p3.roundrobin.
        scale_for_misfit`).
    notes : tuple of str
    """

    unit: str
    roles: Mapping[str, str]
    estimate: RoundRobinEstimate
    series: Mapping[str, Series]
    scales: Mapping[str, AccelerometerScale]
    windows: tuple[P3Window, ...]
    k2_target_g_per_g2: float
    series_fit: FitQuality | None = None
    notes: tuple[str, ...] = ()
    input_axis: str = "x"
    procedure: str = "p3"

    @property
    def k2_test_g_per_g2(self) -> tuple[float, float]:
        """K2 of the test accelerometer and its σ. [g/g²]"""
        return (self.estimate.value("K2_T") * _G_PER_G2, self.estimate.std("K2_T") * _G_PER_G2)

    @property
    def fit_quality(self) -> tuple[FitQuality, ...]:
        """The round-robin fit's χ²/ν and each series' fit (misfit verdicts)."""
        return (self.estimate.quality, *(s.quality for s in self.series.values()))

    @property
    def decision(self) -> Decision:
        """Pass when U(K2_T) = 2σ (Birge-scaled on a misfit) is within the target.

        One check (:data:`K2_CHECK`) of one row, U against ``k2_target_g_per_g2`` [g/g²], under
        :data:`DECISION_RULE`; the misfits that scaled σ in its notes.
        """
        u = 2.0 * self.k2_test_g_per_g2[1]
        ok = bool(u <= self.k2_target_g_per_g2)
        row = CheckRow("U(K2_T) = 2σ", u, self.k2_target_g_per_g2, "g/g^2", ok,
                       detail=f"K2_T = {self.k2_test_g_per_g2[0]:.3g} g/g²")
        check = Check(K2_CHECK, ok, f"U(K2) = 2σ = {u:.2g} g/g² {'within' if ok else 'beyond'}"
                      f" the target {self.k2_target_g_per_g2:.2g} g/g²", (row,))
        return Decision(passed=ok, rule=DECISION_RULE, failed=() if ok else (K2_CHECK,),
                        checks=(check,),
                        notes=tuple(q.summary() for q in self.fit_quality if q.misfit))

    def parameter_rows(self) -> list[ReportedParameter]:
        """Every estimate, SI: the round-robin's five (P3.3), the naive K2_T, each K1 and K0.

        ``std`` is the σ reported: the round-robin's from its covariance, Birge-scaled by the
        series' misfits (:func:`~imucalib.procedures.p3.roundrobin.scale_for_misfit`) and its
        own; the naive K2_T's from its series' scaled σ; K1's and K0's from the tumble's means
        (with the gravity's Type B σ on K1) or as given. ``std_noise`` is the same σ before
        any Birge scaling: the round-robin's from
        :attr:`~imucalib.procedures.p3.roundrobin.RoundRobinEstimate.covariance_unscaled` (the
        reported estimate's operator on the m's noise-only covariance, K1's Type B σ kept),
        the naive K2_T's from its series' noise-only σ; K1's and K0's are no fit's (equal).
        """
        units_of = {"K2_A": "1/(m/s^2)", "K2_B": "1/(m/s^2)", "K2_T": "1/(m/s^2)",
                    "c": "m/(rad/s)^2", "c_loaded": "m/(rad/s)^2"}
        est = self.estimate
        rows = [ReportedParameter(p, est.value(p), est.std(p), units_of[p], est.std_unscaled(p))
                for p in PARAMETERS]
        rows.append(ReportedParameter("K2_T_naive", est.naive_k2_t, est.naive_k2_t_std,
                                      "1/(m/s^2)", est.naive_k2_t_noise_std))
        for role in _ROLES:
            sc = self.scales[self.roles[role]]
            rows += [ReportedParameter(f"K1_{role}", sc.k1, sc.k1_std, "1", sc.k1_std),
                     ReportedParameter(f"K0_{role}", sc.k0, sc.k0_std, "m/s^2", sc.k0_std)]
        return rows

    def triad_parameters(self) -> TriadParameters:
        """Return K2 of the test accelerometer's input axis as a triad parameter, with its variance.

        Named as :mod:`imucalib.models.result` names it (``accel_K2_x``), for
        :func:`~imucalib.estimation.combine.combine_triad_parameters`; its variance is the reported
        σ² (the ``K2_T`` row of :meth:`parameter_rows`).
        """
        std = self.estimate.std("K2_T")
        return ([f"accel_K2_{self.input_axis}"], np.array([self.estimate.value("K2_T")]),
                np.array([[std * std]]))

    def to_dict(self) -> dict[str, Any]:
        """Return the whole result as JSON-able data."""
        est = self.estimate
        k2, k2_std = self.k2_test_g_per_g2
        return {
            "procedure": self.procedure, "unit": self.unit, "passed": self.passed,
            "decision": self.decision.to_dict(), "roles": dict(self.roles),
            "k2_test_g_per_g2": k2, "k2_test_std_g_per_g2": k2_std,
            "k2_test_naive_g_per_g2": est.naive_k2_t * _G_PER_G2,
            "k2_target_g_per_g2": self.k2_target_g_per_g2,
            "parameters": [r._asdict() for r in self.parameter_rows()],
            "covariance": {"names": list(PARAMETERS), "matrix": est.covariance.tolist(),
                           "noise_only": est.covariance_noise.tolist(),
                           "unscaled": None if est.covariance_unscaled is None
                           else est.covariance_unscaled.tolist()},
            "round_robin_fit": {"chi2": est.quality.chi2, "dof": est.quality.dof,
                                "misfit": est.quality.misfit,
                                "summary": est.quality.summary()},
            "series_fit": None if self.series_fit is None else {
                "chi2": self.series_fit.chi2, "dof": self.series_fit.dof,
                "misfit": self.series_fit.misfit, "summary": self.series_fit.summary()},
            "series": {k: {"m": s.m, "m_std": s.m_std, "m_noise_std": s.m_noise_std,
                           "sigma_scale": s.sigma_scale, "radius_m": s.radius_m,
                           "radius_std_m": s.radius_std_m, "rest_output": s.rest_output,
                           "chi2": s.quality.chi2, "dof": s.quality.dof,
                           "misfit": s.quality.misfit, "radius_used_m": float(r)}
                       for (k, s), r in zip(self.series.items(), est.radii_m, strict=True)},
            "scales": {u: sc.to_dict() for u, sc in self.scales.items()},
            "records": [{"step": w.step_index, "label": w.label, "unit": w.unit,
                         "role": w.role, "config": w.config, "rate_rps": w.rate_rps,
                         "revolutions": w.n_revolutions, "mean_mps2": w.mean,
                         "se_mps2": w.se, "duration_s": w.duration_s}
                        for w in self.windows],
            "notes": list(self.notes),
        }


def _roles(rec: Recording, opt: P3Options, steps: Sequence[Any]) -> dict[str, str]:
    named = p3_unit_names(rec, steps)
    given = {"ref-a": opt.reference_a, "ref-b": opt.reference_b, "test": opt.test}
    roles = {r: given[r] or named.get(r, "") for r in _ROLES}
    missing = [r for r in _ROLES if not roles[r]]
    if missing:
        raise RecordingError(
            f"{rec.path}: which unit is {', '.join(missing)}? The recording's mounting check "
            "does not name them (tags ref-a=, ref-b=, test=); give reference_a, reference_b "
            "and test")
    if len(set(roles.values())) != 3:
        raise InvalidInputError(f"references A, B and the test accelerometer must be three "
                                f"different units; got {roles}")
    return roles


def analyze_p3(recording: Recording | str | os.PathLike[str], *,
               options: P3Options | None = None,
               progress: Callable[[float], None] | None = None) -> P3Result:
    """Analyse a P3 recording (module docstring).

    Raises
    ------
    RecordingError
        Not a P3 recording, units not named, no latitude.
    MissingSegmentError
        A configuration, a rest phase or a tumble pose missing; a record with dropouts or
        short of its revolutions.
    SaturationError
        A record with saturated samples.
    InsufficientExcitationError
        A series with fewer than four rates.
    """
    opt = options or P3Options()
    if isinstance(recording, Recording):
        return _analyze(recording, opt, progress)
    with open_recording(Path(recording)) as rec:
        return _analyze(rec, opt, progress)


def _analyze(rec: Recording, opt: P3Options,
             progress: Callable[[float], None] | None) -> P3Result:
    meta = rec.metadata
    lat = float(meta.get("latitude_deg", math.nan))
    if not math.isfinite(lat):
        raise RecordingError(f"{rec.path} does not record the latitude (latitude_deg): the "
                             "vertical Earth rate needs it")
    site = Site(latitude_deg=lat, gravity_mps2=opt.gravity_mps2)
    g = site.local_gravity_mps2
    g_rel = (opt.gravity_rel_std if opt.gravity_rel_std is not None
             else (0.0 if opt.gravity_mps2 is not None else 2e-5))
    earth_up = float(site.earth_rate_t_rps[2])
    steps = rec.steps
    roles = _roles(rec, opt, steps)
    windows: dict[str, list[P3Window]] = {}
    for i, role in enumerate(_ROLES):
        unit = roles[role]

        def part(f: float, i: int = i) -> None:
            if progress is not None:
                progress((i + f) / 3.0)

        windows[unit] = extract_p3_windows(rec, unit, processing=opt.processing, steps=steps,
                                           progress=part)
    scales: dict[str, AccelerometerScale] = {}
    notes = []
    for role in _ROLES:
        unit = roles[role]
        if unit in opt.k1:
            k1, k1_std = opt.k1[unit]
            k0, k0_std = opt.k0.get(unit, (math.nan, math.nan))
            scales[unit] = AccelerometerScale(unit, float(k1), float(k1_std), float(k0),
                                              float(k0_std), "input")
        else:
            if not any(w.role == P3_TUMBLE for w in windows[unit]):
                raise MissingSegmentError(
                    f"unit {unit}: no tumble records (role {P3_TUMBLE}) and no K1 given: "
                    "record the 1 g tumble or give k1 (value, σ)")
            scales[unit] = tumble_scale(unit, windows[unit], g, g_rel)
    notes.append(f"local gravity {g:.7g} m/s² ({'given' if opt.gravity_mps2 else 'normal'}"
                 f" gravity, relative σ {g_rel:.1g}); vertical Earth rate "
                 f"{earth_up / units.DEG_PER_H:.4g} °/h")
    series = build_series(windows, roles, scales, earth_up, drift=opt.drift)
    radii = None
    if opt.radii == "nominal":
        assert opt.nominal_radii_m is not None
        r_ref, r_t = opt.nominal_radii_m
        radii = {k: (r_t if k == "T3" else r_ref) for k in SERIES_NAMES}
        notes.append(f"nominal radii in (P3.3): references {r_ref:g} m, test {r_t:g} m")
    else:
        notes.append("each series' own effective radius (its ω² coefficient) in (P3.3)")
    series, pooled = scale_for_misfit(series)
    estimate = solve_round_robin(series, radii_m=radii)
    notes += [s.quality.summary() for s in series.values() if s.quality.misfit]
    notes.append(pooled.summary())
    if estimate.quality.misfit:
        notes.append(estimate.quality.summary())
    if progress is not None:
        progress(1.0)
    return P3Result(unit=roles["test"], roles=roles, estimate=estimate, series=series,
                    scales=scales,
                    windows=tuple(w for unit in windows for w in windows[unit]),
                    k2_target_g_per_g2=opt.k2_target_g_per_g2, series_fit=pooled,
                    notes=tuple(notes), input_axis=opt.processing.input_axis)
