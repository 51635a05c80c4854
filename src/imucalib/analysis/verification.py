"""Verification of a calibration: residuals, held-out accuracy, repeatability, the decision.

Pure functions over numbers; a procedure gathers them into its decision (docs/p1.md).

Contents
--------
:class:`CheckRow`, :class:`Check`, :class:`Decision`
    One compared quantity, one named check (its rows and verdict), the overall decision.
:func:`check_residuals`
    P1 rule 5 (docs/p1.md): at every position and rate point the residual mean ≈ 0 and its standard
    deviation within the limit (0.002 g, 0.1 °/s), and no significant misfit overall (a χ² test of
    the residual means against their standard errors: "a trend or a large residual means the
    model is too simple").
:func:`check_accuracy`
    P1 rule 7 (docs/p1.md): after compensation, the error at held-out positions and rates within the
    IMU's specification (0.01 g, 0.5 °/s by default).
:func:`check_repeatability`
    P1 rule 6 (docs/p1.md): over the repetitions, the coefficient of variation of each scale factor
    ≤ 1 %; for parameters near zero (biases, misalignments, g-sensitivities), where a CV means
    nothing, the spread (sample standard deviation) within k times the parameter's typical
    standard uncertainty.
:func:`decide`
    The overall verdict and its rule.

Decision rule
-------------
*Simple acceptance* (ISO/IEC Guide 98-4 §8.2, ILAC-G8 "simple acceptance"): a check passes when
every measured value lies within its limit, with no guard band; the calibration passes when every
assessed check passes. Checks that could not be assessed (e.g. repeatability with one
repetition) are listed and do not count. A plan may choose *guarded acceptance* instead
(:func:`decision_rule_text`, :func:`check_specification`): a specified parameter passes only when
|value| + k·u is within its limit.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike
from scipy import stats

from imucalib.errors import InvalidInputError
from imucalib.models.decision import Check, CheckRow, Decision

__all__ = [
    "DECISION_RULE",
    "Check",
    "CheckRow",
    "Decision",
    "check_accuracy",
    "check_repeatability",
    "check_residuals",
    "check_specification",
    "decide",
    "decision_rule_text",
]

DECISION_RULE = ("simple acceptance (ISO/IEC Guide 98-4 §8.2; ILAC-G8): each value within its "
                 "limit, no guard band; pass when every assessed check passes")


def decision_rule_text(rule: str = "simple", guard_band_k: float = 2.0) -> str:
    """Return the statement of a decision rule (``"simple"`` or ``"guarded"`` acceptance).

    Guarded acceptance (ISO/IEC Guide 98-4:2012 §8.3.2; ILAC-G8:09/2019 §4.2.2): a value passes
    when |value| + w ≤ limit, with the guard band w = k·u.
    """
    if rule == "simple":
        return DECISION_RULE
    if rule == "guarded":
        return (f"guarded acceptance (ISO/IEC Guide 98-4 §8.3.2; ILAC-G8 §4.2.2): a specified "
                f"parameter passes when |value| + {guard_band_k:g}·u is within its limit "
                f"(guard band w = {guard_band_k:g}u); pass when every assessed check passes")
    raise InvalidInputError(f"decision rule must be 'simple' or 'guarded'; got {rule!r}")


def check_specification(name: str, rows: Sequence[tuple[str, float, float, float | None, str]],
                        *, rule: str = "simple", guard_band_k: float = 2.0) -> Check:
    """Check calibrated parameters against the unit's specification.

    Parameters
    ----------
    name : str
        The check's name (``"specification"``).
    rows : sequence of (label, value, u, limit, unit)
        Each specified quantity in its display unit: the value (its magnitude is compared),
        its standard uncertainty u, its limit (None: not specified, skipped).
    rule : {"simple", "guarded"}
        Simple acceptance: |value| ≤ limit; guarded: |value| + k·u ≤ limit
        (:func:`decision_rule_text`).
    guard_band_k : float
        k of the guard band.

    Returns
    -------
    Check
        Not assessed (None) when no row has a limit.
    """
    decision_rule_text(rule, guard_band_k)  # validates the rule
    out: list[CheckRow] = []
    for label, value, u, limit, unit in rows:
        if limit is None:
            continue
        band = guard_band_k * u if rule == "guarded" else 0.0
        magnitude = abs(value) + band
        detail = (f"|value| {abs(value):.3g} + {guard_band_k:g}u {band:.3g}" if band else "")
        out.append(CheckRow(label, magnitude, float(limit), unit, magnitude <= limit, detail))
    if not out:
        return Check(name, None, "no specification limits given: not assessed")
    failed = [r for r in out if not r.passed]
    what = "within" if rule == "simple" else "within, with the guard band,"
    summary = (f"{len(out)} specified quantities {what} their limits" if not failed
               else f"{len(failed)} of {len(out)} specified quantities beyond their limits: "
                    + ", ".join(r.name for r in failed[:6]) + ("…" if len(failed) > 6 else ""))
    return Check(name, not failed, summary, tuple(out))


def check_residuals(name: str, groups: Sequence[tuple[str, ArrayLike, ArrayLike]],
                    *, mean_limit: float, std_limit: float, unit: str, scale: float,
                    chi2: float, dof: int, significance: float = 1e-3) -> Check:
    """Check residuals group by group and their overall consistency.

    Parameters
    ----------
    name : str
        The check's name (``"accelerometer residuals"``).
    groups : sequence of (label, mean (3,), std (3,))
        Residual mean and standard deviation of each window, SI.
    mean_limit, std_limit : float
        Limits in the display unit (`unit`; e.g. 0.002 g, 0.1 °/s).
    unit : str
        Display unit.
    scale : float
        SI value of one display unit (g → 9.80665).
    chi2 : float
        Σ (residual mean / its standard error)² of the fit.
    dof : int
        Its degrees of freedom.
    significance : float
        p-value below which the residual means are too large for their noise (model too simple).
    """
    rows: list[CheckRow] = []
    for label, mean, std in groups:
        worst_mean = float(np.max(np.abs(mean))) / scale
        worst_std = float(np.max(std)) / scale
        rows.append(CheckRow(f"{label}: |mean|", worst_mean, mean_limit, unit,
                             worst_mean <= mean_limit))
        rows.append(CheckRow(f"{label}: std", worst_std, std_limit, unit, worst_std <= std_limit))
    p_value = float(stats.chi2.sf(chi2, dof)) if dof > 0 else 1.0
    rows.append(CheckRow("χ² of the residual means (p-value)", p_value, significance, "",
                         p_value >= significance,
                         f"χ² = {chi2:.4g} with {dof} degrees of freedom"))
    failed = [r for r in rows if not r.passed]
    summary = ("all residuals within limits and consistent with the noise" if not failed
               else f"{len(failed)} of {len(rows)} residual criteria exceeded (model too simple "
                    "or bad data)")
    return Check(name, not failed, summary, tuple(rows))


def check_accuracy(name: str, errors: Sequence[tuple[str, ArrayLike]], *, limit: float,
                   unit: str, scale: float) -> Check:
    """Check held-out errors after compensation against the specification.

    `errors` holds (label, error (3,) SI) per held-out window; `limit` is in `unit`.
    """
    if not errors:
        return Check(name, None, "no held-out windows: accuracy not assessed")
    rows = []
    for label, err in errors:
        worst = float(np.max(np.abs(err))) / scale
        rows.append(CheckRow(label, worst, limit, unit, worst <= limit))
    failed = [r for r in rows if not r.passed]
    worst_all = max(r.value for r in rows)
    summary = (f"largest held-out error {worst_all:.3g} {unit} (limit {limit:g} {unit})")
    return Check(name, not failed, summary, tuple(rows))


def check_repeatability(name: str, estimates: Mapping[str, Sequence[float]],
                        sigmas: Mapping[str, Sequence[float]], units: Mapping[str, str],
                        *, scale_names: Sequence[str], cv_limit: float = 0.01,
                        spread_k: float = 3.0) -> Check:
    """Check the spread of each parameter over repetitions.

    Parameters
    ----------
    estimates, sigmas : mapping of name to sequence of float
        The parameter's estimate and standard uncertainty in each repetition.
    units : mapping of name to str
    scale_names : sequence of str
        Parameters judged by their coefficient of variation (scale factors, ≈ 1).
    cv_limit : float
        Largest CV (docs/p1.md, rule 6: 1 %).
    spread_k : float
        Other parameters: the sample standard deviation must stay within `spread_k` × the RMS
        of their reported standard uncertainties.
    """
    counts = {len(v) for v in estimates.values()}
    n = min(counts) if counts else 0
    if n < 2:
        return Check(name, None, f"{n} repetition(s): repeatability needs at least 2")
    rows = []
    for pname, values in estimates.items():
        v = np.asarray(values, dtype=np.float64)
        spread = float(v.std(ddof=1))
        if pname in scale_names:
            mean = float(v.mean())
            cv = spread / abs(mean) if mean != 0 else math.inf
            rows.append(CheckRow(pname, cv, cv_limit, "CV", cv <= cv_limit,
                                 f"mean {mean:.9g}, std {spread:.3g}"))
        else:
            typical = float(np.sqrt(np.mean(np.square(sigmas[pname]))))
            limit = spread_k * typical
            rows.append(CheckRow(pname, spread, limit, units.get(pname, ""), spread <= limit,
                                 f"spread vs {spread_k:g}× typical σ {typical:.3g}"))
    failed = [r for r in rows if not r.passed]
    summary = (f"{n} repetitions: {len(rows) - len(failed)} of {len(rows)} parameters repeat "
               "within their limits")
    return Check(name, not failed, summary, tuple(rows))


def decide(checks: Sequence[Check], *, notes: Sequence[str] = (),
           rule: str = DECISION_RULE) -> Decision:
    """Return the overall decision under `rule` (its statement; :func:`decision_rule_text`).

    `notes` are what the decision must say besides its checks (a model misfit and the scaled
    uncertainties that go with it); they are printed with its summary.
    """
    failed = tuple(c.name for c in checks if c.passed is False)
    not_assessed = tuple(c.name for c in checks if c.passed is None)
    return Decision(passed=not failed and any(c.assessed for c in checks), rule=rule,
                    failed=failed, not_assessed=not_assessed, checks=tuple(checks),
                    notes=tuple(notes))
