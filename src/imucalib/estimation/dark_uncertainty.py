"""Scatter between observations that their own noise does not explain: paule_mandel_floor.

Observations whose standard errors σ_i come from their own white noise may scatter more than
σ_i says: a hand-held pose's mean carries the sensor's bias as it wandered since the last pose
(bias instability, random walk), which the pose's samples cannot show. Paule and Mandel (1982)
take one extra standard deviation s, common to every observation and added in quadrature, and
choose it so that the weighted fit's χ² equals its expectation::

    χ²(s) = Σ_i r_i(s)² / (σ_i² + s²) = ν,   s ≥ 0;   s = 0 when χ²(0) ≤ ν            (PM.1)

(r_i(s) the residuals of the fit refitted with those weights). χ²(s) decreases with s, so the
root is unique. For a weighted mean of n values with equal σ it is
s² = max(0, S² − σ²), S² the sample variance (n − 1 in the divisor). Thompson & Ellison (2011)
call s the "dark uncertainty" of a set of measurements (Accred. Qual. Assur. 16:483–487).

Contents
--------
:func:`paule_mandel_floor`
"""

from __future__ import annotations

import math
from collections.abc import Callable

from scipy.optimize import brentq

from imucalib.errors import InvalidInputError

__all__ = ["paule_mandel_floor"]


def paule_mandel_floor(chi2_of: Callable[[float], tuple[float, int]], *, scale: float,
                       rtol: float = 1e-4) -> float:
    """Return s ≥ 0 with χ²(s) = ν, Eq. (PM.1).

    Parameters
    ----------
    chi2_of : callable
        ``chi2_of(s) -> (χ², ν)``: the fit refitted with every observation's σ_i replaced by
        √(σ_i² + s²).
    scale : float
        A typical σ_i (> 0), where the search for an upper bracket starts.
    rtol : float
        Relative tolerance of s.

    Returns
    -------
    float
        s (0 when the fit's χ² does not exceed ν, or ν = 0).

    Raises
    ------
    InvalidInputError
        `scale` not positive and finite, or no s up to 10⁹·scale brings χ² down to ν.
    """
    if not (math.isfinite(scale) and scale > 0):
        raise InvalidInputError(f"`scale` must be positive and finite; got {scale!r}")
    chi2, dof = chi2_of(0.0)
    if dof <= 0 or chi2 <= dof:
        return 0.0

    def excess(s: float) -> float:
        c, n = chi2_of(s)
        return c - n

    hi = scale
    while excess(hi) > 0:
        hi *= 4.0
        if hi > 1e9 * scale:
            raise InvalidInputError(f"no floor up to {hi:.3g} brings χ² = {chi2:.4g} down to "
                                    f"ν = {dof}: the residuals are not noise")
    return float(brentq(excess, 0.0, hi, xtol=rtol * scale * 1e-3, rtol=rtol))
