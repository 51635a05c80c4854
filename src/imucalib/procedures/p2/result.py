"""P2's result of one unit and its decision: the points, the temperature models, the verdict.

:class:`P2UnitResult` is what :func:`~imucalib.procedures.p2.analysis.analyze_unit` returns for
a unit (a :class:`~imucalib.models.procedure_result.ProcedureResult`, docs/procedures.md, "The
result contract"); :class:`PointResult` one of its temperature points. The decision
(:attr:`P2UnitResult.decision`, rule :data:`DECISION_RULE`, docs/p2.md "The decision"): at
every held-out point (at every calibration point when none was held out) the output error left
after compensation at the reference input must be within the specification's accuracy, and
the closed form must agree with least squares within :data:`AGREEMENT_LIMIT` σ; a unit that
could not be calibrated fails with its error. The held-out consistency of the temperature
models (:data:`HELD_OUT_CHECK`: each model's max|z| ≤ :data:`HELD_OUT_Z_LIMIT` and p ≥
:data:`HELD_OUT_ALPHA` at the held-out points) is one of the decision's checks, not part of the
rule.

Contents
--------
:class:`PointResult`, :class:`P2UnitResult`, :data:`AGREEMENT_LIMIT`, :data:`DECISION_RULE`,
:data:`HELD_OUT_CHECK`, :data:`HELD_OUT_Z_LIMIT`, :data:`HELD_OUT_ALPHA`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Final

import numpy as np
from scipy import stats

from imucalib import units as u
from imucalib.estimation.temperature_model import HeldOutCheck, TemperatureModelFit
from imucalib.models.decision import Check, CheckRow, Decision
from imucalib.models.fit_quality import FitQuality
from imucalib.models.procedure_result import (
    ProcedureResult,
    TriadParameters,
    no_triad_parameters,
)
from imucalib.models.reported import ReportedParameter
from imucalib.models.result import CalibrationResult, Provenance
from imucalib.procedures.p2.reduction import PointEstimate

__all__ = ["AGREEMENT_LIMIT", "DECISION_RULE", "HELD_OUT_ALPHA", "HELD_OUT_CHECK",
           "HELD_OUT_Z_LIMIT", "P2UnitResult", "PointResult"]

#: The largest |closed form − least squares| accepted, in σ of the least-squares estimate.
AGREEMENT_LIMIT: Final = 4.0
#: P2's acceptance rule in words (docs/p2.md, "The decision").
DECISION_RULE: Final = (
    "P2 acceptance (docs/p2.md): the largest accelerometer and gyro output error left after "
    "compensation, at the held-out temperature points (the calibration points when none is "
    "held out), within the plan's accuracy; the closed form agrees with least squares within "
    f"{AGREEMENT_LIMIT:g} σ")
#: The name of the check of the temperature models at the held-out points (not in the rule).
HELD_OUT_CHECK: Final = "held-out consistency of the temperature models"
#: A model is consistent at the held-out points when every |z_i| ≤ this (Eq. (10)) ...
HELD_OUT_Z_LIMIT: Final = 3.0
#: ... and the p-value of their χ² (Eq. (11)) is at least this.
HELD_OUT_ALPHA: Final = 0.01




@dataclass(frozen=True)
class PointResult:
    """One temperature point of one unit.

    Attributes
    ----------
    point, leg, held_out : int, str, bool
    temperature_degc, temperature_rate_degc_ps : float
        Mean internal temperature of the point's windows and their mean slope.
    least_squares, closed_form, naive : PointEstimate
        The full fit, the patent's closed form, and the closed form ignoring the lever arm.
    agreement_sigma : float
        max |closed form − least squares| / σ(least squares) over the parameters.
    """

    point: int
    leg: str
    held_out: bool
    temperature_degc: float
    temperature_rate_degc_ps: float
    least_squares: PointEstimate
    closed_form: PointEstimate
    naive: PointEstimate
    agreement_sigma: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form."""
        ls = self.least_squares
        std = np.sqrt(np.diag(ls.covariance_scaled()))
        return {
            "point": self.point, "leg": self.leg, "held_out": self.held_out,
            "temperature_degc": self.temperature_degc,
            "temperature_rate_degc_ps": self.temperature_rate_degc_ps,
            "parameters": {n: {"value": float(v), "std": float(s),
                               "closed_form": float(c), "naive": float(nv)}
                           for n, v, s, c, nv in zip(ls.names, ls.values, std,
                                                     self.closed_form.values,
                                                     self.naive.values, strict=True)},
            "fit_quality": [_quality_dict(q) for q in ls.fit_quality],
            "agreement_sigma": self.agreement_sigma,
        }


def _quality_dict(q: FitQuality) -> dict[str, Any]:
    return {"group": q.group, "chi2": q.chi2, "dof": q.dof, "reduced_chi2": q.reduced_chi2,
            "misfit": q.misfit, "birge_ratio": q.birge_ratio}


@dataclass(frozen=True)
class P2UnitResult:
    """The P2 result of one unit (a :class:`~imucalib.models.procedure_result.ProcedureResult`).

    ``error`` is set (and everything else empty) when the unit could not be calibrated; the
    other units of the array are not affected.

    Attributes
    ----------
    unit : str
    passed : bool or None
        The verdict of :attr:`decision` (False with an `error`).
    points, models, held_out
        Each temperature point's estimates, each parameter's temperature model and its
        held-out check.
    result : CalibrationResult or None
        The parameters at T0 with the covariance of Eq. (P2.12) (docs/p2.md), Birge ratios
        included; None when the unit could not be calibrated.
    compensated_error, error_limits : mapping of str to float
        The largest output error after compensation and its limit (``accel_mps2``,
        ``gyro_rps``). [m/s², rad/s]
    reasons : tuple of str
        Why the unit failed (the decision's failed checks).
    notes : tuple of str
    error, error_type : str
        Why the unit could not be calibrated, and the error's type.
    procedure : str
    std_noise : mapping of str to float
        Each parameter's σ at T0 before Birge scaling: Eq. (P2.12) with s = 1 and each point's
        noise-only covariance C_k, the same GLS weights W (empty for a unit not calibrated).
    """

    unit: str
    passed: bool | None
    points: tuple[PointResult, ...] = ()
    models: Mapping[str, TemperatureModelFit] = field(default_factory=dict)
    held_out: Mapping[str, HeldOutCheck] = field(default_factory=dict)
    result: CalibrationResult | None = None
    compensated_error: Mapping[str, float] = field(default_factory=dict)
    error_limits: Mapping[str, float] = field(default_factory=dict)
    reasons: tuple[str, ...] = ()
    notes: tuple[str, ...] = ()
    error: str = ""
    error_type: str = ""
    procedure: str = "p2"
    std_noise: Mapping[str, float] = field(default_factory=dict)

    @property
    def fit_quality(self) -> tuple[FitQuality, ...]:
        """Each temperature model's χ²/ν and misfit verdict (Birge-scaled where a misfit)."""
        return tuple(m.quality for m in self.models.values())

    @property
    def calibration(self) -> CalibrationResult | None:
        """The parameters at T0 (:attr:`result`), or None for a unit not calibrated."""
        return self.result

    @property
    def provenance(self) -> Provenance | None:
        """The calibration's provenance, or None for a unit not calibrated."""
        return None if self.result is None else self.result.provenance

    @property
    def members(self) -> tuple[ProcedureResult, ...]:
        """No members: the result of one unit."""
        return ()

    @property
    def omitted(self) -> tuple[str, ...]:
        """Nothing left out: a unit is calibrated whole or fails with its error."""
        return ()

    @property
    def decision(self) -> Decision:
        """The unit's verdict under :data:`DECISION_RULE` (docs/p2.md, "The decision").

        ``failed`` are the :attr:`reasons`; the checks are the accelerometer's and the gyro's
        error after compensation against their limits and the agreement of the closed form
        with least squares. A unit that could not be calibrated fails with its error.
        """
        if self.error:
            return Decision(passed=self.passed, rule="a P2 unit that could not be calibrated "
                            "fails (docs/p2.md)", failed=self.reasons or (self.error,),
                            not_assessed=("error after compensation",))
        checks = []
        for name, key, unit, scale in (
                ("accelerometer error after compensation", "accel_mps2", "g", u.G0_MPS2),
                ("gyro error after compensation", "gyro_rps", "°/s", u.DEG)):
            if key in self.compensated_error and key in self.error_limits:
                value, limit = self.compensated_error[key], self.error_limits[key]
                ok = not value > limit
                checks.append(Check(name, ok, f"{value / scale:.3g} {unit} (limit "
                                    f"{limit / scale:g} {unit})",
                                    (CheckRow(name, value / scale, limit / scale, unit, ok),)))
        if self.points:
            worst = max(p.agreement_sigma for p in self.points)
            ok = not worst > AGREEMENT_LIMIT
            checks.append(Check("closed form against least squares", ok,
                                f"largest difference {worst:.2g} σ (limit {AGREEMENT_LIMIT:g} σ)",
                                (CheckRow("largest |closed form − least squares|", worst,
                                          AGREEMENT_LIMIT, "σ", ok),)))
        misfits = sum(m.quality.misfit for m in self.models.values())
        notes = [f"the temperature models of {misfits} parameter(s) are misfits: their σ are "
                 "Birge-scaled by √(χ²/ν)"] if misfits else []
        if self.held_out:
            held, note = self._held_out_check()
            checks.append(held)
            if note:
                notes.append(note)
        return Decision(passed=self.passed, rule=DECISION_RULE, failed=tuple(self.reasons),
                        checks=tuple(checks), notes=tuple(notes))

    @property
    def held_out_inconsistent(self) -> tuple[str, ...]:
        """The parameters whose temperature model is NOT consistent at the held-out points."""
        return tuple(n for n, c in self.held_out.items() if not c.consistent)

    def _held_out_check(self) -> tuple[Check, str]:
        """Return the check :data:`HELD_OUT_CHECK` (verdict None: not in the rule) and its note.

        Its rows: each model NOT consistent at the held-out points, with its max|z| against
        :data:`HELD_OUT_Z_LIMIT` where that is what fails, else its χ² p-value against
        :data:`HELD_OUT_ALPHA`. The note (empty when every model is consistent) names them and
        says why the verdict does not count them, and whether their number is beyond what
        chance gives: each model is tested on its own, at a false-alarm rate q of at most
        α + ν_h·2Φ(−3), so among n models about n·q fail by chance (a binomial tail below
        :data:`HELD_OUT_ALPHA` says more than chance).
        """
        bad = self.held_out_inconsistent
        n = len(self.held_out)
        rows = []
        for name in bad:
            c = self.held_out[name]
            z = float(np.max(np.abs(c.normalised_residuals)))
            detail = f"max|z| {z:.2g}, χ² = {c.chi2:.3g} (ν = {c.dof}), p = {c.p_value:.2g}"
            rows.append(CheckRow(name, z, HELD_OUT_Z_LIMIT, "|z|", False, detail)
                        if z > HELD_OUT_Z_LIMIT else
                        CheckRow(f"{name} (p-value)", c.p_value, HELD_OUT_ALPHA, "", False,
                                 detail))
        why = ("not part of P2's rule (docs/p2.md, \"The decision\"): the verdict judges the "
               "error left after compensation at the held-out points")
        if not bad:
            return Check(HELD_OUT_CHECK, None, f"all {n} temperature models consistent at the "
                         f"held-out points (max|z| ≤ {HELD_OUT_Z_LIMIT:g}, p ≥ "
                         f"{HELD_OUT_ALPHA:g}); {why}"), ""
        dof = max(c.dof for c in self.held_out.values())
        rate = min(1.0, HELD_OUT_ALPHA + dof * 2.0 * float(stats.norm.sf(HELD_OUT_Z_LIMIT)))
        tail = float(stats.binom.sf(len(bad) - 1, n, rate))
        named = ", ".join(bad[:8]) + (", …" if len(bad) > 8 else "")
        summary = (f"{len(bad)} of {n} temperature models NOT consistent at the held-out "
                   f"points ({named}): they do not predict the held-out estimates within their "
                   f"uncertainty; {why}")
        chance = (f"more than chance gives (about {n * rate:.2g} of {n} by chance, binomial "
                  f"p = {tail:.2g}): these models' uncertainties understate their error "
                  "between the calibration points" if tail < HELD_OUT_ALPHA else
                  f"within what chance gives (about {n * rate:.2g} of {n} by chance, "
                  f"binomial p = {tail:.2g})")
        note = (f"{HELD_OUT_CHECK}: {len(bad)} of {n} NOT consistent ({named}); not counted "
                f"in the verdict: P2's rule judges the error left after compensation "
                f"(docs/p2.md); {chance}")
        return Check(HELD_OUT_CHECK, None, summary, tuple(rows)), note

    def parameter_rows(self) -> list[ReportedParameter]:
        """Return every parameter at T0: value, σ of Eq. (P2.12), SI unit, σ before scaling.

        ``std`` is the σ the result reports (its covariance holds the Birge ratios of misfit
        point fits and temperature models, docs/p2.md Eq. (P2.12)); ``std_noise`` the same σ
        before any Birge scaling (:attr:`std_noise`; ``std`` where it is not known). Empty for a
        unit that could not be calibrated.
        """
        cal = self.result
        if cal is None:
            return []
        std = cal.std(scaled=True)
        return [ReportedParameter(n, float(v), std[n], str(cal.units.get(n, "")),
                                  float(self.std_noise.get(n, std[n])))
                for n, v in zip(cal.param_names, cal.values, strict=True)]

    def triad_parameters(self) -> TriadParameters:
        """Return the parameters at T0 with the covariance of Eq. (P2.12) (none if failed)."""
        cal = self.result
        if cal is None:
            return no_triad_parameters()
        return list(cal.param_names), cal.values.copy(), cal.covariance_scaled.copy()

    def to_dict(self) -> dict[str, Any]:
        """Return the whole result as JSON-able data."""
        return {
            "procedure": self.procedure, "unit": self.unit, "passed": self.passed,
            "error": self.error, "error_type": self.error_type,
            "reasons": list(self.reasons), "notes": list(self.notes),
            "compensated_error": dict(self.compensated_error),
            "error_limits": dict(self.error_limits),
            "points": [p.to_dict() for p in self.points],
            "temperature_models": {
                n: {"order": m.order, "criterion": m.criterion,
                    "reference_temperature_degc": m.model.reference_temperature_degc,
                    "coefficients": list(m.model.coefficients),
                    "coefficients_std": m.std().tolist(),
                    "rate_coefficient": m.model.rate_coefficient,
                    "leg_coefficient": m.model.leg_coefficient,
                    "chi2": m.chi2, "dof": m.dof, "misfit": m.quality.misfit, "note": m.note,
                    **({"held_out": {"max_abs_z": float(np.max(np.abs(
                        self.held_out[n].normalised_residuals))),
                        "chi2": self.held_out[n].chi2, "dof": self.held_out[n].dof,
                        "p_value": self.held_out[n].p_value,
                        "consistent": self.held_out[n].consistent}}
                       if n in self.held_out else {})}
                for n, m in self.models.items()},
            "result": None if self.result is None else self.result.to_dict(),
        }
