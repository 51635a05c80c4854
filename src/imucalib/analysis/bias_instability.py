"""Bias instability from the Allan minimum, only where the curve says so (docs/noise.md).

Contents
--------
:func:`read_allan_minimum` → :class:`AllanMinimum`
    The minimum of an overlapping Allan deviation over its *usable* τ (enough equivalent degrees
    of freedom), whether it is a detection (the curve has flattened) and, when it is not, the
    upper bound the curve still gives.
:data:`EDF_MIN`, :data:`DETECTION_Z`, :data:`UPPER_BOUND_CONFIDENCE`

The rule
--------
1. **Usable τ.** Only points with EDF ν ≥ :data:`EDF_MIN` (= 10) are read. At ν = 10 the χ²
   interval of σ̂ at ±1σ is about −19 % … +28 % (NIST SP 1065 [2]_ eq. (45)); the last octaves
   of a record, with 2–5 clusters and ν ≈ 2–6, scatter by a factor 2 and their minimum is
   mostly chance (a white-noise record "shows" a bias instability there).
2. **Minimum.** σ_min is the smallest σ̂ among the usable points, at τ_min.
3. **Flattening test.** White rate noise falls as τ^−½. Over the usable points from τ_min/4 to
   the largest usable τ (two octaves before the minimum, everything after it) the log-log slope
   s is fitted by least squares with weights 2ν (var ln σ̂ ≈ 1/(2ν)); its standard error u_s is
   inflated by √2 for the correlation ≈ 0.5 of neighbouring overlapping estimates (Greenhall and
   Riley [3]_), which the weights ignore. The minimum is a detection when
   s > −½ + :data:`DETECTION_Z`·u_s (z = 3: the curve is flat or rising, not still falling
   like white noise, at 3σ) and at least three points enter the slope.
4. **Upper bound.** Each term adds to the Allan variance, so the flicker plateau 0.6643·B lies
   below σ(τ) at every τ ([1]_ Annex C). Without a detection the reading is the bound
   σ_plateau < min over usable τ of the upper confidence limit of σ̂ at
   :data:`UPPER_BOUND_CONFIDENCE` (two-sided 95.45 %, i.e. the one-sided 97.7 % limit, the same
   2σ as the fit's detection).

References
----------
.. [1] IEEE Std 952-1997 (R2008), Annex C.
.. [2] W. J. Riley, "Handbook of Frequency Stability Analysis", NIST SP 1065, 2008, §5.3.
.. [3] C. A. Greenhall and W. J. Riley, "Uncertainty of stability variances based on finite
   differences", Proc. 35th PTTI Meeting, 2003.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import special

from imucalib.analysis.allan import DeviationResult
from imucalib.analysis.edf import compute_confidence_interval
from imucalib.errors import InvalidInputError

__all__ = ["DETECTION_Z", "EDF_MIN", "UPPER_BOUND_CONFIDENCE", "AllanMinimum",
           "read_allan_minimum"]

#: Fewest equivalent degrees of freedom of a point the minimum is read from.
EDF_MIN = 10.0
#: One-sided z of the flattening test (slope above −½).
DETECTION_Z = 3.0
#: Two-sided probability content of the interval whose upper limit bounds an undetected minimum.
UPPER_BOUND_CONFIDENCE = float(special.erf(2.0 / math.sqrt(2.0)))
_WHITE_SLOPE = -0.5
_BEFORE_MIN = 16.0  # the slope window starts four octaves before τ_min
_CORRELATION_INFLATION = math.sqrt(2.0)


@dataclass(frozen=True)
class AllanMinimum:
    """Result of :func:`read_allan_minimum` (SI units of the deviation)."""

    value: float  # σ_min over the usable τ (NaN when no point is usable)
    std: float  # its standard uncertainty σ_min/√(2ν)
    tau_s: float  # τ of the minimum [s]
    detected: bool  # the curve has flattened there (module docstring, rule 3)
    upper_bound: float  # lowest usable upper confidence limit (rule 4)
    slope: float  # fitted log-log slope of the test window (NaN with < 2 points)
    slope_std: float  # its standard error, correlation-inflated
    usable_tau_s: tuple[float, float]  # range of τ with ν ≥ EDF_MIN [s]


def read_allan_minimum(result: DeviationResult, *, edf_min: float = EDF_MIN,
                       z: float = DETECTION_Z) -> AllanMinimum:
    """Read the Allan minimum and decide whether it is a bias-instability detection.

    Parameters
    ----------
    result : DeviationResult
        Overlapping ADEV with its EDF (:func:`~imucalib.analysis.compute_oadev`).
    edf_min : float
        Fewest EDF of a usable point (rule 1 of the module docstring).
    z : float
        One-sided z of the flattening test (rule 3).

    Returns
    -------
    AllanMinimum
        ``detected`` False, ``value`` NaN and ``upper_bound`` NaN when no point is usable.

    Raises
    ------
    InvalidInputError
        Not an overlapping ADEV, or `edf_min` / `z` not > 0.
    """
    if not isinstance(result, DeviationResult) or result.kind != "oadev":
        got = getattr(result, "kind", type(result).__name__)
        raise InvalidInputError(f"`result` must be an overlapping Allan deviation (kind 'oadev'); "
                                f"got {got!r}")
    if not (edf_min > 0 and z > 0):
        raise InvalidInputError(f"`edf_min` and `z` must be > 0; got {edf_min!r}, {z!r}")
    tau, dev, edf = result.taus_s, result.deviation, result.edf
    usable = np.flatnonzero((edf >= edf_min) & np.isfinite(dev) & (dev > 0))
    if usable.size == 0:
        return AllanMinimum(math.nan, math.nan, math.nan, False, math.nan, math.nan, math.nan,
                            (math.nan, math.nan))
    k = int(usable[np.argmin(dev[usable])])
    _, high = compute_confidence_interval(dev[usable], edf[usable], UPPER_BOUND_CONFIDENCE)
    window = usable[tau[usable] >= tau[k] / _BEFORE_MIN]
    slope, slope_std = _slope(np.log(tau[window]), np.log(dev[window]), 2.0 * edf[window])
    detected = bool(window.size >= 3 and slope > _WHITE_SLOPE + z * slope_std)
    return AllanMinimum(value=float(dev[k]), std=float(dev[k] / math.sqrt(2.0 * edf[k])),
                        tau_s=float(tau[k]), detected=detected,
                        upper_bound=float(np.min(high)), slope=slope, slope_std=slope_std,
                        usable_tau_s=(float(tau[usable].min()), float(tau[usable].max())))


def _slope(x: np.ndarray, y: np.ndarray, w: np.ndarray) -> tuple[float, float]:
    """Weighted LSQ slope of y on x and its standard error × √2 (module docstring, rule 3)."""
    if x.size < 2:
        return math.nan, math.nan
    xm = float(np.sum(w * x) / np.sum(w))
    sxx = float(np.sum(w * (x - xm) ** 2))
    if sxx <= 0:
        return math.nan, math.nan
    slope = float(np.sum(w * (x - xm) * y) / sxx)
    return slope, _CORRELATION_INFLATION / math.sqrt(sxx)
