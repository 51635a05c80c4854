"""The accelerometer triad from static poses of *known* (nominal) orientation.

With a fixture (a cube, a machined block, a vice on a surface plate) each static pose puts a
known direction d_k of the fixture frame along the vertical: the six faces give d_k = ±x, ±y,
±z, and any other nominal direction may be added. The triad model (docs/processing-
estimation.md, "Field calibration", Eq. (F.11))

    y_k = b + (I + M)·g·d_k + e_k                                                        (F.11)

is linear in the bias b and the 3 × 3 scale/misalignment matrix M (row: sensor axis, column:
input axis of the fixture frame), and separates per sensor axis i into

    y_k,i = b_i + g·d_k,i + g·Σ_j M_ij·d_k,j                                             (F.12)

four unknowns (b_i, M_i·) per axis; the six faces give six equations per axis (ν = 2 each).
With ``k2=True`` a quadratic term K2_i·(g·d_k,i)² joins each axis (F.12′; ν = 1).
:func:`fit_six_position` solves (F.12) by weighted least squares per axis
(the operations of :func:`~imucalib.estimation.linear.solve_weighted_lsq`, through its core
without the diagnostics this fit does not read), with the covariance (AᵀWA)⁻¹, χ²/ν
over the three axes and the Birge-scaled covariance on a misfit (the project's
rule): a pose placed off its nominal direction is a misfit here, which the gravity-norm fit of
:mod:`imucalib.estimation.gravity_norm` does not mind. A Type B standard uncertainty of g adds
M an exactly correlated term (∂M/∂g = −(I + M)/g).

Contents
--------
:class:`SixPositionFit`, :func:`fit_six_position`, :func:`nominal_directions`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib._checks import as_array
from imucalib.errors import InsufficientExcitationError, InvalidInputError
from imucalib.estimation.linear import _checked, _solve_known
from imucalib.models.fit_quality import FitQuality, assess_fit

__all__ = ["SixPositionFit", "fit_six_position", "nominal_directions"]

_F64 = NDArray[np.float64]
_AXES = "xyz"


@dataclass(frozen=True)
class SixPositionFit:
    """The solution of (F.12).

    Attributes
    ----------
    bias : ndarray, shape (3,)
        b. [m/s²]
    scale_misalignment : ndarray, shape (3, 3)
        M (row sensor axis, column input axis). [–]
    k2 : ndarray, shape (3,) or (0,)
        K2 per axis when fitted. [1/(m/s²)]
    covariance : ndarray, shape (12, 12) or (15, 15)
        Of (b_x, b_y, b_z, M_xx, M_xy, …, M_zz[, K2_x, K2_y, K2_z]) (row-major M), g's Type B
        included, Birge-scaled on a misfit.
    covariance_noise : ndarray, shape (12, 12)
        The same before the Birge scaling.
    quality : FitQuality
        χ²/ν of (F.12) over the three axes.
    residuals : ndarray, shape (n, 3)
        y_k − b − (I + M)·g·d_k. [m/s²]
    """

    bias: _F64
    scale_misalignment: _F64
    k2: _F64
    covariance: _F64
    covariance_noise: _F64
    quality: FitQuality
    residuals: _F64

    @property
    def values(self) -> _F64:
        """(b, M row-major[, K2]), the order of :attr:`covariance`."""
        return np.concatenate([self.bias, self.scale_misalignment.ravel(), self.k2])


def nominal_directions(y: ArrayLike, *, max_off_axis_deg: float = 20.0) -> _F64:
    """Return, per pose, the fixture axis ±x, ±y, ±z nearest its mean output `y` (n, 3).

    Raises
    ------
    InvalidInputError
        A pose more than `max_off_axis_deg` from every axis (it was not placed on a face).
    """
    yy = as_array(y, "y", shape=(None, 3))
    unit = yy / np.linalg.norm(yy, axis=1, keepdims=True)
    k = np.argmax(np.abs(unit), axis=1)
    d = np.zeros_like(unit)
    d[np.arange(len(k)), k] = np.sign(unit[np.arange(len(k)), k])
    off = np.degrees(np.arccos(np.clip(np.sum(unit * d, axis=1), -1.0, 1.0)))
    bad = np.flatnonzero(off > max_off_axis_deg)
    if bad.size:
        raise InvalidInputError(
            f"static pose(s) {bad.tolist()} lie {np.round(off[bad], 1).tolist()}° from the "
            f"nearest axis (at most {max_off_axis_deg:g}° expected of a pose on a fixture "
            "face); use the gravity-norm form for poses of unknown orientation")
    return d


def fit_six_position(y: ArrayLike, y_std: ArrayLike, directions: ArrayLike,
                     gravity_mps2: float, *, gravity_std_mps2: float = 0.0,
                     k2: bool = False) -> SixPositionFit:
    """Solve (F.12) per sensor axis (module docstring).

    Parameters
    ----------
    y, y_std : array_like, shape (n, 3)
        Mean accelerometer output of each pose and its standard error. [m/s²]
    directions : array_like, shape (n, 3)
        The nominal up direction d_k of each pose in the fixture frame (unit vectors).
    gravity_mps2, gravity_std_mps2 : float
        Local g and its standard uncertainty. [m/s²]
    k2 : bool
        Add the quadratic term K2_i·(g·d_k,i)² per axis (F.12′): the ± faces of axis i then
        give b_i + K2_i·g² and the other four b_i, so six faces separate it (ν = 1 per axis).

    Raises
    ------
    InvalidInputError
        Mis-shaped or non-finite input, σ ≤ 0, directions that are not unit vectors.
    InsufficientExcitationError
        Directions that do not span the three axes (the M columns they leave unseen named),
        or fewer than five poses (no redundancy for χ²).
    """
    yy = as_array(y, "y", shape=(None, 3))
    sy = as_array(y_std, "y_std", shape=yy.shape)
    d = as_array(directions, "directions", shape=yy.shape)
    if np.any(sy <= 0):
        raise InvalidInputError("`y_std` must be positive")
    if not np.allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-9):
        raise InvalidInputError("`directions` must be unit vectors")
    if not (np.isfinite(gravity_mps2) and gravity_mps2 > 0 and gravity_std_mps2 >= 0):
        raise InvalidInputError(f"`gravity_mps2` must be positive and `gravity_std_mps2` ≥ 0; "
                                f"got {gravity_mps2!r}, {gravity_std_mps2!r}")
    n = yy.shape[0]
    a = np.column_stack([np.ones(n), gravity_mps2 * d])
    extra = 1 if k2 else 0
    sv = np.linalg.svd(a, compute_uv=False)
    if n < 5 + extra or sv[-1] < 1e-9 * sv[0]:
        unseen = [f"M_{i}{_AXES[j]}" for j in range(3) if np.allclose(d[:, j], d[0, j])
                  for i in _AXES]
        raise InsufficientExcitationError(
            unseen or ["bias", "M"],
            f"{n} pose(s) with up directions {np.round(d, 3).tolist()} do not separate the bias "
            "from the scale/misalignment (at least five poses, both signs of every axis)")
    k = 12 + 3 * extra
    values = np.zeros(k)
    cov = np.zeros((k, k))
    resid = np.zeros_like(yy)
    chi2 = 0.0
    for i, ax in enumerate(_AXES):
        names = [f"bias_{ax}", *(f"M_{ax}{j}" for j in _AXES), *([f"K2_{ax}"] if k2 else [])]
        # the one solver's x̂, Σ_x, r and χ² by its operations (estimation.linear), without
        # the diagnostics this fit does not read
        args = _checked(np.column_stack([a, (gravity_mps2 * d[:, i]) ** 2]) if k2 else a,
                        yy[:, i] - gravity_mps2 * d[:, i], names, None, None, sy[:, i])
        fit = _solve_known(
            args[0], args[1], args[3], args[2],
            context=f"six-position design of axis {ax} (F.12)",
            advice=f"the poses do not separate K2_{ax} from the bias (both faces of {ax} and "
                   "one across are needed)" if k2 else None)
        idx = [i, *range(3 + 3 * i, 6 + 3 * i), *([12 + i] if k2 else [])]
        values[idx] = fit.estimate
        cov[np.ix_(idx, idx)] = fit.covariance_noise
        resid[:, i] = fit.residuals
        chi2 += fit.chi2
    # g's Type B: (I + M)·g is what the poses fix ⇒ ∂M/∂g = −(I + M)/g, exactly correlated;
    # then the three axes' χ² pooled, the misfit rule of estimation.linear (Eqs. (6)–(7))
    jg = np.concatenate([np.zeros(3), -(np.eye(3) + values[3:12].reshape(3, 3)).ravel()
                         / gravity_mps2, -2.0 * values[12:] / gravity_mps2])
    cov = cov + np.outer(jg, jg) * gravity_std_mps2**2
    quality = assess_fit("accel (six-position)", chi2, 3 * (n - 4 - extra))
    return SixPositionFit(bias=values[:3], scale_misalignment=values[3:12].reshape(3, 3),
                          k2=values[12:],
                          covariance=cov * quality.sigma_scale**2, covariance_noise=cov,
                          quality=quality, residuals=resid)
