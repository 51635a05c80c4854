"""P2's plan optimiser: the temperature points and dwell meeting σ targets in the least time.

:func:`optimize_p2` searches P2's design variables (:class:`P2Design`: the number of
calibration temperature points K and their placement within the range, the static record per
pose and the revolutions per turn) and judges each candidate with
:func:`~imucalib.procedures.p2.predict.predict_p2_detail` (Eqs. (TD.P1)–(TD.P3)). Its cost is
the station time with the chamber's ramps (at the plan's ramp, within the chamber's limit),
the units' approach to each setpoint, the soaks, re-soaks, settling and moves
(:func:`~imucalib.plan.budget.plan_run_duration_s`). Placements of K points on [T_lo, T_hi],
with T = (T_lo + T_hi)/2 + (T_hi − T_lo)/2·x:

    equal:      x_j = −1 + 2j/(K − 1)                                            (TD.P4)
    Chebyshev:  x_j = −cos(π·j/(K − 1))          (Chebyshev–Gauss–Lobatto)        (TD.P5)
    Lobatto:    x_j ∈ {−1, +1} ∪ {roots of P′_{K−1}(x)}  (Legendre–Gauss–Lobatto) (TD.P6)

The Legendre–Gauss–Lobatto points are the D-optimal design of a polynomial of degree K − 1
on an interval (Guest 1958; de la Garza 1954, as the rate transfer's (TD.R1)–(TD.R2)); the
Chebyshev points minimise the largest prediction variance's growth towards the ends.

Kept fixed (choices of the procedure or the station, not of the design): the pose order
(temperature-major: six remounts at every point), the turns' rate, the settling, the soak
criteria (band, stability time, re-soak), the chamber's ramp, the held-out points and the
hysteresis sweep. P2's plan has no repetitions: a longer dwell per pose is its repetition.
Margins: K ≥ q + 2 (AICc can choose the assumed order, :func:`~.predict.min_points`), a
placement that keeps clear of the held-out points (0.5 °C).

Objectives (docs/test-design.md, "P2: temperature points"): without a budget the least station
time with every target met, r_i = σ_i/σ_target,i ≤ 1 (Eq. (TD.7)); with a budget the least
worst ratio (``"targets"``), log det (``"D"``, (TD.5)) or trace (``"A"``, (TD.6)) of the
covariance normalised by the targets. The search is exhaustive over the grid, candidates
visited in order of station time (a prediction costs about 0.1 s).

Contents
--------
:class:`P2Design`, :class:`OptimizeSettingsP2`, :class:`P2Candidate`, :class:`P2OptimizeResult`,
:func:`placement`, :func:`optimize_p2`, :func:`optimize_request`, :func:`parse_targets_p2`
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from imucalib.errors import ConfigurationError, InvalidInputError
from imucalib.models.noise import NoiseModel
from imucalib.plan.budget import estimate_plan_recording
from imucalib.plan.schema import Plan
from imucalib.procedures.common.prediction import (
    OptimizedPlan,
    OptimizeRequest,
    Prediction,
    parse_target_text,
)
from imucalib.procedures.p2.options import P2PlanOptions
from imucalib.procedures.p2.plan import generate_p2_plan
from imucalib.procedures.p2.predict import (
    CRITERION_LABEL,
    DEFAULT_ORDER,
    Criterion,
    P2PredictionDetail,
    min_points,
    predict_p2_detail,
)
from imucalib.procedures.p2.reduction import PARAM_NAMES

__all__ = ["OptimizeSettingsP2", "P2Candidate", "P2Design", "P2OptimizeResult",
           "optimize_p2", "optimize_request", "parse_targets_p2", "placement"]

Spacing = Literal["base", "equal", "chebyshev", "lobatto"]
#: A ratio this close to 1 meets its target (the default plan against itself).
_RATIO_TOL = 1e-6
#: Least distance of a calibration point from a held-out point. [°C]
_HELD_OUT_CLEARANCE_DEGC = 0.5
_SPACING_LABEL = {"base": "the base plan's", "equal": "equally spaced",
                  "chebyshev": "Chebyshev–Lobatto", "lobatto": "Legendre–Lobatto"}


def placement(spacing: str, n_points: int, low_degc: float, high_degc: float
              ) -> tuple[float, ...]:
    """Return `n_points` temperatures on [low, high] by Eqs. (TD.P4)–(TD.P6), rounded to 0.1 °C.

    Raises
    ------
    ConfigurationError
        Fewer than two points, an empty range or an unknown spacing.
    """
    if n_points < 2 or not high_degc > low_degc:
        raise ConfigurationError(f"a placement needs ≥ 2 points on a range; got {n_points} on "
                                 f"[{low_degc:g}, {high_degc:g}] °C")
    j = np.arange(n_points)
    if spacing == "equal":
        x = -1.0 + 2.0 * j / (n_points - 1)
    elif spacing == "chebyshev":
        x = -np.cos(np.pi * j / (n_points - 1))
    elif spacing == "lobatto":
        inner = np.polynomial.legendre.Legendre.basis(n_points - 1).deriv().roots()
        x = np.concatenate([[-1.0], np.sort(np.real(inner)), [1.0]])
    else:
        raise ConfigurationError(f"spacing must be equal, chebyshev or lobatto; got {spacing!r}")
    mid, half = 0.5 * (low_degc + high_degc), 0.5 * (high_degc - low_degc)
    return tuple(float(round(mid + half * v, 1)) for v in x)


@dataclass(frozen=True)
class P2Design:
    """The design variables the optimiser chooses (fields of :class:`~.options.P2PlanOptions`).

    Attributes
    ----------
    temperatures_degc : tuple of float
        Calibration points. [°C]
    spacing : str
        How they were placed (``"base"``: the base plan's own).
    static_s : float
        Each static record. [s]
    revolutions : int
        Whole revolutions per turn.
    """

    temperatures_degc: tuple[float, ...]
    spacing: str
    static_s: float
    revolutions: int

    def options(self, base: P2PlanOptions) -> P2PlanOptions:
        """Return `base` with this design's variables."""
        return dataclasses.replace(base, temperatures_degc=self.temperatures_degc,
                                   static_s=self.static_s, revolutions=self.revolutions)

    def describe(self) -> str:
        """One line: the points, their placement, the dwell."""
        temps = ", ".join(f"{t:g}" for t in self.temperatures_degc)
        return (f"{len(self.temperatures_degc)} points ({_SPACING_LABEL[self.spacing]}: {temps}"
                f" °C), static {self.static_s:g} s, {self.revolutions} revolutions per turn")


@dataclass(frozen=True)
class OptimizeSettingsP2:
    """The search's objective, grid and margins (module docstring).

    Attributes
    ----------
    criterion : {"targets", "D", "A"}
    time_budget_s : float, optional
        Station time allowed; without it, the least time meeting every target. [s]
    order : int
        The temperature models' assumed order (the analysis's ``max_order``).
    order_criterion : {"aicc", "cv", "fixed"}
        How the analysis will choose the order (the least K, :func:`~.predict.min_points`).
    max_points : int
        The most calibration points tried.
    spacings : tuple of str
        Placements tried (besides the base plan's own points).
    static_s_grid : tuple of float
        Static records tried. [s]
    revolutions_grid : tuple of int
        Revolutions per turn tried.
    temperature_std_degc : float, optional
        σ_T of (TD.P3) (None: the plan's band/√12).
    noise : mapping of str to NoiseModel, optional
        ``{"accel": …, "gyro": …}`` instead of the grade's.
    """

    criterion: Literal["targets", "D", "A"] = "targets"
    time_budget_s: float | None = None
    order: int = DEFAULT_ORDER
    order_criterion: Criterion = "aicc"
    max_points: int = 9
    spacings: tuple[str, ...] = ("equal", "chebyshev", "lobatto")
    static_s_grid: tuple[float, ...] = (10.0, 15.0, 20.0, 30.0, 45.0, 60.0, 90.0, 120.0)
    revolutions_grid: tuple[int, ...] = (2, 3, 4, 5, 6, 8)
    temperature_std_degc: float | None = None
    noise: Mapping[str, NoiseModel] | None = None

    def __post_init__(self) -> None:
        if self.criterion not in ("targets", "D", "A"):
            raise ConfigurationError(f"--criterion must be targets, D or A; got "
                                     f"{self.criterion!r}")
        if self.criterion != "targets" and self.time_budget_s is None:
            raise ConfigurationError(f"--criterion {self.criterion} needs --time-budget (the "
                                     "least time is judged by the targets)")
        if self.time_budget_s is not None and not self.time_budget_s > 0:
            raise ConfigurationError(f"--time-budget must be > 0; got {self.time_budget_s}")
        if not self.static_s_grid or not self.revolutions_grid or not self.spacings:
            raise ConfigurationError("the search grid is empty")

    @classmethod
    def coarse(cls, **kwargs: object) -> OptimizeSettingsP2:
        """Return a smaller grid: Lobatto and equal spacing, 3 records, 3 revolution counts."""
        grid: dict[str, object] = dict(spacings=("equal", "lobatto"),
                                       static_s_grid=(10.0, 30.0, 60.0),
                                       revolutions_grid=(2, 4, 6))
        grid.update(kwargs)
        return cls(**grid)  # type: ignore[arg-type]


@dataclass(frozen=True)
class P2Candidate:
    """One predicted candidate: its design, plan, prediction and ratios to the targets."""

    design: P2Design
    plan: Plan
    detail: P2PredictionDetail
    ratios: dict[str, float]
    worst_ratio: float
    score: float

    @property
    def station_time_s(self) -> float:
        """Station time of the plan. [s]"""
        return self.detail.prediction.station_time_s

    @property
    def prediction(self) -> Prediction:
        """The candidate's prediction."""
        return self.detail.prediction

    @property
    def worst_name(self) -> str:
        """The coefficient with the largest ratio."""
        return max(self.ratios, key=lambda n: self.ratios[n]) if self.ratios else ""

    def describe(self) -> str:
        """Return the design in one line."""
        return self.design.describe()


@dataclass(frozen=True)
class P2OptimizeResult:
    """:func:`optimize_p2`'s answer: the best candidate, the default's, what was searched."""

    best: P2Candidate
    reference: P2Candidate
    targets: dict[str, float]
    settings: OptimizeSettingsP2
    evaluated: int
    notes: tuple[str, ...] = field(default=())


def default_target_names(detail: P2PredictionDetail) -> tuple[str, ...]:
    """Return the default targets: each parameter at T0 (c_0) and over the range.

    The value at T0 (the result's parameter) and the largest σ of the model's value over the
    calibration range (``<name>_range``) do not depend on the basis the polynomial is written
    in; the monomial coefficients c_j about T0 do (a placement that serves the curve well can
    serve c_3 about 25 °C worse), so they are targets only when named (``--target``).
    """
    del detail  # the same names for every design
    return (*PARAM_NAMES, *(f"{n}_range" for n in PARAM_NAMES))


def _score(detail: P2PredictionDetail, targets: Mapping[str, float], criterion: str,
           ratios: Mapping[str, float]) -> float:
    """Return the criterion: worst ratio (TD.7), log det (TD.5) or trace (TD.6), normalised."""
    if criterion == "targets":
        return max(ratios.values())
    idx = [i for i, n in enumerate(detail.names) if n in targets]
    if not idx:
        raise InvalidInputError(f"--criterion {criterion} needs targets on model coefficients "
                                "(c_0 … c_m), not only on the range σ")
    s = np.array([targets[detail.names[i]] for i in idx])
    p = detail.covariance[np.ix_(idx, idx)] / np.outer(s, s)
    if criterion == "A":
        return float(np.trace(p))
    sign, logdet = np.linalg.slogdet(p)
    return float(logdet) if sign > 0 else math.inf


def _ratios(detail: P2PredictionDetail, targets: Mapping[str, float]) -> dict[str, float]:
    std = detail.prediction.std()
    return {n: (math.inf if std.get(n) is None else float(std[n]) / t)  # type: ignore[arg-type]
            for n, t in targets.items()}


def _designs(base: P2PlanOptions, settings: OptimizeSettingsP2, n_extra: int
             ) -> list[P2Design]:
    """Every design of the grid whose points keep clear of the held-out points."""
    lo, hi = min(base.temperatures_degc), max(base.temperatures_degc)
    least = min_points(settings.order, settings.order_criterion, n_extra)
    out = [P2Design(tuple(base.temperatures_degc), "base", s, r)
           for s in settings.static_s_grid for r in settings.revolutions_grid]
    for k in range(least, settings.max_points + 1):
        for spacing in settings.spacings:
            temps = placement(spacing, k, lo, hi)
            if any(abs(t - h) < _HELD_OUT_CLEARANCE_DEGC for t in temps
                   for h in base.held_out_degc):
                continue
            if spacing != "equal" and temps == placement("equal", k, lo, hi):
                continue
            out += [P2Design(temps, spacing, s, r)
                     for s in settings.static_s_grid for r in settings.revolutions_grid]
    return out


def optimize_p2(base: P2PlanOptions | None = None, *,
                targets: Mapping[str, float] | None = None,
                settings: OptimizeSettingsP2 | None = None) -> P2OptimizeResult:
    """Return the P2 plan meeting `targets` in the least station time (module docstring).

    Parameters
    ----------
    base : P2PlanOptions, optional
        The plan whose points and dwell are chosen (its range, held-out points, soaks, grade,
        units); P2's default plan when omitted.
    targets : mapping of str to float, optional
        σ_target per coefficient (SI, :func:`~.predict.coefficient_names`); each coefficient of
        the base plan's prediction no worse than it when omitted.
    settings : OptimizeSettingsP2, optional

    Raises
    ------
    ConfigurationError
        An order the search's points cannot determine (one line), a budget no design fits.
    InvalidInputError
        Targets no design meets (with the best worst ratio reached) or that name a coefficient
        the base plan does not determine.
    """
    base = base or P2PlanOptions()
    settings = settings or OptimizeSettingsP2()
    hyst = 1 if base.hysteresis else 0
    least = min_points(settings.order, settings.order_criterion, hyst)
    if least > settings.max_points:
        raise ConfigurationError(
            f"a temperature model of order {settings.order} needs at least {least} calibration "
            f"points ({CRITERION_LABEL[settings.order_criterion]}); the search tries at most "
            f"{settings.max_points}: lower the order or allow more points")

    def predict(design: P2Design) -> tuple[Plan, P2PredictionDetail]:
        plan = generate_p2_plan(**_kwargs(design.options(base)))
        return plan, predict_p2_detail(plan, noise=settings.noise, order=settings.order,
                                       criterion=settings.order_criterion,
                                       temperature_std_degc=settings.temperature_std_degc)

    ref_design = P2Design(tuple(base.temperatures_degc), "base", base.static_s,
                          base.revolutions)
    ref_plan, ref_detail = predict(ref_design)
    if targets is None:
        if ref_detail.prediction.confounded:
            raise InvalidInputError(
                f"the base plan determines no order-{settings.order} models "
                f"({len(base.temperatures_degc)} points; "
                f"{CRITERION_LABEL[settings.order_criterion]} needs {least}): give --target or "
                "more points")
        targets = {n: s for n, s in ref_detail.prediction.std().items()
                   if s is not None and n in default_target_names(ref_detail)}
    known = set(ref_detail.names) | {f"{n}_range" for n in ref_detail.range_std}
    unknown = [n for n in targets if n not in known]
    if unknown:
        raise InvalidInputError(f"target(s) {', '.join(unknown[:4])} name no coefficient the "
                                f"order-{settings.order} models determine")
    targets = dict(targets)
    ref_ratios = _ratios(ref_detail, targets)
    reference = P2Candidate(ref_design, ref_plan, ref_detail, ref_ratios,
                            max(ref_ratios.values()),
                            _score(ref_detail, targets, settings.criterion, ref_ratios))
    # station time first (cheap), then predictions in order of it
    timed = []
    for d in _designs(base, settings, hyst):
        plan = generate_p2_plan(**_kwargs(d.options(base)))
        timed.append((estimate_plan_recording(plan).duration_s, d))
    timed.sort(key=lambda x: (x[0], x[1].spacing))
    budget = settings.time_budget_s
    if budget is not None:
        shortest = timed[0][0] if timed else math.inf
        timed = [x for x in timed if x[0] <= budget]
        if not timed:
            raise ConfigurationError(f"no P2 design fits --time-budget {budget / 3600:.3g} h "
                                     f"(the shortest needs {shortest / 3600:.3g} h)")
    best: P2Candidate | None = None
    closest: P2Candidate | None = None
    evaluated = 0
    for _, design in timed:
        plan, detail = predict(design)
        evaluated += 1
        ratios = _ratios(detail, targets)
        worst = max(ratios.values())
        cand = P2Candidate(design, plan, detail, ratios, worst,
                           _score(detail, targets, settings.criterion, ratios))
        if closest is None or worst < closest.worst_ratio:
            closest = cand
        if budget is None:
            if worst <= 1.0 + _RATIO_TOL:
                best = cand
                break
        elif best is None or cand.score < best.score:
            best = cand
    if best is None:
        reached = closest.worst_ratio if closest is not None else math.inf
        raise InvalidInputError(
            f"no P2 design of the grid meets the targets: the best worst σ/target is "
            f"{reached:.3g} ({closest.worst_name if closest else '?'}); relax the targets or "
            "allow more points")
    notes = (
        f"searched {evaluated} of {len(timed)} designs in order of station time: "
        f"{CRITERION_LABEL[settings.order_criterion]} order-{settings.order} models need ≥ {least} "
        f"points; at most {settings.max_points}",
        "kept: the pose order, the turns' rate, settling, soak criteria, the chamber ramp "
        f"({base.ramp_degc_per_min:g} °C/min), the held-out points "
        f"({', '.join(f'{t:g}' for t in base.held_out_degc)} °C) and the sweep; P2 has no "
        "repetitions (the dwell per pose is its repetition)",
    )
    return P2OptimizeResult(best=best, reference=reference, targets=targets, settings=settings,
                            evaluated=evaluated, notes=notes)


def _suffix(name: str) -> tuple[str, str]:
    """Split a coefficient's name into (parameter, ``_c<j>``/``_leg`` or ``""``)."""
    m = re.match(r"^(.*?)(_c\d|_leg)?$", name)
    assert m is not None
    return m.group(1), m.group(2) or ""


def parse_targets_p2(text: str, names: Sequence[str]) -> dict[str, float]:
    """Parse ``NAME=σ,…`` for P2: NAME a coefficient, or a prefix with the same coefficient.

    ``gyro_bias=1e-5`` targets the gyro biases at T0 (c_0), ``gyro_bias_c1=1e-7`` their
    linear coefficients (SI per K), ``accel_M_xx_c3=…`` one coefficient.

    Raises
    ------
    ConfigurationError
        A malformed item or a name no coefficient matches (one line).
    """
    out: dict[str, float] = {}
    for item in (t.strip() for t in text.split(",")):
        if not item:
            continue
        key, sep, value = item.partition("=")
        stem, suffix = _suffix(key.strip())
        same = [n for n in names if _suffix(n)[1] == suffix]
        bases = {_suffix(n)[0]: n for n in same}
        found = parse_target_text(f"{stem}{sep}{value}", list(bases), "P2")
        out.update({bases[b]: v for b, v in found.items()})
    if not out:
        raise ConfigurationError("--target names no parameter")
    return out


def _kwargs(options: P2PlanOptions) -> dict[str, Any]:
    return {f.name: getattr(options, f.name) for f in dataclasses.fields(options)}


def optimize_request(request: OptimizeRequest) -> OptimizedPlan:
    """Answer ``imucalib plan optimize p2``: targets and settings, then :func:`optimize_p2`.

    P1's margins of the request (``min_repetitions``, ``min_static_s``,
    ``min_lack_of_fit_dof``) have no meaning for P2 and are not used.

    Raises
    ------
    ConfigurationError
        An unknown grade, ``--target-from-spec`` (P2's specification limits the compensated
        output, not a coefficient), settings :class:`OptimizeSettingsP2` refuses.
    InvalidInputError
        Targets that name no coefficient, or that no design meets.
    """
    if request.grade not in ("consumer", "tactical", "navigation"):
        raise ConfigurationError(f"--grade must be consumer, tactical or navigation; got "
                                 f"{request.grade!r}")
    if request.targets == "spec":
        raise ConfigurationError("--target-from-spec is not available for P2 (its specification "
                                 "limits the compensated output, not a model coefficient): "
                                 "use --target-default or --target")
    base = P2PlanOptions(grade=request.grade)  # type: ignore[arg-type]
    make = OptimizeSettingsP2.coarse if request.coarse else OptimizeSettingsP2
    settings = make(criterion=request.criterion,  # type: ignore[arg-type]  # checked there
                    time_budget_s=request.time_budget_s)
    targets = None
    if request.targets == "given":
        ref = predict_p2_detail(generate_p2_plan(**_kwargs(base)), order=settings.order)
        targets = parse_targets_p2(request.target_text, ref.names)
    result = optimize_p2(base, targets=targets, settings=settings)
    best, ref_c = result.best, result.reference
    return OptimizedPlan(
        plan=best.plan, prediction=best.prediction, reference=ref_c.prediction,
        targets=dict(result.targets), ratios=dict(best.ratios), worst_ratio=best.worst_ratio,
        reference_worst_ratio=ref_c.worst_ratio, criterion=settings.criterion,
        design=best.describe(), notes=result.notes)
