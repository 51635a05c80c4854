"""Unit systems of IMU noise coefficients: SI (two-sided) to the units users see.

Contents
--------
:class:`UnitValue`, :func:`convert_noise_term`, :data:`SI_UNITS`, :data:`TERM_LABELS`,
:data:`SENSORS`, :data:`DENSITY_CONVENTION`.

Conventions (docs/equations.md §1): white-noise coefficients N are the
**two-sided** densities of IEEE 952 (σ_Allan(1 s) = N; a sample at interval Δt has standard
deviation N/√Δt); Kalibr's and OpenVINS' continuous-time σ_c is this N. A datasheet noise density
ND is **one-sided**: ND = √2·N. The rows below are exactly what :func:`convert_noise_term` returns
(display value = SI value / factor):

==================  ===============  ======================================  ====================
sensor, term        unit             factor (SI per display unit)             note
==================  ===============  ======================================  ====================
gyro white          °/√h             π/180/60                                ARW (two-sided)
gyro white          (°/s)/√Hz        π/180                                   two-sided N
gyro white          (°/s)/√Hz        π/180/√2                                one-sided, datasheet
gyro white          (°/h)/√Hz        π/180/3600                              two-sided N
gyro white          rad/s/√Hz        1                                       Kalibr σ_c
gyro bias instab.   °/h, °/s         π/180/3600, π/180
gyro random walk    °/h/√h           π/180/3600^1.5                          RRW
gyro random walk    rad/s²/√Hz       1                                       Kalibr σ_bg
gyro rate ramp      °/h², °/s²       π/180/3600², π/180
gyro quantization   ″, °, rad        π/180/3600, π/180, 1
accel white         µg/√Hz           9.80665e-6                              two-sided N
accel white         µg/√Hz           9.80665e-6/√2                           one-sided, datasheet
accel white         m/s/√h           1/60                                    VRW (two-sided)
accel white         m/s²/√Hz         1                                       Kalibr σ_c
accel bias instab.  µg, mg           9.80665e-6, 9.80665e-3
accel random walk   µg/√h            9.80665e-6/60                           acceleration RW
accel random walk   m/s³/√Hz         1                                       Kalibr σ_ba
accel rate ramp     µg/h             9.80665e-6/3600
accel quantization  m/s, mm/s        1, 1e-3
==================  ===============  ======================================  ====================
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from imucalib import units
from imucalib.errors import InvalidInputError

__all__ = ["DENSITY_CONVENTION", "SENSORS", "SI_UNITS", "TERM_LABELS", "UnitValue",
           "convert_noise_term"]

SENSORS = ("gyro", "accel")
#: Stated in every result: the densities are two-sided (IEEE 952; Kalibr σ_c).
DENSITY_CONVENTION = ("two-sided PSD coefficients (IEEE 952 Annex C): sigma_Allan(1 s) = N; "
                      "Kalibr/OpenVINS continuous-time densities equal N; one-sided datasheet "
                      "density = sqrt(2)*N")
_RT2 = math.sqrt(2.0)

#: SI unit of each term per sensor.
SI_UNITS: dict[str, dict[str, str]] = {
    "gyro": {"quantization": "rad", "white": "rad/√s", "bias_instability": "rad/s",
             "bias_instability_allan_minimum": "rad/s", "random_walk": "rad/s/√s",
             "rate_ramp": "rad/s²", "markov_sigma": "rad/s", "markov_time_constant": "s"},
    "accel": {"quantization": "m/s", "white": "m/s/√s", "bias_instability": "m/s²",
              "bias_instability_allan_minimum": "m/s²", "random_walk": "m/s²/√s",
              "rate_ramp": "m/s³", "markov_sigma": "m/s²", "markov_time_constant": "s"},
}

#: Human labels per sensor.
TERM_LABELS: dict[str, dict[str, str]] = {
    "gyro": {"quantization": "angle quantization Q", "white": "angle random walk N (ARW)",
             "bias_instability": "bias instability B (flicker; = σ_min/0.664)",
             "bias_instability_allan_minimum": "Allan minimum σ_min (no 0.664 factor)",
             "random_walk": "rate random walk K (RRW)", "rate_ramp": "rate ramp R",
             "markov_sigma": "Gauss–Markov σ", "markov_time_constant": "Gauss–Markov T_c"},
    "accel": {"quantization": "velocity quantization Q", "white": "velocity random walk N (VRW)",
              "bias_instability": "bias instability B (flicker; = σ_min/0.664)",
              "bias_instability_allan_minimum": "Allan minimum σ_min (no 0.664 factor)",
              "random_walk": "acceleration random walk K", "rate_ramp": "acceleration ramp R",
              "markov_sigma": "Gauss–Markov σ", "markov_time_constant": "Gauss–Markov T_c"},
}

_TWO = "two-sided"
_ONE = "one-sided (datasheet) = √2·N"
_TABLE: dict[str, dict[str, tuple[tuple[str, float, str], ...]]] = {
    "gyro": {
        "quantization": (("″", units.ARCSEC, ""), ("°", units.DEG, ""), ("rad", 1.0, "")),
        "white": (("°/√h", units.DEG_PER_RTH, "ARW, " + _TWO),
                  ("(°/s)/√Hz", units.DEG_PER_S_PER_RTHZ, _TWO),
                  ("(°/s)/√Hz", units.DEG_PER_S_PER_RTHZ / _RT2, _ONE),
                  ("(°/h)/√Hz", units.DEG_PER_H_PER_RTHZ, _TWO),
                  ("rad/s/√Hz", 1.0, _TWO + "; Kalibr gyroscope_noise_density")),
        "bias_instability": (("°/h", units.DEG_PER_H, ""), ("°/s", units.DEG, ""),
                             ("rad/s", 1.0, "")),
        "random_walk": (("°/h/√h", units.DEG_PER_H_RTH, "RRW"),
                        ("(°/s)/√s", units.DEG, ""),
                        ("rad/s²/√Hz", 1.0, _TWO + "; Kalibr gyroscope_random_walk")),
        "rate_ramp": (("°/h²", units.DEG_PER_H / units.HOUR, ""), ("°/s²", units.DEG, ""),
                      ("rad/s²", 1.0, "")),
        "markov_sigma": (("°/h", units.DEG_PER_H, ""), ("rad/s", 1.0, "")),
        "markov_time_constant": (("s", 1.0, ""),),
    },
    "accel": {
        "quantization": (("m/s", 1.0, ""), ("mm/s", 1e-3, "")),
        "white": (("µg/√Hz", units.UG_PER_RTHZ, _TWO),
                  ("µg/√Hz", units.UG_PER_RTHZ / _RT2, _ONE),
                  ("m/s/√h", units.MPS_PER_RTH, "VRW, " + _TWO),
                  ("m/s²/√Hz", 1.0, _TWO + "; Kalibr accelerometer_noise_density")),
        "bias_instability": (("µg", units.UG, ""), ("mg", units.MG, ""), ("m/s²", 1.0, "")),
        "random_walk": (("µg/√h", units.UG / math.sqrt(units.HOUR), ""),
                        ("m/s³/√Hz", 1.0, _TWO + "; Kalibr accelerometer_random_walk")),
        "rate_ramp": (("µg/h", units.UG / units.HOUR, ""), ("m/s³", 1.0, "")),
        "markov_sigma": (("µg", units.UG, ""), ("m/s²", 1.0, "")),
        "markov_time_constant": (("s", 1.0, ""),),
    },
}


@dataclass(frozen=True)
class UnitValue:
    """A value and its standard uncertainty in one display unit."""

    unit: str
    value: float
    std: float
    note: str = ""
    upper: float | None = None  # upper bound of a term not detected (docs/noise.md)


def convert_noise_term(sensor: str, term: str, value_si: float,
                       std_si: float = math.nan,
                       upper_si: float | None = None) -> tuple[UnitValue, ...]:
    """Express a term (and its upper bound, if any) in every unit of the module table.

    ``bias_instability_allan_minimum`` converts like ``bias_instability``.

    Raises
    ------
    InvalidInputError
        Unknown sensor (``"gyro"``, ``"accel"``) or term.
    """
    if sensor not in _TABLE:
        raise InvalidInputError(f"`sensor` must be one of {list(SENSORS)}; got {sensor!r}")
    key = "bias_instability" if term == "bias_instability_allan_minimum" else term
    rows = _TABLE[sensor].get(key)
    if rows is None:
        raise InvalidInputError(f"unknown noise term {term!r}; expected one of "
                                f"{sorted(SI_UNITS[sensor])}")
    return tuple(UnitValue(u, value_si / f, std_si / f, note,
                           None if upper_si is None else upper_si / f)
                 for u, f, note in rows)
