"""The D-optimal rate set of the rate transfer (docs/rate-transfer.md, TD.R1–TD.R3).

The rate transfer fits, per axis, the means y_j of turns at rates x_j to a model linear in its
parameters, y = f(x)ᵀθ: a polynomial of order p (``"poly1"``, the IEEE line (RT-5);
``"poly2"``, ``"poly3"``) or the procedure's second fit (RT-7), f = (1, x, |x|, x²)
(``"transfer"``). On the normalised rate interval u = x/ω_max ∈ [−1, 1], with white noise the
information of a turn is T_j·f(u_j)f(u_j)ᵀ/N², so per unit of recording time

    (TD.R1)  M(ξ) = Σ_j w_j·f(u_j)·f(u_j)ᵀ,   w_j = T_j / Σ_k T_k,

and the D-efficiency of a design ξ against the D-optimal ξ*, m the number of parameters,

    (TD.R2)  eff_D(ξ) = (det M(ξ) / det M(ξ*))^(1/m).

For a polynomial of order p, ξ* puts equal time at the p + 1 Legendre–Lobatto points, the zeros
of (1 − u²)·P′_p(u) (de la Garza 1954; Guest 1958): {±1} for the line, {−1, 0, 1}, {±1, ±1/√5}
(:func:`lobatto_points`). For (RT-7) and for a design restricted to |u| ≥ u_min (a turn needs
a rate: the plan refuses 0 °/s), ξ* is found numerically on a grid by the multiplicative
algorithm (Silvey, Titterington & Torsney 1978; :func:`d_optimal_on_grid`).

Time at equal generalized variance: det Cov(θ̂) = N^(2m) / det(Σ_j T_j·f f ᵀ), so the optimised
rate set reaches the default's generalized variance with

    (TD.R3)  T_opt = T_def · eff_D(ξ_def) / eff_D(ξ_opt)

of recording; :func:`compare_rate_designs` rounds each turn up to whole revolutions (≥ 2, as
the plan requires), finds the least total for which det(Σ T_j f fᵀ) ≥ the default's, and
prices both plans' station time (moves and settling) with
:func:`~imucalib.plan.budget.estimate_plan_recording`.

Limitation: (TD.R1)–(TD.R3) assume white noise (N²/T per mean, as the analysis's σ (RT-4)).
Flicker and rate random walk make long turns less informative than T suggests; the σ of a
given plan with them is :func:`~imucalib.procedures.rate_transfer.predict.predict_rate_transfer`.

Contents
--------
:data:`MODELS`, :func:`basis`, :func:`lobatto_points`, :func:`information_matrix`,
:func:`d_efficiency`, :func:`d_optimal_on_grid`, :func:`optimal_design`,
:func:`plan_dwell_design`, :class:`RateDesignComparison`, :func:`compare_rate_designs`,
:func:`move_time_s`, :func:`station_time_s`
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.polynomial import legendre
from numpy.typing import ArrayLike, NDArray

from imucalib.errors import ConfigurationError, InsufficientExcitationError
from imucalib.plan.budget import MIN_SETTLE_PHASE_S, estimate_plan_recording
from imucalib.plan.schema import Plan, RateStep
from imucalib.procedures.rate_transfer.roles import RATE_TRANSFER_RATE

__all__ = ["MODELS", "RateDesignComparison", "basis", "compare_rate_designs", "d_efficiency",
           "d_optimal_on_grid", "information_matrix", "lobatto_points", "move_time_s",
           "optimal_design", "plan_dwell_design", "station_time_s"]

_F64 = NDArray[np.float64]

#: The models of the rate transfer's D-criterion and their number of parameters m.
MODELS: dict[str, int] = {"poly1": 2, "poly2": 3, "poly3": 4, "transfer": 4}


def _check_model(model: str) -> int:
    if model not in MODELS:
        raise ConfigurationError(f"model must be one of {sorted(MODELS)}; got {model!r}")
    return MODELS[model]


def basis(model: str, u: ArrayLike) -> _F64:
    """Return the regressors f(u) of `model` at the normalised rates `u`, shape (n, m)."""
    _check_model(model)
    x = np.asarray(u, dtype=np.float64).ravel()
    if model == "transfer":  # (RT-7)
        return np.column_stack([np.ones_like(x), x, np.abs(x), x * x])
    return np.vander(x, MODELS[model], increasing=True)


def lobatto_points(order: int) -> _F64:
    """Return the p + 1 zeros of (1 − u²)·P′_p(u) on [−1, 1], ascending (the D-optimal support).

    Raises
    ------
    ConfigurationError
        `order` < 1.
    """
    if order < 1:
        raise ConfigurationError(f"order must be ≥ 1; got {order}")
    c = np.zeros(order + 1)
    c[order] = 1.0
    inner = legendre.legroots(legendre.legder(c)) if order > 1 else np.zeros(0)
    return np.sort(np.concatenate([[-1.0], np.real(inner), [1.0]]))


def information_matrix(model: str, u: ArrayLike, weights: ArrayLike | None = None) -> _F64:
    """Return M(ξ) of (TD.R1); `weights` are normalised to sum 1 (equal when omitted)."""
    f = basis(model, u)
    w = (np.full(f.shape[0], 1.0) if weights is None
         else np.asarray(weights, dtype=np.float64).ravel())
    if w.shape[0] != f.shape[0] or np.any(w < 0) or not np.sum(w) > 0:
        raise ConfigurationError("weights must be ≥ 0, one per rate, not all zero")
    w = w / np.sum(w)
    return np.asarray((f * w[:, None]).T @ f)


def optimal_design(model: str, u_min: float = 0.0) -> tuple[_F64, _F64]:
    """Return the D-optimal (rates, weights) on u ∈ [−1, −u_min] ∪ [u_min, 1].

    Polynomials with no Lobatto point inside (−u_min, u_min): :func:`lobatto_points`, equal
    weights. Otherwise (the transfer model (RT-7), or an excluded zero rate) the grid optimum
    of :func:`d_optimal_on_grid`, pruned to its support.
    """
    m = _check_model(model)
    if model != "transfer":
        pts = lobatto_points(m - 1)
        if not np.any(np.abs(pts) < u_min):
            return pts, np.full(pts.size, 1.0 / pts.size)
    mags = np.linspace(u_min, 1.0, 401)
    grid = np.unique(np.concatenate([-mags, mags]))
    w = d_optimal_on_grid(model, grid, tol=1e-4)
    # the grid optimum spreads each support point over its neighbours: merge clusters
    # (gaps < 0.05) into their weighted mean, then re-weight on that support
    keep = np.flatnonzero(w > 1e-4)
    groups = np.split(keep, np.flatnonzero(np.diff(grid[keep]) > 0.05) + 1)
    support = np.array([float(np.average(grid[g], weights=w[g])) for g in groups])
    for edge in (u_min, 1.0):  # a cluster at an edge of the interval is the edge
        support = np.where(np.abs(np.abs(support) - edge) < 0.01, np.sign(support) * edge,
                           support)
    return support, d_optimal_on_grid(model, support)


def d_efficiency(model: str, u: ArrayLike, weights: ArrayLike | None = None) -> float:
    """Return eff_D of (TD.R2) against the unrestricted D-optimal design of `model`.

    Returns 0 for a design that cannot identify `model` (singular M).
    """
    m = _check_model(model)
    det = float(np.linalg.det(information_matrix(model, u, weights)))
    star_u, star_w = optimal_design(model)
    det_star = float(np.linalg.det(information_matrix(model, star_u, star_w)))
    return max(det, 0.0) ** (1.0 / m) / det_star ** (1.0 / m)


def d_optimal_on_grid(model: str, grid: ArrayLike, *, iterations: int = 5000,
                      tol: float = 1e-9) -> _F64:
    """Return the D-optimal weights on the candidate rates `grid` (multiplicative algorithm).

    w_j ← w_j·d_j/m, d_j = f_jᵀ M(w)⁻¹ f_j; it converges to the D-optimum, at which
    max_j d_j = m (the Kiefer–Wolfowitz equivalence theorem), used as the stopping rule.
    """
    m = _check_model(model)
    f = basis(model, grid)
    w = np.full(f.shape[0], 1.0 / f.shape[0])
    for _ in range(iterations):
        d = np.einsum("ij,jk,ik->i", f, np.linalg.inv((f * w[:, None]).T @ f), f)
        if float(np.max(d)) <= m * (1.0 + tol):
            break
        w = w * d / m
    return np.asarray(w / np.sum(w))


def _turns(plan: Plan, axis: str | None = None) -> list[RateStep]:
    """Return the plan's rate-transfer turns (of one body axis when given)."""
    return [s for s in plan.steps if isinstance(s, RateStep) and s.role == RATE_TRANSFER_RATE
            and (axis is None or f"axis={axis}" in s.tags)]


def _dwell_s(step: RateStep) -> float:
    """Return a turn's averaged span: its whole revolutions, or record_s. [s]"""
    if step.revolutions is not None and step.rate_dps != 0.0:
        return step.revolutions * 360.0 / abs(step.rate_dps)
    return float(step.record_s or 0.0)


def plan_dwell_design(plan: Plan, axis: str | None = None) -> tuple[_F64, _F64, float]:
    """Return one axis' (signed rates [°/s], dwell T_j [s], ω_max [°/s]) of a rate-transfer plan.

    The first axis tested when `axis` is None.

    Raises
    ------
    ConfigurationError
        No rate-transfer turn.
    """
    turns = _turns(plan)
    if not turns:
        raise ConfigurationError(f"plan {plan.name!r} has no rate-transfer turn (role "
                                 f"{RATE_TRANSFER_RATE})")
    if axis is None:
        axis = next((t.split("=", 1)[1] for t in turns[0].tags if t.startswith("axis=")), None)
    mine = _turns(plan, axis) if axis is not None else turns
    rates = np.array([s.rate_dps for s in mine])
    dwell = np.array([_dwell_s(s) for s in mine])
    return rates, dwell, float(np.max(np.abs(rates)))


def move_time_s(plan: Plan) -> float:
    """Return the table's moves beyond the settle phase the budget counts. [s]

    The table accelerates at the plan's ``[limits] max_accel_dps2`` α: the change from the
    previous rate ω_(j−1) (0 after a remount) to ω_j takes |ω_j − ω_(j−1)|/α, and the runner
    settles until the rate has held for ``[guards] settle_check_s`` t_c. The budget
    (:func:`~imucalib.plan.budget.estimate_plan_recording`) counts a settle phase of
    max(settle_s, ``MIN_SETTLE_PHASE_S``); this returns Σ_j max(0, |Δω_j|/α + t_c −
    max(settle_s, ``MIN_SETTLE_PHASE_S``)): zero unless the table is slow.
    """
    accel, check = plan.limits.max_accel_dps2, plan.guards.settle_check_s
    extra, prev = 0.0, 0.0
    for step in plan.steps:
        if not isinstance(step, RateStep):
            prev = 0.0  # a remount: the table stops
            continue
        move = abs(step.rate_dps - prev) / accel
        extra += max(0.0, move + check - max(step.settle_s, MIN_SETTLE_PHASE_S))
        prev = step.rate_dps
    return extra


def station_time_s(plan: Plan) -> float:
    """Return the plan's station time with the table's moves (:func:`move_time_s`). [s]"""
    return estimate_plan_recording(plan).duration_s + move_time_s(plan)


@dataclass(frozen=True)
class RateDesignComparison:
    """The default rate set against the D-optimal one at equal generalized variance (TD.R3).

    Attributes
    ----------
    model : str
        A key of :data:`MODELS`.
    default_rates_dps : tuple of float
        The plan's signed rates (one axis). [°/s]
    efficiency_equal_dwell : float
        eff_D (TD.R2) of those rates with equal time at each (the issue's convention).
    efficiency_plan_dwell : float
        eff_D of the plan as written: time T_j = revolutions·360°/|ω_j| at each rate.
    optimal_rates_dps : tuple of float
        The realizable D-optimal rates (|ω| ≥ the plan's smallest rate). [°/s]
    optimal_revolutions : tuple of int
        Whole revolutions at each, the least reaching the default's generalized variance.
    optimal_efficiency : float
        eff_D of the optimised plan as rounded (its dwell).
    default_record_s, optimal_record_s : float
        Recording time of one axis' turns. [s]
    default_station_s, optimal_station_s : float
        Station time of the whole plans (every axis; moves and settling). [s]
    """

    model: str
    default_rates_dps: tuple[float, ...]
    efficiency_equal_dwell: float
    efficiency_plan_dwell: float
    optimal_rates_dps: tuple[float, ...]
    optimal_revolutions: tuple[int, ...]
    optimal_efficiency: float
    default_record_s: float
    optimal_record_s: float
    default_station_s: float
    optimal_station_s: float

    @property
    def time_saved_fraction(self) -> float:
        """1 − optimised station time / default station time."""
        return 1.0 - self.optimal_station_s / self.default_station_s


def _revolutions(total_s: float, rates_dps: _F64, weights: _F64, least: int) -> NDArray[
        np.int64]:
    wanted = total_s * weights * np.abs(rates_dps) / 360.0
    return np.maximum(np.ceil(wanted - 1e-9), least).astype(np.int64)


def compare_rate_designs(plan: Plan, model: str, *, least_revolutions: int = 2
                         ) -> RateDesignComparison:
    """Compare `plan`'s rate set with the D-optimal one for `model` (module docstring).

    The optimised design keeps the plan's rate interval [ω_min, ω_max] (its smallest and
    largest magnitudes) and its axes, settling and twin; each turn gets the least whole
    revolutions (≥ `least_revolutions`) such that det(Σ_j T_j f_j f_jᵀ) of every axis reaches
    the plan's (equal generalized variance, white noise).

    Raises
    ------
    ConfigurationError
        A plan without rate-transfer turns, or an unknown model.
    InsufficientExcitationError
        The plan's rates cannot identify `model` (its generalized variance is infinite).
    """
    from imucalib.procedures.rate_transfer.plan import generate_rate_transfer_plan

    m = _check_model(model)
    rates, dwell, top = plan_dwell_design(plan)
    u = rates / top
    info_def = (basis(model, u) * dwell[:, None]).T @ basis(model, u)
    det_def = float(np.linalg.det(info_def))
    if not det_def > 0.0:
        raise InsufficientExcitationError(
            [model], f"the rates {sorted(set(rates.tolist()))} °/s cannot identify the "
                     f"{m} parameters of {model}")
    u_min = float(np.min(np.abs(u)))
    opt_u, opt_w = optimal_design(model, u_min)
    opt_rates = opt_u * top

    def det_of(revs: NDArray[np.int64]) -> float:
        t = revs * 360.0 / np.abs(opt_rates)
        f = basis(model, opt_u)
        return float(np.linalg.det((f * t[:, None]).T @ f))

    eff_plan = d_efficiency(model, u, dwell)
    eff_opt = d_efficiency(model, opt_u, opt_w)
    lo, hi = 0.0, float(np.sum(dwell)) * eff_plan / eff_opt  # (TD.R3), before rounding
    while det_of(_revolutions(hi, opt_rates, opt_w, least_revolutions)) < det_def:
        lo, hi = hi, 2.0 * hi
    for _ in range(60):  # the least total recording reaching the default's det
        mid = 0.5 * (lo + hi)
        if det_of(_revolutions(mid, opt_rates, opt_w, least_revolutions)) >= det_def:
            hi = mid
        else:
            lo = mid
    revs = _revolutions(hi, opt_rates, opt_w, least_revolutions)
    t_opt = revs * 360.0 / np.abs(opt_rates)
    # the optimised plan: the plan's axes and settling, its rates and revolutions
    axes = tuple(dict.fromkeys(t.split("=", 1)[1] for s in _turns(plan) for t in s.tags
                               if t.startswith("axis=")))
    settle = _turns(plan)[0].settle_s
    grade = plan.imu.grade or "tactical"
    mags = sorted({abs(float(r)) for r in np.round(opt_rates, 9)})
    new = generate_rate_transfer_plan(rates_dps=mags, axes=axes, settle_s=settle, grade=grade,
                                      twin=plan.twin, name=f"{plan.name}-d-optimal-{model}")
    by_rate = {round(float(r), 9): int(n) for r, n in zip(opt_rates, revs, strict=True)}
    steps = tuple(s.model_copy(update={"revolutions": by_rate[round(s.rate_dps, 9)]})
                  if isinstance(s, RateStep) and s.role == RATE_TRANSFER_RATE else s
                  for s in new.steps)
    new = new.model_copy(update={"steps": steps})
    return RateDesignComparison(
        model=model, default_rates_dps=tuple(float(r) for r in rates),
        efficiency_equal_dwell=d_efficiency(model, u),
        efficiency_plan_dwell=eff_plan,
        optimal_rates_dps=tuple(float(r) for r in opt_rates),
        optimal_revolutions=tuple(int(n) for n in revs),
        optimal_efficiency=d_efficiency(model, opt_u, t_opt),
        default_record_s=float(np.sum(dwell)), optimal_record_s=float(np.sum(t_opt)),
        default_station_s=station_time_s(plan),
        optimal_station_s=station_time_s(new))

