"""Scatter of repeated estimates, the random drift, the Allan deviation of the sequence.

σ with its chi-square interval, the 2.7·√Σσ² random drift, and the Allan deviation at the
repetition interval (docs/random-drift.md, Eqs. (1)–(5)).

For R repeated estimates x_r of one coefficient:

    s = √(Σ (x_r − x̄)²/(R − 1)),   u(s) = s/√(2(R − 1))                                    (1)
    [s·√((R − 1)/χ²_{R−1}(1 − α/2)), s·√((R − 1)/χ²_{R−1}(α/2))]  (95 %: α = 0.05)           (2)
    random drift = 2.7·√(s_D0² + (g·s_D1)² + (g·s_D2)² + (g·s_D3)²)                          (3)
    u(random drift) = random drift/√(2(R − 1))                                                (4)
    σ_A(T) = √(Σ (x_{r+1} − x_r)²/(2(R − 1)))   (T the repetition interval)                   (5)

In (3) the g-sensitive terms enter as their drift at 1 g (the MIMU chapter, docs/procedures.md,
sums them with D0 in °/h); (4) takes the four s as independent and (1)'s relative uncertainty
for each.

Contents
--------
:class:`Scatter`, :func:`scatter`, :func:`random_drift`, :func:`allan_at_interval`
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy import stats

from imucalib.errors import InsufficientExcitationError

__all__ = ["Scatter", "allan_at_interval", "random_drift", "scatter"]


@dataclass(frozen=True)
class Scatter:
    """(1) and (2) of one coefficient: s, u(s), the 95 % interval, R."""

    std: float
    std_uncertainty: float
    low: float
    high: float
    n: int


def scatter(values: ArrayLike, name: str = "estimate", *, confidence: float = 0.95) -> Scatter:
    """Return (1) and (2) of repeated estimates.

    Raises
    ------
    InsufficientExcitationError
        Fewer than 3 values (naming `name`).
    """
    x = np.asarray(values, dtype=np.float64).ravel()
    r = x.size
    if r < 3:
        raise InsufficientExcitationError([name], f"the scatter of {name} needs at least 3 "
                                                  f"repetitions; got {r}")
    s = float(np.std(x, ddof=1))
    a = 1.0 - confidence
    lo = s * math.sqrt((r - 1) / stats.chi2.ppf(1 - a / 2, r - 1))
    hi = s * math.sqrt((r - 1) / stats.chi2.ppf(a / 2, r - 1))
    return Scatter(s, s / math.sqrt(2 * (r - 1)), lo, hi, r)


def random_drift(s_d0: float, s_g: ArrayLike, gravity_mps2: float, n: int
                 ) -> tuple[float, float]:
    """Return (3) and (4): the random drift and its standard uncertainty. [rad/s]"""
    sg = np.asarray(s_g, dtype=np.float64) * gravity_mps2
    value = 2.7 * math.sqrt(s_d0**2 + float(sg @ sg))
    return value, value / math.sqrt(2 * (n - 1))


def allan_at_interval(values: ArrayLike) -> float:
    """Return (5), the Allan deviation of a sequence at its spacing (NaN for fewer than 2)."""
    x = np.asarray(values, dtype=np.float64).ravel()
    if x.size < 2:
        return math.nan
    return float(math.sqrt(np.mean(np.diff(x) ** 2) / 2.0))
