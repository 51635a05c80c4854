"""Goodness of fit of a weighted least squares fit and the Birge ratio.

The equations are those of docs/processing-estimation.md, "Goodness of fit".

A fit weighted by the known noise of its observations has, when its model is right,
χ² = rᵀC⁻¹r distributed as χ² with ν = n − p degrees of freedom, so χ²/ν is near 1 within
[χ²_ν(q_lo)/ν, χ²_ν(q_hi)/ν]. A χ² above its upper quantile (99 % by default) says the model
does not describe the data to their noise (a missing term, wrong poses, bad data): the
covariance computed from the noise alone then understates the errors. The Birge ratio
R_B = √(χ²/ν) (R. T. Birge, Phys. Rev. 40, 207 (1932); the PDG's scale factor S, Particle Data
Group, Review of Particle Physics, "Introduction", §5.2.2) scales every standard uncertainty of
that fit by R_B, which is what a misfit that looks like extra white noise in the residuals
would need:

    χ²/ν,  expected range [χ²_ν⁻¹(q_lo)/ν, χ²_ν⁻¹(q_hi)/ν]                        (1)
    misfit  ⇔  χ² > χ²_ν⁻¹(q_hi)                                                   (2)
    R_B = √(χ²/ν);  σ_scaled = σ·R_B when misfit, σ otherwise                      (3)

Scaling only when (2) holds keeps a good fit's σ at the noise level (scaling by every chance
fluctuation of χ² would widen half of all good fits); a misfit is reported, never silently
absorbed.

Contents
--------
:class:`FitQuality` (one fit's χ², ν, expected range, misfit flag, Birge ratio), :func:`assess_fit`,
:data:`MISFIT_QUANTILE`, :data:`EXPECTED_RANGE`. Procedures carry it in their results
(:attr:`imucalib.models.result.CalibrationResult.fit_quality`, the Allan noise fits); the one
least-squares solver, :func:`imucalib.estimation.linear.solve_weighted_lsq`, returns it with every
solution (Eqs. (6)–(7) there are (2)–(3) here) and its Birge-scaled covariance.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Final

from imucalib.errors import InvalidInputError

__all__ = ["EXPECTED_RANGE", "MISFIT_QUANTILE", "FitQuality", "assess_fit"]

#: The χ² quantile above which a fit is flagged as a misfit, Eq. (2).
MISFIT_QUANTILE: Final = 0.99
#: The quantiles of the expected range of χ²/ν, Eq. (1).
EXPECTED_RANGE: Final = (0.01, 0.99)


@dataclass(frozen=True)
class FitQuality:
    """How well one fitted group (a triad) describes its data (docs/processing-estimation.md).

    Computed by :func:`assess_fit`.

    Attributes
    ----------
    group : str
        The fitted group: the prefix of its parameter names (``"accel"``, ``"gyro"``).
    chi2 : float
        rᵀC⁻¹r of the residuals, C the noise covariance of the observations.
    dof : int
        Degrees of freedom ν = n − p (0: nothing to test).
    expected_low, expected_high : float
        The range of χ²/ν that 1 % … 99 % of fits of a right model fall in (NaN when ν = 0).
    misfit : bool
        χ² above the `quantile` of χ²_ν: the model does not describe the data to their noise.
    quantile : float
        The misfit threshold's quantile (0.99).
    """

    group: str
    chi2: float
    dof: int
    expected_low: float
    expected_high: float
    misfit: bool
    quantile: float = 0.99

    @property
    def reduced_chi2(self) -> float:
        """χ²/ν (NaN when ν = 0)."""
        return self.chi2 / self.dof if self.dof > 0 else math.nan

    @property
    def birge_ratio(self) -> float:
        """R_B = √(χ²/ν) (NaN when ν = 0)."""
        return math.sqrt(self.reduced_chi2) if self.dof > 0 else math.nan

    @property
    def sigma_scale(self) -> float:
        """The factor applied to the group's σ: R_B for a misfit, else 1."""
        return self.birge_ratio if self.misfit else 1.0

    def summary(self) -> str:
        """One line: χ²/ν, its expected range and the verdict."""
        if self.dof == 0:
            return f"{self.group}: χ² not testable (no redundant observations)"
        text = (f"{self.group}: χ²/ν = {self.reduced_chi2:.3g} (ν = {self.dof}; a right model "
                f"gives {self.expected_low:.2g}–{self.expected_high:.2g})")
        if self.misfit:
            text += (f" — MODEL MISFIT above the {self.quantile:.0%} quantile: σ scaled by the "
                     f"Birge ratio √(χ²/ν) = {self.birge_ratio:.3g} are reported beside the "
                     "noise-only σ")
        return text


def assess_fit(group: str, chi2: float, dof: int, *,
               quantile: float = MISFIT_QUANTILE) -> FitQuality:
    """Return the goodness of fit of one weighted least-squares fit, Eqs. (1)–(3).

    Parameters
    ----------
    group : str
        What was fitted (``"accel"``, ``"gyro"``: the prefix of its parameter names).
    chi2 : float
        rᵀC⁻¹r of the fit's residuals (≥ 0).
    dof : int
        Its degrees of freedom n − p (0: no redundancy, nothing can be tested).
    quantile : float
        The misfit threshold's quantile of χ²_ν, in (0.5, 1).

    Returns
    -------
    FitQuality

    Raises
    ------
    InvalidInputError
        A negative or non-finite χ², a negative `dof`, a quantile outside (0.5, 1).

    Examples
    --------
    >>> q = assess_fit("accel", 300.0 * 6, 6)
    >>> q.misfit, round(q.birge_ratio, 2), round(q.expected_high, 2)
    (True, 17.32, 2.8)
    >>> assess_fit("gyro", 5.0, 6).misfit
    False
    """
    if not (isinstance(chi2, int | float) and math.isfinite(chi2) and chi2 >= 0):
        raise InvalidInputError(f"`chi2` must be a finite number ≥ 0; got {chi2!r}")
    if isinstance(dof, bool) or not isinstance(dof, int) or dof < 0:
        raise InvalidInputError(f"`dof` must be an int ≥ 0; got {dof!r}")
    if not 0.5 < quantile < 1.0:
        raise InvalidInputError(f"`quantile` must be in (0.5, 1); got {quantile!r}")
    if dof == 0:
        return FitQuality(group=group, chi2=float(chi2), dof=0, expected_low=math.nan,
                          expected_high=math.nan, misfit=False, quantile=quantile)
    low, high, threshold = _quantiles(dof, float(quantile))
    return FitQuality(group=group, chi2=float(chi2), dof=dof, expected_low=low,
                      expected_high=high, misfit=bool(chi2 > threshold), quantile=quantile)


@functools.lru_cache(maxsize=4096)
def _quantiles(dof: int, quantile: float) -> tuple[float, float, float]:
    """χ²_ν⁻¹(q_lo)/ν, χ²_ν⁻¹(q_hi)/ν and the threshold χ²_ν⁻¹(q) of Eqs. (1)–(2) (cached)."""
    from scipy import stats  # imported when used: reading a result file needs no scipy

    lo, hi = EXPECTED_RANGE
    return (float(stats.chi2.ppf(lo, dof)) / dof, float(stats.chi2.ppf(hi, dof)) / dof,
            float(stats.chi2.ppf(quantile, dof)))
