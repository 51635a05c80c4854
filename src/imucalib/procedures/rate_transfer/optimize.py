"""The rate transfer's plan optimiser: the rate set and dwell meeting σ targets in the least time.

``imucalib plan optimize rate-transfer`` (docs/test-design.md, "Rate transfer: the optimiser").
The design variables (:class:`RateTransferDesign`), per axis alike:

- the rate set: the base plan's magnitudes; the D-optimal supports of (TD.R1)–(TD.R2) for the
  line, the quadratic, the cubic and the procedure's second fit (RT-7) on the base plan's
  interval |ω| ∈ [ω_min, ω_max] (:func:`~.design.optimal_design`: the Legendre–Lobatto points
  (de la Garza 1954; Guest 1958) where no point falls inside (−ω_min, ω_min), else the
  multiplicative algorithm's optimum (Silvey, Titterington & Torsney 1978)); and 3 to 5
  magnitudes equally spaced on that interval;
- the dwell: whole revolutions per magnitude, either the same count at every rate, or a total
  recording time per axis shared in the D-optimal time fractions of the second fit (RT-7) on
  that support (:func:`~.design.d_optimal_on_grid`), each rounded up to whole revolutions
  (≥ 2, as the plan requires);
- both directions at every magnitude (+ω then −ω, a reversal): the asymmetry (RT-8) needs
  both signs, and a ±ω pair separates the bias from the scale factor at every rate.

Kept from the base plan: the axes, their remounts, the settling, the grade, the twin and its
sample rate, the order of the turns (magnitudes ascending).

The cost is the station time of the plan with the table's moves (:func:`~.design.station_time_s`:
:func:`~imucalib.plan.budget.estimate_plan_recording` — settling, records, remounts — plus
:func:`~.design.move_time_s`: the table accelerates at the plan's ``[limits] max_accel_dps2`` α,
so the change from ω_prev to ω takes |ω − ω_prev|/α, and where that move and the settling
check (``[guards] settle_check_s``) outlast the settle phase the budget counts, the difference is
added). No rate beyond the base plan's largest is proposed: the candidates keep its interval,
within the plan's ``[limits] max_rate_dps`` and the gyro's full scale (checked by the plan
generator).

Each candidate is judged by its prediction (:func:`~.predict.predict_rate_transfer`, Eq. (TD.R4):
the analysis's GLS under the grade's white, flicker and random-walk noise), so the search sees
what the coloured noise does to long turns, which the white-noise D-criterion (TD.R1) does not.
Objective (Eq. (TD.7)): the least station time with every target met, r_i = σ_i/σ_target,i ≤ 1;
with ``--time-budget`` the least worst ratio within it. Candidates are visited in order of
station time (a prediction costs about 0.1 s). A candidate that leaves a targeted parameter
confounded (fewer than three magnitudes: the second fit's terms) never meets its targets; when
no candidate within the budget can identify a targeted parameter the request is refused naming
them (:class:`~imucalib.errors.InsufficientExcitationError`).

Contents
--------
:class:`RateTransferDesign`, :class:`RateTransferCandidate`, :class:`RateTransferOptimum`,
:func:`candidate_designs`, :func:`optimize_rate_transfer`, :func:`optimize_request`;
:func:`~.design.move_time_s` and :func:`~.design.station_time_s` re-exported
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from imucalib.errors import ConfigurationError, InsufficientExcitationError, InvalidInputError
from imucalib.plan.schema import Plan, RateStep
from imucalib.procedures.common.prediction import (
    OptimizedPlan,
    OptimizeRequest,
    Prediction,
    parse_target_text,
)
from imucalib.procedures.rate_transfer.design import (
    MODELS,
    basis,
    d_optimal_on_grid,
    move_time_s,
    optimal_design,
    plan_dwell_design,
    station_time_s,
)
from imucalib.procedures.rate_transfer.plan import generate_rate_transfer_plan
from imucalib.procedures.rate_transfer.predict import predict_rate_transfer
from imucalib.procedures.rate_transfer.roles import RATE_TRANSFER_RATE

__all__ = ["RateTransferCandidate", "RateTransferDesign", "RateTransferOptimum",
           "candidate_designs", "move_time_s", "optimize_rate_transfer", "optimize_request",
           "station_time_s"]

#: A ratio this close to 1 meets its target (the base plan against itself).
_RATIO_TOL = 1e-6
#: Least whole revolutions of a turn (the analysis accepts one fewer at the window edges).
LEAST_REVOLUTIONS = 2
#: Same revolutions at every rate tried.
_EQUAL_REVOLUTIONS = (2, 3, 4, 5, 6, 8, 10, 12, 16, 20, 24, 32)
_EQUAL_REVOLUTIONS_COARSE = (2, 4, 8, 16)
#: Recording time per axis shared in D-optimal fractions, tried. [s]
_TOTALS_S = tuple(float(t) for t in np.geomspace(60.0, 6000.0, 25))
_TOTALS_S_COARSE = tuple(float(t) for t in np.geomspace(60.0, 6000.0, 9))


@dataclass(frozen=True)
class RateTransferDesign:
    """One candidate: rate magnitudes and whole revolutions at each (both signs).

    Attributes
    ----------
    rates_dps : tuple of float
        Magnitudes, ascending; each turned +ω and −ω. [°/s]
    revolutions : tuple of int
        Whole revolutions at each magnitude (both signs alike).
    label : str
        Where the rate set comes from.
    dwell : str
        How the revolutions were chosen.
    """

    rates_dps: tuple[float, ...]
    revolutions: tuple[int, ...]
    label: str
    dwell: str

    def describe(self) -> str:
        """One line: the rates, revolutions and their origin."""
        rates = ", ".join(f"±{r:.4g} ({n})" for r, n in
                          zip(self.rates_dps, self.revolutions, strict=True))
        return f"{self.label}: {rates} °/s (revolutions), {self.dwell}"

    def plan(self, base: Plan, axes: Sequence[str], settle_s: float, grade: str) -> Plan:
        """Return `base`'s plan with this design's rates and revolutions."""
        plan = generate_rate_transfer_plan(rates_dps=self.rates_dps, axes=axes, settle_s=settle_s,
                                           grade=grade, twin=base.twin,
                                           name=f"{base.name}-optimised")
        by_rate = {round(r, 9): n for r, n in zip(self.rates_dps, self.revolutions, strict=True)}
        steps = tuple(s.model_copy(update={"revolutions": by_rate[round(abs(s.rate_dps), 9)]})
                      if isinstance(s, RateStep) and s.role == RATE_TRANSFER_RATE else s
                      for s in plan.steps)
        return plan.model_copy(update={"steps": steps, "limits": base.limits})


@dataclass(frozen=True)
class RateTransferCandidate:
    """A predicted candidate: design, plan, prediction, station time and ratios to targets."""

    design: RateTransferDesign
    plan: Plan
    prediction: Prediction
    station_time_s: float
    ratios: dict[str, float]

    @property
    def worst_ratio(self) -> float:
        """The largest σ/target (∞ where a targeted parameter is confounded)."""
        return max(self.ratios.values())

    @property
    def worst_name(self) -> str:
        """The targeted parameter with the largest ratio."""
        return max(self.ratios, key=lambda n: self.ratios[n])


@dataclass(frozen=True)
class RateTransferOptimum:
    """:func:`optimize_rate_transfer`'s answer: the best candidate and the base plan's."""

    best: RateTransferCandidate
    reference: RateTransferCandidate
    targets: dict[str, float]
    evaluated: int
    notes: tuple[str, ...] = field(default=())


def _fractions(mags: np.ndarray, top: float) -> np.ndarray:
    """Return the D-optimal time fractions of (RT-7) on ±`mags`, per magnitude (summed ±)."""
    u = np.concatenate([-mags[::-1], mags]) / top
    if np.unique(np.round(np.abs(u), 9)).size < 3:
        w = np.full(u.size, 1.0 / u.size)
    else:
        f = basis("transfer", u)
        if np.linalg.matrix_rank(f) < f.shape[1]:
            w = np.full(u.size, 1.0 / u.size)
        else:
            w = d_optimal_on_grid("transfer", u, tol=1e-6)
    n = mags.size
    return np.asarray(w[:n][::-1] + w[n:], dtype=np.float64)


def candidate_designs(base_rates_dps: Sequence[float], base_revolutions: int, *,
                      coarse: bool = False) -> list[RateTransferDesign]:
    """Return every design of the search grid (module docstring).

    Parameters
    ----------
    base_rates_dps : sequence of float
        The base plan's magnitudes: its set, and its interval [ω_min, ω_max]. [°/s]
    base_revolutions : int
        The base plan's revolutions (its own design is one candidate).
    coarse : bool
        Fewer dwell choices.
    """
    mags = np.unique(np.round(np.abs(np.asarray(base_rates_dps, dtype=float)), 9))
    lo, hi = float(mags[0]), float(mags[-1])
    sets: dict[tuple[float, ...], str] = {tuple(float(m) for m in mags): "the base plan's rates"}
    for model in MODELS:
        u, _ = optimal_design(model, lo / hi)
        key = tuple(float(v) for v in np.unique(np.round(np.abs(u) * hi, 6)))
        sets.setdefault(key, f"D-optimal for {model}")
    for n in (3, 4, 5):
        key = tuple(float(v) for v in np.round(np.linspace(lo, hi, n), 6))
        sets.setdefault(key, f"{n} magnitudes equally spaced")
    equal = _EQUAL_REVOLUTIONS_COARSE if coarse else _EQUAL_REVOLUTIONS
    totals = _TOTALS_S_COARSE if coarse else _TOTALS_S
    out: list[RateTransferDesign] = []
    seen: set[tuple[tuple[float, ...], tuple[int, ...]]] = set()

    def add(rates: tuple[float, ...], revs: tuple[int, ...], label: str, dwell: str) -> None:
        if (rates, revs) not in seen:
            seen.add((rates, revs))
            out.append(RateTransferDesign(rates, revs, label, dwell))

    for rates, label in sets.items():
        arr = np.asarray(rates)
        for n in sorted({base_revolutions, *equal}):
            add(rates, (n,) * len(rates), label, f"{n} revolutions at every rate")
        frac = _fractions(arr, hi)
        for total in totals:
            wanted = total * frac * arr / 360.0 / 2.0  # each sign gets half
            revs = tuple(int(v) for v in np.maximum(np.ceil(wanted - 1e-9), LEAST_REVOLUTIONS))
            add(rates, revs, label, "time shared in the D-optimal fractions of (RT-7)")
    return out


def _ratios(prediction: Prediction, targets: Mapping[str, float]) -> dict[str, float]:
    std = prediction.std()
    return {n: (math.inf if std.get(n) is None else float(std[n] or math.inf) / t)
            for n, t in targets.items()}


def optimize_rate_transfer(base: Plan | None = None, *,
                           targets: Mapping[str, float] | None = None,
                           time_budget_s: float | None = None,
                           coarse: bool = False) -> RateTransferOptimum:
    """Return the rate-transfer plan meeting `targets` in the least station time (module docstring).

    Parameters
    ----------
    base : Plan, optional
        The plan whose rates and dwell are chosen (its axes, settling, grade and twin kept); the
        default rate-transfer plan when omitted.
    targets : mapping of str to float, optional
        σ_target per parameter (SI, the result's names); every parameter the base plan
        identifies no worse than its σ when omitted.
    time_budget_s : float, optional
        Station time allowed: the least worst ratio within it instead of the least time. [s]
    coarse : bool
        A smaller dwell grid.

    Raises
    ------
    ConfigurationError
        A plan of another procedure or without turns, a budget no design fits, a target on a
        parameter the procedure does not report.
    InsufficientExcitationError
        No design (within the budget) identifies a targeted parameter: they are named.
    InvalidInputError
        Targets no design meets (with the best worst ratio reached).
    """
    base = base or generate_rate_transfer_plan()
    if base.procedure and base.procedure != "rate-transfer":
        raise ConfigurationError(f"plan {base.name!r} is a {base.procedure} plan, not a "
                                 "rate-transfer plan")
    if time_budget_s is not None and not time_budget_s > 0:
        raise ConfigurationError(f"--time-budget must be > 0; got {time_budget_s}")
    rates, _, _ = plan_dwell_design(base)
    turns = [s for s in base.steps if isinstance(s, RateStep) and s.role == RATE_TRANSFER_RATE]
    axes = tuple(dict.fromkeys(t.split("=", 1)[1] for s in turns for t in s.tags
                               if t.startswith("axis=")))
    settle = turns[0].settle_s
    base_revs = int(turns[0].revolutions or LEAST_REVOLUTIONS)
    from imucalib.procedures.common.grade import plan_grade

    grade = plan_grade(base)
    ref_pred = predict_rate_transfer(base)
    names = [p.name for p in ref_pred.parameters]
    if targets is None:
        targets = {n: s for n, s in ref_pred.std().items() if s is not None}
        if not targets:
            raise InsufficientExcitationError(list(ref_pred.confounded), (
                f"the base plan {base.name!r} identifies no parameter "
                f"(confounded: {', '.join(ref_pred.confounded)}): give --target"))
    unknown = [n for n in targets if n not in names]
    if unknown:
        raise ConfigurationError(f"target(s) {', '.join(unknown[:4])} name no rate-transfer "
                                 f"parameter of this plan (e.g. {', '.join(names[:2])})")
    targets = dict(targets)
    reference = RateTransferCandidate(
        RateTransferDesign(tuple(float(r) for r in np.unique(np.round(np.abs(rates), 9))),
                           (base_revs,) * np.unique(np.round(np.abs(rates), 9)).size,
                           "the base plan", f"{base_revs} revolutions at every rate"),
        base, ref_pred, station_time_s(base), _ratios(ref_pred, targets))
    timed: list[tuple[float, RateTransferDesign, Plan]] = []
    for d in candidate_designs(rates.tolist(), base_revs, coarse=coarse):
        plan = d.plan(base, axes, settle, grade)
        timed.append((station_time_s(plan), d, plan))
    timed.sort(key=lambda x: x[0])
    if time_budget_s is not None:
        shortest = timed[0][0]
        timed = [x for x in timed if x[0] <= time_budget_s]
        if not timed:
            raise ConfigurationError(f"no rate-transfer design fits --time-budget "
                                     f"{time_budget_s / 3600:.3g} h (the shortest needs "
                                     f"{shortest / 3600:.3g} h)")
    best: RateTransferCandidate | None = None
    closest: RateTransferCandidate | None = None
    identified: set[str] = set()
    evaluated = 0
    for t, design, plan in timed:
        pred = predict_rate_transfer(plan)
        evaluated += 1
        cand = RateTransferCandidate(design, plan, pred, t, _ratios(pred, targets))
        identified |= {n for n, r in cand.ratios.items() if math.isfinite(r)}
        if closest is None or cand.worst_ratio < closest.worst_ratio:
            closest = cand
        if time_budget_s is None:
            if cand.worst_ratio <= 1.0 + _RATIO_TOL:
                best = cand
                break
        elif best is None or cand.worst_ratio < best.worst_ratio:
            best = cand
    never = [n for n in targets if n not in identified]
    if never:
        within = "" if time_budget_s is None else (
            f" within --time-budget {time_budget_s / 3600:.3g} h")
        raise InsufficientExcitationError(never, (
            f"no rate-transfer design{within} identifies {', '.join(never)}: confounded "
            "(the second fit (RT-7) needs ≥ 3 rate magnitudes of both signs); allow more time "
            "or drop those targets"))
    if best is None or not math.isfinite(best.worst_ratio):
        assert closest is not None
        raise InvalidInputError(
            f"no rate-transfer design of the grid meets the targets: the best worst σ/target is "
            f"{closest.worst_ratio:.3g} ({closest.worst_name}); relax the targets or allow more "
            "time")
    notes = (
        f"searched {evaluated} of {len(timed)} designs in order of station time (the table's "
        f"moves at {base.limits.max_accel_dps2:g} °/s² included); σ predicted under the grade "
        f"{grade}'s white, flicker and random-walk noise (TD.R4)",
        f"kept: the axes ({', '.join(axes)}), their remounts, settling {settle:g} s, both "
        "directions at every rate, the twin",
    )
    return RateTransferOptimum(best=best, reference=reference, targets=targets,
                               evaluated=evaluated, notes=notes)


def optimize_request(request: OptimizeRequest) -> OptimizedPlan:
    """Answer ``imucalib plan optimize rate-transfer`` with :func:`optimize_rate_transfer`.

    P1's margins of the request (``min_repetitions``, ``min_static_s``,
    ``min_lack_of_fit_dof``) have no meaning for the rate transfer and are not used.

    Raises
    ------
    ConfigurationError
        An unknown grade; ``--target-from-spec`` (the default plan states no gyro scale-factor
        limit); ``--criterion`` D or A (one line each).
    InsufficientExcitationError, InvalidInputError
        As :func:`optimize_rate_transfer`.
    """
    if request.grade not in ("consumer", "tactical", "navigation"):
        raise ConfigurationError(f"--grade must be consumer, tactical or navigation; got "
                                 f"{request.grade!r}")
    if request.criterion != "targets":
        raise ConfigurationError(f"--criterion {request.criterion} is not available for the rate "
                                 "transfer (it judges σ per parameter): use the targets")
    if request.targets == "spec":
        raise ConfigurationError("--target-from-spec is not available for the rate transfer: its "
                                 "plan states no [imu.limits] gyro_scale_ppm; use --target "
                                 "gyro_M=σ (or --target-default)")
    base = generate_rate_transfer_plan(grade=request.grade)
    targets = None
    if request.targets == "given":
        names = [p.name for p in predict_rate_transfer(base).parameters]
        targets = parse_target_text(request.target_text, names, "rate-transfer")
    result = optimize_rate_transfer(base, targets=targets, time_budget_s=request.time_budget_s,
                                    coarse=request.coarse)
    best, ref = result.best, result.reference
    return OptimizedPlan(
        plan=best.plan, prediction=best.prediction, reference=ref.prediction,
        targets=dict(result.targets), ratios=dict(best.ratios), worst_ratio=best.worst_ratio,
        reference_worst_ratio=ref.worst_ratio, criterion="targets",
        design=best.design.describe(), notes=result.notes)
