"""A test's decision against the unit's specification.

Every procedure that estimates quantities the unit's specification bounds decides on them as P1
does (docs/p1.md, "Acceptance"; docs/procedures.md, "The result contract"): the per-parameter
limits of the plan's ``[imu.limits]`` (:class:`imucalib.plan.schema.SpecLimits`) as the
recording states them (:class:`~imucalib.io.context.RecordingContext`), the decision rule of its
``[acceptance]`` (simple, or guarded with the guard band k·u), one
:func:`~imucalib.analysis.verification.check_specification` of the quantities the test
estimates, and :func:`~imucalib.analysis.verification.decide`. A test whose quantities no limit
covers makes an explicit *no decision* whose rule says so and names the limits that would.

Which limit bounds which parameter (:func:`spec_field`), by the parameter's name in the triad
model's terms (:mod:`imucalib.models.result`): ``<triad>_bias_<i>`` the bias (|b| ≤ limit),
``<triad>_M_<ii>`` (or a per-axis ``<triad>_K_<i>``, less 1) the scale factor's deviation,
``<triad>_M_<ij>`` (i ≠ j) the misalignment, ``gyro_G_<ij>`` the g-sensitivity; anything else
(an accelerometer's K2, a nonlinearity) has no limit in the specification.

Contents
--------
:data:`SPEC_KINDS`, :func:`spec_field`, :func:`triad_specification_rows`,
:class:`Specification`, :func:`decide_against`, :func:`decide_triad`
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from imucalib import units
from imucalib.analysis.verification import check_specification, decide, decision_rule_text
from imucalib.errors import InvalidInputError
from imucalib.io.context import SPEC_LIMIT_KEYS, RecordingContext
from imucalib.models.decision import Check, Decision, no_decision

__all__ = ["SPEC_CHECK", "SPEC_KINDS", "SpecRow", "Specification", "decide_against",
           "decide_triad", "spec_field", "triad_specification_rows"]

#: The name of the check against the specification (P1's too).
SPEC_CHECK = "specification"
#: Display unit, SI value of one display unit and the SpecLimits field, per (triad, kind).
SPEC_KINDS: dict[tuple[str, str], tuple[str, float, str]] = {
    ("accel", "bias"): ("µg", units.UG, "accel_bias_ug"),
    ("accel", "scale"): ("ppm", units.PPM, "accel_scale_ppm"),
    ("accel", "misalignment"): ("µrad", units.URAD, "accel_misalignment_urad"),
    ("gyro", "bias"): ("°/h", units.DEG_PER_H, "gyro_bias_dph"),
    ("gyro", "scale"): ("ppm", units.PPM, "gyro_scale_ppm"),
    ("gyro", "misalignment"): ("µrad", units.URAD, "gyro_misalignment_urad"),
    ("gyro", "g-sensitivity"): ("(°/h)/g", units.DEG_PER_H / units.G0_MPS2,
                                "gyro_g_sensitivity_dph_per_g"),
}

#: One row of :func:`~imucalib.analysis.verification.check_specification`:
#: (label, value, u, limit or None, unit), in the display unit.
SpecRow = tuple[str, float, float, float | None, str]


def _kind(name: str) -> tuple[str, str] | None:
    """Return (triad, kind) of a triad parameter's name, None when no limit can bound it."""
    parts = name.split("_")
    if len(parts) != 3 or parts[0] not in ("accel", "gyro"):
        return None
    triad, symbol, axes = parts
    if symbol in ("bias", "b") and len(axes) == 1:
        kind = "bias"
    elif symbol == "K" and len(axes) == 1:
        kind = "scale"
    elif symbol == "M" and len(axes) == 2:
        kind = "scale" if axes[0] == axes[1] else "misalignment"
    elif symbol == "G" and len(axes) == 2:
        kind = "g-sensitivity"
    else:
        return None
    return (triad, kind) if (triad, kind) in SPEC_KINDS else None


def spec_field(name: str) -> tuple[str, float, str] | None:
    """Return (display unit, SI value of one display unit, SpecLimits field) of a parameter.

    None for a parameter no specification limit bounds (an accelerometer's K2, a gyro's
    quadratic term, a name outside the triad model).
    """
    kind = _kind(name)
    return None if kind is None else SPEC_KINDS[kind]


def triad_specification_rows(names: Sequence[str], values: ArrayLike, covariance: ArrayLike,
                             limits: Mapping[str, float]) -> list[SpecRow]:
    """Return each parameter a limit can bound, in its display unit: (label, value, u, limit, unit).

    Parameters
    ----------
    names : sequence of str
        Triad parameter names (module docstring).
    values : array_like, shape (n,)
        Their values, SI; a scale factor ``K`` is its whole factor (1 is taken off), ``M_ii``
        its deviation.
    covariance : array_like, shape (n, n)
        Their covariance as reported (u = √ of its diagonal, used by a guarded rule).
    limits : mapping of str to float
        The SpecLimits fields given (absent: that quantity is not specified; its row has limit
        None and :func:`~imucalib.analysis.verification.check_specification` skips it).
    """
    v = np.asarray(values, dtype=np.float64).reshape(-1)
    cov = np.asarray(covariance, dtype=np.float64)
    u = np.sqrt(np.clip(np.diag(cov), 0.0, None)) if cov.size else np.zeros(v.size)
    rows: list[SpecRow] = []
    for k, name in enumerate(names):
        spec = spec_field(name)
        if spec is None:
            continue
        unit, scale, field_name = spec
        value = float(v[k]) - (1.0 if name.split("_")[1] == "K" else 0.0)
        rows.append((name, value / scale, float(u[k]) / scale, limits.get(field_name), unit))
    return rows


@dataclass(frozen=True)
class Specification:
    """The unit's per-parameter limits and the decision rule a test is judged by.

    Attributes
    ----------
    limits : mapping of str to float
        The :class:`~imucalib.plan.schema.SpecLimits` fields the recording gives (none: no
        limit, the test makes no decision).
    rule : {"simple", "guarded"}
    guard_band_k : float
        k of a guarded rule's guard band w = k·u.
    source : str
        Where the limits come from, in words (the rule text of a decision names it).

    Raises
    ------
    InvalidInputError
        An unknown limit, a limit that is not a finite number ≥ 0, an unknown rule, k ≤ 0.
    """

    limits: Mapping[str, float] = field(default_factory=dict)
    rule: str = "simple"
    guard_band_k: float = 2.0
    source: str = "[imu.limits] as recorded"

    def __post_init__(self) -> None:
        unknown = sorted(set(self.limits) - set(SPEC_LIMIT_KEYS))
        if unknown:
            raise InvalidInputError(f"specification limits {unknown} are not SpecLimits fields "
                                    f"({', '.join(SPEC_LIMIT_KEYS)})")
        for key, value in self.limits.items():
            if not (isinstance(value, int | float) and math.isfinite(value) and value >= 0):
                raise InvalidInputError(f"specification limit {key} must be a finite number "
                                        f"≥ 0; got {value!r}")
        if not (math.isfinite(self.guard_band_k) and self.guard_band_k > 0):
            raise InvalidInputError(f"the guard band k must be > 0; got {self.guard_band_k!r}")
        decision_rule_text(self.rule, self.guard_band_k)  # the rule must be known
        object.__setattr__(self, "limits", dict(self.limits))

    @classmethod
    def of_context(cls, context: RecordingContext) -> Specification:
        """Return the specification a recording states (its limits, rule and guard band).

        Raises
        ------
        InvalidInputError
            The recording's ``acceptance`` is neither ``simple`` nor ``guarded``, or its guard
            band is not > 0.
        """
        return cls(limits=dict(context.spec_limits), rule=context.acceptance or "simple",
                   guard_band_k=(context.guard_band_k if context.guard_band_k is not None
                                 else 2.0))

    @classmethod
    def of_metadata(cls, metadata: Mapping[str, Any]) -> Specification:
        """Return the specification of a recording's metadata (:meth:`of_context`)."""
        return cls.of_context(RecordingContext.of(metadata))

    @property
    def rule_text(self) -> str:
        """The decision rule's statement (:func:`~.verification.decision_rule_text`)."""
        return decision_rule_text(self.rule, self.guard_band_k)

    def to_dict(self) -> dict[str, Any]:
        """Return the JSON-able form."""
        return {"limits": dict(self.limits), "rule": self.rule,
                "guard_band_k": self.guard_band_k, "source": self.source}


def decide_against(spec: Specification, rows: Sequence[SpecRow], *, test: str, what: str,
                   notes: Sequence[str] = (), checks: Sequence[Check] = ()) -> Decision:
    """Return a test's decision on `rows` against `spec` (module docstring).

    Parameters
    ----------
    spec : Specification
    rows : sequence of SpecRow
        Every quantity of the test a specification limit can bound
        (:func:`triad_specification_rows`), with its limit (None where not specified).
    test : str
        The test, as the rule text names it (``"the tumble"``).
    what : str
        What the test measures and where it is described, for the rule of a *no decision*
        (``"it estimates the accelerometers' coefficients (docs/tumble.md)"``).
    notes : sequence of str
        What the decision must say besides (each misfit's summary).
    checks : sequence of Check
        The test's other checks, before the specification's (they count in the verdict when
        they are assessed).

    Returns
    -------
    Decision
        The check ``specification`` of the rows with a limit and the verdict under the rule;
        *no decision* when no row has a limit and no other check was assessed: its rule says
        that no specification limit covers the test's quantities and names the limits
        (``[imu.limits]`` fields) that would.
    """
    covering = _fields(rows)
    limited = [r for r in rows if r[3] is not None]
    if not limited and not any(c.assessed for c in checks):
        which = (f"gives none of the limits that would cover its quantities ({', '.join(covering)})"
                 if covering else "has no limit for its quantities")
        return no_decision(f"{test} has no acceptance limits: the unit's specification "
                           f"({spec.source}) {which}; {what}", notes=tuple(notes))
    check = check_specification(SPEC_CHECK, limited, rule=spec.rule,
                                guard_band_k=spec.guard_band_k)
    unspecified = _fields([r for r in rows if r[3] is None])
    if unspecified:
        check = Check(check.name, check.passed,
                      f"{check.summary}; not specified, not judged: {', '.join(unspecified)}",
                      check.rows)
    return decide([*checks, check], notes=notes,
                  rule=f"{spec.rule_text}; limits: {spec.source} ({', '.join(_fields(limited))})")


def decide_triad(spec: Specification, triad: tuple[Sequence[str], ArrayLike, ArrayLike], *,
                 test: str, what: str, notes: Sequence[str] = ()) -> Decision:
    """Return the decision on a test's triad parameters (names, values, covariance as reported).

    :func:`triad_specification_rows` of `triad` against ``spec.limits``, then
    :func:`decide_against` (a *no decision* when no limit covers them).
    """
    names, values, covariance = triad
    return decide_against(spec, triad_specification_rows(names, values, covariance, spec.limits),
                          test=test, what=what, notes=notes)


def _fields(rows: Sequence[SpecRow]) -> list[str]:
    """Return the SpecLimits fields that bound `rows`, in the order of :data:`SPEC_LIMIT_KEYS`."""
    found = {spec[2] for r in rows if (spec := spec_field(r[0])) is not None}
    return [k for k in SPEC_LIMIT_KEYS if k in found]
