"""The 4-position and up/down Earth-rate bias estimators of one gyro axis (docs/earth-rate-bias.md).

With d_k = ȳ_k − ω_k, ȳ_k the window mean of the gyro axis and ω_k the reference Earth rate on
it (IEEE Std 1431-2004 and 952-2020 static tests; the MIMU chapter, docs/procedures.md):

- 4-position (the axis horizontal, at azimuths ψ = 0, 90, 180, 270° in one pose):

      b̂_4 = ¼·Σ_ψ ȳ_ψ  (the Ω_N·cos ψ terms cancel),  σ = ¼·√(Σ σ_ψ²)                     (1)

  the poses with the axis horizontal are combined by their inverse-variance weighted mean; in
  opposite poses (±z up for the x axis) the g-sensitivity G_i,up·g and the vertical Earth rate
  through the misalignment change sign and cancel in that mean;
- up/down (the axis vertical, each pose averaged over its four azimuths, ȳ_up and ȳ_dn):

      b̂_ud = (ȳ_up + ȳ_dn)/2,  σ = ½·√(σ_up² + σ_dn²)                                    (2)
      (ȳ_up − ȳ_dn)/2 = (1 + s)·Ω_e·sin L + G_ii·g                                          (3)
      L̂ = asin(((ȳ_up − ȳ_dn)/2)/Ω_e)   (with s and G_ii taken as zero)                      (4)

- the two compared: Δ = b̂_4 − b̂_ud, z = Δ/√(σ_4² + σ_ud²)                                  (5)
- at the known latitude, the scale error (G_ii taken as zero):

      ŝ = ((ȳ_up − ȳ_dn)/2)/(Ω_e·sin L) − 1,  σ = σ_half/(Ω_e·sin L)                         (6)

Contents
--------
:class:`AxisWindow`, :class:`AxisBias`, :func:`four_position_bias`, :func:`up_down_bias`,
:func:`compare_methods`, :func:`scale_at`
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from imucalib.errors import InvalidInputError
from imucalib.units import EARTH_RATE_RPS

__all__ = ["AxisBias", "AxisWindow", "compare_methods", "four_position_bias", "scale_at",
           "up_down_bias"]


@dataclass(frozen=True)
class AxisWindow:
    """One window of one gyro axis: its mean, standard error and reference rate. [rad/s]"""

    mean_rps: float
    se_rps: float
    reference_rps: float


@dataclass(frozen=True)
class AxisBias:
    """A bias estimate and its standard uncertainty. [rad/s]"""

    value_rps: float
    std_rps: float


def four_position_bias(poses: Sequence[Sequence[AxisWindow]]) -> AxisBias:
    """Return (1): each pose's mean of its four azimuths, then their weighted mean.

    Raises
    ------
    InvalidInputError
        No pose, or a pose without exactly four windows.
    """
    if not poses or any(len(p) != 4 for p in poses):
        raise InvalidInputError(f"the 4-position method needs poses of 4 azimuths; got "
                                f"{[len(p) for p in poses]}")
    vals = np.array([np.mean([w.mean_rps - w.reference_rps for w in p]) for p in poses])
    var = np.array([np.sum([w.se_rps**2 for w in p]) / 16.0 for p in poses])
    wts = 1.0 / var
    return AxisBias(float(wts @ vals / wts.sum()), float(math.sqrt(1.0 / wts.sum())))


def _pose_mean(windows: Sequence[AxisWindow]) -> tuple[float, float, float]:
    n = len(windows)
    if n == 0:
        raise InvalidInputError("the up/down method needs windows in the up and the down pose")
    return (float(np.mean([w.mean_rps for w in windows])),
            float(np.mean([w.reference_rps for w in windows])),
            math.sqrt(sum(w.se_rps**2 for w in windows)) / n)


def up_down_bias(up: Sequence[AxisWindow], down: Sequence[AxisWindow]
                 ) -> tuple[AxisBias, AxisBias, AxisBias]:
    """Return (2), the half-difference (3) and the latitude (4) in degrees with their σ."""
    y_up, r_up, s_up = _pose_mean(up)
    y_dn, r_dn, s_dn = _pose_mean(down)
    sigma = 0.5 * math.hypot(s_up, s_dn)
    bias = AxisBias(0.5 * ((y_up - r_up) + (y_dn - r_dn)), sigma)
    half = 0.5 * (y_up - y_dn)
    ratio = half / EARTH_RATE_RPS
    if abs(ratio) < 1.0:
        lat = math.degrees(math.asin(ratio))
        lat_std = math.degrees(sigma / (EARTH_RATE_RPS * math.sqrt(1.0 - ratio**2)))
    else:
        lat, lat_std = math.nan, math.nan
    return bias, AxisBias(half, sigma), AxisBias(lat, lat_std)


def compare_methods(four: AxisBias, updown: AxisBias) -> tuple[float, float]:
    """Return (5): Δ [rad/s] and z."""
    diff = four.value_rps - updown.value_rps
    return diff, diff / math.hypot(four.std_rps, updown.std_rps)


def scale_at(half_difference: AxisBias, latitude_deg: float) -> AxisBias:
    """Return (6): the scale error from the half-difference at a known latitude (NaN at L = 0)."""
    up = EARTH_RATE_RPS * math.sin(math.radians(latitude_deg))
    if abs(up) < 1e-12:
        return AxisBias(math.nan, math.nan)
    return AxisBias(half_difference.value_rps / up - 1.0, half_difference.std_rps / abs(up))
