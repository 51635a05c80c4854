"""P1's plan optimiser: the plan that meets σ targets in the least station time (issue 30).

:func:`optimize_p1` searches P1's design variables (:class:`P1Design`: repetitions, record at
each position, level static record, revolutions per rate point, the calibration rate set) and
judges each candidate with :func:`~imucalib.procedures.p1.predict.predict_p1` (Eqs. (TD.1)–
(TD.4)). The station's limits are not choices: settling (``settle_s``, ``rate_settle_s``) stays
at the procedure's minimums, the warm-up at the grade's, moves and ramps are priced by
:func:`~imucalib.plan.budget.estimate_plan_recording`, rates stay within the table's limit.

Objectives (docs/test-design.md, "The optimiser (P1)"):

- ``criterion="targets"`` without a budget: the least station time with every target met,
  r_i = σ_i / σ_target,i ≤ 1 (Eq. (TD.7));
- with ``time_budget_s``: the least worst ratio max_i r_i (``"targets"``), the least
  log det of the normalised covariance (``"D"``, Eq. (TD.5)) or its trace (``"A"``, Eq. (TD.6))
  within the budget.

Search (deterministic): the station time is linear in the static record (each repetition has
one), t = t₀ + n_rep·(s − s₀), so for every (repetitions, record, revolutions) the static is a
1-D choice: within a budget, the longest that fits; for the least time, the shortest that meets
the targets (bisection to :attr:`OptimizeSettings.static_tolerance_s`, the σ falling as the static
grows). Grid states are visited in order of their least time and skipped when they cannot beat
the best so far; the best state's rate set is then varied. Margins kept beyond the optimum
(:class:`OptimizeSettings`): at least three repetitions (the repeatability check, docs/p1.md
rule 6), the base plan's held-out rates and positions with their lengths (verification), a
least lack-of-fit ν per triad, the Z rate points (identifiability) and a least static record.
A design may run its last repetition's parts in reverse order (the six positions close the
run): every step is kept, and under flicker the biases gain from their windows' span.

Contents
--------
:class:`P1Design`, :class:`OptimizeSettings`, :class:`Candidate`, :class:`OptimizeResult`,
:func:`optimize_p1`, :func:`default_targets`, :func:`spec_targets`, :func:`parse_targets`
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from imucalib.errors import ConfigurationError, InsufficientExcitationError
from imucalib.models.noise import NoiseModel
from imucalib.plan.budget import estimate_plan_recording
from imucalib.plan.schema import Plan
from imucalib.procedures.common.grade import declared_noise
from imucalib.procedures.common.prediction import (
    OptimizedPlan,
    OptimizeRequest,
    Prediction,
    parse_target_text,
)
from imucalib.procedures.p1.options import P1PlanOptions
from imucalib.procedures.p1.plan import generate_p1_plan
from imucalib.procedures.p1.predict import predict_p1_covariance
from imucalib.procedures.p1.roles import P1_ACCEL_POSITION, P1_GYRO_BIAS, P1_GYRO_RATE

__all__ = ["Candidate", "OptimizeResult", "OptimizeSettings", "P1Design", "default_targets",
           "optimize_p1", "parse_targets", "spec_targets"]

Criterion = Literal["targets", "D", "A"]
#: A grid state: repetitions, rate set, revolutions, position record [s], last repetition
#: reversed (the static record is chosen within it).
_State = tuple[int, tuple[float, ...], int, float, bool]
#: The default k of ``--target-from-spec``: σ ≤ limit / k (Eq. (TD.8)).
SPEC_K = 3.0
#: A ratio this close to 1 meets its target (the default plan against itself).
_RATIO_TOL = 1e-6


@dataclass(frozen=True)
class P1Design:
    """The design variables the optimiser chooses (fields of :class:`~.options.P1PlanOptions`).

    Attributes
    ----------
    repetitions : int
        Complete calibrations.
    rates_dps : tuple of float
        Calibration rate points per axis (both signs and 0). [°/s]
    revolutions : int
        Whole turns at each non-zero rate.
    record_s : float
        Record at each position. [s]
    static_s : float
        The level static record of each repetition. [s]
    reverse_last : bool
        The last repetition's parts in reverse order (the six positions close the run;
        :func:`~imucalib.procedures.p1.plan.generate_p1_plan`).
    """

    repetitions: int
    rates_dps: tuple[float, ...]
    revolutions: int
    record_s: float
    static_s: float
    reverse_last: bool = False

    def options(self, base: P1PlanOptions) -> P1PlanOptions:
        """Return `base` with this design's variables.

        The held-out points keep `base`'s lengths (its ``held_out_record_s`` and
        ``held_out_revolutions``, else its ``record_s`` and ``revolutions``): the verification
        is the base plan's, whatever the calibration windows' lengths.
        """
        held_turns = (base.revolutions if base.held_out_revolutions is None
                      else base.held_out_revolutions)
        held_record = base.record_s if base.held_out_record_s is None else base.held_out_record_s
        return dataclasses.replace(base, repetitions=self.repetitions, rates_dps=self.rates_dps,
                                   revolutions=self.revolutions, record_s=self.record_s,
                                   static_s=self.static_s, reverse_last=self.reverse_last,
                                   held_out_revolutions=held_turns,
                                   held_out_record_s=held_record)


@dataclass(frozen=True)
class OptimizeSettings:
    """The search's objective, grid and robustness margins (docs/test-design.md).

    Attributes
    ----------
    criterion : {"targets", "D", "A"}
        Every target met (the default), or, within `time_budget_s`, D (Eq. (TD.5)) or A
        (Eq. (TD.6)) on the parameters normalised by their targets.
    time_budget_s : float, optional
        Station time allowed; without it, the least time meeting every target. [s]
    min_repetitions : int
        Margin: complete calibrations kept (docs/p1.md rule 6 asks for three; 2 is the least
        with which the repeatability check can be made at all).
    max_repetitions : int
        The largest number of repetitions tried.
    min_static_s, max_static_s : float
        The static record's range. The least is by default the procedure's 60 min
        (docs/p1.md, step 2), from which the analysis fits the whole noise model of every
        window mean's σ. A record of minutes cannot show the flicker floor: the analysis then
        takes the grade's flicker and random walk as a Type B input (docs/p1.md, "Noise model
        of the window means"), the noise the prediction assumes, so a plan with a static down
        to 120 s (the shortest the analysis fits) is calibrated with its predicted σ
        (docs/test-design.md, "Truth on the twin") — but its biases' σ rest on the grade's
        declared noise, not on the unit's own record. [s]
    static_tolerance_s : float
        The 1-D search's resolution on the static record. [s]
    min_lack_of_fit_dof : int
        Margin: least ν = 3·windows − parameters of each triad's fit, to detect a misfit.
    record_s_grid : tuple of float
        Position records tried (≥ 10 s, the procedure's minimum). [s]
    revolutions_grid : tuple of int
        Revolutions tried.
    reverse_last_grid : tuple of bool
        Step orders tried: the procedure's (False) and the last repetition reversed (True).
    rate_magnitudes_dps : tuple of float
        Magnitudes the 5-point rate sets (0, ±a, ±b) are built from, within `max_rate_dps`. [°/s]
    max_rate_dps : float, optional
        The table's rate limit; the base plan's ``[limits] max_rate_dps`` when None. [°/s]
    """

    criterion: Criterion = "targets"
    time_budget_s: float | None = None
    min_repetitions: int = 3
    max_repetitions: int = 6
    min_static_s: float = 3600.0
    max_static_s: float = 3600.0
    static_tolerance_s: float = 30.0
    min_lack_of_fit_dof: int = 6
    record_s_grid: tuple[float, ...] = (10.0, 20.0, 30.0, 60.0, 120.0)
    revolutions_grid: tuple[int, ...] = (2, 3, 4, 5, 8, 12)
    reverse_last_grid: tuple[bool, ...] = (False, True)
    rate_magnitudes_dps: tuple[float, ...] = (50.0, 100.0, 200.0, 300.0)
    max_rate_dps: float | None = None

    @classmethod
    def coarse(cls, **kwargs: object) -> OptimizeSettings:
        """Return settings with a small grid (tests, a quick look)."""
        small: dict[str, object] = {"max_repetitions": 4, "record_s_grid": (10.0, 30.0),
                                    "revolutions_grid": (3, 5), "static_tolerance_s": 120.0,
                                    "reverse_last_grid": (True,),
                                    "rate_magnitudes_dps": (50.0, 100.0, 200.0)}
        small.update(kwargs)
        return cls(**small)  # type: ignore[arg-type]

    def check(self) -> None:
        """Raise :class:`~imucalib.errors.ConfigurationError` for settings that make no sense."""
        if self.criterion not in ("targets", "D", "A"):
            raise ConfigurationError(f"the criterion must be targets, D or A; got "
                                     f"{self.criterion!r}")
        if self.criterion != "targets" and self.time_budget_s is None:
            raise ConfigurationError(f"criterion {self.criterion} needs a time budget "
                                     "(--time-budget H)")
        if self.time_budget_s is not None and not self.time_budget_s > 0:
            raise ConfigurationError(f"the time budget must be > 0; got {self.time_budget_s}")
        if not 1 <= self.min_repetitions <= self.max_repetitions:
            raise ConfigurationError(f"repetitions: need 1 ≤ min ({self.min_repetitions}) ≤ max "
                                     f"({self.max_repetitions})")
        if not 0 <= self.min_static_s <= self.max_static_s:
            raise ConfigurationError(f"static record: need 0 ≤ min ({self.min_static_s:g} s) ≤ "
                                     f"max ({self.max_static_s:g} s)")
        if not self.record_s_grid or min(self.record_s_grid) < 10.0:
            raise ConfigurationError("position records must be ≥ 10 s (docs/p1.md step 1)")
        if not self.revolutions_grid or min(self.revolutions_grid) < 1:
            raise ConfigurationError("revolutions must be ≥ 1")
        if not self.reverse_last_grid:
            raise ConfigurationError("reverse_last_grid needs at least one step order")


@dataclass(frozen=True)
class Candidate:
    """One evaluated plan.

    Attributes
    ----------
    design : P1Design
    plan : Plan
    prediction : Prediction
        Its :func:`~imucalib.procedures.p1.predict.predict_p1`.
    ratios : dict of str to float
        σ_i / σ_target,i of each targeted parameter (Eq. (TD.7)); inf where not identified.
    worst_ratio : float
        The largest ratio.
    criterion_value : float
        D (Eq. (TD.5)) or A (Eq. (TD.6)) of the normalised covariance; the worst ratio for
        ``"targets"``.
    lack_of_fit_dof : dict of str to int
        ν of each triad's fit.
    """

    design: P1Design
    plan: Plan
    prediction: Prediction
    ratios: dict[str, float]
    worst_ratio: float
    criterion_value: float
    lack_of_fit_dof: dict[str, int]

    @property
    def station_time_s(self) -> float:
        """The station time with moves and settling. [s]"""
        return self.prediction.station_time_s

    @property
    def meets_targets(self) -> bool:
        """True when every ratio is ≤ 1."""
        return self.worst_ratio <= 1.0 + _RATIO_TOL


@dataclass(frozen=True)
class OptimizeResult:
    """The optimiser's answer.

    Attributes
    ----------
    best : Candidate
        The optimised plan.
    reference : Candidate
        The default plan (the base options) judged by the same targets.
    targets : dict of str to float
        σ_target per parameter, SI.
    settings : OptimizeSettings
    n_evaluated : int
        Predictions made.
    elapsed_s : float
        The search's wall time. [s]
    notes : tuple of str
    """

    best: Candidate
    reference: Candidate
    targets: dict[str, float]
    settings: OptimizeSettings
    n_evaluated: int
    elapsed_s: float
    notes: tuple[str, ...] = field(default=())


def _generate(options: P1PlanOptions) -> Plan:
    kwargs = {f.name: getattr(options, f.name) for f in dataclasses.fields(options)}
    return generate_p1_plan(**kwargs)


def default_targets(base: P1PlanOptions | None = None, *,
                    noise: Mapping[str, NoiseModel] | None = None) -> dict[str, float]:
    """Return the default plan's predicted σ per parameter (``--target-default``), SI.

    Raises
    ------
    InsufficientExcitationError
        When the base plan cannot identify a parameter.
    """
    base = base or P1PlanOptions()
    plan = _generate(base)
    prediction = predict_p1_covariance(plan, noise=noise or declared_noise(plan)[0])[0]
    if prediction.confounded:
        raise InsufficientExcitationError(prediction.confounded, "the base plan cannot identify "
                                          f"{', '.join(prediction.confounded)}: no default σ")
    return {p.name: float(p.predicted_std) for p in prediction.parameters
            if p.predicted_std is not None}


def spec_targets(plan: Plan, names: Sequence[str], k: float = SPEC_K) -> dict[str, float]:
    """Return σ_target = limit / k for each parameter the specification limits (Eq. (TD.8)), SI.

    The limits are the plan's ``[imu.limits]`` (the grade's by default), matched to the
    parameters `names` as the decision matches them
    (:func:`~imucalib.procedures.common.spec_decision.spec_field`).

    Raises
    ------
    ConfigurationError
        For k ≤ 0 or a specification that limits none of the parameters.
    """
    from imucalib.procedures.common.spec_decision import spec_field

    if not (k > 0 and math.isfinite(k)):
        raise ConfigurationError(f"k must be > 0; got {k}")
    limits = plan.imu.limits.model_dump() if plan.imu.limits is not None else {}
    out: dict[str, float] = {}
    for name in names:
        spec = spec_field(name)
        if spec is None or limits.get(spec[2]) is None:
            continue
        out[name] = float(limits[spec[2]]) * spec[1] / k
    if not out:
        raise ConfigurationError(f"plan {plan.name!r} limits none of P1's parameters "
                                 "([imu.limits]): no targets from the specification")
    return out


def parse_targets(text: str, names: Sequence[str]) -> dict[str, float]:
    """Parse ``NAME=σ,…`` (SI, the result's units) into targets.

    A NAME is a parameter (``gyro_bias_z``) or a prefix of several (``gyro_bias``,
    ``accel_M``): :func:`~imucalib.procedures.common.prediction.parse_target_text`.

    Raises
    ------
    ConfigurationError
        For a malformed item, an unknown name or a σ that is not > 0.
    """
    return parse_target_text(text, names, "P1")


def _lack_of_fit_dof(plan: Plan, prediction: Prediction) -> dict[str, int]:
    """ν = 3·windows − parameters of each triad's fit (the windows the analysis selects)."""
    roles = [s.role for s in plan.steps]
    n_accel = roles.count(P1_ACCEL_POSITION)
    n_gyro = n_accel + roles.count(P1_GYRO_BIAS) + roles.count(P1_GYRO_RATE)
    groups = {g.name: g.n_parameters for g in prediction.groups}
    return {"accel": 3 * n_accel - groups.get("accel", 12),
            "gyro": 3 * n_gyro - groups.get("gyro", 12)}


class _Search:
    """Evaluate candidates, cached by design."""

    def __init__(self, base: P1PlanOptions, targets: Mapping[str, float],
                 scales: Mapping[str, float], settings: OptimizeSettings,
                 noise: Mapping[str, NoiseModel]) -> None:
        self.base, self.targets, self.scales = base, dict(targets), dict(scales)
        self.settings, self.noise = settings, noise
        self.cache: dict[P1Design, Candidate] = {}
        self.times: dict[P1Design, float] = {}

    def time_s(self, d: P1Design) -> float:
        """Station time of a design (no prediction). [s]"""
        if d not in self.times:
            self.times[d] = estimate_plan_recording(_generate(d.options(self.base))).duration_s
        return self.times[d]

    def evaluate(self, d: P1Design) -> Candidate:
        """Predict a design and score it (Eqs. (TD.5)–(TD.7))."""
        if d in self.cache:
            return self.cache[d]
        plan = _generate(d.options(self.base))
        prediction, covs = predict_p1_covariance(plan, noise=self.noise)
        std = prediction.std()
        ratios = {n: (math.inf if std.get(n) is None else float(std[n] or 0.0) / t)
                  for n, t in self.targets.items()}
        worst = max(ratios.values())
        crit = self.settings.criterion
        if crit == "targets":
            value = worst
        elif prediction.confounded or len(covs) < 2:
            value = math.inf
        else:
            value = 0.0
            for names, cov in covs.values():
                s = np.array([self.scales[n] for n in names])
                c = cov / np.outer(s, s)
                value += (float(np.linalg.slogdet(c)[1]) if crit == "D"
                          else float(np.trace(c)))
        self.times[d] = prediction.station_time_s
        cand = Candidate(d, plan, prediction, ratios, worst, value,
                         _lack_of_fit_dof(plan, prediction))
        self.cache[d] = cand
        return cand

    def admissible(self, c: Candidate) -> bool:
        """Return True when identifiable with each triad's ν at least the least (margins)."""
        return (not c.prediction.confounded and
                min(c.lack_of_fit_dof.values()) >= self.settings.min_lack_of_fit_dof)


def _rate_sets(settings: OptimizeSettings, limit: float, base: Sequence[float]
               ) -> list[tuple[float, ...]]:
    mags = sorted({m for m in settings.rate_magnitudes_dps if 0 < m <= limit})
    sets = [(-b, -a, 0.0, a, b) for i, a in enumerate(mags) for b in mags[i + 1:]]
    base_t = tuple(float(r) for r in base)
    return [base_t, *(s for s in sets if s != base_t)]


def optimize_p1(base: P1PlanOptions | None = None, *, targets: Mapping[str, float],
                settings: OptimizeSettings | None = None,
                noise: Mapping[str, NoiseModel] | None = None,
                progress: Callable[[str], None] | None = None) -> OptimizeResult:
    """Return the optimised P1 plan (module docstring).

    Parameters
    ----------
    base : P1PlanOptions, optional
        The plan's other options (grade, held-out rates, settling, twin…) and the reference
        plan; :class:`~.options.P1PlanOptions`'s defaults when omitted.
    targets : mapping of str to float
        σ_target per parameter, SI (:func:`default_targets`, :func:`spec_targets`,
        :func:`parse_targets`).
    settings : OptimizeSettings, optional
        Objective, grid and margins.
    noise : mapping of str to NoiseModel, optional
        The unit's noise model; when omitted, the base plan's declared noise (its
        ``noise_characterization``, else the grade's:
        :func:`~imucalib.procedures.common.grade.declared_noise`).
    progress : callable, optional
        Called with a line per improvement.

    Returns
    -------
    OptimizeResult

    Raises
    ------
    ConfigurationError
        Bad settings or targets, or no plan within the grid and budget that meets the targets
        (the line says the best worst ratio reached and what would help).
    """
    t0 = time.perf_counter()
    base = base or P1PlanOptions()
    settings = settings or OptimizeSettings()
    settings.check()
    if not base.z_rates:
        raise ConfigurationError("the optimiser keeps z_rates (the Z gyro's scale and "
                                 "misalignments need them)")
    if not targets:
        raise ConfigurationError("no targets: give --target-default, --target NAME=σ,… or "
                                 "--target-from-spec")
    ref_plan = _generate(base)
    noise = dict(noise) if noise is not None else declared_noise(ref_plan)[0]
    ref_std = predict_p1_covariance(ref_plan, noise=noise)[0].std()
    scales = {n: float(targets.get(n) or v or 1.0) for n, v in ref_std.items()}
    search = _Search(base, targets, scales, settings, noise)
    reference = search.evaluate(P1Design(base.repetitions, tuple(base.rates_dps),
                                         base.revolutions, base.record_s, base.static_s,
                                         base.reverse_last))
    limit = settings.max_rate_dps or ref_plan.limits.max_rate_dps
    rate_sets = _rate_sets(settings, limit, base.rates_dps)
    say = progress or (lambda _line: None)
    smin, smax = settings.min_static_s, settings.max_static_s
    states = [(r, rates_sets_0, rev, rec, rev_last)
              for r in range(settings.min_repetitions, settings.max_repetitions + 1)
              for rates_sets_0 in rate_sets[:1]
              for rev in settings.revolutions_grid for rec in settings.record_s_grid
              for rev_last in settings.reverse_last_grid]
    budget = settings.time_budget_s
    best: Candidate | None = None
    best_any: Candidate | None = None  # the least worst ratio seen, for the error line

    def design(state: _State, static: float) -> P1Design:
        r, rates, rev, rec, rev_last = state
        return P1Design(r, rates, rev, rec, float(static), rev_last)

    def static_for(state: _State, t_limit: float) -> float:
        """Return the longest static whose station time is ≤ t_limit (linear in it)."""
        t_min = search.time_s(design(state, smin))
        return min(smax, smin + (t_limit - t_min) / state[0])

    def better(c: Candidate) -> bool:
        if not search.admissible(c):
            return False
        if budget is None:
            return c.meets_targets and (best is None or c.station_time_s < best.station_time_s)
        return best is None or c.criterion_value < best.criterion_value

    def note_any(c: Candidate) -> None:
        nonlocal best_any
        if search.admissible(c) and (best_any is None or c.worst_ratio < best_any.worst_ratio):
            best_any = c

    def visit(state: _State) -> None:
        nonlocal best
        t_cap = budget if budget is not None else (
            best.station_time_s if best is not None else math.inf)
        if search.time_s(design(state, smin)) >= t_cap:
            return
        hi = float(math.floor(static_for(state, t_cap))) if math.isfinite(t_cap) else smax
        if hi < smin:
            return
        top = search.evaluate(design(state, hi))
        note_any(top)
        if budget is not None:
            if better(top):
                best = top
                say(f"{_describe(top.design)}: {top.station_time_s / 3600:.2f} h, "
                    f"{settings.criterion} {top.criterion_value:.4g}")
            return
        if not (top.meets_targets and search.admissible(top)):
            return
        lo = smin  # bisection: the shortest static meeting the targets
        low = search.evaluate(design(state, lo))
        note_any(low)
        if low.meets_targets:
            hi, top = lo, low
        while hi - lo > settings.static_tolerance_s:
            mid = float(math.ceil(0.5 * (lo + hi)))  # whole seconds
            if mid >= hi:
                break
            c = search.evaluate(design(state, mid))
            note_any(c)
            if c.meets_targets:
                hi, top = mid, c
            else:
                lo = mid
        if better(top):
            best = top
            say(f"{_describe(top.design)}: {top.station_time_s / 3600:.2f} h, worst ratio "
                f"{top.worst_ratio:.3f}")

    rd = reference.design
    if (budget is None and rd.repetitions >= settings.min_repetitions
            and rd.static_s >= smin and better(reference)):
        best = reference  # the base plan itself is a candidate (its step order may be off-grid)
    states.sort(key=lambda s: search.time_s(design(s, smin)))
    for state in states:
        visit(state)
    if best is not None:  # the best state's rate set varied
        d = best.design
        for rates in rate_sets[1:]:
            visit((d.repetitions, rates, d.revolutions, d.record_s, d.reverse_last))
    elapsed = time.perf_counter() - t0
    if best is None:
        reach = ("" if best_any is None else
                 f"; the best reaches a worst σ/target of {best_any.worst_ratio:.3g} "
                 f"({_worst_name(best_any)}) in {best_any.station_time_s / 3600:.2f} h")
        if budget is not None and best_any is None:
            least = min(search.time_s(design(st, smin)) for st in states)
            raise ConfigurationError(
                f"no P1 plan fits within {budget / 3600:.2f} h: the shortest the margins allow "
                f"({settings.min_repetitions} repetitions, {smin:g}-s static records, the "
                f"warm-up) takes {least / 3600:.2f} h")
        where = (f"within {budget / 3600:.2f} h" if budget is not None else
                 f"with up to {settings.max_repetitions} repetitions and "
                 f"{smax / 60:g}-min static records")
        raise ConfigurationError(f"no P1 plan {where} meets the targets{reach}: relax the "
                                 "targets or allow more time")
    notes = [f"{len(search.cache)} plans predicted in {elapsed:.1f} s"]
    if budget is not None and not best.meets_targets:
        notes.append(f"within the budget the worst σ/target is {best.worst_ratio:.3g} "
                     f"({_worst_name(best)}): not every target is met")
    return OptimizeResult(best=best, reference=reference, targets=dict(targets),
                          settings=settings, n_evaluated=len(search.cache), elapsed_s=elapsed,
                          notes=tuple(notes))


def _worst_name(c: Candidate) -> str:
    return max(c.ratios, key=lambda n: c.ratios[n])


def _describe(d: P1Design) -> str:
    rates = "/".join(f"{r:g}" for r in d.rates_dps if r > 0)
    return (f"{d.repetitions} rep, record {d.record_s:g} s, static {d.static_s:.0f} s, "
            f"{d.revolutions} rev, rates 0/±{rates} °/s"
            + (", last repetition reversed" if d.reverse_last else ""))


def optimize_request(request: OptimizeRequest) -> OptimizedPlan:
    """Answer ``imucalib plan optimize p1``: targets and settings, then :func:`optimize_p1`.

    The request is the command's :class:`~imucalib.procedures.common.prediction.OptimizeRequest`.
    Its ``noise_characterization`` (a noise JSON of the unit) is the base options' (every plan,
    the default and the optimised one, carries it as its ``[imu.noise]``), so it replaces the
    grade's noise in the default plan's σ and in every candidate's (the same noise on both sides
    of the comparison), and the analysis of the optimised plan's run takes it for its declared
    flicker floor.

    Raises
    ------
    ConfigurationError
        An unknown grade, targets given two ways, or settings :class:`OptimizeSettings` refuses.
    InvalidInputError
        Targets that name no P1 parameter, or that no plan meets; a noise characterisation
        that cannot be read.
    """
    if request.grade not in ("consumer", "tactical", "navigation"):
        raise ConfigurationError(f"--grade must be consumer, tactical or navigation; got "
                                 f"{request.grade!r}")
    base = P1PlanOptions(grade=request.grade,  # type: ignore[arg-type]
                         noise_characterization=request.noise_characterization)
    noise, source = declared_noise(_generate(base))
    if request.noise_characterization:
        source += ", carried by both plans as [imu.noise]"
    defaults = default_targets(base, noise=noise)
    if request.targets == "given":
        targets = parse_targets(request.target_text, list(defaults))
    elif request.targets == "spec":
        targets = spec_targets(generate_p1_plan(grade=request.grade), list(defaults),
                               request.spec_k)
    else:
        targets = defaults
    make = OptimizeSettings.coarse if request.coarse else OptimizeSettings
    settings = make(criterion=request.criterion,  # type: ignore[arg-type]  # checked there
                    time_budget_s=request.time_budget_s,
                    min_repetitions=request.min_repetitions,
                    min_lack_of_fit_dof=request.min_lack_of_fit_dof)
    settings = dataclasses.replace(settings, min_static_s=request.min_static_s,
                                   max_static_s=max(settings.max_static_s,
                                                    request.min_static_s))
    result = optimize_p1(base, targets=targets, settings=settings, noise=noise)
    best, ref = result.best, result.reference
    d = best.design
    return OptimizedPlan(
        plan=best.plan, prediction=best.prediction, reference=ref.prediction,
        targets=dict(result.targets), ratios=dict(best.ratios), worst_ratio=best.worst_ratio,
        reference_worst_ratio=ref.worst_ratio, criterion=result.settings.criterion,
        design=(f"{d.repetitions} repetitions, record {d.record_s:g} s per position, static "
                f"{d.static_s:g} s, {d.revolutions} revolutions, rates "
                f"{', '.join(f'{r:g}' for r in d.rates_dps)} °/s"
                + ("; the last repetition reversed" if d.reverse_last else "")),
        notes=(f"noise model of both plans: {source}", *result.notes))
