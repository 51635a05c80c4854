"""P1's predicted σ beside the achieved σ, and whether a run is worse than its plan predicted.

After a run, the plan that made it predicts each parameter's σ twice
(:func:`~imucalib.procedures.p1.predict.predict_p1_covariance`, docs/test-design.md,
Eqs. (TD.1)–(TD.4)): with the unit grade's nominal noise model — what the plan promised — and
with the noise model the analysis fitted to the run's static record — the like-for-like
comparison, which reproduces the achieved noise-only σ to about 1 %. The achieved σ is the one
the calibration reports (Birge-scaled under a misfit, the model choice's TS.4 term included).

The rule (docs/test-design.md, "Predicted against achieved", Eqs. (PA.1)–(PA.4)): per triad t,
the geometric mean of the variance ratios of its parameters,

    r_i = σ²_achieved,i / σ²_pred,i                                           (PA.1)
    R_t = exp( (1/p_t) Σ_i ln r_i )                                           (PA.2)

against the upper 99 % quantile of χ²_ν/ν, ν the effective degrees of freedom of the noise
estimate the achieved σ rests on (Welch–Satterthwaite: the white density is known from the
record's samples, the flicker and random-walk terms only with ν_B, the EDF of the flicker Allan
variance at the Allan fit's longest averaging time, summed over the pooled static records;
φ_t the share of the triad's predicted variance those
terms carry):

    ν_t = ν_B / φ_t²                                                         (PA.3)
    worse than predicted  ⇔  R_t > χ²_ν_t⁻¹(0.99) / ν_t                       (PA.4)

Contents
--------
:class:`PredictedRow`, :class:`PredictedGroup`, :class:`PredictionCheck`,
:func:`compare_with_prediction`, :data:`WORSE_QUANTILE`
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Final

import numpy as np
from scipy import stats

from imucalib.analysis.edf import compute_edf_greenhall
from imucalib.errors import ConfigurationError, InsufficientExcitationError
from imucalib.models.noise import NoiseModel
from imucalib.procedures.common.noise import noise_records

if TYPE_CHECKING:
    from imucalib.plan.schema import Plan
    from imucalib.procedures.p1.windows import P1Observations

__all__ = ["WORSE_QUANTILE", "PredictedGroup", "PredictedRow", "PredictionCheck",
           "compare_with_prediction"]

#: The quantile of χ²_ν/ν above which a triad's achieved σ is worse than predicted, Eq. (PA.4).
WORSE_QUANTILE: Final = 0.99


@dataclass(frozen=True)
class PredictedRow:
    """One parameter: its predicted σ (grade noise, fitted noise), achieved σ, ratio. [SI]

    ``predicted_fitted_std`` is None without a fitted noise model (no static record long enough);
    ``ratio`` is σ_achieved / σ_pred (grade), the square root of Eq. (PA.1).
    """

    name: str
    unit: str
    predicted_std: float
    predicted_fitted_std: float | None
    achieved_std: float

    @property
    def ratio(self) -> float:
        """σ_achieved / σ_predicted (grade noise)."""
        return self.achieved_std / self.predicted_std

    @property
    def fitted_ratio(self) -> float | None:
        """σ_achieved / σ_predicted (fitted noise), None without a fitted noise model."""
        f = self.predicted_fitted_std
        return None if f is None else self.achieved_std / f

    def to_dict(self) -> dict[str, Any]:
        """Return the row as JSON-able data."""
        return {"name": self.name, "unit": self.unit, "predicted_std": self.predicted_std,
                "predicted_std_fitted_noise": self.predicted_fitted_std,
                "achieved_std": self.achieved_std, "ratio": self.ratio,
                "ratio_fitted_noise": self.fitted_ratio}


@dataclass(frozen=True)
class PredictedGroup:
    """One triad's test, Eqs. (PA.2)–(PA.4).

    Attributes
    ----------
    name : str
        ``"accel"`` or ``"gyro"``.
    variance_ratio : float
        R_t, the geometric mean of its parameters' variance ratios (PA.2).
    correlated_share : float
        φ_t, the share of its predicted variance carried by flicker and random walk.
    dof : float
        ν_t of (PA.3) (inf when only white noise matters).
    limit : float
        χ²_ν_t⁻¹(0.99)/ν_t, the largest R_t the noise estimate allows (PA.4).
    worst : str
        Its parameter of the largest ratio.
    """

    name: str
    variance_ratio: float
    correlated_share: float
    dof: float
    limit: float
    worst: str

    @property
    def worse(self) -> bool:
        """Whether the achieved σ is worse than predicted, Eq. (PA.4)."""
        return self.variance_ratio > self.limit

    def to_dict(self) -> dict[str, Any]:
        """Return the group as JSON-able data (an infinite ν as None)."""
        return {"group": self.name, "variance_ratio": self.variance_ratio,
                "sigma_ratio": math.sqrt(self.variance_ratio),
                "correlated_share": self.correlated_share,
                "dof": self.dof if math.isfinite(self.dof) else None, "limit": self.limit,
                "worst": self.worst, "worse_than_predicted": self.worse}


@dataclass(frozen=True)
class PredictionCheck:
    """The plan's predicted σ beside the achieved σ, per parameter and per triad.

    Attributes
    ----------
    rows : tuple of PredictedRow
        The parameters both the prediction and the calibration hold, in the result's order.
    groups : tuple of PredictedGroup
        Each triad's test (PA.4).
    flicker_dof : float
        ν_B of (PA.3), summed over the pooled static records (0 without one).
    """

    rows: tuple[PredictedRow, ...]
    groups: tuple[PredictedGroup, ...]
    flicker_dof: float

    @property
    def worse(self) -> tuple[PredictedGroup, ...]:
        """The triads whose achieved σ is worse than predicted."""
        return tuple(g for g in self.groups if g.worse)

    def warning(self) -> str | None:
        """Return the note of a run worse than predicted (None when none is)."""
        if not self.worse:
            return None
        parts = []
        for g in self.worse:
            row = next(r for r in self.rows if r.name == g.worst)
            parts.append(f"{g.name} σ × {math.sqrt(g.variance_ratio):.2f} of the plan's "
                         f"prediction (variance ratio {g.variance_ratio:.3g} > "
                         f"{g.limit:.3g}, the 99 % bound of χ²_ν/ν with ν = {g.dof:.3g}; "
                         f"worst {g.worst} × {row.ratio:.2f})")
        return ("achieved σ worse than predicted: " + "; ".join(parts)
                + " — the unit is noisier than its grade, or the station worse than declared "
                  "(docs/test-design.md, \"Predicted against achieved\")")

    def summary(self) -> str:
        """One line: each triad's σ ratio against its bound, and the worst parameter."""
        worst = max(self.rows, key=lambda r: r.ratio)
        triads = ", ".join(f"{g.name} × {math.sqrt(g.variance_ratio):.2f} "
                           f"(bound × {math.sqrt(g.limit):.2f})" for g in self.groups)
        return (f"achieved σ / predicted σ (plan, grade noise): {triads}; largest "
                f"{worst.name} × {worst.ratio:.2f}")

    def to_dict(self) -> dict[str, Any]:
        """Return the check as JSON-able data (the report JSON's ``prediction``)."""
        return {"rule": "Eqs. (PA.1)-(PA.4) of docs/test-design.md",
                "quantile": WORSE_QUANTILE, "flicker_dof": self.flicker_dof,
                "parameters": [r.to_dict() for r in self.rows],
                "groups": [g.to_dict() for g in self.groups],
                "worse_than_predicted": bool(self.worse), "summary": self.summary()}


def _flicker_dof(obs: P1Observations) -> float:
    """ν_B: the EDF of the flicker Allan variance at the fit's longest τ, over the pooled records.

    Greenhall's EDF (:func:`~imucalib.analysis.edf.compute_edf_greenhall`, overlapping Allan
    variance, flicker FM) at the longest cluster size of the Allan fit (the largest power of two
    ≤ n/2 samples, :func:`~imucalib.processing.statistics.compute_window_statistics`): where
    the flicker plateau rests; 1.0–2.6 per record. The records
    :func:`~imucalib.procedures.common.noise.estimate_noise` pools (static, with an Allan fit,
    at least :data:`~imucalib.procedures.common.noise.NOISE_RECORD_MIN_S` and half the longest,
    :func:`~imucalib.procedures.common.noise.noise_records`).
    """
    total = 0.0
    for w in noise_records(obs.windows):
        n = max(round(w.duration_s * obs.sample_rate_hz), 8)
        m = 1 << max((n // 2).bit_length() - 1, 0)
        total += compute_edf_greenhall(-1, 2, m, n + 1, overlapping=True, modified=False)
    return total


def _white(noise: Mapping[str, NoiseModel]) -> dict[str, NoiseModel]:
    return {k: NoiseModel(white_density=v.white_density) for k, v in noise.items()}


def _limit(dof: float) -> float:
    """χ²_ν⁻¹(0.99)/ν (1 for ν = ∞)."""
    if not math.isfinite(dof):
        return 1.0
    return float(stats.chi2.ppf(WORSE_QUANTILE, dof) / dof)


def compare_with_prediction(plan: Plan, obs: P1Observations, names: Sequence[str],
                            achieved: Mapping[str, float], units: Mapping[str, str]
                            ) -> PredictionCheck:
    """Compare the achieved σ with the plan's prediction, Eqs. (PA.1)–(PA.4).

    Parameters
    ----------
    plan : Plan
        The plan the recording ran.
    obs : P1Observations
        The run's observations: its fitted noise model and static records.
    names : sequence of str
        The calibration's parameters (the result's order).
    achieved : mapping of str to float
        Their σ as reported (Birge-scaled under a misfit). [SI]
    units : mapping of str to str
        Their units.

    Returns
    -------
    PredictionCheck

    Raises
    ------
    ConfigurationError
        A plan the prediction cannot use (no grade, off the dual-axis table, another
        procedure), or one that shares no identified parameter with the calibration.
    """
    from imucalib.procedures.p1.predict import predict_p1

    try:
        nominal = predict_p1(plan).std()
        fitted = predict_p1(plan, noise=obs.noise).std() if obs.noise else {}
        white = predict_p1(plan, noise=_white(obs.noise)).std() if obs.noise else {}
    except InsufficientExcitationError as exc:  # pragma: no cover - _group catches these
        raise ConfigurationError(f"the plan's prediction failed: {exc}") from exc
    rows = tuple(PredictedRow(n, units.get(n, ""), float(p), fitted.get(n), float(achieved[n]))
                 for n in names if (p := nominal.get(n)) is not None and p > 0.0
                 and n in achieved)
    if not rows:
        raise ConfigurationError("the plan's prediction shares no identified parameter with "
                                 "the calibration (another model)")
    nu_b = _flicker_dof(obs)
    groups = []
    for triad in ("accel", "gyro"):
        mine = [r for r in rows if r.name.startswith(triad + "_")]
        if not mine:
            continue
        ratio = math.exp(float(np.mean([2.0 * math.log(r.ratio) for r in mine])))
        shares = [1.0 - (w / f) ** 2 for r in mine
                  if (f := fitted.get(r.name)) and (w := white.get(r.name)) is not None]
        share = float(np.clip(np.mean(shares), 0.0, 1.0)) if shares else 1.0
        dof = (math.inf if share == 0.0 else nu_b / share**2) if nu_b > 0.0 else 1.0
        worst = max(mine, key=lambda r: r.ratio).name
        groups.append(PredictedGroup(triad, ratio, share, dof, _limit(dof), worst))
    return PredictionCheck(rows, tuple(groups), nu_b)
