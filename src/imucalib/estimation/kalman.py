"""Linear Kalman filter (pure functions and a thin stateful twin) and sequential refinement.

Contents
--------
:func:`kf_predict`, :func:`kf_update`
    Pure prediction and Joseph-form update, in the style of filterpy.
:class:`KalmanFilter`
    Holds x, P and calls the pure functions; no computation in ``__init__``.
:class:`KalmanUpdate`
    What one update returns: posterior, innovation, its covariance, gain, NIS.
:class:`KalmanRefinement`, :func:`refine_with_kalman`
    P1 processing rule 4 (docs/p1.md): the least-squares observations processed sequentially by a
    Kalman filter over a static (optionally slowly wandering) parameter vector.

Equations
---------
Prediction and update [1]_, [2]_::

    x⁻ = F·x,            P⁻ = F·P·Fᵀ + Q                                     (1)
    ν  = z − H·x⁻,       S  = H·P⁻·Hᵀ + R,     K = P⁻·Hᵀ·S⁻¹                 (2)
    x⁺ = x⁻ + K·ν,       P⁺ = (I − K·H)·P⁻·(I − K·H)ᵀ + K·R·Kᵀ                (3) Joseph form
    NIS = νᵀ·S⁻¹·ν ~ χ²(dim z) for a consistent filter                        (4)

The Joseph form (3) keeps P symmetric and positive semi-definite in floating point for any gain.
S⁻¹ is applied through a Cholesky solve, never an explicit inverse.

Agreement with least squares
----------------------------
For a static parameter (F = I, Q = 0) and a Gaussian prior N(x₀, P₀), the filter after the last
block equals the weighted least-squares solution of all blocks plus the prior as pseudo-observations
(recursive least squares [2]_ §3.3). With a *diffuse* prior (P₀ → ∞) it tends to the plain WLS
estimate and covariance of :func:`~imucalib.estimation.linear.solve_weighted_lsq`, and the sum of
the NIS over the blocks tends to the WLS χ². :func:`refine_with_kalman` builds its diffuse prior
as P₀ = diag(κ/Iⱼⱼ), with Iⱼⱼ the diagonal of the total information HᵀR⁻¹H and κ = 10⁸: the
prior then holds 10⁻⁸ of the data's information per parameter and shifts the estimate by about
10⁻⁸ of its standard deviation, while staying well inside double-precision range. A process noise
Q ≠ 0 turns the static model into a random walk of the parameters; the result is then the
estimate at the *last* block, not the batch estimate, and agrees with WLS only as Q → 0.

References
----------
.. [1] R. E. Kalman, "A new approach to linear filtering and prediction problems", J. Basic Eng.
   82(1):35–45, 1960.
.. [2] Y. Bar-Shalom, X. R. Li and T. Kirubarajan, *Estimation with Applications to Tracking and
   Navigation*, Wiley, 2001, §5.2 (Eqs. 5.2.3-x), §5.4 (NIS), §7.3 (RLS / information form).
.. [3] R. Labbe, *Kalman and Bayesian Filters in Python* / filterpy, 2015 (pure-function API).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike, NDArray

from imucalib._checks import as_array
from imucalib.errors import InvalidInputError
from imucalib.estimation._common import as_names
from imucalib.estimation.observability import DEFAULT_COND_LIMIT, compute_observability

__all__ = [
    "DIFFUSE_PRIOR_FACTOR",
    "KalmanFilter",
    "KalmanRefinement",
    "KalmanUpdate",
    "kf_predict",
    "kf_update",
    "refine_with_kalman",
]

#: κ of the diffuse prior P₀ = diag(κ/Iⱼⱼ) (module docstring).
DIFFUSE_PRIOR_FACTOR = 1e8


@dataclass(frozen=True, eq=False)
class KalmanUpdate:
    """Result of one measurement update (Eqs. (2)–(4) of :mod:`~imucalib.estimation.kalman`).

    Attributes
    ----------
    x : ndarray, shape (n,)
        Posterior state x⁺.
    P : ndarray, shape (n, n)
        Posterior covariance P⁺ (Joseph form).
    innovation : ndarray, shape (k,)
        ν = z − H·x⁻.
    S : ndarray, shape (k, k)
        Innovation covariance.
    K : ndarray, shape (n, k)
        Gain.
    nis : float
        Normalised innovation squared νᵀS⁻¹ν.
    """

    x: NDArray[np.float64]
    P: NDArray[np.float64]
    innovation: NDArray[np.float64]
    S: NDArray[np.float64]
    K: NDArray[np.float64]
    nis: float


def _state(x: ArrayLike, P: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    xv = as_array(x, "x")
    if xv.ndim != 1 or xv.size < 1:
        raise InvalidInputError(f"`x` must have shape (n,) with n ≥ 1; got {xv.shape}")
    n = xv.size
    Pm = as_array(P, "P", shape=(n, n))
    return xv, Pm


def kf_predict(x: ArrayLike, P: ArrayLike, F: ArrayLike | None = None,
               Q: ArrayLike | None = None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Predict the state and covariance one step, Eq. (1).

    Parameters
    ----------
    x : array_like, shape (n,)
        State.
    P : array_like, shape (n, n)
        State covariance.
    F : array_like, shape (n, n), optional
        Transition matrix; identity when omitted (a static state).
    Q : array_like, shape (n, n), optional
        Process-noise covariance; zero when omitted.

    Returns
    -------
    x_pred : ndarray, shape (n,)
    P_pred : ndarray, shape (n, n)

    Raises
    ------
    InvalidInputError
        If a shape does not match n or a value is NaN or infinite.
    """
    xv, Pm = _state(x, P)
    n = xv.size
    if F is not None:
        Fm = as_array(F, "F", shape=(n, n))
        xv = Fm @ xv
        Pm = Fm @ Pm @ Fm.T
    if Q is not None:
        Pm = Pm + as_array(Q, "Q", shape=(n, n))
    return xv, 0.5 * (Pm + Pm.T)


def kf_update(x: ArrayLike, P: ArrayLike, z: ArrayLike, R: ArrayLike,
              H: ArrayLike) -> KalmanUpdate:
    """Update with a measurement z = H·x + v, v ~ N(0, R), Eqs. (2)–(4), Joseph form.

    Parameters
    ----------
    x : array_like, shape (n,)
        Prior state x⁻.
    P : array_like, shape (n, n)
        Prior covariance P⁻.
    z : array_like, shape (k,)
        Measurement.
    R : array_like, shape (k, k), (k,) or scalar
        Measurement noise covariance (full, variances, or a common variance).
    H : array_like, shape (k, n)
        Measurement matrix.

    Returns
    -------
    KalmanUpdate
        Posterior, innovation, its covariance, gain and NIS.

    Raises
    ------
    InvalidInputError
        If shapes disagree, a value is not finite, or S is not positive definite.
    """
    xv, Pm = _state(x, P)
    n = xv.size
    zv = as_array(z, "z")
    if zv.ndim != 1 or zv.size < 1:
        raise InvalidInputError(f"`z` must have shape (k,) with k ≥ 1; got {zv.shape}")
    k = zv.size
    Hm = as_array(H, "H", shape=(k, n))
    Rm = _as_cov(R, "R", k)
    nu = zv - Hm @ xv
    PHt = Pm @ Hm.T
    S = Hm @ PHt + Rm
    S = 0.5 * (S + S.T)
    try:
        cho = scipy.linalg.cho_factor(S, lower=True)
    except np.linalg.LinAlgError as exc:
        raise InvalidInputError("the innovation covariance S = H·P·Hᵀ + R must be positive "
                                "definite; its Cholesky factorisation failed") from exc
    K = scipy.linalg.cho_solve(cho, PHt.T).T  # K = P Hᵀ S⁻¹
    x_new = xv + K @ nu
    IKH = np.eye(n) - K @ Hm
    P_new = IKH @ Pm @ IKH.T + K @ Rm @ K.T  # Eq. (3), Joseph form
    P_new = 0.5 * (P_new + P_new.T)
    nis = float(nu @ scipy.linalg.cho_solve(cho, nu))
    return KalmanUpdate(x=x_new, P=P_new, innovation=nu, S=S, K=K, nis=nis)


def _as_cov(R: ArrayLike, name: str, k: int) -> NDArray[np.float64]:
    Rm = as_array(R, name)
    if Rm.ndim == 0:
        Rm = np.eye(k) * float(Rm)
    elif Rm.ndim == 1:
        if Rm.shape != (k,):
            raise InvalidInputError(
                f"`{name}` must have shape ({k},) or ({k}, {k}); got {Rm.shape}"
            )
        Rm = np.diag(Rm)
    elif Rm.shape != (k, k):
        raise InvalidInputError(f"`{name}` must have shape ({k}, {k}); got {Rm.shape}")
    return Rm


class KalmanFilter:
    """Stateful twin of :func:`kf_predict` / :func:`kf_update` (filterpy style).

    Parameters
    ----------
    x : array_like, shape (n,)
        Initial state.
    P : array_like, shape (n, n)
        Initial covariance.
    F : array_like, shape (n, n), optional
        Transition matrix used by :meth:`predict` (identity when omitted).
    Q : array_like, shape (n, n), optional
        Process-noise covariance used by :meth:`predict` (zero when omitted).

    Attributes
    ----------
    x, P : ndarray
        Current state and covariance.
    last_update : KalmanUpdate or None
        What the last :meth:`update` returned.
    """

    def __init__(self, x: ArrayLike, P: ArrayLike, *, F: ArrayLike | None = None,
                 Q: ArrayLike | None = None) -> None:
        self.x, self.P = _state(x, P)
        self.F = F
        self.Q = Q
        self.last_update: KalmanUpdate | None = None

    def predict(self) -> None:
        """Advance one step with the stored F and Q, Eq. (1)."""
        self.x, self.P = kf_predict(self.x, self.P, self.F, self.Q)

    def update(self, z: ArrayLike, R: ArrayLike, H: ArrayLike) -> KalmanUpdate:
        """Apply one measurement, Eqs. (2)–(4); returns the :class:`KalmanUpdate`."""
        upd = kf_update(self.x, self.P, z, R, H)
        self.x, self.P, self.last_update = upd.x, upd.P, upd
        return upd


@dataclass(frozen=True, eq=False)
class KalmanRefinement:
    """Result of :func:`refine_with_kalman`. Arrays are read-only.

    Attributes
    ----------
    param_names : tuple of str
        State order.
    estimate : ndarray, shape (p,)
        State after the last block.
    covariance : ndarray, shape (p, p)
        Its covariance.
    std : ndarray, shape (p,)
        √diag(covariance).
    nis : ndarray, shape (n_blocks,)
        NIS of each block, Eq. (4).
    nis_dof : ndarray of int, shape (n_blocks,)
        Dimension of each block (the χ² degrees of freedom of its NIS).
    estimate_history : ndarray, shape (n_blocks, p)
        State after each block (for convergence plots).
    std_history : ndarray, shape (n_blocks, p)
        Standard deviations after each block.
    diffuse_prior : bool
        Whether the prior was the diffuse one of the module docstring.
    """

    param_names: tuple[str, ...]
    estimate: NDArray[np.float64]
    covariance: NDArray[np.float64]
    std: NDArray[np.float64]
    nis: NDArray[np.float64]
    nis_dof: NDArray[np.int64]
    estimate_history: NDArray[np.float64]
    std_history: NDArray[np.float64]
    diffuse_prior: bool

    @property
    def nis_total(self) -> float:
        """Σ NIS; equals the WLS χ² in the diffuse, static case (module docstring)."""
        return float(self.nis.sum())


def refine_with_kalman(
    H_blocks: Sequence[ArrayLike],
    z_blocks: Sequence[ArrayLike],
    R_blocks: Sequence[ArrayLike],
    *,
    param_names: Sequence[str],
    prior_mean: ArrayLike | None = None,
    prior_covariance: ArrayLike | None = None,
    process_noise: ArrayLike | None = None,
    cond_limit: float = DEFAULT_COND_LIMIT,
) -> KalmanRefinement:
    """Process observation blocks sequentially with a Kalman filter (docs/p1.md, rule 4).

    The parameters are the state, static between blocks (F = I) unless `process_noise` is given.
    Block i is zᵢ = Hᵢ·x + vᵢ, vᵢ ~ N(0, Rᵢ) — for P1 one block per position or rate point.

    Parameters
    ----------
    H_blocks : sequence of array_like, each shape (kᵢ, p)
        Measurement matrices.
    z_blocks : sequence of array_like, each shape (kᵢ,)
        Observations.
    R_blocks : sequence of array_like, each shape (kᵢ, kᵢ), (kᵢ,) or scalar
        Observation covariances.
    param_names : sequence of str, length p
        State names.
    prior_mean : array_like, shape (p,), optional
        x₀; zero when omitted.
    prior_covariance : array_like, shape (p, p) or (p,), optional
        P₀ (full or variances). When omitted the prior is diffuse (module docstring) and the
        stacked design is first checked for observability.
    process_noise : array_like, shape (p, p) or (p,), optional
        Q added before each block after the first (a random walk of the parameters).
    cond_limit : float
        κ_max of the observability check (diffuse prior only).

    Returns
    -------
    KalmanRefinement
        Final estimate, covariance, and per-block NIS and history.

    Raises
    ------
    InvalidInputError
        If the block lists differ in length or are empty, or a block is malformed.
    InsufficientExcitationError
        With a diffuse prior, if the stacked whitened design does not determine every parameter.
    """
    if not (len(H_blocks) == len(z_blocks) == len(R_blocks)):
        raise InvalidInputError(
            "`H_blocks`, `z_blocks`, `R_blocks` must have the same length; got "
            f"{len(H_blocks)}, {len(z_blocks)}, {len(R_blocks)}"
        )
    if len(H_blocks) == 0:
        raise InvalidInputError("`H_blocks` must hold at least one block; got none")
    blocks = [_block(H, z, R, i) for i, (H, z, R) in enumerate(zip(H_blocks, z_blocks, R_blocks,
                                                                   strict=True))]
    p = blocks[0][0].shape[1]
    for i, (Hm, _, _) in enumerate(blocks):
        if Hm.shape[1] != p:
            raise InvalidInputError(f"`H_blocks[{i}]` must have {p} columns; got {Hm.shape[1]}")
    names = as_names(param_names, p)
    x0 = np.zeros(p) if prior_mean is None else as_array(prior_mean, "prior_mean", shape=(p,))
    Q = None if process_noise is None else _as_cov(process_noise, "process_noise", p)
    diffuse = prior_covariance is None
    if diffuse:
        whitened = []
        for Hm, _, Rm in blocks:
            chol = np.linalg.cholesky(Rm)
            whitened.append(scipy.linalg.solve_triangular(chol, Hm, lower=True))
        A = np.vstack(whitened)
        report = compute_observability(A, names, cond_limit=cond_limit)
        report.raise_if_unobservable("stacked Kalman measurement design")
        info_diag = np.einsum("ij,ij->j", A, A)
        P0 = np.diag(DIFFUSE_PRIOR_FACTOR / info_diag)
    else:
        P0 = _as_cov(np.asarray(prior_covariance), "prior_covariance", p)
        lam_min = float(np.min(np.linalg.eigvalsh(0.5 * (P0 + P0.T))))
        if lam_min <= 0.0:
            raise InvalidInputError("`prior_covariance` must be positive definite; got smallest "
                                    f"eigenvalue {lam_min:.3g}")
    kf = KalmanFilter(x0, P0, Q=Q)
    n_b = len(blocks)
    nis = np.empty(n_b)
    dof = np.empty(n_b, dtype=np.int64)
    hist_x = np.empty((n_b, p))
    hist_s = np.empty((n_b, p))
    for i, (Hm, zv, Rm) in enumerate(blocks):
        if i > 0 and Q is not None:
            kf.predict()
        upd = kf.update(zv, Rm, Hm)
        nis[i], dof[i] = upd.nis, zv.size
        hist_x[i] = kf.x
        hist_s[i] = np.sqrt(np.clip(np.diag(kf.P), 0.0, None))
    x = kf.x.copy()
    P = kf.P.copy()
    std = np.sqrt(np.clip(np.diag(P), 0.0, None))
    for arr in (x, P, std, nis, dof, hist_x, hist_s):
        arr.setflags(write=False)
    return KalmanRefinement(param_names=names, estimate=x, covariance=P, std=std, nis=nis,
                            nis_dof=dof, estimate_history=hist_x, std_history=hist_s,
                            diffuse_prior=diffuse)


def _block(H: ArrayLike, z: ArrayLike, R: ArrayLike, i: int
           ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    zv = as_array(z, f"z_blocks[{i}]")
    if zv.ndim == 0:
        zv = zv.reshape(1)
    if zv.ndim != 1:
        raise InvalidInputError(f"`z_blocks[{i}]` must have shape (k,); got {zv.shape}")
    k = zv.size
    Hm = as_array(H, f"H_blocks[{i}]")
    if Hm.ndim == 1:
        Hm = Hm.reshape(1, -1)
    if Hm.ndim != 2 or Hm.shape[0] != k:
        raise InvalidInputError(f"`H_blocks[{i}]` must have shape ({k}, p); got {Hm.shape}")
    Rm = _as_cov(R, f"R_blocks[{i}]", k)
    if not np.allclose(Rm, Rm.T, rtol=1e-10, atol=0.0):
        raise InvalidInputError(f"`R_blocks[{i}]` must be symmetric; got max |R - Rᵀ| = "
                                f"{np.abs(Rm - Rm.T).max():.3g}")
    lam_min = float(np.min(np.linalg.eigvalsh(Rm)))
    if lam_min <= 0.0:
        raise InvalidInputError(f"`R_blocks[{i}]` must be positive definite; got smallest "
                                f"eigenvalue {lam_min:.3g}")
    return Hm, zv, Rm
