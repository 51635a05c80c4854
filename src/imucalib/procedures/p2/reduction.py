"""P2's reduction of one IMU at one temperature: the closed form and the full least squares.

At one temperature point an IMU has been placed in six orientations (each body axis up and
down, the table's spin axis vertical); in each it was recorded static and turning at +ω and −ω,
each turn averaged over whole revolutions. From those window means this module computes the
gyro and accelerometer bias, scale factors and installation (misalignment) terms, and the
lever arm of the IMU from the spin axis, two ways that must agree (docs/p2.md derives every
equation):

- :func:`closed_form`: the patent's reduction, averages and differences of the window means,
  Eqs. (P2.4)–(P2.9), with σ by linear propagation of the means' standard errors;
- :func:`least_squares`: all windows in one weighted least-squares fit of the triad model
  (the framework's design, :func:`~imucalib.estimation.designs.build_design`), the
  accelerometer by Gauss–Newton because the centripetal term multiplies the scale matrix,
  Eq. (P2.10), with χ²/ν and the Birge scaling of a misfit; every linear (and Gauss–Newton)
  step is solved by :func:`~imucalib.estimation.linear.solve_weighted_lsq` (its checks and
  core).

Model (docs/p2.md, Eqs. (P2.1)–(P2.3)); u_o the body-frame up vector of orientation o (a
signed unit axis), ω the table rate, Ω_U the vertical Earth rate, g local gravity, r the IMU's
position from the spin axis in its body frame, P_o = I − u_o u_oᵀ::

    gyro, turning:    ȳ = b_g + (I + M_g)·u_o·(ω + Ω_U)                            (P2.1)
    accel, static:    ā = b_a + (I + M_a)·g·u_o                                    (P2.2)
    accel, turning:   ā = b_a + (I + M_a)·(g·u_o − ω²·P_o·r)                       (P2.3)

Averaging over whole revolutions removes everything fixed in the local-level frame that turns
in the IMU (the horizontal Earth rate, gravity leaking through a tilted spin axis); a static
orientation recorded at table angles 0° and 180° and averaged cancels the tilt the same way.
The static gyro means are not used: their horizontal Earth-rate projection depends on the
IMU's heading on the fixture, which the analysis does not assume.

Contents
--------
:class:`PointWindows` (the input), :class:`PointEstimate` (the output), :func:`closed_form`,
:func:`least_squares`, :data:`ORIENTATIONS`, :data:`PARAM_NAMES`, :data:`LEVER_ARM_NAMES`,
:data:`LEVER_ARM_MODES`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import ClassVar, Final, Literal

import numpy as np
from numpy.typing import NDArray

from imucalib.conventions import AXES
from imucalib.errors import InvalidInputError
from imucalib.estimation.designs import build_design
from imucalib.estimation.linear import _checked, _solve_known
from imucalib.models.fit_quality import FitQuality, assess_fit

__all__ = [
    "LEVER_ARM_MODES",
    "LEVER_ARM_NAMES",
    "ORIENTATIONS",
    "PARAM_NAMES",
    "LeverArmMode",
    "PointEstimate",
    "PointWindows",
    "closed_form",
    "least_squares",
    "orientation_of",
    "up_vector",
]

_F64 = NDArray[np.float64]

#: The six orientations: the body axis pointing up, in this order.
ORIENTATIONS: Final = ("+x", "-x", "+y", "-y", "+z", "-z")
#: The calibration parameters, in the order of :attr:`PointEstimate.values`.
PARAM_NAMES: Final = (
    *(f"gyro_bias_{a}" for a in AXES), *(f"gyro_M_{i}{j}" for i in AXES for j in AXES),
    *(f"gyro_G_{i}{j}" for i in AXES for j in AXES),
    *(f"accel_bias_{a}" for a in AXES), *(f"accel_M_{i}{j}" for i in AXES for j in AXES),
    *(f"accel_K2_{a}" for a in AXES),
)
#: The lever arm r (IMU origin from the spin axis, body frame), after the parameters. [m]
LEVER_ARM_NAMES: Final = tuple(f"lever_arm_{a}_m" for a in AXES)
#: How the centripetal term of Eq. (P2.3) is treated (docs/p2.md, "The lever arm"):
#: ``"estimate"`` r with the parameters (every window used); ``"cancel"`` the accelerometer from
#: the static windows alone (r still reported from the turning ones); ``"ignore"`` the naive
#: analysis that takes turning accelerometer means for gravity alone (biased off the axis;
#: for comparison only).
LEVER_ARM_MODES: Final = ("estimate", "cancel", "ignore")
LeverArmMode = Literal["estimate", "cancel", "ignore"]


def up_vector(orientation: str) -> _F64:
    """Return u_o, the body-frame up vector of an orientation (``"+x"`` → [1, 0, 0])."""
    if orientation not in ORIENTATIONS:
        raise InvalidInputError(f"an orientation is one of {ORIENTATIONS}; got {orientation!r}")
    u = np.zeros(3)
    u[AXES.index(orientation[1])] = 1.0 if orientation[0] == "+" else -1.0
    return u


@dataclass(frozen=True)
class PointWindows:
    """The window means of one IMU at one temperature point, by orientation.

    Each array has one row per orientation in :data:`ORIENTATIONS` order. Static means are the
    average of the orientation's static windows; turning means are over whole revolutions.

    Attributes
    ----------
    static_accel_mps2, static_accel_se_mps2 : ndarray, shape (6, 3)
        Static accelerometer means and their standard errors. [m/s²]
    plus_gyro_rps, minus_gyro_rps : ndarray, shape (6, 3)
        Gyro means turning at +ω and −ω. [rad/s]
    plus_gyro_se_rps, minus_gyro_se_rps : ndarray, shape (6, 3)
        Their standard errors. [rad/s]
    plus_accel_mps2, minus_accel_mps2, plus_accel_se_mps2, minus_accel_se_mps2 :
        ndarray, shape (6, 3)
        Accelerometer means turning and their standard errors. [m/s²]
    plus_rate_rps, minus_rate_rps : ndarray, shape (6,)
        The measured mean table rates (signed: positive, negative). [rad/s]
    gravity_mps2 : float
        Local gravity g. [m/s²]
    earth_rate_up_rps : float
        Ω_U = Ω_e·sin(latitude), the Earth rate along the vertical spin axis. [rad/s]
    """

    static_accel_mps2: _F64
    static_accel_se_mps2: _F64
    plus_gyro_rps: _F64
    plus_gyro_se_rps: _F64
    minus_gyro_rps: _F64
    minus_gyro_se_rps: _F64
    plus_accel_mps2: _F64
    plus_accel_se_mps2: _F64
    minus_accel_mps2: _F64
    minus_accel_se_mps2: _F64
    plus_rate_rps: _F64
    minus_rate_rps: _F64
    gravity_mps2: float
    earth_rate_up_rps: float

    def __post_init__(self) -> None:
        for name in ("static_accel_mps2", "static_accel_se_mps2", "plus_gyro_rps",
                     "plus_gyro_se_rps", "minus_gyro_rps", "minus_gyro_se_rps",
                     "plus_accel_mps2", "plus_accel_se_mps2", "minus_accel_mps2",
                     "minus_accel_se_mps2"):
            arr = np.asarray(getattr(self, name), dtype=np.float64)
            if arr.shape != (6, 3) or not np.all(np.isfinite(arr)):
                raise InvalidInputError(f"`{name}` must be finite, shape (6, 3) (one row per "
                                        f"orientation {ORIENTATIONS}); got shape {arr.shape}")
            if name.endswith("_se_mps2") or name.endswith("_se_rps"):
                if np.any(arr <= 0.0):
                    raise InvalidInputError(f"`{name}` must be positive standard errors")
            object.__setattr__(self, name, arr)
        for name, sign in (("plus_rate_rps", 1.0), ("minus_rate_rps", -1.0)):
            arr = np.asarray(getattr(self, name), dtype=np.float64)
            if arr.shape != (6,) or not np.all(np.isfinite(arr)) or np.any(sign * arr <= 0.0):
                raise InvalidInputError(f"`{name}` must be 6 finite rates of sign {sign:+g}; "
                                        f"got {arr}")
            object.__setattr__(self, name, arr)

    # the vector of every mean and its standard error, for the propagation of closed_form
    _FIELDS: ClassVar[tuple[tuple[str, str], ...]] = (("static_accel_mps2", "static_accel_se_mps2"),
                      ("plus_gyro_rps", "plus_gyro_se_rps"),
                      ("minus_gyro_rps", "minus_gyro_se_rps"),
                      ("plus_accel_mps2", "plus_accel_se_mps2"),
                      ("minus_accel_mps2", "minus_accel_se_mps2"))

    def means_vector(self) -> tuple[_F64, _F64]:
        """Return (every mean, its standard error), each shape (90,), in a fixed order."""
        means = np.concatenate([getattr(self, m).ravel() for m, _ in self._FIELDS])
        ses = np.concatenate([getattr(self, s).ravel() for _, s in self._FIELDS])
        return means, ses


@dataclass(frozen=True)
class PointEstimate:
    """The parameters of one IMU at one temperature point.

    Attributes
    ----------
    method : str
        ``"closed-form"`` or ``"least-squares"``.
    lever_arm : str
        One of :data:`LEVER_ARM_MODES`.
    names : tuple of str
        :data:`PARAM_NAMES` then :data:`LEVER_ARM_NAMES`.
    values : ndarray, shape (39,)
        SI (rad/s, m/s², dimensionless, m).
    covariance : ndarray, shape (39, 39)
        From the window means' standard errors (noise only).
    fit_quality : tuple of FitQuality
        Least squares only: χ²/ν of the gyro and the accelerometer fit.
    gain : ndarray, shape (39, 90), or None
        Least squares only: the estimator's gain at the solution, ∂values/∂means in the order
        of :meth:`PointWindows.means_vector` (the gyro's and, linearised at the last
        Gauss–Newton step, the accelerometer's weighted least squares, Eq. (P2.10)); zero rows
        for the lever arm when it is not estimated with the parameters. It carries any
        covariance of the means, not only their standard errors, into the parameters
        (docs/p2.md, Eq. (P2.13)).
    jacobian : ndarray, shape (90, 39), or None
        Least squares only: the model's ∂means/∂values at the solution (the design H of each
        triad, rows in the order of :meth:`PointWindows.means_vector`, zero for means not
        fitted), for the fit's χ² under another covariance of the means.
    residuals : ndarray, shape (90,), or None
        Least squares only: means − model at the solution (zero for means not fitted).
    """

    method: str
    lever_arm: str
    names: tuple[str, ...]
    values: _F64
    covariance: _F64
    fit_quality: tuple[FitQuality, ...] = ()
    gain: _F64 | None = None
    jacobian: _F64 | None = None
    residuals: _F64 | None = None

    @property
    def std(self) -> _F64:
        """√diag of the covariance."""
        return np.sqrt(np.diag(self.covariance))

    def covariance_scaled(self) -> _F64:
        """Return the covariance, each misfit triad's block scaled by its Birge ratio squared."""
        cov = self.covariance.copy()
        scale = np.ones(len(self.names))
        for q in self.fit_quality:
            if q.misfit:
                scale[[i for i, n in enumerate(self.names) if n.startswith(q.group + "_")
                       or (q.group == "accel" and n.startswith("lever_arm"))]] = q.birge_ratio
        return np.asarray(cov * np.outer(scale, scale), dtype=np.float64)

    def value(self, name: str) -> float:
        """Return the value of parameter `name`."""
        return float(self.values[self.names.index(name)])


def _check_mode(mode: str) -> None:
    if mode not in LEVER_ARM_MODES:
        raise InvalidInputError(f"`lever_arm` must be one of {LEVER_ARM_MODES}; got {mode!r}")


# ---------------------------------------------------------------------------------------------
# the closed form


def _closed_form_batch(w: PointWindows, mode: str, means: _F64) -> _F64:
    """Eqs. (P2.4)–(P2.9) of docs/p2.md for B mean vectors (B, 90) at once; returns (B, 39).

    Row b uses the means ``means[b]`` (the order of :meth:`PointWindows.means_vector`) with the
    rates, g, Ω_U and standard errors of `w`. Orientation rows are in :data:`ORIENTATIONS`
    order, so rows 2a and 2a + 1 are body axis a up and down.
    """
    nb = means.shape[0]
    s, gp, gm, ap, am = (part.reshape(nb, 6, 3) for part in np.split(means, 5, axis=1))
    ups = np.array([up_vector(o) for o in ORIENTATIONS])            # (6, 3)
    own = np.abs(ups)                                               # 1 on the up axis
    off_axis = 1.0 - own
    g = w.gravity_mps2
    omega2 = 0.5 * (w.plus_rate_rps**2 + w.minus_rate_rps**2)       # ω̄², (6,)
    # accelerometer (P2.6)–(P2.7) from the static means: K columns from the up/down pairs; the
    # bias of sensor i from the four orientations with i horizontal; K2 from the other two
    def accel(means_6: _F64) -> tuple[_F64, _F64, _F64]:
        k = ((means_6[:, 0::2, :] - means_6[:, 1::2, :]) / (2.0 * g)).transpose(0, 2, 1)
        b = (means_6 * off_axis[None]).sum(axis=1) / 4.0
        k2 = ((means_6 * own[None]).sum(axis=1) / 2.0 - b) / g**2
        return b, k, k2
    b_a, k_a, k2_a = accel(s)
    # lever arm (P2.8): the turning half-sum minus the static mean is −ω̄²·K·P_o·r
    # (the K2 term adds K2⊙ω̄⁴·(P_o·r)², second order: a fixed-point iteration removes it)
    omega4 = 0.5 * (w.plus_rate_rps**4 + w.minus_rate_rps**4)
    turn = 0.5 * (ap + am)
    p_r = np.zeros_like(turn)
    lever = np.zeros((nb, 3))
    # the naive analysis ("ignore") sets r to zero below and reads nothing the iteration forms
    for _ in range(0 if mode == "ignore" else 3):
        quad = k2_a[:, None, :] * omega4[None, :, None] * p_r**2
        pr = -np.linalg.solve(k_a, (turn - s - quad).transpose(0, 2, 1)).transpose(0, 2, 1) \
            / omega2[None, :, None]                                 # P_o·r, (B, 6, 3)
        # component j of r from the four orientations whose up axis is not j
        lever = (pr * off_axis[None]).sum(axis=1) / off_axis.sum(axis=0)[None]
        p_r = lever[:, None, :] - ups[None] * (lever @ ups.T)[:, :, None]      # P_o·r
    if mode in ("estimate", "ignore"):
        # (P2.9): each orientation's turning mean, freed of its centripetal term (or not, for
        # the naive analysis), averaged with the static mean, weighted by their variances
        if mode == "estimate":
            centripetal = -omega2[None, :, None] * np.einsum("bij,boj->boi", k_a, p_r) \
                + k2_a[:, None, :] * omega4[None, :, None] * p_r**2
        else:
            centripetal = np.zeros_like(turn)
        v_s = w.static_accel_se_mps2**2
        v_t = 0.25 * (w.plus_accel_se_mps2**2 + w.minus_accel_se_mps2**2)
        combined = (s / v_s + (turn - centripetal) / v_t) / (1.0 / v_s + 1.0 / v_t)
        b_a, k_a, k2_a = accel(combined)
        if mode == "ignore":
            lever = np.zeros_like(lever)
            p_r = np.zeros_like(p_r)
    # gyro (P2.4)–(P2.5): half-differences give the columns of K = I + M; the half-sums freed
    # of K·u_o·(ω̄ + Ω_U) leave e_o = b + G·f_o, f_o = g·u_o − ω̄²·P_o·r
    span = (w.plus_rate_rps - w.minus_rate_rps)[None, :, None]      # ω₊ − ω₋ > 0
    d = (gp - gm) / span                                            # K·u_o, (B, 6, 3)
    k_g = 0.5 * (d[:, 0::2, :] - d[:, 1::2, :]).transpose(0, 2, 1)  # column a = axis a
    mid = (0.5 * (w.plus_rate_rps + w.minus_rate_rps) + w.earth_rate_up_rps)[None, :, None]
    e = 0.5 * (gp + gm) - d * mid
    # up/down pair of axis a: e₊ − e₋ = G·(2g·e_a − (ω̄²₊ − ω̄²₋)·P_a·r), solved for G exactly
    rhs = (e[:, 0::2, :] - e[:, 1::2, :]).transpose(0, 2, 1)        # column a
    dw2 = omega2[0::2] - omega2[1::2]                               # (3,)
    basis = 2.0 * g * np.eye(3)[None] - (dw2[None, None, :] * p_r[:, 0::2, :].transpose(0, 2, 1))
    g_sens = np.linalg.solve(basis.transpose(0, 2, 1), rhs.transpose(0, 2, 1)).transpose(0, 2, 1)
    mean_f = -(omega2[None, :, None] * p_r).mean(axis=1)            # mean of f_o over o
    b_g = e.mean(axis=1) - np.einsum("bij,bj->bi", g_sens, mean_f)
    eye = np.eye(3)[None]
    return np.concatenate([b_g, (k_g - eye).reshape(nb, 9), g_sens.reshape(nb, 9),
                           b_a, (k_a - eye).reshape(nb, 9), k2_a, lever], axis=1)


def _propagate(func: Callable[[_F64], _F64], means: _F64, ses: _F64) -> tuple[_F64, _F64]:
    """Values and covariance J·diag(se²)·Jᵀ, J by central differences of one σ each.

    The closed form is linear in the means but for the product of K and r in its centripetal
    correction (second order), so central differences give J to far better than σ. `func`
    maps (B, n) mean vectors to (B, p) values.
    """
    n = means.size
    steps = np.diag(ses)
    batch = np.vstack([means[None, :], means + steps, means - steps])
    out = func(batch)
    values = out[0]
    jac = ((out[1:n + 1] - out[n + 1:]) / (2.0 * ses[:, None])).T
    cov = (jac * ses**2) @ jac.T
    return values, 0.5 * (cov + cov.T)


def closed_form(windows: PointWindows, *, lever_arm: LeverArmMode = "estimate"
                ) -> PointEstimate:
    """Reduce one temperature point by the patent's closed form (docs/p2.md, (P2.4)–(P2.9)).

    Parameters
    ----------
    windows : PointWindows
        The six orientations' static and ± turning means.
    lever_arm : {"estimate", "cancel", "ignore"}
        :data:`LEVER_ARM_MODES`.

    Returns
    -------
    PointEstimate
        Values and covariance (linear propagation of the means' standard errors, which are
        independent between windows).
    """
    _check_mode(lever_arm)
    means, ses = windows.means_vector()
    values, cov = _propagate(lambda m: _closed_form_batch(windows, lever_arm, m), means, ses)
    if lever_arm == "ignore":
        cov[-3:, :] = 0.0
        cov[:, -3:] = 0.0
    return PointEstimate(method="closed-form", lever_arm=lever_arm,
                         names=(*PARAM_NAMES, *LEVER_ARM_NAMES), values=values, covariance=cov)


# ---------------------------------------------------------------------------------------------
# the least squares


@dataclass(frozen=True)
class _Step:
    """What the fits here read of a solution: x̂, its noise-only Σ_x and the FitQuality."""

    estimate: _F64
    covariance_noise: _F64
    fit_quality: FitQuality
    gain: _F64


def _solve(h: _F64, z: _F64, se: _F64, names: Sequence[str], what: str, group: str) -> _Step:
    """Weighted LSQ z = H·θ by the one solver, refusing a rank-deficient design (named).

    :func:`~imucalib.estimation.linear.solve_weighted_lsq`'s checks and core (the same
    errors and bits), without the parts of its solution no fit here reads (the normalised
    residuals, the Birge-scaled covariance, the observability report of a good design).
    """
    a0, y, names_t, whitener, _ = _checked(h, z, names, None, None, se)
    core = _solve_known(a0, y, whitener, names_t, context=f"{what} design",
                        advice="the six orientations and both turning directions are needed",
                        gain=True)
    assert core.gain is not None  # asked for
    return _Step(estimate=core.estimate, covariance_noise=core.covariance_noise,
                 fit_quality=assess_fit(group, core.chi2, core.dof), gain=core.gain)


def least_squares(windows: PointWindows, *, lever_arm: LeverArmMode = "estimate",
                  iterations: int = 8) -> PointEstimate:
    """Fit every window of one temperature point by weighted least squares (docs/p2.md, (P2.10)).

    The accelerometer first: Eqs. (P2.2)–(P2.3) for the 6 static and 12 turning windows by
    Gauss–Newton on (b_a, M_a, K2_a, r) from zero, the Jacobian of a row in r being
    −ω²·(K_a + 2·diag(K2_a⊙x))·P_o; with ``lever_arm="cancel"`` only the static rows, with
    ``"ignore"`` the turning rows as if gravity alone. Then the gyro: Eq. (P2.1) for the 12
    turning windows, z = ȳ − x with x = u_o·(ω + Ω_U) and the specific force f_o = g·u_o −
    ω²·P_o·r̂ of the g-sensitivity term, the design of
    :func:`~imucalib.estimation.designs.build_design` (bias, scale-misalignment,
    g-sensitivity). r̂'s own uncertainty enters the gyro only through G·ω²·P_o·r̂, a
    second-order term, and is not propagated.

    Returns
    -------
    PointEstimate
        Values, the noise-only covariance, and the FitQuality of each triad.

    Raises
    ------
    InsufficientExcitationError
        A rank-deficient design.
    """
    _check_mode(lever_arm)
    ups = np.array([up_vector(o) for o in ORIENTATIONS])
    g = windows.gravity_mps2
    # accelerometer
    use_turning = lever_arm != "cancel"
    y_a = [windows.static_accel_mps2]
    se_a = [windows.static_accel_se_mps2]
    ups_a, omega2 = [ups], [np.zeros(6)]
    if use_turning:
        y_a += [windows.plus_accel_mps2, windows.minus_accel_mps2]
        se_a += [windows.plus_accel_se_mps2, windows.minus_accel_se_mps2]
        ups_a += [ups, ups]
        omega2 += [windows.plus_rate_rps**2, windows.minus_rate_rps**2]
    y = np.vstack(y_a)
    se = np.vstack(se_a).ravel()
    u_all = np.vstack(ups_a)
    w2 = np.concatenate(omega2)
    estimate_r = lever_arm == "estimate"
    n_p = 15 + (3 if estimate_r else 0)
    names_a = PARAM_NAMES[21:] + (LEVER_ARM_NAMES if estimate_r else ())
    theta = np.zeros(n_p)
    cov_a = np.zeros((n_p, n_p))
    gain_a = np.zeros((n_p, se.size))
    h = np.zeros((se.size, n_p))
    proj = np.eye(3)[None, :, :] - u_all[:, :, None] * u_all[:, None, :]   # P_o per row

    def unpack(th: _F64) -> tuple[_F64, _F64, _F64, _F64]:
        r = th[15:18] if estimate_r else np.zeros(3)
        return th[:3], th[3:12].reshape(3, 3), th[12:15], r

    for _ in range(max(1, iterations)):
        b, m, k2, r = unpack(theta)
        x = g * u_all - w2[:, None] * (proj @ r)                   # true specific force
        pred = b + x @ (np.eye(3) + m).T + k2 * x**2
        base = build_design(x, ("bias", "scale_misalignment", "k2")).H
        if estimate_r:
            slope = (np.eye(3) + m)[None, :, :] + 2.0 * (k2 * x)[:, :, None] * np.eye(3)[None]
            jr = -(w2[:, None, None] * (slope @ proj))                           # (n, 3, 3)
            h = np.hstack([base, jr.reshape(-1, 3)])
        else:
            h = base
        step = _solve(h, (y - pred).ravel(), se, names_a, "accelerometer", "accel")
        delta, cov_a, gain_a = step.estimate, step.covariance_noise, step.gain
        theta = theta + delta
        if np.max(np.abs(delta[3:])) < 1e-13:
            break
    b, m, k2, r = unpack(theta)
    x = g * u_all - w2[:, None] * (proj @ r)
    resid_a = (y - (b + x @ (np.eye(3) + m).T + k2 * x**2)).ravel()
    resid = resid_a / se
    q_a = assess_fit("accel", float(resid @ resid), se.size - n_p)
    cov_r = np.zeros((3, 3))
    if lever_arm == "cancel":
        # the parameters from the static rows; r from the turning rows with them held
        r, cov_r = _lever_arm_given(windows, b, m, k2)
    # gyro
    rates = np.concatenate([windows.plus_rate_rps, windows.minus_rate_rps])
    u12 = np.vstack([ups, ups])
    x_g = u12 * (rates + windows.earth_rate_up_rps)[:, None]
    proj12 = np.eye(3)[None, :, :] - u12[:, :, None] * u12[:, None, :]
    f_g = g * u12 - (rates**2)[:, None] * (proj12 @ r)
    y_g = np.vstack([windows.plus_gyro_rps, windows.minus_gyro_rps])
    se_g = np.vstack([windows.plus_gyro_se_rps, windows.minus_gyro_se_rps]).ravel()
    design = build_design(x_g, ("bias", "scale_misalignment", "g_sensitivity"),
                          specific_force_b=f_g)
    fit_g = _solve(design.H, (y_g - x_g).ravel(), se_g, PARAM_NAMES[:21], "gyro", "gyro")
    theta_g, cov_g, q_g = fit_g.estimate, fit_g.covariance_noise, fit_g.fit_quality
    values = np.concatenate([theta_g, theta[:15], r])
    n = len(PARAM_NAMES) + 3
    cov = np.zeros((n, n))
    cov[:21, :21] = cov_g
    cov[21:21 + n_p, 21:21 + n_p] = cov_a
    if lever_arm == "cancel":
        cov[36:, 36:] = cov_r
    # the gain on the means, in means_vector's order: static accel, ±ω gyro, ±ω accel
    gain = np.zeros((n, 90))
    jac = np.zeros((90, n))
    res = np.zeros(90)
    gain[:21, 18:54] = fit_g.gain
    jac[18:54, :21] = design.H
    res[18:54] = (y_g - x_g).ravel() - design.H @ theta_g
    accel_rows = np.r_[0:18, 54:90] if use_turning else np.r_[0:18]
    gain[21:21 + n_p, accel_rows] = gain_a
    jac[np.ix_(accel_rows, np.arange(21, 21 + n_p))] = h
    res[accel_rows] = resid_a
    return PointEstimate(method="least-squares", lever_arm=lever_arm,
                         names=(*PARAM_NAMES, *LEVER_ARM_NAMES), values=values,
                         covariance=0.5 * (cov + cov.T), fit_quality=(q_g, q_a), gain=gain,
                         jacobian=jac, residuals=res)


def _lever_arm_given(windows: PointWindows, b: _F64, m: _F64, k2: _F64,
                     iterations: int = 8) -> tuple[_F64, _F64]:
    """Fit r to the turning accelerometer rows with b, M, K2 held (Gauss–Newton)."""
    ups = np.array([up_vector(o) for o in ORIENTATIONS])
    u_all = np.vstack([ups, ups])
    w2 = np.concatenate([windows.plus_rate_rps**2, windows.minus_rate_rps**2])
    y = np.vstack([windows.plus_accel_mps2, windows.minus_accel_mps2])
    se = np.vstack([windows.plus_accel_se_mps2, windows.minus_accel_se_mps2]).ravel()
    proj = np.eye(3)[None, :, :] - u_all[:, :, None] * u_all[:, None, :]
    r = np.zeros(3)
    cov = np.zeros((3, 3))
    for _ in range(iterations):
        x = windows.gravity_mps2 * u_all - w2[:, None] * (proj @ r)
        pred = b + x @ (np.eye(3) + m).T + k2 * x**2
        slope = (np.eye(3) + m)[None, :, :] + 2.0 * (k2 * x)[:, :, None] * np.eye(3)[None]
        jr = -(w2[:, None, None] * (slope @ proj)).reshape(-1, 3)
        step = _solve(jr, (y - pred).ravel(), se, LEVER_ARM_NAMES, "accelerometer lever arm",
                      "accel")
        delta, cov = step.estimate, step.covariance_noise
        r = r + delta
        if np.max(np.abs(delta)) < 1e-15:
            break
    return r, cov


def orientation_of(accel_mean_mps2: Sequence[float], gravity_mps2: float, *,
                   tolerance: float = 0.25) -> str | None:
    """Return the orientation whose up axis reads about +g, or None when none does.

    The axis with the largest |ā| must read within `tolerance`·g of ±g and the other two within
    `tolerance`·g of zero (an IMU mounted square to the fixture faces).
    """
    a = np.asarray(accel_mean_mps2, dtype=np.float64) / gravity_mps2
    i = int(np.argmax(np.abs(a)))
    others = np.delete(a, i)
    if abs(abs(a[i]) - 1.0) > tolerance or np.any(np.abs(others) > tolerance):
        return None
    return ("+" if a[i] > 0 else "-") + AXES[i]
