"""Accelerometer calibration from static poses of unknown orientation: the gravity-norm fit.

Without a fixture the orientation of each static pose is unknown, but the specific force at
rest has the magnitude of local gravity g whatever the orientation (Tedaldi, Pretto &
Menegatti, "A robust and easy to implement method for IMU calibration without external
equipments", ICRA 2014; docs/processing-estimation.md, "Field calibration"). With the
correction model of the accelerometer triad

    a = T·(I + diag(s))·(y − b),   T = [[1, −α_yz, α_zy], [0, 1, −α_zx], [0, 0, 1]]       (F.1)

(b the bias [m/s²], s the scale-factor errors, α the three non-orthogonality angles of the
sensor axes to an orthogonal frame whose x is sensor x and y in the sensors' x–y plane, y the
mean output of a pose), the nine unknowns θ = (b, s, α) minimise

    χ²(θ) = Σ_k (‖a_k(θ)‖ − g)² / σ_k²,   σ_k² = û_kᵀ·diag(σ_y,k²)·û_k                  (F.2)

(û_k = a_k/‖a_k‖: only the noise along gravity moves the norm). A consumer accelerometer's
quadratic scale factor (K2 up to 10⁻³ g/g²) is a misfit of (F.1) at the 10⁻⁴ level; the
optional model

    a = T·(I + diag s)·(d − k2∘d²),   d = y − b                                          (F.1′)

(k2 per axis, [1/(m/s²)]; to first order the forward model's y_i += K2_i·x_i², K2 = k2) adds
three unknowns; its cubic extension

    a = T·(I + diag s)·(d − k2∘d² − k3∘d³)                                              (F.1⁗)

(k3 [1/(m/s²)²], K3 = k3 to first order) three more. Gravity's components at a pose near a
face are ±g and a little, where k3·d³ is g²·k3·d: a scale factor; only poses with gravity
between the axes tell the two apart (:func:`k3_separation` says how well a pose set does).
A bias that wanders over the session (a consumer accelerometer's bias
instability) is a misfit the Birge ratio covers badly (it is correlated in time); the optional
linear drift

    y_k → y_k − ḃ·(t_k − t̄)                                                            (F.1″)

(t̄ the poses' mean time, b then the bias at t̄) adds three rates. A unit that warms during
the session (self-heating after power-up: a consumer accelerometer's scale factors move by about
10⁻⁴ per °C) changes its scale factors with its temperature sensor's reading T_k; the optional
temperature term

    s → s + ṡ_T·(T_k − T̄)                                                              (F.1‴)

(T̄ the poses' mean temperature, s then the scale-factor errors at T̄, ṡ_T [1/°C] per axis) adds
three coefficients; the bias's own temperature dependence is in (F.1″) when the temperature
follows the time (a warm-up), and the two are not told apart. :func:`fit_gravity_norm`
solves (F.2) by Gauss–Newton with the analytic Jacobian (each step the estimate of
:func:`~imucalib.estimation.linear.solve_weighted_lsq` by its operations,
:func:`~imucalib.estimation.linear.solve_step`), returns the covariance
(JᵀW J)⁻¹ (the Cramér–Rao bound of the design for white noise), χ²/ν and its Birge-scaled
covariance on a misfit (the project's rule, docs/processing-estimation.md), and refuses a
rank-deficient design naming the parameters it cannot see (:class:`InsufficientExcitationError`:
all poses about one axis leave a scale or an angle free). A rotation of the whole triad is not
observable from norms (three angles): (F.1) fixes it by construction.

:func:`pose_coverage` says which of the six directions ±x, ±y, ±z no pose's gravity comes
within 45° of, and how many more poses in each missing direction would bring every parameter's
σ under a target (from the bound of the design with those poses added).

Contents
--------
:class:`GravityNormFit`, :func:`fit_gravity_norm`, :func:`correct_accel`, :func:`pose_coverage`,
:data:`PARAMETERS`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib._checks import as_array
from imucalib.errors import (
    ConvergenceError,
    InsufficientExcitationError,
    InvalidInputError,
)
from imucalib.estimation._common import check_rank
from imucalib.estimation.linear import _checked, _solve_known, solve_step, solve_weighted_lsq
from imucalib.models.fit_quality import FitQuality, assess_fit

__all__ = ["DRIFT_PARAMETERS", "K2_PARAMETERS", "K3_PARAMETERS", "PARAMETERS",
           "TEMPERATURE_PARAMETERS", "GravityNormFit", "correct_accel", "fit_gravity_norm",
           "k3_separation", "pose_coverage"]

_F64 = NDArray[np.float64]
#: The unknowns of (F.1), in order.
PARAMETERS: Final = ("bias_x", "bias_y", "bias_z", "scale_x", "scale_y", "scale_z",
                     "alpha_yz", "alpha_zy", "alpha_zx")
#: The optional quadratic terms of (F.1′), after :data:`PARAMETERS`.
K2_PARAMETERS: Final = ("k2_x", "k2_y", "k2_z")
#: The optional cubic terms of (F.1⁗), after the quadratic ones. [1/(m/s²)²]
K3_PARAMETERS: Final = ("k3_x", "k3_y", "k3_z")
#: The optional bias rates of (F.1″), last. [m/s³]
DRIFT_PARAMETERS: Final = ("bias_rate_x", "bias_rate_y", "bias_rate_z")
#: The optional scale factors' temperature coefficients of (F.1‴), after the rates. [1/°C]
TEMPERATURE_PARAMETERS: Final = ("scale_tc_x", "scale_tc_y", "scale_tc_z")
_DIRECTIONS: Final = {"+x": (1, 0, 0), "-x": (-1, 0, 0), "+y": (0, 1, 0), "-y": (0, -1, 0),
                      "+z": (0, 0, 1), "-z": (0, 0, -1)}
#: Where added poses go once no axis direction is missing: the 12 directions halfway between
#: two axes (poses along the axes alone leave the non-orthogonality angles unseen).
_BETWEEN: Final = tuple(tuple(v) for v in (
    np.array([[a, b, 0], [a, 0, b], [0, a, b]], dtype=float) / np.sqrt(2.0)
    for a in (1, -1) for b in (1, -1)) for v in v)


def correct_accel(theta: ArrayLike, y: ArrayLike) -> _F64:
    """Apply (F.1) or (F.1′): the corrected specific force of outputs `y` (n, 3). [m/s²]

    θ holds the nine values of :data:`PARAMETERS`, twelve with the quadratic terms of
    :data:`K2_PARAMETERS`, or fifteen with the cubic ones of :data:`K3_PARAMETERS` too (F.1⁗).
    """
    p = np.asarray(theta, dtype=np.float64)
    if p.shape not in ((9,), (12,), (15,)):
        raise InvalidInputError(f"`theta` must hold 9, 12 or 15 values; got shape {p.shape}")
    return _jacobian(p, np.atleast_2d(as_array(y, "y")), k3=p.size == 15)[0]


def _jacobian(p: _F64, y: _F64, scale_offset: _F64 | None = None, *, k2: bool | None = None,
              k3: bool = False) -> tuple[_F64, _F64]:
    """Return the corrected forces (n, 3) and ∂‖a‖/∂θ (n, 9, 12 or 15) of (F.1)–(F.1⁗).

    `scale_offset` (n, 3) adds to s pose by pose: ṡ_T·(T_k − T̄) of (F.1‴). θ holds the
    quadratic terms when `k2` (by default: when it holds 12 values), then the cubic ones when
    `k3`.
    """
    has_k2 = p.size in (12, 15) if k2 is None else k2
    d = y - p[:3]                                   # y − b
    k = 1.0 + p[3:6] if scale_offset is None else 1.0 + p[3:6] + scale_offset
    k2v = p[9:12] if has_k2 else np.zeros(3)
    k3v = p[9 + 3 * has_k2:12 + 3 * has_k2] if k3 else None
    w = d - k2v * d**2                              # the quadratic term removed (F.1′)
    if k3v is not None:
        w = w - k3v * d**3                          # and the cubic one (F.1⁗)
    v = w * k                                       # (I + diag s)(y − b − k2∘(y − b)² …)
    t = np.array([[1.0, -p[6], p[7]], [0.0, 1.0, -p[8]], [0.0, 0.0, 1.0]])
    a = v @ t.T
    u = a / np.linalg.norm(a, axis=1, keepdims=True)
    # ∂a/∂b = −T·diag(k·(1 − 2 k2 d)); ∂a/∂s_j = T[:, j]·w_j; ∂a/∂α: a_x −= α_yz v_y,
    # a_x += α_zy v_z, a_y −= α_zx v_z; ∂a/∂k2_j = −T[:, j]·k_j·d_j²
    ut = u @ t
    dw = 1.0 - 2.0 * k2v * d if k3v is None else 1.0 - 2.0 * k2v * d - 3.0 * k3v * d**2
    jb = -ut * k * dw
    js = ut * w
    ja = np.column_stack([-u[:, 0] * v[:, 1], u[:, 0] * v[:, 2], -u[:, 1] * v[:, 2]])
    cols = [jb, js, ja]
    if has_k2:
        cols.append(-ut * k * d**2)
    if k3v is not None:                             # ∂a/∂k3_j = −T[:, j]·k_j·d_j³
        cols.append(-ut * k * d**3)
    return a, np.column_stack(cols)


@dataclass(frozen=True)
class GravityNormFit:
    """The solution of (F.2).

    Attributes
    ----------
    values : ndarray, shape (9,) or (12,)
        θ = (b [m/s²], s [–], α [rad]) of :data:`PARAMETERS` (and k2 [1/(m/s²)] of
        :data:`K2_PARAMETERS`).
    covariance : ndarray, shape (9, 9) or (12, 12)
        Birge-scaled on a misfit.
    covariance_noise : ndarray, shape (9, 9)
        (JᵀW J)⁻¹: the Cramér–Rao bound of the design for the means' σ.
    quality : FitQuality
        χ²/ν of (F.2).
    residuals : ndarray, shape (n,)
        ‖a_k‖ − g. [m/s²]
    iterations : int
    forces : ndarray, shape (n, 3)
        Each pose's corrected specific force a_k by the fitted model (with its drift and
        temperature terms at the pose). [m/s²]
    """

    values: _F64
    covariance: _F64
    covariance_noise: _F64
    quality: FitQuality
    residuals: _F64
    iterations: int
    forces: _F64

    def std(self) -> _F64:
        """Return the standard uncertainties of :data:`PARAMETERS` (Birge-scaled on a misfit)."""
        return np.sqrt(np.diag(self.covariance))


def _check_rank(j: _F64, sw: _F64, names: Sequence[str]) -> None:
    check_rank(j * sw[:, None], tuple(names), subject="the poses",
               advice="add poses with gravity along other axes; pose_coverage says which")


def fit_gravity_norm(y: ArrayLike, y_std: ArrayLike, gravity_mps2: float, *,
                     k2: bool = False, k3: bool = False, times_s: ArrayLike | None = None,
                     temperatures_degc: ArrayLike | None = None, max_iter: int = 50,
                     tol: float = 1e-12) -> GravityNormFit:
    """Solve (F.2) by Gauss–Newton from b = 0, s = 0, α = 0 (module docstring).

    With ``k2=True`` the model is (F.1′), three quadratic terms more (:data:`K2_PARAMETERS`,
    [1/(m/s²)]): their poses need every axis at several |x_i| (tilted poses), else the design
    is refused as rank-deficient; ``k3=True`` adds the cubic terms of (F.1⁗)
    (:data:`K3_PARAMETERS`, after the quadratic ones), which only poses with gravity between the
    axes separate from the scale factors. With `times_s` (each pose's mid-time) the bias drifts
    linearly over the session (F.1″): y_k is replaced by y_k − ḃ·(t_k − t̄), t̄ the mean time,
    three rates more (:data:`DRIFT_PARAMETERS`); b is then the bias at t̄. With
    `temperatures_degc` (each pose's mean temperature) the scale factors move with it (F.1‴),
    three coefficients more (:data:`TEMPERATURE_PARAMETERS`, last); s is then that at the poses'
    mean temperature T̄.

    Parameters
    ----------
    y : array_like, shape (n, 3)
        Mean accelerometer output of each static pose, n ≥ 10. [m/s²]
    y_std : array_like, shape (n, 3)
        Their standard errors. [m/s²]
    gravity_mps2 : float
        Local gravity. [m/s²]

    Raises
    ------
    InvalidInputError
        Mis-shaped or non-finite input, fewer than 10 poses, σ ≤ 0.
    InsufficientExcitationError
        A rank-deficient design (the parameters named).
    ConvergenceError
        No convergence in `max_iter` steps.
    """
    yy = as_array(y, "y", shape=(None, 3))
    sy = as_array(y_std, "y_std", shape=yy.shape)
    n = yy.shape[0]
    core = len(PARAMETERS) + (len(K2_PARAMETERS) if k2 else 0) + (len(K3_PARAMETERS) if k3
                                                                  else 0)
    drift = times_s is not None
    dt = np.zeros(n)
    if times_s is not None:
        tk = as_array(times_s, "times_s", shape=(n,))
        dt = tk - float(np.mean(tk))
    dtemp: _F64 | None = None
    if temperatures_degc is not None:
        tc = as_array(temperatures_degc, "temperatures_degc", shape=(n,))
        dtemp = tc - float(np.mean(tc))
    m = core + (3 if drift else 0) + (3 if dtemp is not None else 0)
    if n < m + 1:
        raise InvalidInputError(f"the gravity-norm fit needs at least {m + 1} static poses "
                                f"({m} unknowns and a degree of freedom); got {n}")
    if np.any(sy <= 0):
        raise InvalidInputError("`y_std` must be positive")
    if not (np.isfinite(gravity_mps2) and gravity_mps2 > 0):
        raise InvalidInputError(f"`gravity_mps2` must be positive; got {gravity_mps2!r}")
    t0 = core + (3 if drift else 0)                # where (F.1‴)'s coefficients start

    def evaluate(p: _F64) -> tuple[_F64, _F64]:
        if not drift and dtemp is None:
            return _jacobian(p, yy, k2=k2, k3=k3)
        ya = yy - np.outer(dt, p[core:core + 3]) if drift else yy
        a, j = _jacobian(p[:core], ya, None if dtemp is None else np.outer(dtemp, p[t0:]),
                         k2=k2, k3=k3)
        cols = [j]
        if drift:
            cols.append(j[:, :3] * dt[:, None])
        if dtemp is not None:
            cols.append(j[:, 3:6] * dtemp[:, None])
        return a, np.column_stack(cols)

    names = [*PARAMETERS, *(K2_PARAMETERS if k2 else ()), *(K3_PARAMETERS if k3 else ()),
             *(DRIFT_PARAMETERS if drift else ()),
             *(TEMPERATURE_PARAMETERS if dtemp is not None else ())]

    def residual(p: _F64, check: bool) -> tuple[_F64, _F64, _F64, _F64]:
        """Return the Jacobian, r, σ_r and a at p (the rank checked when `check`)."""
        a, j = evaluate(p)
        norm = np.linalg.norm(a, axis=1)
        sr = np.sqrt(np.sum((a / norm[:, None] * sy) ** 2, axis=1))  # u = a/‖a‖
        r = norm - gravity_mps2
        if check:
            _check_rank(j, 1.0 / sr, names)
        return j, r, sr, a

    context = "gravity-norm Jacobian"
    advice = ("poses along the axes alone cannot see the non-orthogonality; add tilted poses, "
              "or use the six-position form for a fixture's faces")
    p = np.zeros(m)
    for it in range(1, max_iter + 1):
        j, r, sr, _ = residual(p, it == 1)
        # the step alone (the one solver's x̂ by its operations, no diagnostics)
        step = solve_step(j, -r, sigma=sr, param_names=names, context=context, advice=advice)
        p = p + step
        if np.max(np.abs(step)) < tol:
            break
    else:
        raise ConvergenceError(f"the gravity-norm fit did not converge in {max_iter} "
                               "iterations")
    j, r, sr, forces = residual(p, True)  # checked at the solution too: axis poses
    # (JᵀW J)⁻¹ at the solution: the one solver's Σ_x by its operations (Eq. (2) there)
    args = _checked(j, -r, names, None, None, sr)
    cov = _solve_known(args[0], args[1], args[3], args[2], context=context,
                       advice=advice).covariance_noise
    quality = assess_fit("accel (gravity norm)", float(np.sum((r / sr) ** 2)), n - m)
    return GravityNormFit(values=p, covariance=cov * quality.sigma_scale**2,
                          covariance_noise=cov, quality=quality, residuals=r, iterations=it,
                          forces=forces)


def k3_separation(y: ArrayLike, y_std: ArrayLike, theta: ArrayLike) -> float:
    """How well the poses tell the cubic terms (F.1⁗) from the scale factors.

    At θ (the 9 values of (F.1) or 12 of (F.1′), k3 = 0) the Cramér–Rao σ of each parameter is
    computed from the design of (F.2) with and without the three k3 columns (one solver,
    :func:`~imucalib.estimation.linear.solve_weighted_lsq`, on a zero right-hand side); the
    largest ratio σ_with/σ_without over the shared parameters is returned (∞ when the k3
    columns make the design rank-deficient). Near 1, the poses separate K3; poses near the faces
    give 15–60 (hand-held sessions of the twin: 3–60), the scale factors then taking K3's
    place.

    Parameters
    ----------
    y, y_std : array_like, shape (n, 3)
        The poses' mean outputs and their standard errors. [m/s²]
    theta : array_like, shape (9,) or (12,)
        Where the design is evaluated (a fit of (F.1) or (F.1′)).
    """
    yy = as_array(y, "y", shape=(None, 3))
    sy = as_array(y_std, "y_std", shape=yy.shape)
    p = np.asarray(theta, dtype=np.float64)
    if p.shape not in ((9,), (12,)):
        raise InvalidInputError(f"`theta` must hold 9 or 12 values; got shape {p.shape}")
    with_k3 = np.concatenate([p, np.zeros(3)])
    a, j = _jacobian(with_k3, yy, k2=p.size == 12, k3=True)
    u = a / np.linalg.norm(a, axis=1, keepdims=True)
    sr = np.sqrt(np.sum((u * sy) ** 2, axis=1))
    names = [*PARAMETERS, *(K2_PARAMETERS if p.size == 12 else ()), *K3_PARAMETERS]
    zero = np.zeros(yy.shape[0])
    without = solve_weighted_lsq(j[:, :p.size], zero, sigma=sr, param_names=names[:p.size],
                                 context="gravity-norm Jacobian")
    try:
        with_ = solve_weighted_lsq(j, zero, sigma=sr, param_names=names,
                                   context="gravity-norm Jacobian")
    except InsufficientExcitationError:
        return math.inf
    ratio = np.sqrt(np.diag(with_.covariance_noise)[:p.size]
                    / np.diag(without.covariance_noise))
    return float(np.max(ratio))


def pose_coverage(y: ArrayLike, y_std: ArrayLike, gravity_mps2: float, *,
                  target_std: ArrayLike | None = None, max_added: int = 50
                  ) -> tuple[list[str], dict[str, int]]:
    """Return the missing directions and, per parameter, the poses to add for `target_std`.

    A direction of ±x, ±y, ±z is missing when no pose's gravity (its mean output) lies within
    45° of it. With `target_std` (9 values, in the units of :data:`PARAMETERS`), poses are
    added one at a time in the missing directions, then in the twelve directions halfway
    between two axes in turn (poses along the axes alone do not see the non-orthogonality),
    each with the median σ of the given poses, until each parameter's bound from
    the design drops under its target: the count per parameter (``max_added + 1`` when not
    reached, 0 when already there).
    """
    yy = as_array(y, "y", shape=(None, 3))
    sy = as_array(y_std, "y_std", shape=yy.shape)
    unit = yy / np.linalg.norm(yy, axis=1, keepdims=True)
    missing = [name for name, d in _DIRECTIONS.items()
               if not np.any(unit @ np.asarray(d, dtype=float) > np.cos(np.radians(45.0)))]
    if target_std is None:
        return missing, {}
    target = as_array(target_std, "target_std", shape=(9,))
    order = [np.asarray(_DIRECTIONS[m], dtype=float) for m in missing]
    order += [np.asarray(v, dtype=float) for v in _BETWEEN]
    typical = np.median(sy, axis=0)
    need: dict[str, int] = {}
    rows, sigmas = [*yy], [*sy]
    for added in range(0, max_added + 1):
        ys, ss = np.array(rows), np.array(sigmas)
        try:
            a, j = _jacobian(np.zeros(9), ys)
            u = a / np.linalg.norm(a, axis=1, keepdims=True)
            sr = np.sqrt(np.sum((u * ss) ** 2, axis=1))
            jw = j / sr[:, None]
            var = np.diag(np.linalg.inv(jw.T @ jw))
            std = np.sqrt(np.where(var > 0, var, np.inf))   # a singular design: unseen
        except np.linalg.LinAlgError:
            std = np.full(9, np.inf)
        for i, name in enumerate(PARAMETERS):
            if name not in need and std[i] <= target[i]:
                need[name] = added
        if len(need) == len(PARAMETERS):
            break
        direction = order[added] if added < len(missing) else \
            order[len(missing) + (added - len(missing)) % len(_BETWEEN)]
        rows.append(direction * gravity_mps2)
        sigmas.append(typical)
    return missing, {name: need.get(name, max_added + 1) for name in PARAMETERS}
