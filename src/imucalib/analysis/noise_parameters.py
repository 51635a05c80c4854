"""The four continuous-time noise densities of a VIO filter, from per-axis noise-term fits.

Kalibr and OpenVINS model the white noise as a continuous-time process of density σ_c and the
bias as a random walk ḃ = σ_b·w(t) (docs/noise.md §5). From the Allan fits
(:func:`~imucalib.analysis.noise_fit.fit_noise_terms`):

- ``*_noise_density`` = N, the two-sided white-noise density (σ_Allan(1 s));
- ``*_random_walk`` = K, the rate (or acceleration) random walk (σ_Allan(3 s) = K);

one number per triad: the largest axis (``combine="max"``, conservative) or the RMS over axes. A
random walk that the fit did not detect is given as its 1σ scale (the uncertainty of the absent
term) and noted: a filter needs a non-zero value. The noise characterisation's own output
formats write the files (docs/noise.md, §5 "Exports").

Contents
--------
:class:`ImuNoiseParameters`, :func:`noise_parameters_from_fits`
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from imucalib._checks import check_positive
from imucalib.analysis.noise_fit import NoiseFit
from imucalib.errors import InvalidInputError

__all__ = ["ImuNoiseParameters", "noise_parameters_from_fits"]


@dataclass(frozen=True)
class ImuNoiseParameters:
    """Continuous-time noise densities of one IMU (two-sided = Kalibr convention), SI."""

    gyroscope_noise_density: float  # [rad/s/√Hz]
    gyroscope_random_walk: float  # [rad/s²/√Hz]
    accelerometer_noise_density: float  # [m/s²/√Hz]
    accelerometer_random_walk: float  # [m/s³/√Hz]
    update_rate_hz: float  # [Hz]
    notes: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        for name in ("gyroscope_noise_density", "gyroscope_random_walk",
                     "accelerometer_noise_density", "accelerometer_random_walk",
                     "update_rate_hz"):
            check_positive(getattr(self, name), name)


def _combine(values: Sequence[float], how: str) -> float:
    arr = np.asarray(values, dtype=np.float64)
    if how == "max":
        return float(arr.max())
    return float(math.sqrt(np.mean(arr**2)))


def _pick(fits: Sequence[NoiseFit], sensor: str, name: str, how: str,
          notes: list[str]) -> float:
    if not fits:
        raise InvalidInputError(f"no {sensor} fits given")
    values = []
    for k, fit in enumerate(fits):
        if fit.sensor != sensor:
            raise InvalidInputError(f"{sensor} fit {k} is a {fit.sensor!r} fit")
        term = fit.term(name)
        if term.detected and term.value_si > 0:
            values.append(term.value_si)
        else:
            values.append(term.std_si)
            notes.append(f"{sensor} axis {k}: {name} not detected; its 1-sigma scale "
                         f"{term.std_si:.4g} {term.unit_si} is used")
    return _combine(values, how)


def noise_parameters_from_fits(gyro: Sequence[NoiseFit], accel: Sequence[NoiseFit],
                               update_rate_hz: float, *, combine: str = "max",
                               noise_inflation: float = 1.0,
                               walk_inflation: float = 1.0) -> ImuNoiseParameters:
    """Kalibr/OpenVINS densities from the per-axis fits of a gyro and an accelerometer triad.

    Uses the fitted ``white`` (N) and ``random_walk`` (K) terms (module docstring), combined
    over axes by ``"max"`` or ``"rms"``, times the inflation factors.

    Raises
    ------
    InvalidInputError
        Missing fits, a fit of the wrong sensor or without these terms, a bad `combine`.
    """
    if combine not in ("max", "rms"):
        raise InvalidInputError(f"`combine` must be 'max' or 'rms'; got {combine!r}")
    check_positive(noise_inflation, "noise_inflation")
    check_positive(walk_inflation, "walk_inflation")
    notes: list[str] = []
    out = ImuNoiseParameters(
        gyroscope_noise_density=noise_inflation * _pick(gyro, "gyro", "white", combine, notes),
        gyroscope_random_walk=walk_inflation * _pick(gyro, "gyro", "random_walk", combine,
                                                     notes),
        accelerometer_noise_density=noise_inflation * _pick(accel, "accel", "white", combine,
                                                            notes),
        accelerometer_random_walk=walk_inflation * _pick(accel, "accel", "random_walk",
                                                         combine, notes),
        update_rate_hz=update_rate_hz,
        notes=(f"combined over axes by {combine}; inflation: noise x{noise_inflation:g}, "
               f"random walk x{walk_inflation:g}", *notes))
    return out
