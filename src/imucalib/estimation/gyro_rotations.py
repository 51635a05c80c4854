"""Gyro calibration from hand rotations between static poses, without a rate table.

The accelerometer triad calibrated from the static poses (:mod:`.gravity_norm`, Eq. (F.1))
defines the orthogonal frame a: x along sensor x, y in the sensors' x–y plane. Between two
static poses the hand turns the IMU; the gyro is calibrated against what the accelerometer
says that turn did (Tedaldi, Pretto & Menegatti, ICRA 2014, the imu_tk method; Ferraris,
Grimaldi & Parvis, Sensors and Materials 7(5), 1995, known angles). docs/processing-estimation.md,
"Gyro from rotations", derives what follows.

Model. The gyro output is y = b + (I + M)·ω_a + noise, ω_a the true rate in frame a; the nine
entries of M (row = gyro axis, column = input axis, :data:`PARAMETERS`, the names of
:func:`imucalib.models.result.triad_parameter_names`) hold the scale errors, the
non-orthogonality and the misalignment of the gyro to frame a. The bias b of a rotation is
given (the mean of the two neighbouring static means, :mod:`imucalib.processing.static_detector`)
with its standard error. The corrected rate is

    ω̂ = (I + M)⁻¹·(y − b)                                                         (F.3)

Between the last sample of the static pose before (k) and the first of the one after (k+1),
the attitude of the body relative to the body at k is integrated sample by sample,

    R_{i+1} = R_i·exp([φ_i×]),  φ_i = ½(ω̂_i + ω̂_{i+1})·Δt_i,  R_0 = I              (F.4)

(the exact exponential of the trapezoid rate over each interval: a local error O(Δt³), the
coning term Δt³·ω×ω̇/12, hence O(Δt²) over the rotation; exact for a rotation about a fixed
body axis up to the trapezoid rule of the angle). At rest the specific force in body
coordinates is f_k = C_kᵀ·f_n, C_k the body-to-level attitude, and C_{k+1} = C_k·R_T, so

    f_{k+1} = R_Tᵀ·f_k                                                             (F.5)

Two kinds of observation:

* ``"gravity"`` (Tedaldi): u = a/‖a‖ of the CORRECTED accelerometer mean of each pose (F.1);
  the residual is the part of u_after − R_Tᵀ·u_before across u_after, two components
  along e₁, e₂ ⊥ u_after (a unit vector has two degrees of freedom):

      r = [e₁ e₂]ᵀ·(u_after − R_Tᵀ·u_before)                                       (F.6)

* ``"turn"`` (Ferraris): a turn flat on a desk about the vertical through a known whole angle
  |φ| = n·2π. About a body-fixed axis n (the vertical in body coordinates: the mean of u_before
  and u_after, normalised) ω_a = φ̇·n, so the bias-free integral of the RAW output is exactly
  Θ = ∫(y − b)dt = (I + M)·φ·n, linear in M:

      r = Θ − (I + M)·φ·n,   φ = sign(Θ·n)·|φ_known|                                (F.7)

  (the sign from the integral: the user need not know the sense of the turn). Θ is the
  trapezoid sum over the samples.

Noise of the residuals (first order; (I + M) ≈ I in the noise terms):

* gyro white noise of density N: the angle error δφ_T = R_Tᵀ·Σ_t W_t·δω_t (W_t the trapezoid
  weight of sample t times the attitude halfway through its intervals), Var δω_t = N²/Δt:
  N²·T per axis over a rotation of duration T (the angle random walk);
* the bias' standard error: δφ_T = −B·δb, B = R_Tᵀ·Σ_t W_t (≈ T·I for small angles); for a
  turn δΘ = −T·δb;
* the accelerometer means' noise through the directions: δu = (I − uuᵀ)·D·δy/‖a‖, D the
  Jacobian of (F.1) in y;

      gravity: δr = −[e₁ e₂]ᵀ·[v×]·δφ_T + [e₁ e₂]ᵀ·δu_after − [e₁ e₂]ᵀ·R_Tᵀ·δu_before,
               v = R_Tᵀ·u_before                                                  (F.8)
      turn:    δr = δΘ − φ·δn

Two rotations that share a pose (the "after" mean of one is, value for value, the "before"
mean of the other) share its accelerometer noise, and their biases share that static
interval's gyro mean: Cov(δb_k, δb_k') = σ_b,k·σ_b,k'/2 per axis (each bias the mean of two
static means taken of equal weight). The covariance C of all residuals is therefore full,
block-tridiagonal along a chain of poses. Neglected: the Earth's rate during a rotation
(15 °/h over 5 s is 0.02°: below a consumer or tactical gyro's angle random walk over the same
time; the static means carry it into the bias, which is right), a turn's axis wobble (a desk
keeps it to the desk's flatness; the residual's χ² shows more), the drift of the bias within a
rotation.

:func:`fit_gyro_rotations` minimises rᵀC⁻¹r over all rotations, of either kind, by
Gauss–Newton from M = 0, with the Jacobian of (F.6) in M from the same perturbation as (F.8),
δω̂ = −(I + M)⁻¹·δM·ω̂:

    ∂r/∂M_ij = [e₁ e₂]ᵀ·[v×]·R_Tᵀ·Σ_t W_t·(I + M)⁻¹·e_i·ω̂_t,j                     (F.9)

(the derivative of the continuous integral: it differs from that of the discrete (F.4) by
O(Δt²), which changes the steps, not the solution). The steps are chord steps: J and C of
M = 0 are kept (each step then cuts the error by about ‖M‖) until a step is under `tol`,
then J and C are evaluated there and the steps repeated (C depends on M only through R); each
step is the GLS of :func:`~imucalib.estimation.linear.solve_weighted_lsq` with the full C.
A step must lower χ² = rᵀC⁻¹r: one that does not (a large M, a rotation that disagrees with
the others, a stale J) brings J and C at the current M, and if the step from there does not
either, it is damped (Levenberg 1944; Marquardt 1963):

    δM = argmin ‖L⁻¹(r + J·δM)‖² + λ‖D·δM‖²,   D² = diag(JᵀC⁻¹J)                    (F.9′)

λ growing tenfold from 10⁻⁴ until χ² falls, shrinking tenfold after each accepted step. The
covariance is (JᵀC⁻¹J)⁻¹ — the Cramér–Rao bound of the design for this noise — Birge-scaled
when χ²/ν flags a misfit (:func:`imucalib.models.fit_quality.assess_fit`). With the
covariance C_a of the accelerometer θ the fit used, the accelerometer's own error is
propagated by the implicit-function rule,

    A = ∂θ_g/∂θ_a = −(JᵀC⁻¹J)⁻¹·JᵀC⁻¹·∂r/∂θ_a = −K·∂r/∂θ_a,   cov_g += A·C_a·Aᵀ,
    cov(θ_g, θ_a) = A·C_a                                                          (F.10)

(K the solver's gain; ∂r/∂θ_a by central differences; the error of θ_a is taken as
independent of the noise of the pose means used here, though the accelerometer fit used the
same means: a correlation this neglects). Turns alone make a linear problem: (F.7) is
Θ − φn = M·φn, solved in closed form by :func:`fit_turns_linear` (its C does not depend on M,
so Gauss–Newton reaches the same solution).

A design that leaves entries of M unseen (turns about one axis only; hand rotations all about
one body axis, or about the vertical) is refused naming them
(:class:`~imucalib.errors.InsufficientExcitationError`): at M = 0 and at the solution, a
column of the whitened J under 5 % of the largest is not excited (at M = 0 an unseen entry
still shows through the misalignment's leak of the other axes' rates, ≤ a few %), and the
columns at unit norm must have no singular value under 10⁻³ of the largest.

Contents
--------
:class:`RotationObservation`, :class:`GyroRotationFit`, :func:`fit_gyro_rotations`,
:func:`fit_turns_linear`, :func:`rotation_disagreement`, :data:`PARAMETERS`, :data:`KINDS`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib._checks import as_array
from imucalib.errors import ConvergenceError, InvalidInputError
from imucalib.estimation._common import check_rank
from imucalib.estimation.gravity_norm import correct_accel
from imucalib.estimation.linear import LsqSolution, solve_weighted_lsq
from imucalib.models.fit_quality import FitQuality, assess_fit

__all__ = ["KINDS", "PARAMETERS", "GyroRotationFit", "RotationObservation",
           "fit_gyro_rotations", "fit_turns_linear", "rotation_disagreement"]

_F64 = NDArray[np.float64]
_AXES: Final = ("x", "y", "z")
#: The nine entries of M in (F.3), row-major (row = gyro axis, column = input axis).
PARAMETERS: Final = tuple(f"gyro_M_{i}{j}" for i in _AXES for j in _AXES)
#: The kinds of rotation observation, (F.6) and (F.7).
KINDS: Final = ("gravity", "turn")
#: A column of the whitened Jacobian under this fraction of the largest is not excited: a gyro
#: entry seen only through the leak of other axes' rates by the misalignment (≤ a few %).
_WEAK: Final = 0.05
#: A direction of the design (columns at unit norm) whose singular value is under this fraction
#: of the largest is not separable (a good gravity-only design has 0.1–0.2).
_COLLINEAR: Final = 1e-3
#: The most a turn's poses may differ in gravity direction (a desk turn keeps it). [°]
_TURN_APART_DEG: Final = 10.0
_ADVICE: Final = ("add rotations about other axes: turns flat on a desk with each axis up, or "
                  "hand rotations that tip each axis through the vertical")


def _vec3(value: ArrayLike, name: str) -> _F64:
    return as_array(value, name, shape=(3,))


@dataclass(frozen=True, eq=False)
class RotationObservation:
    """One motion between two static poses, as :func:`fit_gyro_rotations` uses it.

    Attributes
    ----------
    kind : {"gravity", "turn"}
        (F.6): any hand rotation; (F.7): a turn flat on a desk through a known angle.
    time_s : ndarray, shape (m,)
        Sample times, strictly increasing, from the last sample of the static pose before to
        the first of the one after, m ≥ 2. [s]
    gyro_rps : ndarray, shape (m, 3)
        Raw gyro output over those samples. [rad/s]
    bias_rps, bias_std_rps : ndarray, shape (3,)
        The gyro bias taken for the motion (mean of the two static means) and its standard
        error. [rad/s]
    accel_before_mps2, accel_before_std : ndarray, shape (3,)
        RAW accelerometer mean of the pose before and its standard error. [m/s²]
    accel_after_mps2, accel_after_std : ndarray, shape (3,)
        Likewise for the pose after. [m/s²]
    angle_rad : float or None
        For a ``"turn"``: the known angle (n·2π; its sign is taken from the integral, (F.7)).
        [rad]

    Raises
    ------
    InvalidInputError
        An unknown kind, mis-shaped or non-finite arrays, non-increasing times, a standard
        error ≤ 0, a turn without a non-zero angle.
    """

    kind: str
    time_s: _F64
    gyro_rps: _F64
    bias_rps: _F64
    bias_std_rps: _F64
    accel_before_mps2: _F64
    accel_before_std: _F64
    accel_after_mps2: _F64
    accel_after_std: _F64
    angle_rad: float | None = None

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise InvalidInputError(f"`kind` must be one of {list(KINDS)}; got {self.kind!r}")
        t = as_array(self.time_s, "time_s", shape=(None,))
        if t.size < 2:
            raise InvalidInputError(f"`time_s` must hold at least 2 samples; got {t.size}")
        if np.any(np.diff(t) <= 0):
            bad = int(np.argmax(np.diff(t) <= 0))
            raise InvalidInputError(f"`time_s` must be strictly increasing; got "
                                    f"{t[bad]!r} then {t[bad + 1]!r} at samples {bad}, {bad + 1}")
        fields = {"time_s": t, "gyro_rps": as_array(self.gyro_rps, "gyro_rps",
                                                    shape=(t.size, 3))}
        for name in ("bias_rps", "bias_std_rps", "accel_before_mps2", "accel_before_std",
                     "accel_after_mps2", "accel_after_std"):
            fields[name] = _vec3(getattr(self, name), name)
        for name in ("bias_std_rps", "accel_before_std", "accel_after_std"):
            if np.any(fields[name] <= 0):
                raise InvalidInputError(f"`{name}` must be > 0; got {fields[name].tolist()}")
        for name in ("accel_before_mps2", "accel_after_mps2"):
            if not np.linalg.norm(fields[name]) > 0:
                raise InvalidInputError(f"`{name}` must not be zero (a pose at rest sees g)")
        for name, value in fields.items():
            object.__setattr__(self, name, value)
        if self.kind == "turn":
            a = self.angle_rad
            if a is None or not isinstance(a, int | float) or not math.isfinite(a) or a == 0:
                raise InvalidInputError("a \"turn\" needs `angle_rad`, its known non-zero angle "
                                        f"(e.g. 2π); got {a!r}")
            object.__setattr__(self, "angle_rad", float(a))


@dataclass(frozen=True, eq=False)
class GyroRotationFit:
    """The solution of (F.6)–(F.7) over all rotations.

    Attributes
    ----------
    values : ndarray, shape (9,)
        The entries of M, :data:`PARAMETERS`. [–]
    covariance : ndarray, shape (9, 9)
        ``covariance_noise`` Birge-scaled on a misfit, plus ``covariance_accel`` when the
        accelerometer covariance was given.
    covariance_noise : ndarray, shape (9, 9)
        (JᵀC⁻¹J)⁻¹: the bound of the design for the gyro's and the poses' noise.
    quality : FitQuality
        χ²/ν of the fit (group ``"gyro (rotations)"``).
    residuals : tuple of ndarray
        Per rotation, (F.6) (2 values) or (F.7) (3 values) at the solution. [rad]
    iterations : int
        Gauss–Newton steps (0 for :func:`fit_turns_linear`).
    covariance_accel : ndarray, shape (9, 9), or None
        A·C_a·Aᵀ of (F.10): the accelerometer calibration's error carried into M.
    cross_covariance : ndarray, shape (9, 9), or None
        cov(θ_g, θ_a) = A·C_a (rows :data:`PARAMETERS`, columns
        :data:`imucalib.estimation.gravity_norm.PARAMETERS`): with the accelerometer's C_a and
        ``covariance`` it builds the joint covariance.
    accel_sensitivity : ndarray, shape (9, 9), or None
        A = ∂θ_g/∂θ_a of (F.10).
    """

    values: _F64
    covariance: _F64
    covariance_noise: _F64
    quality: FitQuality
    residuals: tuple[_F64, ...]
    iterations: int
    covariance_accel: _F64 | None = None
    cross_covariance: _F64 | None = None
    accel_sensitivity: _F64 | None = None

    def std(self) -> _F64:
        """Return the standard uncertainties of :data:`PARAMETERS` (as ``covariance``)."""
        return np.sqrt(np.diag(self.covariance))

    def matrix(self) -> _F64:
        """Return M as a 3 × 3 matrix (row = gyro axis)."""
        return self.values.reshape(3, 3).copy()


# --- quaternions [w, x, y, z] (Hamilton: R(p ⊗ q) = R(p)·R(q)) ------------------------------

def _qmul(p: _F64, q: _F64) -> _F64:
    pw, px, py, pz = p[..., 0], p[..., 1], p[..., 2], p[..., 3]
    qw, qx, qy, qz = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    out = np.empty(np.broadcast_shapes(p.shape, q.shape))
    out[..., 0] = pw * qw - px * qx - py * qy - pz * qz
    out[..., 1] = pw * qx + px * qw + py * qz - pz * qy
    out[..., 2] = pw * qy - px * qz + py * qw + pz * qx
    out[..., 3] = pw * qz + px * qy - py * qx + pz * qw
    return out


def _qexp(phi: _F64) -> _F64:
    """Return the unit quaternions (…, 4) of rotation vectors (…, 3): exp."""
    angle = np.linalg.norm(phi, axis=-1, keepdims=True)
    return np.concatenate([np.cos(0.5 * angle), 0.5 * np.sinc(angle / (2 * np.pi)) * phi],
                          axis=-1)


def _qmat(q: _F64) -> _F64:
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    out = np.empty((*q.shape[:-1], 3, 3))
    out[..., 0, 0] = 1 - 2 * (y * y + z * z)
    out[..., 0, 1] = 2 * (x * y - w * z)
    out[..., 0, 2] = 2 * (x * z + w * y)
    out[..., 1, 0] = 2 * (x * y + w * z)
    out[..., 1, 1] = 1 - 2 * (x * x + z * z)
    out[..., 1, 2] = 2 * (y * z - w * x)
    out[..., 2, 0] = 2 * (x * z - w * y)
    out[..., 2, 1] = 2 * (y * z + w * x)
    out[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return out


def _prefix(q: _F64, block: int = 16) -> _F64:
    """Return the running products q₀ ⊗ q₁ ⊗ … ⊗ q_i along axis 1 of (K, n, 4), in order.

    Two levels, vectorised: running products inside blocks of `block` quaternions, then of the
    blocks' totals, then each block's products premultiplied by the product of the blocks
    before it.
    """
    k, n, _ = q.shape
    nb = -(-n // block)
    padded = np.zeros((k, nb * block, 4))
    padded[..., 0] = 1.0
    padded[:, :n] = q
    blocks = padded.reshape(k, nb, block, 4)
    for i in range(1, block):
        blocks[:, :, i] = _qmul(blocks[:, :, i - 1], blocks[:, :, i])
    for b in range(1, nb):
        blocks[:, b] = _qmul(blocks[:, b - 1, -1:], blocks[:, b])
    return blocks.reshape(k, nb * block, 4)[:, :n]


def _skew(v: _F64) -> _F64:
    z = np.zeros(v.shape[:-1])
    x, y, w = np.moveaxis(v, -1, 0)
    return np.stack([np.stack([z, -w, y], -1), np.stack([w, z, -x], -1),
                     np.stack([-y, x, z], -1)], axis=-2)


def _accel_jacobian(theta_a: _F64) -> _F64:
    """D = ∂a/∂y of (F.1)."""
    t = np.array([[1.0, -theta_a[6], theta_a[7]], [0.0, 1.0, -theta_a[8]], [0.0, 0.0, 1.0]])
    return np.asarray(t * (1.0 + theta_a[3:6]), dtype=np.float64)


def _basis(u: _F64) -> _F64:
    """Two unit vectors (K, 3, 2) across each unit vector u (K, 3)."""
    ref = np.eye(3)[np.argmin(np.abs(u), axis=1)]
    e1 = np.cross(u, ref)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    return np.stack([e1, np.cross(u, e1)], axis=-1)


class _Design:
    """The rotations packed for batched evaluation (padding: zero rate, zero Δt)."""

    def __init__(self, rotations: Sequence[RotationObservation], theta_a: _F64,
                 density: _F64) -> None:
        rots = list(rotations)
        if len(rots) < 3:
            raise InvalidInputError(f"the gyro rotation fit needs at least 3 rotations; got "
                                    f"{len(rots)}")
        for i, r in enumerate(rots):
            if not isinstance(r, RotationObservation):
                raise InvalidInputError(f"rotation {i} must be a RotationObservation; got "
                                        f"{type(r).__name__}")
        k, length = len(rots), max(r.time_s.size for r in rots)
        self.k = k
        self.turn = np.array([r.kind == "turn" for r in rots])
        self.rate = np.zeros((k, length, 3))
        self.dt = np.zeros((k, length))            # Δt_i of interval i (last: 0)
        for i, r in enumerate(rots):
            self.rate[i, : r.time_s.size] = r.gyro_rps - r.bias_rps
            self.dt[i, : r.time_s.size - 1] = np.diff(r.time_s)
        self.c = 0.5 * (self.dt + np.concatenate([np.zeros((k, 1)), self.dt[:, :-1]], axis=1))
        self.duration = np.array([r.time_s[-1] - r.time_s[0] for r in rots])
        self.theta_raw = np.einsum("kl,kla->ka", self.c, self.rate)       # Θ of (F.7)
        self.bias_std = np.array([r.bias_std_rps for r in rots])
        self.yb = np.array([r.accel_before_mps2 for r in rots])
        self.sb = np.array([r.accel_before_std for r in rots])
        self.ya = np.array([r.accel_after_mps2 for r in rots])
        self.sa = np.array([r.accel_after_std for r in rots])
        self.density2 = np.broadcast_to(density**2, (3,))
        # residual rows: 2 per gravity rotation, 3 per turn
        self.rows = [np.arange(3 * i, 3 * i + (3 if t else 2)) for i, t in enumerate(self.turn)]
        self.sel = np.concatenate(self.rows)
        self.slices = np.cumsum([0, *(len(r) for r in self.rows)])
        self._pose_ids()
        self.set_accel(theta_a)
        self.basis = _basis(self.ua)           # e₁, e₂ of (F.6), fixed at the θ_a given
        apart = np.degrees(np.arccos(np.clip(np.sum(self.ub * self.ua, axis=1), -1.0, 1.0)))
        bad = np.flatnonzero(self.turn & (apart > _TURN_APART_DEG))
        if bad.size:
            raise InvalidInputError(
                f"a \"turn\" ends in the pose it started from (gravity within "
                f"{_TURN_APART_DEG:g}°); rotation {int(bad[0])}'s poses are "
                f"{apart[bad[0]]:.1f}° apart (tag it \"gravity\")")
        n = self._axis(self.ub, self.ua)
        angle = np.array([abs(r.angle_rad) if r.angle_rad is not None else 0.0 for r in rots])
        self.phi = np.where(np.einsum("ka,ka->k", self.theta_raw, n) < 0, -angle, angle)

    def _pose_ids(self) -> None:
        """Poses (equal where a mean and its σ repeat) and the biases' covariance (F.8)."""
        keys: dict[bytes, int] = {}
        before = [keys.setdefault(np.concatenate([y, s]).tobytes(), len(keys))
                  for y, s in zip(self.yb, self.sb, strict=True)]
        after = [keys.setdefault(np.concatenate([y, s]).tobytes(), len(keys))
                 for y, s in zip(self.ya, self.sa, strict=True)]
        eye = np.eye(len(keys))
        self.at_before, self.at_after = eye[:, before], eye[:, after]     # (poses, K)
        self.pose_var = np.zeros((len(keys), 3))
        self.pose_var[before] = self.sb**2
        self.pose_var[after] = self.sa**2
        # rotation i's bias shares a static interval with j's when i's after is j's before
        shared = (self.at_after.T @ self.at_before) > 0
        shared = shared | shared.T
        np.fill_diagonal(shared, False)
        self.bias_cov = np.where(shared[:, :, None],
                                 0.5 * self.bias_std[:, None] * self.bias_std[None], 0.0)
        self.bias_cov[np.arange(self.k), np.arange(self.k)] = self.bias_std**2

    def set_accel(self, theta_a: _F64) -> None:
        """Correct the poses' means with θ_a (F.1) (the basis of (F.6) stays as it was)."""
        self.theta_a = theta_a
        ab, aa = correct_accel(theta_a, self.yb), correct_accel(theta_a, self.ya)
        self.nb, self.na = np.linalg.norm(ab, axis=1), np.linalg.norm(aa, axis=1)
        self.ub, self.ua = ab / self.nb[:, None], aa / self.na[:, None]

    @staticmethod
    def _axis(ub: _F64, ua: _F64) -> _F64:
        """Return a turn's axis, the mean of its two up directions.

        0 where they are opposite (a gravity-referenced rotation of 180°, which is no turn
        and never uses it): no division by zero.
        """
        s = ub + ua
        return np.asarray(s / _safe_norm(s)[:, None], dtype=np.float64)

    def end_attitudes(self, m: _F64) -> _F64:
        """R_T (K, 3, 3) of (F.4) alone, by a pairwise product tree (in order)."""
        inv = np.linalg.inv(np.eye(3) + m.reshape(3, 3))
        w = self.rate @ inv.T
        q = _qexp(0.5 * (w[:, 1:] + w[:, :-1]) * self.dt[:, :-1, None])
        while q.shape[1] > 1:
            if q.shape[1] % 2:
                q = np.concatenate([q, np.tile([1.0, 0.0, 0.0, 0.0], (self.k, 1, 1))], axis=1)
            q = _qmul(q[:, 0::2], q[:, 1::2])
        return _qmat(q[:, 0])

    def attitudes(self, m: _F64) -> tuple[_F64, _F64, _F64]:
        """ω̂ (K, L, 3) of (F.3), R_t (K, L, 3, 3) of (F.4) and the weights W_t (K, L, 3, 3)."""
        inv = np.linalg.inv(np.eye(3) + m.reshape(3, 3))
        w = self.rate @ inv.T
        phi = 0.5 * (w[:, 1:] + w[:, :-1]) * self.dt[:, :-1, None]
        q = _prefix(_qexp(phi))
        ident = np.zeros((self.k, 1, 4))
        ident[..., 0] = 1.0
        r = _qmat(np.concatenate([ident, q], axis=1))
        mid = 0.5 * (r[:, 1:] + r[:, :-1]) * (0.5 * self.dt[:, :-1, None, None])
        wt = np.zeros_like(r)
        wt[:, :-1] += mid
        wt[:, 1:] += mid
        return w, r, wt

    def residuals(self, m: _F64, rt: _F64) -> _F64:
        """(F.6) and (F.7) stacked (n,), given R_T (K, 3, 3)."""
        v = np.einsum("kba,kb->ka", rt, self.ub)                       # R_Tᵀ·u_before
        grav = np.einsum("kab,ka->kb", self.basis, self.ua - v)
        full = np.zeros((self.k, 3))
        full[:, :2] = grav
        n = self._axis(self.ub, self.ua)
        turn = self.theta_raw - (self.phi[:, None] * n) @ (np.eye(3) + m.reshape(3, 3)).T
        full[self.turn] = turn[self.turn]
        return np.asarray(full.ravel()[self.sel], dtype=np.float64)

    def evaluate(self, m: _F64) -> tuple[_F64, _F64, _F64, _F64]:
        """Return r (n,), J = ∂r/∂M (n, 9) of (F.9), C (n, n) of (F.8) and R_T (K, 3, 3)."""
        w, r, wt = self.attitudes(m)
        rt = r[:, -1]
        res = self.residuals(m, rt)
        inv = np.linalg.inv(np.eye(3) + m.reshape(3, 3))
        v = np.einsum("kba,kb->ka", rt, self.ub)
        g = -np.einsum("kab,kac->kbc", self.basis, _skew(v))               # ∂r/∂δφ_T (K,2,3)
        # ∂φ_T/∂M_ij = −R_Tᵀ·Σ_t W_t·(I+M)⁻¹·e_i·ω̂_t,j
        x = (np.swapaxes(w, 1, 2) @ wt.reshape(self.k, -1, 9)).reshape(self.k, 3, 3, 3)
        dphi = -np.einsum("kca,kjcb,bi->kaij", rt, x, inv).reshape(self.k, 3, 9)
        jg = np.einsum("kbc,kcp->kbp", g, dphi)
        n = self._axis(self.ub, self.ua)
        jt = -np.einsum("ai,kj->kaij", np.eye(3), self.phi[:, None] * n).reshape(self.k, 3, 9)
        jfull = np.zeros((self.k, 3, 9))
        jfull[:, :2] = jg
        jfull[self.turn] = jt[self.turn]
        jac = jfull.reshape(-1, 9)[self.sel]
        return res, np.asarray(jac, dtype=np.float64), self._covariance(g, r, wt), rt

    def _covariance(self, g: _F64, r: _F64, wt: _F64) -> _F64:
        """C of all residuals, (F.8)."""
        k, rt = self.k, r[:, -1]
        # gyro white noise and the bias, per rotation
        cinv = np.divide(1.0, self.c, out=np.zeros_like(self.c), where=self.c > 0)
        scaled = wt * (self.density2[None, None, None, :] * cinv[:, :, None, None])
        sw = (np.swapaxes(scaled, 1, 2).reshape(k, 3, -1)
              @ np.swapaxes(wt, 1, 2).reshape(k, 3, -1).transpose(0, 2, 1))
        b = np.einsum("kca,kcb->kab", rt, wt.sum(axis=1))                 # B = R_Tᵀ·Σ_t W_t
        hb = np.where(self.turn[:, None, None], -self.duration[:, None, None] * np.eye(3),
                      np.concatenate([-g @ b, np.zeros((k, 1, 3))], axis=1))   # ∂r/∂b
        sphi = np.einsum("kba,kbc,kcd->kad", rt, sw, rt)                    # R_Tᵀ Σ R_T
        white = np.where(self.turn[:, None, None],
                         self.duration[:, None, None] * np.diag(self.density2),
                         np.pad(g @ sphi @ np.swapaxes(g, 1, 2), ((0, 0), (0, 1), (0, 1))))
        c4 = np.einsum("iab,ijb,jcb->iajc", hb, self.bias_cov, hb)
        c4[np.arange(k), :, np.arange(k), :] += white
        # accelerometer means, one source per pose
        d = _accel_jacobian(self.theta_a)
        pb = (np.eye(3) - np.einsum("ka,kb->kab", self.ub, self.ub)) @ d / self.nb[:, None, None]
        pa = (np.eye(3) - np.einsum("ka,kb->kab", self.ua, self.ua)) @ d / self.na[:, None, None]
        n = self._axis(self.ub, self.ua)
        pn = (np.eye(3) - np.einsum("ka,kb->kab", n, n)) / _safe_norm(
            self.ub + self.ua)[:, None, None]  # used for turns only (np.where below)
        grav_b = -np.einsum("kab,kca,kcd->kbd", self.basis, rt, pb)
        grav_a = np.einsum("kab,kad->kbd", self.basis, pa)
        pad = ((0, 0), (0, 1), (0, 0))
        hyb = np.where(self.turn[:, None, None], -self.phi[:, None, None] * pn @ pb,
                       np.pad(grav_b, pad))
        hya = np.where(self.turn[:, None, None], -self.phi[:, None, None] * pn @ pa,
                       np.pad(grav_a, pad))
        sens = (self.at_before[:, :, None, None] * hyb[None]
                + self.at_after[:, :, None, None] * hya[None])          # (poses, K, 3, 3)
        c4 += np.einsum("pkab,pb,pjcb->kajc", sens, self.pose_var, sens, optimize=True)
        return np.asarray(c4.reshape(3 * k, 3 * k)[np.ix_(self.sel, self.sel)],
                          dtype=np.float64)

    def per_rotation(self, r: _F64) -> tuple[_F64, ...]:
        return tuple(r[a:b].copy() for a, b in zip(self.slices[:-1], self.slices[1:],
                                                   strict=True))


def _safe_norm(v: _F64) -> _F64:
    """‖v‖ per row, 1 where it is 0 (rows only the turns use, which never have 0)."""
    norm = np.linalg.norm(v, axis=1)
    return np.asarray(np.where(norm > 0.0, norm, 1.0), dtype=np.float64)


def _prepare(rotations: Sequence[RotationObservation], accel_theta: ArrayLike,
             density: ArrayLike) -> _Design:
    theta_a = as_array(accel_theta, "accel_theta")
    if theta_a.shape not in ((9,), (12,)):
        raise InvalidInputError(f"`accel_theta` must hold the 9 values of (F.1) or the 12 of "
                                f"(F.1′); got shape {theta_a.shape}")
    dens = np.asarray(as_array(density, "gyro_noise_density_rps_rthz"))
    if dens.shape not in ((), (3,)) or np.any(dens <= 0):
        raise InvalidInputError("`gyro_noise_density_rps_rthz` must be one or three values > 0; "
                                f"got {dens.tolist()}")
    return _Design(rotations, theta_a, dens)


def _whiten(c: _F64, a: _F64) -> _F64:
    """L⁻¹·a, C = L·Lᵀ.

    Raises
    ------
    InvalidInputError
        C not finite or not positive definite (samples far beyond the others in a rotation).
    """
    try:
        chol = np.linalg.cholesky(c) if np.isfinite(c).all() else None
    except np.linalg.LinAlgError:
        chol = None
    if chol is None:
        raise InvalidInputError(
            "the rotations' noise covariance is not finite or not positive definite; expected "
            "gyro and accelerometer samples within a sensor's range (a spike of absurd size "
            "in a rotation?)")
    return np.asarray(np.linalg.solve(chol, a), dtype=np.float64)


def _step(jac: _F64, r: _F64, c: _F64, *, gain: bool = False) -> LsqSolution:
    """Solve for the Gauss–Newton step δM minimising (r + J·δM)ᵀC⁻¹(r + J·δM)."""
    return solve_weighted_lsq(jac, -r, covariance=c, param_names=PARAMETERS, gain=gain,
                              group="gyro (rotations)", context="rotations' Jacobian",
                              advice=_ADVICE)


def _check(jac: _F64, c: _F64) -> None:
    check_rank(_whiten(c, jac), PARAMETERS, subject="the rotations", advice=_ADVICE,
               weak_column=_WEAK, weak_singular=_COLLINEAR)


def _finish(design: _Design, m: _F64, it: int, accel_covariance: ArrayLike | None,
            jac: _F64, c: _F64) -> GyroRotationFit:
    """Return the result at `m`, J and C of (F.8)–(F.9) evaluated there (or a step < tol away).

    With the accelerometer's covariance C_a the residuals' covariance becomes
    C + D·C_a·Dᵀ (D = ∂r/∂θ_a): one more Gauss–Newton step is taken with it, and χ²/ν, the
    covariance and the cross-covariance come from it (F.10).
    """
    rt = design.end_attitudes(m)
    r = design.residuals(m, rt)
    _check(jac, c)
    cov_noise = _step(jac, r, c).covariance_noise
    extra: dict[str, _F64] = {}
    cov, c_fit = cov_noise, c
    if accel_covariance is not None:
        theta_a = design.theta_a
        na = theta_a.size
        ca = as_array(accel_covariance, "accel_covariance", shape=(na, na))
        da = np.zeros((r.size, na))
        for p in range(na):
            h = 1e-6 * max(1.0, abs(theta_a[p]))
            cols = []
            for sign in (1.0, -1.0):
                design.set_accel(theta_a + sign * h * np.eye(na)[p])
                cols.append(design.residuals(m, rt))
            da[:, p] = (cols[0] - cols[1]) / (2 * h)
        design.set_accel(theta_a)
        c_fit = c + da @ ca @ da.T
        c_fit = 0.5 * (c_fit + c_fit.T)
        step = _step(jac, r, c_fit, gain=True)
        m = m + step.estimate
        rt = design.end_attitudes(m)
        r = design.residuals(m, rt)
        cov = step.covariance_noise
        assert step.gain is not None  # asked for
        a = -step.gain @ da                                              # (F.10)
        extra = {"covariance_accel": cov - cov_noise, "cross_covariance": a @ ca,
                 "accel_sensitivity": a}
    rw = _whiten(c_fit, r)
    quality = assess_fit("gyro (rotations)", float(rw @ rw), int(r.size - 9))
    total = cov * quality.sigma_scale**2
    return GyroRotationFit(values=m, covariance=0.5 * (total + total.T),
                           covariance_noise=cov_noise, quality=quality,
                           residuals=design.per_rotation(r), iterations=it, **extra)


def fit_gyro_rotations(rotations: Sequence[RotationObservation], accel_theta: ArrayLike, *,
                       gyro_noise_density_rps_rthz: ArrayLike,
                       accel_covariance: ArrayLike | None = None, max_iter: int = 50,
                       tol: float = 1e-10) -> GyroRotationFit:
    """Fit M of (F.3) to rotations of either kind by Gauss–Newton from M = 0 (module docstring).

    Parameters
    ----------
    rotations : sequence of RotationObservation
        At least 3, ``"gravity"`` (F.6) and ``"turn"`` (F.7) in any mix.
    accel_theta : array_like, shape (9,) or (12,)
        The accelerometer's θ of (F.1) or (F.1′) (:func:`.gravity_norm.fit_gravity_norm`'s
        values).
    gyro_noise_density_rps_rthz : float or array_like, shape (3,)
        The gyro's white noise density N (angle random walk). [rad/s/√Hz]
    accel_covariance : array_like, shape like θ's, optional
        The covariance of `accel_theta`: propagated into the result by (F.10).

    Returns
    -------
    GyroRotationFit

    Raises
    ------
    InvalidInputError
        Fewer than 3 rotations, a bad θ, noise density or covariance.
    InsufficientExcitationError
        Rotations that leave some entries of M unseen (named).
    ConvergenceError
        No convergence in `max_iter` steps.
    """
    design = _prepare(rotations, accel_theta, gyro_noise_density_rps_rthz)
    m = np.zeros(9)
    r, jac, c, _ = design.evaluate(m)
    _check(jac, c)
    cost = _chi2(c, r)
    it, fresh, lam = 0, True, 0.0
    # chord steps with J and C of M = 0 (each cuts the error by about ‖M‖) while they lower
    # χ²; a step that raises it brings J and C at the current M, then Levenberg–Marquardt
    # damping (F.9′); done when a step is under tol with J and C evaluated there
    while True:
        if it >= max_iter:
            raise ConvergenceError(
                f"the gyro rotation fit did not converge in {max_iter} iterations (χ² "
                f"{cost:.4g} on {r.size} residuals; the worst rotation: "
                f"{_worst(design, r, c)})")
        step = _step(jac, r, c).estimate if lam == 0.0 else _damped_step(jac, r, c, lam)
        it += 1
        m_try = m + step
        r_try = design.residuals(m_try, design.end_attitudes(m_try))
        cost_try = _chi2(c, r_try) if np.isfinite(r_try).all() else math.inf
        if cost_try <= cost * (1.0 + 1e-9) + 1e-300:
            m, r, cost = m_try, r_try, cost_try
            lam = 0.0 if lam < 1e-6 else lam / 10.0
            if bool(np.max(np.abs(step)) < tol):
                if fresh:
                    return _finish(design, m, it, accel_covariance, jac, c)
                r, jac, c, _ = design.evaluate(m)
                cost, fresh = _chi2(c, r), True
            else:
                fresh = False
        elif not fresh:      # a stale J led astray: take J and C at M
            r, jac, c, _ = design.evaluate(m)
            cost, fresh = _chi2(c, r), True
        else:                # damp (F.9′)
            lam = max(1e-4, 10.0 * lam)


def _chi2(c: _F64, r: _F64) -> float:
    w = _whiten(c, r)
    return float(w @ w)


def _damped_step(jac: _F64, r: _F64, c: _F64, lam: float) -> _F64:
    """Return the Levenberg–Marquardt step of (F.9′)."""
    jw, rw = _whiten(c, jac), _whiten(c, r)
    d = np.sqrt(np.maximum(np.sum(jw * jw, axis=0), 1e-300))
    a = np.vstack([jw, math.sqrt(lam) * np.diag(d)])
    b = np.concatenate([-rw, np.zeros(d.size)])
    return np.asarray(np.linalg.lstsq(a, b, rcond=None)[0], dtype=np.float64)


def _worst(design: _Design, r: _F64, c: _F64) -> str:
    """Name the rotation whose residual is largest against its own σ (for the message)."""
    sd = np.sqrt(np.maximum(np.diag(c), 1e-300))
    per = design.per_rotation(np.abs(r) / sd)
    k = int(np.argmax([float(np.max(p)) if p.size else 0.0 for p in per]))
    return f"number {k + 1} of {len(per)}, {float(np.max(per[k])):.3g}σ"


def rotation_disagreement(rotations: Sequence[RotationObservation], accel_theta: ArrayLike, *,
                          gyro_noise_density_rps_rthz: ArrayLike,
                          m: ArrayLike | None = None) -> _F64:
    """Return each rotation's largest residual of (F.6)/(F.7) against its own σ of (F.8) at M.

    Parameters
    ----------
    rotations, accel_theta, gyro_noise_density_rps_rthz
        As :func:`fit_gyro_rotations`.
    m : array_like, shape (9,), optional
        The gyro's M (row-major) to evaluate at; zero by default (the nominal scale).

    Returns
    -------
    ndarray, shape (K,)
        max_i |r_i|/σ_i per rotation: how far it disagrees with the model at M. [σ]
    """
    design = _prepare(rotations, accel_theta, gyro_noise_density_rps_rthz)
    m_arr = np.zeros(9) if m is None else as_array(m, "m", shape=(9,))
    r, _, c, _ = design.evaluate(m_arr)
    per = design.per_rotation(np.abs(r) / np.sqrt(np.maximum(np.diag(c), 1e-300)))
    return np.array([float(np.max(p)) if p.size else 0.0 for p in per])


def fit_turns_linear(rotations: Sequence[RotationObservation], accel_theta: ArrayLike, *,
                     gyro_noise_density_rps_rthz: ArrayLike,
                     accel_covariance: ArrayLike | None = None) -> GyroRotationFit:
    """Solve (F.7) for turns only in closed form: Θ − φn = M·φn, weighted by C of (F.8).

    Same parameters, result and errors as :func:`fit_gyro_rotations`; every rotation must be a
    ``"turn"`` (InvalidInputError otherwise). ``iterations`` is 0.
    """
    design = _prepare(rotations, accel_theta, gyro_noise_density_rps_rthz)
    if not design.turn.all():
        raise InvalidInputError("fit_turns_linear takes turns only; got "
                                f"{int((~design.turn).sum())} \"gravity\" rotation(s)")
    r0, jac, c, _ = design.evaluate(np.zeros(9))       # r(M) = r0 + J·M exactly
    _check(jac, c)
    m = np.array(_step(jac, r0, c).estimate)
    return _finish(design, m, 0, accel_covariance, jac, c)
