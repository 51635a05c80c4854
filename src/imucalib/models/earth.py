"""The Earth as the station sees it: Earth rate, local gravity and the table's orientation.

Contents
--------
:class:`Site`
    Where the station stands (latitude, height, heading of the table's x axis, optional measured
    local g) and what a point at rest there experiences, in the n and t frames.
:func:`normal_gravity_mps2`
    WGS-84 normal gravity at a latitude and ellipsoidal height.
:func:`normal_gravity_gradient_ps2`
    Its vertical gradient ∂γ/∂h (negative: gravity weakens upwards).
:func:`earth_rate_n_rps`
    Earth rate in NED.
:func:`gravity_n_mps2`
    The gravity vector (gravitation plus the centrifugal term of Earth rotation) in NED.
:func:`rot_nt`
    Rotation from the table base frame t (z up, x at the heading) to NED.

Conventions
-----------
Frames are those of :mod:`imucalib.conventions`. ``n`` is North-East-Down. ``t`` has ``z_t`` up
and ``x_t`` at azimuth ψ (the heading, clockwise from North seen from above), ``y_t = z_t × x_t``
(so ψ = 0 gives North-West-Up and ψ = 90° gives East-North-Up)::

    mat_nt = [[cos ψ,  sin ψ,  0],
              [sin ψ, −cos ψ,  0],
              [0,      0,     −1]]      (columns: x_t, y_t, z_t in n)

Gravity ``g`` is the plumb-line vector (it points *down*, ``[0, 0, +γ]`` in n, ``[0, 0, −γ]`` in
t). A point at rest relative to the Earth has specific force ``f = −g``, i.e. ``[0, 0, +γ]`` in t:
a level accelerometer with its axis up reads +γ.

References
----------
.. [1] NIMA TR8350.2, *Department of Defense World Geodetic System 1984*, 3rd ed., 2000,
   Eqs. (4-1) (Somigliana) and (4-3) (normal gravity above the ellipsoid), Table 3.1/3.4.
.. [2] ``docs/conventions.md`` (frames and signs); WGS-84 normal gravity at 45° latitude is
   γ(45°) = 9.806198 m/s² by [1]_.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from imucalib._checks import check_finite_scalar
from imucalib.errors import InvalidInputError
from imucalib.units import EARTH_RATE_RPS

__all__ = [
    "Site",
    "earth_rate_n_rps",
    "gravity_n_mps2",
    "normal_gravity_gradient_ps2",
    "normal_gravity_mps2",
    "rot_nt",
]

# WGS-84 defining and derived constants, [1] Tables 3.1 and 3.4.
_A_M = 6378137.0  # semi-major axis [m]
_F = 1.0 / 298.257223563  # flattening
_M = 0.00344978650684  # ω²a²b/GM
_GAMMA_E = 9.7803253359  # normal gravity at the equator [m/s²]
_K = 0.00193185265241  # Somigliana constant
_E2 = 0.00669437999013  # first eccentricity squared


def _check_latitude(latitude_deg: float) -> float:
    lat = check_finite_scalar(latitude_deg, "latitude_deg")
    if not -90.0 <= lat <= 90.0:
        raise InvalidInputError(f"`latitude_deg` must be in [-90, 90]; got {lat}")
    return lat


def normal_gravity_mps2(latitude_deg: float, height_m: float = 0.0) -> float:
    """WGS-84 normal gravity magnitude at a geodetic latitude and ellipsoidal height.

    γ(φ) = γ_e (1 + k sin²φ) / √(1 − e² sin²φ)                       (Somigliana, Eq. (4-1) in [1])
    γ(φ, h) = γ(φ) [1 − 2/a (1 + f + m − 2 f sin²φ) h + 3 h²/a²]      (Eq. (4-3) in [1])

    The height term is the ellipsoidal free-air correction (≈ −3.086·10⁻⁶ m/s² per m near the
    surface, docs/equations.md §2), good to about 1 µm/s² for |h| < 10 km.

    Parameters
    ----------
    latitude_deg : float
        Geodetic latitude, in [−90, 90]. [°]
    height_m : float
        Height above the ellipsoid. [m]

    Returns
    -------
    float
        Normal gravity (gravitation plus the centrifugal term of Earth rotation). [m/s²]

    Raises
    ------
    InvalidInputError
        If the latitude is outside [−90, 90] or either input is not finite.

    Examples
    --------
    >>> round(normal_gravity_mps2(45.0), 6)
    9.806198
    """
    lat = math.radians(_check_latitude(latitude_deg))
    h = check_finite_scalar(height_m, "height_m")
    s2 = math.sin(lat) ** 2
    gamma0 = _GAMMA_E * (1.0 + _K * s2) / math.sqrt(1.0 - _E2 * s2)  # Eq. (4-1) in [1]
    return gamma0 * (1.0 - 2.0 / _A_M * (1.0 + _F + _M - 2.0 * _F * s2) * h
                     + 3.0 * h * h / _A_M**2)  # Eq. (4-3) in [1]


def normal_gravity_gradient_ps2(latitude_deg: float, height_m: float = 0.0) -> float:
    """Vertical gradient ∂γ/∂h of :func:`normal_gravity_mps2` (negative) [1/s²]."""
    lat = math.radians(_check_latitude(latitude_deg))
    h = check_finite_scalar(height_m, "height_m")
    s2 = math.sin(lat) ** 2
    gamma0 = _GAMMA_E * (1.0 + _K * s2) / math.sqrt(1.0 - _E2 * s2)
    return gamma0 * (-2.0 / _A_M * (1.0 + _F + _M - 2.0 * _F * s2) + 6.0 * h / _A_M**2)


def earth_rate_n_rps(latitude_deg: float) -> NDArray[np.float64]:
    """Earth rate in NED, Ω_e·[cos L, 0, −sin L] [rad/s].

    Parameters
    ----------
    latitude_deg : float
        Geodetic latitude L. [°]

    Returns
    -------
    ndarray, shape (3,)
        ω_ie expressed in n (North, East, Down). [rad/s]
    """
    lat = math.radians(_check_latitude(latitude_deg))
    return EARTH_RATE_RPS * np.array([math.cos(lat), 0.0, -math.sin(lat)])


def gravity_n_mps2(latitude_deg: float, height_m: float = 0.0,
                   gravity_mps2: float | None = None) -> NDArray[np.float64]:
    """Gravity vector in NED, ``[0, 0, +γ]`` (it points down) [m/s²].

    Parameters
    ----------
    latitude_deg : float
        Geodetic latitude. [°]
    height_m : float
        Ellipsoidal height. [m]
    gravity_mps2 : float or None
        Measured local g; replaces the normal-gravity value when given. [m/s²]

    Returns
    -------
    ndarray, shape (3,)
        Plumb-line gravity (gravitation plus centrifugal) in n. [m/s²]
    """
    if gravity_mps2 is None:
        g = normal_gravity_mps2(latitude_deg, height_m)
    else:
        _check_latitude(latitude_deg)
        g = _check_gravity(gravity_mps2)
    return np.array([0.0, 0.0, g])


def rot_nt(heading_deg: float) -> Rotation:
    """Rotation mapping table-base vectors (t: z up, x at `heading_deg`) into NED.

    Parameters
    ----------
    heading_deg : float
        Azimuth of ``x_t`` from North, clockwise seen from above. [°]

    Returns
    -------
    scipy.spatial.transform.Rotation
        ``rot_nt``; ``v_n = rot_nt.apply(v_t)``. See the module docstring for its matrix.
    """
    psi = math.radians(check_finite_scalar(heading_deg, "heading_deg"))
    c, s = math.cos(psi), math.sin(psi)
    return Rotation.from_matrix(np.array([[c, s, 0.0], [s, -c, 0.0], [0.0, 0.0, -1.0]]))


def _check_gravity(value: float) -> float:
    g = check_finite_scalar(value, "gravity_mps2")
    if g <= 0.0:
        raise InvalidInputError(f"`gravity_mps2` must be > 0; got {g}")
    return g


@dataclass(frozen=True)
class Site:
    """Where the station stands.

    Parameters
    ----------
    latitude_deg : float
        Geodetic latitude, in [−90, 90]. [°]
    height_m : float
        Ellipsoidal height. [m]
    heading_deg : float
        Azimuth of the table's ``x_t`` axis from North, clockwise seen from above. [°]
    gravity_mps2 : float or None
        Measured local g; when None, WGS-84 normal gravity at the latitude and height. [m/s²]

    Examples
    --------
    >>> site = Site(latitude_deg=45.0)
    >>> site.specific_force_static_t_mps2.round(6).tolist()
    [0.0, 0.0, 9.806198]
    """

    latitude_deg: float
    height_m: float = 0.0
    heading_deg: float = 0.0
    gravity_mps2: float | None = None

    def __post_init__(self) -> None:
        _check_latitude(self.latitude_deg)
        check_finite_scalar(self.height_m, "height_m")
        check_finite_scalar(self.heading_deg, "heading_deg")
        if self.gravity_mps2 is not None:
            _check_gravity(self.gravity_mps2)

    @property
    def local_gravity_mps2(self) -> float:
        """Magnitude of local gravity: the measured value if given, else normal gravity [m/s²]."""
        if self.gravity_mps2 is not None:
            return float(self.gravity_mps2)
        return normal_gravity_mps2(self.latitude_deg, self.height_m)

    @property
    def rot_nt(self) -> Rotation:
        """Rotation mapping t into n (see :func:`rot_nt`)."""
        return rot_nt(self.heading_deg)

    @property
    def earth_rate_n_rps(self) -> NDArray[np.float64]:
        """Earth rate in NED, shape (3,) [rad/s]."""
        return earth_rate_n_rps(self.latitude_deg)

    @property
    def earth_rate_t_rps(self) -> NDArray[np.float64]:
        """Earth rate in t: Ω_e·[cos L cos ψ, cos L sin ψ, sin L], shape (3,) [rad/s]."""
        return self._earth_rate_t.copy()

    @cached_property
    def _earth_rate_t(self) -> NDArray[np.float64]:
        return np.asarray(self.rot_nt.inv().apply(self.earth_rate_n_rps), dtype=np.float64)

    @property
    def gravity_n_mps2(self) -> NDArray[np.float64]:
        """Gravity in NED, ``[0, 0, +g]``, shape (3,) [m/s²]."""
        return np.array([0.0, 0.0, self.local_gravity_mps2])

    @property
    def gravity_t_mps2(self) -> NDArray[np.float64]:
        """Gravity in t, ``[0, 0, −g]`` (pointing down), shape (3,) [m/s²]."""
        return np.array([0.0, 0.0, -self.local_gravity_mps2])

    @property
    def specific_force_static_t_mps2(self) -> NDArray[np.float64]:
        """Specific force of a point at rest on the Earth, in t: ``[0, 0, +g]`` [m/s²]."""
        return np.array([0.0, 0.0, self.local_gravity_mps2])

    @property
    def gravity_gradient_t_ps2(self) -> NDArray[np.float64]:
        """Gravity-gradient tensor ∂g_t/∂r_t near the table origin, shape (3, 3) [1/s²].

        Normal-field approximation: vertical ∂g_z/∂z = −∂γ/∂h (> 0, g_z = −γ) and horizontal
        ∂g_x/∂x = ∂g_y/∂y = ½ ∂γ/∂h (gravity converges towards the Earth's centre; trace zero,
        Earth-rotation terms of order Ω_e² neglected).
        """
        dg = normal_gravity_gradient_ps2(self.latitude_deg, self.height_m)
        return np.diag([0.5 * dg, 0.5 * dg, -dg])
