"""The predicted uncertainty of a plan, before it runs: :class:`Prediction` and the hook.

A procedure that can predict the uncertainty of its result from a plan alone has a method
``predict(plan) -> Prediction`` (:class:`Predicting`); ``imucalib plan show PLAN --predict``
calls it through :func:`predict_plan`. The bound is the Cramér–Rao bound of the procedure's
estimator, CRLB = F⁻¹ with F = Hᵀ·C⁻¹·H (docs/test-design.md, Eqs. (TD.1)–(TD.3)), H the
design the analysis would build from the plan's nominal windows and C the covariance of those
windows' means under the unit's noise model (coloured noise included, Eq. (TD.2)). A
procedure without ``predict`` is refused in one line (:class:`PredictionUnavailableError`).

A procedure that can also choose its plan has ``optimize_plan(request) -> OptimizedPlan``
(:class:`Optimizing`): ``imucalib plan optimize NAME`` fills an :class:`OptimizeRequest` from
its flags and calls it through :func:`optimize_plan` (docs/test-design.md, "The optimiser").

Contents
--------
:class:`PredictedParameter`, :class:`PredictionGroup`, :class:`Prediction`,
:class:`Predicting`, :class:`PredictionUnavailableError`, :func:`predict_plan`,
:class:`OptimizeRequest`, :class:`OptimizedPlan`, :class:`Optimizing`, :func:`optimize_plan`,
:func:`parse_target_text`
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal, Protocol, runtime_checkable

from imucalib.errors import ConfigurationError, InvalidInputError

if TYPE_CHECKING:
    from imucalib.plan.schema import Plan

__all__ = ["OptimizeRequest", "OptimizedPlan", "Optimizing", "PredictedParameter", "Predicting",
           "Prediction", "PredictionGroup", "PredictionUnavailableError", "optimize_plan",
           "parse_target_text", "predict_plan"]


class PredictionUnavailableError(InvalidInputError):
    """The plan's procedure has no ``predict`` (docs/test-design.md: only P1's exists yet)."""


@dataclass(frozen=True)
class PredictedParameter:
    """One parameter's predicted standard deviation.

    Attributes
    ----------
    name : str
        The parameter's name in the procedure's result (``accel_bias_x``, ``gyro_M_xy`` …).
    predicted_std : float or None
        √diag of the bound of Eq. (TD.3), with the Type B terms the analysis adds
        (docs/test-design.md); None when the plan cannot identify the parameter's group.
        [SI, `unit`]
    unit : str
        The result's unit of the parameter (``m/s^2``, ``rad/s``, ``1`` …).
    """

    name: str
    predicted_std: float | None
    unit: str


@dataclass(frozen=True)
class PredictionGroup:
    """The identifiability of one design (P1: one per triad).

    Attributes
    ----------
    name : str
        The group (``"accel"``, ``"gyro"``).
    n_parameters : int
        Columns of its design.
    rank : int
        Numerical rank of its whitened design (:mod:`imucalib.estimation.observability`).
    condition_number : float
        κ of the column-scaled whitened design (inf when rank-deficient).
    confounded : tuple of str
        The parameters it cannot identify (empty when it identifies all).
    """

    name: str
    n_parameters: int
    rank: int
    condition_number: float
    confounded: tuple[str, ...] = ()


@dataclass(frozen=True)
class Prediction:
    """What a plan will determine, before it runs (docs/test-design.md).

    Attributes
    ----------
    procedure : str
        The plan's procedure.
    station_time_s : float
        The run's expected duration with moves and settling
        (:func:`~imucalib.plan.budget.plan_run_duration_s`). [s]
    parameters : tuple of PredictedParameter
        Every parameter the procedure's result will hold, in its order.
    groups : tuple of PredictionGroup
        Each design's rank, condition number and confounded parameters.
    notes : tuple of str
        What the prediction assumed (noise model, Type B, terms).
    """

    procedure: str
    station_time_s: float
    parameters: tuple[PredictedParameter, ...]
    groups: tuple[PredictionGroup, ...]
    notes: tuple[str, ...] = ()

    @property
    def rank(self) -> int:
        """Sum of the groups' ranks."""
        return sum(g.rank for g in self.groups)

    @property
    def n_parameters(self) -> int:
        """Sum of the groups' columns."""
        return sum(g.n_parameters for g in self.groups)

    @property
    def condition_number(self) -> float:
        """The largest condition number of the groups."""
        return max((g.condition_number for g in self.groups), default=math.nan)

    @property
    def confounded(self) -> tuple[str, ...]:
        """Every parameter the plan cannot identify, group by group."""
        return tuple(n for g in self.groups for n in g.confounded)

    @property
    def identifiable(self) -> bool:
        """True when the plan identifies every parameter."""
        return not self.confounded

    def std(self) -> dict[str, float | None]:
        """Return {name: predicted σ} (None for a parameter that is not identified)."""
        return {p.name: p.predicted_std for p in self.parameters}

    def to_dict(self) -> dict[str, Any]:
        """Return the JSON of ``plan show --predict --json`` (docs/test-design.md).

        ``station_time_s``, ``parameters`` (``name``, ``predicted_std``, ``unit``) and
        ``confounded``, then ``procedure``, ``rank``, ``n_parameters``,
        ``condition_number`` (None when infinite), ``groups`` and ``notes``.
        """
        def finite(x: float) -> float | None:
            return x if math.isfinite(x) else None

        return {
            "station_time_s": self.station_time_s,
            "parameters": [{"name": p.name, "predicted_std": p.predicted_std, "unit": p.unit}
                           for p in self.parameters],
            "confounded": list(self.confounded),
            "procedure": self.procedure,
            "rank": self.rank,
            "n_parameters": self.n_parameters,
            "condition_number": finite(self.condition_number),
            "groups": [{"name": g.name, "n_parameters": g.n_parameters, "rank": g.rank,
                        "condition_number": finite(g.condition_number),
                        "confounded": list(g.confounded)} for g in self.groups],
            "notes": list(self.notes),
        }


@runtime_checkable
class Predicting(Protocol):
    """A procedure that predicts its result's uncertainty from a plan (optional capability)."""

    def predict(self, plan: Plan) -> Prediction:
        """Return the predicted uncertainty of `plan`'s result (module docstring)."""
        ...


def predict_plan(procedure: object, plan: Plan) -> Prediction:
    """Return ``procedure.predict(plan)``, or refuse a procedure without it.

    Raises
    ------
    PredictionUnavailableError
        The procedure has no ``predict``: "prediction is not available for procedure X yet".
    InvalidInputError
        A plan the procedure's prediction cannot read.
    """
    if not isinstance(procedure, Predicting):
        name = getattr(procedure, "name", "?")
        raise PredictionUnavailableError(f"prediction is not available for procedure {name} "
                                         "yet")
    return procedure.predict(plan)


@dataclass(frozen=True)
class OptimizeRequest:
    """What ``imucalib plan optimize NAME`` asks of a procedure's optimiser.

    Attributes
    ----------
    targets : {"default", "given", "spec"}
        Each parameter's σ no worse than the default plan's; the σ of `target_text`; or
        limit/`spec_k` of each parameter the specification limits.
    target_text : str
        ``NAME=σ,…`` in SI units (``"given"``).
    spec_k : float
        k of ``"spec"``.
    time_budget_s : float or None
        Station time allowed: the best criterion within it instead of the least time. [s]
    criterion : str
        ``"targets"`` (worst σ/target), ``"D"`` or ``"A"``.
    grade : str
        The unit's grade (its noise model and specification).
    min_repetitions, min_static_s, min_lack_of_fit_dof : int, float, int
        Margins kept beyond the optimum (docs/test-design.md).
    coarse : bool
        A small search grid.
    noise_characterization : str
        Path of a noise characterisation of the unit (the noise JSON ``imucalib allan``
        writes); the default plan's σ and every candidate's are then predicted with its noise
        instead of the grade's (:func:`~imucalib.procedures.common.grade.characterization_noise`;
        docs/test-design.md, "A noise characterisation in place of the grade's"). Empty: the
        grade's.
    """

    targets: Literal["default", "given", "spec"] = "default"
    target_text: str = ""
    spec_k: float = 3.0
    time_budget_s: float | None = None
    criterion: str = "targets"
    grade: str = "tactical"
    min_repetitions: int = 3
    min_static_s: float = 3600.0
    min_lack_of_fit_dof: int = 6
    coarse: bool = False
    noise_characterization: str = ""


@dataclass(frozen=True)
class OptimizedPlan:
    """A procedure optimiser's answer, against its default plan.

    Attributes
    ----------
    plan : Plan
        The optimised plan.
    prediction, reference : Prediction
        Its predicted uncertainty and the default plan's.
    targets : dict of str to float
        σ_target per parameter, SI.
    ratios : dict of str to float
        σ/σ_target of the optimised plan per targeted parameter.
    worst_ratio, reference_worst_ratio : float
        The largest ratio of the optimised and of the default plan.
    criterion : str
    design : str
        One line: what was chosen.
    notes : tuple of str
    """

    plan: Plan
    prediction: Prediction
    reference: Prediction
    targets: dict[str, float]
    ratios: dict[str, float]
    worst_ratio: float
    reference_worst_ratio: float
    criterion: str
    design: str
    notes: tuple[str, ...] = field(default=())


@runtime_checkable
class Optimizing(Protocol):
    """A procedure that chooses its plan for σ targets (optional capability)."""

    def optimize_plan(self, request: OptimizeRequest) -> OptimizedPlan:
        """Return the plan meeting `request` (docs/test-design.md, "The optimiser")."""
        ...


def optimize_plan(procedure: object, request: OptimizeRequest) -> OptimizedPlan:
    """Return ``procedure.optimize_plan(request)``, or refuse a procedure without it.

    Raises
    ------
    PredictionUnavailableError
        "the optimiser is not available for procedure X yet".
    CalibrationError
        Targets, budget or margins the procedure's optimiser refuses (one line).
    """
    if not isinstance(procedure, Optimizing):
        name = getattr(procedure, "name", "?")
        raise PredictionUnavailableError(f"the optimiser is not available for procedure {name} "
                                         "yet")
    return procedure.optimize_plan(request)


def parse_target_text(text: str, names: Sequence[str], procedure: str) -> dict[str, float]:
    """Parse ``--target NAME=σ,…`` (SI, the result's units) into targets for `procedure`.

    A NAME is one of `names` (``gyro_bias_z``) or a prefix of several (``gyro_bias``,
    ``accel_M``).

    Raises
    ------
    ConfigurationError
        A malformed item, a name that is none of `names` nor a prefix of one, or a σ that is
        not > 0 (one line).
    """
    out: dict[str, float] = {}
    for item in (t.strip() for t in text.split(",")):
        if not item:
            continue
        key, sep, value = item.partition("=")
        key = key.strip()
        try:
            sigma = float(value)
        except ValueError:
            sigma = math.nan
        if not sep or not sigma > 0 or not math.isfinite(sigma):
            raise ConfigurationError(f"target {item!r}: write NAME=σ with σ > 0 in SI units "
                                     "(e.g. gyro_bias=5e-6)")
        hits = [n for n in names if n == key or n.startswith(key + "_")]
        if not hits:
            raise ConfigurationError(f"target {key!r} names no {procedure} parameter (e.g. "
                                     f"{', '.join(list(names)[:2])})")
        out.update(dict.fromkeys(hits, sigma))
    if not out:
        raise ConfigurationError("--target names no parameter")
    return out
