"""Unit constants. SI is used inside the library; these convert at the boundary.

Multiply a value in the named unit by the constant to get SI, divide to go back::

    rate_rps = rate_dps * DEG          # °/s -> rad/s
    bias_dph = bias_rps / DEG_PER_H    # rad/s -> °/h

Contents
--------
Angles: ``DEG``, ``ARCSEC``, ``ARCMIN``, ``MRAD``, ``URAD``.
Rates: ``DEG_PER_S``, ``DEG_PER_H``, ``RPM``.
Random-walk coefficients: ``DEG_PER_RTH`` (°/√h), ``DEG_PER_S_PER_RTHZ`` ((°/s)/√Hz),
``DEG_PER_H_PER_RTHZ`` ((°/h)/√Hz), ``MPS_PER_RTH`` ((m/s)/√h), ``UG_PER_RTHZ`` (µg/√Hz),
``DEG_PER_H_RTH`` (°/h/√h, rate random walk), ``DEG_PER_H3_2`` (°/h^{3/2}).
Acceleration: ``G0_MPS2`` (standard gravity, 9.80665 m/s²), ``G``, ``MG``, ``UG``.
Time: ``MINUTE``, ``HOUR``, ``SIDEREAL_DAY_S``.
Relative: ``PPM``, ``PERCENT``.
Temperature: :func:`degc_to_kelvin`, :func:`kelvin_to_degc`.
Parsing: :func:`parse_unit` turns a unit string ("deg/s", "°/h", "g", "m/s^2", …) into its SI
factor.

Notes
-----
The angle-random-walk conversions follow docs/equations.md §1:
1 °/√h = 1/60 °/√s = 60 (°/h)/√Hz, and 1 °/h^{3/2} = 1/216000 °/s^{3/2}. Densities here are the
*two-sided* coefficient N of IEEE 952 (σ_Allan(1 s) = N); see :mod:`imucalib.models.noise` for the
one-sided datasheet convention.
"""

from __future__ import annotations

import math

from imucalib.errors import UnitError

__all__ = [
    "ARCMIN",
    "ARCSEC",
    "DEG",
    "DEG_PER_H",
    "DEG_PER_H3_2",
    "DEG_PER_H_PER_RTHZ",
    "DEG_PER_H_RTH",
    "DEG_PER_RTH",
    "DEG_PER_S",
    "DEG_PER_S_PER_RTHZ",
    "EARTH_RATE_RPS",
    "G0_MPS2",
    "HOUR",
    "MG",
    "MINUTE",
    "MPS_PER_RTH",
    "MRAD",
    "PERCENT",
    "PPM",
    "RPM",
    "SIDEREAL_DAY_S",
    "UG",
    "UG_PER_RTHZ",
    "URAD",
    "G",
    "degc_to_kelvin",
    "kelvin_to_degc",
    "parse_unit",
]

# Angles [rad]
DEG = math.pi / 180.0
ARCMIN = DEG / 60.0
ARCSEC = DEG / 3600.0
MRAD = 1e-3
URAD = 1e-6

# Time [s]
MINUTE = 60.0
HOUR = 3600.0
#: True sidereal day, 23 h 56 min 4.0905 s (docs/conventions.md: one MIMU textbook chapter prints
#: 23 h 59 min 57.33 s, which is wrong).
SIDEREAL_DAY_S = 86164.0905

# Rates [rad/s]
DEG_PER_S = DEG
DEG_PER_H = DEG / HOUR
RPM = 2.0 * math.pi / 60.0
#: WGS-84 Earth rotation rate [rad/s] (15.041067 °/h).
EARTH_RATE_RPS = 7.292115e-5

# Acceleration [m/s²]
G0_MPS2 = 9.80665
G = G0_MPS2
MG = 1e-3 * G0_MPS2
UG = 1e-6 * G0_MPS2

# Random-walk and density coefficients (SI: rad/√s, (m/s)/√s = m/s²/√Hz, rad/s/√s)
DEG_PER_RTH = DEG / math.sqrt(HOUR)  # °/√h -> rad/√s
DEG_PER_S_PER_RTHZ = DEG  # (°/s)/√Hz -> rad/√s (two-sided coefficient)
DEG_PER_H_PER_RTHZ = DEG_PER_H  # (°/h)/√Hz -> rad/√s
MPS_PER_RTH = 1.0 / math.sqrt(HOUR)  # (m/s)/√h -> m/s/√s
UG_PER_RTHZ = UG  # µg/√Hz -> (m/s²)/√Hz
DEG_PER_H_RTH = DEG_PER_H / math.sqrt(HOUR)  # (°/h)/√h -> rad/s/√s (rate random walk)
DEG_PER_H3_2 = DEG_PER_H_RTH  # °/h^{3/2} is the same unit as (°/h)/√h

# Relative
PPM = 1e-6
PERCENT = 1e-2


def degc_to_kelvin(temp_degc: float) -> float:
    """Convert a temperature from °C to K."""
    return temp_degc + 273.15


def kelvin_to_degc(temp_k: float) -> float:
    """Convert a temperature from K to °C."""
    return temp_k - 273.15


# Unit strings accepted at the boundary (CSV headers, plan files, CLI), mapped to SI factors.
_UNIT_FACTORS: dict[str, float] = {
    # dimensionless
    "1": 1.0,
    "": 1.0,
    "counts": 1.0,
    "ppm": PPM,
    "%": PERCENT,
    # time
    "s": 1.0,
    "ms": 1e-3,
    "us": 1e-6,
    "ns": 1e-9,
    "min": MINUTE,
    "h": HOUR,
    # angle
    "rad": 1.0,
    "mrad": MRAD,
    "urad": URAD,
    "deg": DEG,
    "°": DEG,
    "arcmin": ARCMIN,
    "arcsec": ARCSEC,
    '"': ARCSEC,
    # rate
    "rad/s": 1.0,
    "deg/s": DEG,
    "°/s": DEG,
    "dps": DEG,
    "deg/h": DEG_PER_H,
    "°/h": DEG_PER_H,
    "dph": DEG_PER_H,
    "rpm": RPM,
    # acceleration
    "m/s^2": 1.0,
    "m/s²": 1.0,
    "mps2": 1.0,
    "g": G0_MPS2,
    "mg": MG,
    "ug": UG,
    "µg": UG,
    # length
    "m": 1.0,
    "mm": 1e-3,
    "cm": 1e-2,
    # frequency
    "hz": 1.0,
    "khz": 1e3,
}


def parse_unit(unit: str) -> float:
    """Return the factor that converts a value in `unit` to SI.

    Parameters
    ----------
    unit : str
        Unit string such as ``"deg/s"``, ``"°/h"``, ``"g"``, ``"m/s^2"`` (case-insensitive,
        surrounding blanks ignored).

    Returns
    -------
    float
        Multiply by it to convert to SI.

    Raises
    ------
    UnitError
        If the unit is not known; the message lists the accepted units.
    """
    key = unit.strip().lower().replace(" ", "")
    if key not in _UNIT_FACTORS:
        accepted = ", ".join(sorted(k for k in _UNIT_FACTORS if k))
        raise UnitError(f"unknown unit {unit!r}; expected one of: {accepted}")
    return _UNIT_FACTORS[key]
