"""Reference inputs of a window: what the IMU truly felt, from table angles and the site.

The table geometry comes from the axis names (:data:`imucalib.conventions.TABLE_AXIS_VECTORS`:
pitch about −y, roll about x, azimuth about z), outer axis first, with the IMU body frame equal
to the platform frame (docs/conventions.md). For measured angles, rot_tp = Π R_{n_i}(θ_i) and
(docs/p1.md, "Processing"):

- static (:func:`static_inputs_b`): specific force f_b = rot_tpᵀ·[0, 0, g] and angular rate
  ω_b = rot_tpᵀ·Ω_t (Earth rate at the site's latitude and heading);
- turning axis i at the measured mean rate ω (:func:`rate_inputs_b`): the axis in b is
  a_b = (Π_{j>i} R_{n_j}(θ_j))ᵀ·n_i (:func:`spin_axis_b`) and in t a_t = rot_tp·a_b (constant
  while it turns); averaged over whole revolutions ω_b = (ω + Ω_t·a_t)·a_b and
  f_b = (g_t·a_t)·a_b (the components across the axis cancel).

The site's g and Earth rate come from :class:`imucalib.models.earth.Site` (:func:`site_vectors`).

Contents
--------
:func:`table_rotation`, :func:`axis_vector`, :func:`spin_axis_b`, :func:`site_vectors`,
:func:`static_inputs_b`, :func:`rate_inputs_b`
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from imucalib.conventions import TABLE_AXIS_VECTORS
from imucalib.errors import ConfigurationError
from imucalib.models.earth import Site

__all__ = [
    "axis_vector",
    "rate_inputs_b",
    "site_vectors",
    "spin_axis_b",
    "static_inputs_b",
    "table_rotation",
]

_F64 = NDArray[np.float64]


def axis_vector(name: str) -> _F64:
    """Return the unit rotation axis of a table axis by name (``"pitch"``, ``"roll"``, …).

    Raises
    ------
    ConfigurationError
        For an axis name :data:`~imucalib.conventions.TABLE_AXIS_VECTORS` does not know.
    """
    try:
        return np.asarray(TABLE_AXIS_VECTORS[name], dtype=np.float64)
    except KeyError:
        raise ConfigurationError(
            f"unknown table axis {name!r}: the analysis knows {sorted(TABLE_AXIS_VECTORS)}"
        ) from None


def table_rotation(axis_names: Sequence[str], angles_rad: Sequence[float] | _F64) -> Rotation:
    """Return rot_tp = Π R_{n_i}(θ_i) for measured axis angles, outer axis first. [rad]"""
    rot = Rotation.identity()
    for name, angle in zip(axis_names, angles_rad, strict=True):
        rot = rot * Rotation.from_rotvec(float(angle) * axis_vector(name))
    return rot


def spin_axis_b(axis_names: Sequence[str], axis: int, angles_rad: Sequence[float] | _F64
                ) -> _F64:
    """Return a_b, the turning table axis `axis` in the body frame (the inner axes' angles)."""
    inner = table_rotation(axis_names[axis + 1:], angles_rad[axis + 1:])
    return np.asarray(inner.inv().apply(axis_vector(axis_names[axis])), dtype=np.float64)


def site_vectors(latitude_deg: float, heading_deg: float, gravity_mps2: float | None
                 ) -> tuple[float, _F64]:
    """Return (g, Earth rate in t) for a site: the given g or normal gravity. [m/s²], [rad/s]"""
    site = Site(latitude_deg=latitude_deg, heading_deg=heading_deg, gravity_mps2=gravity_mps2)
    return site.local_gravity_mps2, site.earth_rate_t_rps


def static_inputs_b(axis_names: Sequence[str], angles_rad: Sequence[float] | _F64,
                    gravity_mps2: float, earth_rate_t_rps: _F64) -> tuple[_F64, _F64]:
    """Return (ω_b, f_b) of a static window: rot_tpᵀ·Ω_t and rot_tpᵀ·[0, 0, g]. [rad/s], [m/s²]"""
    inv = table_rotation(axis_names, angles_rad).inv()
    return (np.asarray(inv.apply(earth_rate_t_rps), dtype=np.float64),
            np.asarray(inv.apply([0.0, 0.0, gravity_mps2]), dtype=np.float64))


def rate_inputs_b(axis_names: Sequence[str], axis: int, angles_rad: Sequence[float] | _F64,
                  table_rate_rps: float, gravity_mps2: float, earth_rate_t_rps: _F64
                  ) -> tuple[_F64, _F64]:
    """Return (ω_b, f_b) averaged over whole revolutions of axis `axis` (module docstring).

    `angles_rad` are the held axes' angles, the turning axis' at the start of the span.
    [rad/s], [m/s²]
    """
    a_b = spin_axis_b(axis_names, axis, angles_rad)
    a_t = table_rotation(axis_names, angles_rad).apply(a_b)
    rate_b = (table_rate_rps + float(earth_rate_t_rps @ a_t)) * a_b
    force_b = float(np.array([0.0, 0.0, gravity_mps2]) @ a_t) * a_b
    return np.asarray(rate_b, dtype=np.float64), np.asarray(force_b, dtype=np.float64)
