"""Cramér–Rao lower bound of a linear(ised) calibration design, and its closed forms.

Contents
--------
:class:`CrlbResult`, :func:`compute_crlb`
    Generic bound from a Jacobian and a noise covariance, nuisance parameters eliminated by the
    Schur complement, with the observability check (docs/equations.md §11).
:class:`TriadCrlb`, :func:`compute_six_position_accel_crlb`, :func:`compute_sphere_accel_crlb`
    Closed forms for the known-orientation accelerometer triad (docs/equations.md §12).
:class:`RateTableCrlb`, :func:`compute_rate_table_gyro_crlb`
    Closed form for a gyro's bias and scale factor from rate-table points (docs/equations.md §12).

Method (docs/equations.md §11)
------------------------------
For y = h(θ, φ) + n, n ~ N(0, C), with the Jacobian J = [∂h/∂θ, ∂h/∂φ] at the true (or
estimated) parameters::

    F = Jᵀ·C⁻¹·J                                                  (1) Fisher information
    CRLB(θ) = [F⁻¹]_θθ = (F_θθ − F_θφ·F_φφ⁻¹·F_φθ)⁻¹               (2) Schur complement

F⁻¹ is formed from the SVD of the column-scaled whitened Jacobian (as in
:mod:`~imucalib.estimation.linear`), after the rank and conditioning check of
:mod:`~imucalib.estimation.observability`: a rank-deficient F raises
:class:`~imucalib.errors.InsufficientExcitationError` naming the parameters instead of returning
a pseudo-inverse "bound". For a linear-Gaussian model (known orientations) the WLS estimator is
efficient and its covariance *is* the bound, so a plan's achievable accuracy is known before it
runs: build J from the plan's nominal inputs and C from the noise model and per-step durations
(white noise N over a mean of duration T: variance N²/T).

Closed forms (white noise, σ the standard deviation of one position mean)::

    six positions (±g on each axis), 12 parameters:   σ_b = σ/√6,  σ_M = σ/(g·√2)      (3)
    K positions forming a spherical 2-design:          σ_b = σ/√K,  σ_M = σ·√3/(g·√K)   (4)
    gyro, rates ω_k held T_k, y = b + (1 + s)·ω:
        σ_s² = N²/Σ T_k(ω_k − ω̄)²,  σ_b² = N²·Σ T_k ω_k² / (T·Σ T_k(ω_k − ω̄)²)         (5)

with ω̄ = Σ T_k ω_k / T and T = Σ T_k. Eq. (4) is exact when Σ u_k = 0 and
Σ u_k u_kᵀ = (K/3)·I (octahedron K = 6, cube vertices K = 8, icosahedron K = 12, …; a
Fibonacci sphere approximates it). Eq. (5) reduces to σ_b = N/√T, σ_s = N/(ω√T) for a symmetric
±ω design. Derivations and worked examples: docs/equations.md §12.

References
----------
.. [1] S. M. Kay, *Fundamentals of Statistical Signal Processing: Estimation Theory*,
   Prentice Hall, 1993, ch. 3 (Cramér–Rao bound, Fisher information of the linear model).
.. [2] F. Ferraris, U. Grimaldi and M. Parvis, "Procedure for effortless in-field calibration of
   three-axial rate gyro and accelerometers", Sensors and Materials 7(5):311–330, 1995
   (six-position design).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib import units
from imucalib._checks import as_array, check_positive
from imucalib.errors import InvalidInputError
from imucalib.estimation._common import as_design, as_names, make_whitener
from imucalib.estimation.linear import _scaled_svd_factors
from imucalib.estimation.observability import (
    DEFAULT_COND_LIMIT,
    ObservabilityReport,
    compute_observability,
)

__all__ = [
    "CrlbResult",
    "RateTableCrlb",
    "TriadCrlb",
    "compute_crlb",
    "compute_rate_table_gyro_crlb",
    "compute_six_position_accel_crlb",
    "compute_sphere_accel_crlb",
]


@dataclass(frozen=True, eq=False)
class CrlbResult:
    """Cramér–Rao bound of the parameters of interest. Arrays are read-only.

    Attributes
    ----------
    param_names : tuple of str
        Parameters of interest θ (the columns not named as nuisance), in column order.
    covariance : ndarray, shape (q, q)
        CRLB(θ), Eq. (2) of :mod:`~imucalib.estimation.crlb`.
    std : ndarray, shape (q,)
        √diag of the bound: the smallest standard deviation any unbiased estimator can reach.
    information : ndarray, shape (q, q)
        Effective Fisher information of θ (the Schur complement, inverse of `covariance`).
    fisher_information : ndarray, shape (p, p)
        The full F of Eq. (1), all columns (θ and φ).
    all_param_names : tuple of str
        Names of all p columns.
    nuisance_names : tuple of str
        The eliminated φ.
    observability : ObservabilityReport
        Rank and conditioning of the whitened Jacobian.
    """

    param_names: tuple[str, ...]
    covariance: NDArray[np.float64]
    std: NDArray[np.float64]
    information: NDArray[np.float64]
    fisher_information: NDArray[np.float64]
    all_param_names: tuple[str, ...]
    nuisance_names: tuple[str, ...]
    observability: ObservabilityReport

    def std_dict(self) -> Mapping[str, float]:
        """Return {name: bound on the standard deviation}."""
        return dict(zip(self.param_names, self.std.tolist(), strict=True))


def compute_crlb(
    jacobian: ArrayLike,
    noise_covariance: ArrayLike,
    *,
    param_names: Sequence[str],
    nuisance: Sequence[str] = (),
    cond_limit: float = DEFAULT_COND_LIMIT,
) -> CrlbResult:
    """Compute the Cramér–Rao bound of a linear(ised) design (module docstring, Eqs. (1)–(2)).

    Parameters
    ----------
    jacobian : array_like, shape (m, p)
        ∂h/∂(θ, φ) at the nominal parameters (for a linear model, its design matrix H).
        [observation units per parameter unit]
    noise_covariance : float or array_like, shape (m,) or (m, m)
        C: a common variance, per-observation variances, or the full covariance (coloured noise
        correlating the observations, docs/equations.md Eq. (11.2)). [observation units²]
    param_names : sequence of str, length p
        Names of all columns.
    nuisance : sequence of str
        Columns that are nuisance parameters φ (unknown orientations, table errors …), eliminated
        by Eq. (2).
    cond_limit : float
        κ_max of the observability check.

    Returns
    -------
    CrlbResult
        Bound covariance and standard deviations of the parameters of interest.

    Raises
    ------
    InvalidInputError
        If shapes or names disagree, a nuisance name is unknown, every column is nuisance, or the
        covariance is not positive definite.
    InsufficientExcitationError
        If F is rank-deficient or κ > `cond_limit`; names the parameters involved.

    Examples
    --------
    >>> from imucalib.estimation.designs import SIX_POSITION_UP_B, build_triad_design
    >>> d = build_triad_design(9.80665 * SIX_POSITION_UP_B)
    >>> b = compute_crlb(d.H, 1e-6, param_names=d.param_names)
    >>> round(b.std_dict()["bias_x"] * 6**0.5 / 1e-3, 12)
    1.0
    """
    J = as_design(jacobian, "jacobian")
    m, p = J.shape
    names = as_names(param_names, p)
    nuis = tuple(nuisance)
    unknown = [n for n in nuis if n not in names]
    if unknown:
        raise InvalidInputError(f"`nuisance` must name columns of `param_names`; got unknown "
                                f"{unknown}")
    keep = np.array([n not in nuis for n in names])
    if not keep.any():
        raise InvalidInputError(f"at least one parameter must not be nuisance; got all {p} "
                                "columns as nuisance")
    whitener, _ = make_whitener(m, covariance=noise_covariance)
    A = whitener.whiten(J)
    report = compute_observability(A, names, cond_limit=cond_limit)
    report.raise_if_unobservable("Jacobian of the design")
    _, s, vt = _scaled_svd_factors(A, report.column_norms)
    norms = report.column_norms
    F = A.T @ A  # Eq. (1)
    F_inv = (vt.T / s**2) @ vt / np.outer(norms, norms)
    F_inv = 0.5 * (F_inv + F_inv.T)
    cov = F_inv[np.ix_(keep, keep)]  # Eq. (2)
    info = np.linalg.inv(cov)
    info = 0.5 * (info + info.T)
    std = np.sqrt(np.diag(cov))
    for arr in (cov, std, info, F):
        arr.setflags(write=False)
    return CrlbResult(
        param_names=tuple(n for n, k in zip(names, keep, strict=True) if k), covariance=cov,
        std=std, information=info, fisher_information=F, all_param_names=names,
        nuisance_names=tuple(n for n in names if n in nuis), observability=report,
    )


@dataclass(frozen=True)
class TriadCrlb:
    """Closed-form bound of a known-orientation accelerometer triad (Eqs. (3)–(4)).

    Attributes
    ----------
    bias_std_mps2 : float
        σ_b of each bias. [m/s²]
    scale_misalignment_std : float
        σ_M of each element of M (scale factor or misalignment). [–] (rad for misalignment)
    """

    bias_std_mps2: float
    scale_misalignment_std: float


def compute_six_position_accel_crlb(sigma_mps2: float, *,
                                    gravity_mps2: float = units.G0_MPS2) -> TriadCrlb:
    """Return the six-position bound σ_b = σ/√6, σ_M = σ/(g√2), Eq. (3) (docs/equations.md §12).

    Parameters
    ----------
    sigma_mps2 : float
        Standard deviation of one position mean (white noise N over T: N/√T). [m/s²]
    gravity_mps2 : float
        Gravity magnitude g used as the reference. [m/s²]

    Returns
    -------
    TriadCrlb
        The bound on each bias and each element of M.

    Examples
    --------
    >>> b = compute_six_position_accel_crlb(67.1e-6 * 9.80665)   # docs/equations.md §12 example
    >>> round(b.bias_std_mps2 / (1e-6 * 9.80665), 1), round(b.scale_misalignment_std * 1e6, 1)
    (27.4, 47.4)
    """
    sigma = check_positive(sigma_mps2, "sigma_mps2")
    g = check_positive(gravity_mps2, "gravity_mps2")
    return TriadCrlb(bias_std_mps2=sigma / 6.0**0.5,
                     scale_misalignment_std=sigma / (g * 2.0**0.5))


def compute_sphere_accel_crlb(sigma_mps2: float, n_positions: int, *,
                              gravity_mps2: float = units.G0_MPS2) -> TriadCrlb:
    """Return σ_b = σ/√K, σ_M = σ√3/(g√K) for K positions forming a spherical 2-design, Eq. (4).

    Parameters
    ----------
    sigma_mps2 : float
        Standard deviation of one position mean. [m/s²]
    n_positions : int
        K ≥ 4 (the smallest spherical 2-design is the tetrahedron).
    gravity_mps2 : float
        Gravity magnitude. [m/s²]

    Returns
    -------
    TriadCrlb
        The bound; exact for designs with Σu = 0 and Σuuᵀ = (K/3)·I, approximate for
        near-uniform sets (Fibonacci sphere).

    Raises
    ------
    InvalidInputError
        If `n_positions` < 4 or a value is not positive.
    """
    sigma = check_positive(sigma_mps2, "sigma_mps2")
    g = check_positive(gravity_mps2, "gravity_mps2")
    if int(n_positions) != n_positions or n_positions < 4:
        raise InvalidInputError(f"`n_positions` must be an integer ≥ 4; got {n_positions!r}")
    k = float(n_positions)
    return TriadCrlb(bias_std_mps2=sigma / k**0.5,
                     scale_misalignment_std=sigma * 3.0**0.5 / (g * k**0.5))


@dataclass(frozen=True)
class RateTableCrlb:
    """Closed-form bound of a gyro's bias and scale factor from rate points (Eq. (5)).

    Attributes
    ----------
    bias_std_rps : float
        σ_b. [rad/s]
    scale_std : float
        σ_s of the relative scale-factor error. [–]
    """

    bias_std_rps: float
    scale_std: float


def compute_rate_table_gyro_crlb(noise_density_rps_rthz: float, rates_rps: ArrayLike,
                                 dwell_s: ArrayLike) -> RateTableCrlb:
    """Return the bound on b and s of y = b + (1 + s)·ω from rate points, Eq. (5).

    Parameters
    ----------
    noise_density_rps_rthz : float
        White-noise coefficient N (two-sided, σ_Allan(1 s) = N); the mean over T_k has
        variance N²/T_k. [rad/s/√Hz]
    rates_rps : array_like, shape (K,)
        Table rates ω_k. [rad/s]
    dwell_s : float or array_like, shape (K,)
        Averaging time T_k of each rate. [s]

    Returns
    -------
    RateTableCrlb
        σ_b and σ_s.

    Raises
    ------
    InvalidInputError
        If fewer than two distinct rates are given (s is then unobservable), or a dwell or the
        density is not positive.

    Examples
    --------
    >>> from imucalib import units
    >>> b = compute_rate_table_gyro_crlb(0.005 * units.DEG, [100 * units.DEG, -100 * units.DEG],
    ...                                  10.0)
    >>> round(b.scale_std * 1e6, 1)   # docs/equations.md §12: about 11 ppm
    11.2
    """
    n_d = check_positive(noise_density_rps_rthz, "noise_density_rps_rthz")
    w = as_array(rates_rps, "rates_rps")
    if w.ndim != 1:
        raise InvalidInputError(f"`rates_rps` must have shape (K,); got {w.shape}")
    t = as_array(dwell_s, "dwell_s")
    t = np.full(w.shape, float(t)) if t.ndim == 0 else t
    if t.shape != w.shape:
        raise InvalidInputError(
            f"`dwell_s` must be a scalar or have shape {w.shape}; got {t.shape}"
        )
    if np.any(t <= 0):
        raise InvalidInputError(f"`dwell_s` must be > 0; got min {t.min():.6g}")
    total = float(t.sum())
    w_bar = float(t @ w) / total
    sxx = float(t @ (w - w_bar) ** 2)
    if w.size < 2 or sxx <= 1e-24 * max(float(t @ w**2), 1e-300):
        raise InvalidInputError(
            f"`rates_rps` must hold at least two distinct rates (the scale factor is otherwise "
            f"unobservable); got {np.unique(w).size} distinct value(s)"
        )
    var_s = n_d**2 / sxx
    var_b = n_d**2 * float(t @ w**2) / (total * sxx)
    return RateTableCrlb(bias_std_rps=float(np.sqrt(var_b)), scale_std=float(np.sqrt(var_s)))
