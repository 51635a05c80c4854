"""Covariance of window means under coloured sensor noise (docs/equations.md Eq. (11.2)).

Contents
--------
:func:`compute_window_mean_covariance`
    Cov(ȳ_j, ȳ_k) of the means of K time windows of one recording, per axis, for the noise terms
    of a :class:`~imucalib.models.noise.NoiseModel` — the observation covariance C of a
    multi-position fit (:func:`~imucalib.estimation.linear.solve_weighted_lsq` with a full
    `covariance`) and of its Cramér–Rao bound (:func:`~imucalib.estimation.crlb.compute_crlb`).

Method
------
The mean of window j, [a_j, b_j] of length T_j, has Cov(ȳ_j, ȳ_k) = (T_jT_k)⁻¹∫∫R(s, t) ds dt.
For a stationary term with autocovariance R(u), with Φ'' = R and Φ(0) = Φ'(0) = 0 [1]_::

    ∫_{a_j}^{b_j}∫_{a_k}^{b_k} R(s − t) dt ds
        = Φ(b_j − a_k) + Φ(a_j − b_k) − Φ(b_j − b_k) − Φ(a_j − a_k)                   (1)

- white noise N (two-sided density): R = N²δ, Φ(u) = N²|u|/2 — the variance N²/T of a mean;
- quantization Q (white angle noise, the derivative of e_k): window mean (e_end − e_start)/T,
  variance 2Q²/T², uncorrelated between windows that share no end (approximation);
- a first-order Gauss–Markov term of variance σ² and time constant τ: R = σ²e^{−|u|/τ},
  Φ(u) = σ²τ(|u| − τ(1 − e^{−|u|/τ}));
- flicker (bias instability B): the IEEE PSD B²/(2πf) on [f_low, f0] as the sum of Gauss–Markov
  terms with corners f0·10^{−i} (i = 0 … ⌈log₁₀(f0/f_low)⌉ + 1) of variance B²·ln 10/π each
  [2]_ — the construction of :class:`~imucalib.models.noise_generator.NoiseGenerator`, whose Allan
  deviation is within ±1.5 % of the IEEE form; the terms start stationary, so the covariance
  includes the slowly varying flicker *state* (of standard deviation ≈ 2.3·B), which a fit
  with a bias parameter absorbs into the bias and its uncertainty;
- random walk K from `reference_time_s` t₀ (the start of the walk): R(s, t) = K²·min(s − t₀,
  t − t₀), integrated with min(s, t) = (s + t − |s − t|)/2 and Ψ(u) = |u|³/6 for |s − t| in
  Eq. (1).

The rate ramp is deterministic (a drift to model, not noise) and is not included. For two
adjacent windows of length T, ½(C_jj + C_kk − 2C_jk) is σ²_A(T) (Eq. (1) of
:mod:`~imucalib.processing.statistics`); the tests check this and Monte-Carlo covariances of the
generator.

References
----------
.. [1] A. Papoulis and S. U. Pillai, *Probability, Random Variables and Stochastic Processes*,
   4th ed., 2002, §9-4 (integrals of a process, variance of the time average).
.. [2] M. S. Keshner, "1/f noise", Proc. IEEE 70(3):212–218, 1982;
   docs/equations.md §8 and §11.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib._checks import as_array
from imucalib.errors import InvalidInputError
from imucalib.models.noise import NoiseModel

__all__ = ["compute_window_mean_covariance"]


_Kernel = Callable[[NDArray[np.float64]], NDArray[np.float64]]


def _pattern(a: NDArray[np.float64], b: NDArray[np.float64], f: _Kernel) -> NDArray[np.float64]:
    """Eq. (1) for all pairs: f(b_j − a_k) + f(a_j − b_k) − f(b_j − b_k) − f(a_j − a_k)."""
    return (f(b[:, None] - a[None, :]) + f(a[:, None] - b[None, :])
            - f(b[:, None] - b[None, :]) - f(a[:, None] - a[None, :]))


def compute_window_mean_covariance(
    noise_model: NoiseModel,
    window_start_s: ArrayLike,
    window_duration_s: ArrayLike,
    *,
    reference_time_s: float | None = None,
) -> NDArray[np.float64]:
    """Return the covariance of K window means, per axis (module docstring).

    Parameters
    ----------
    noise_model : NoiseModel
        The sensor's noise (two-sided IEEE 952 coefficients).
    window_start_s : array_like, shape (K,)
        Start time of each window on the recording's clock. [s]
    window_duration_s : float or array_like, shape (K,)
        Length T_j of each window, > 0. [s]
    reference_time_s : float, optional
        Start t₀ of the random walk, ≤ every window start; the first window's start when
        omitted. [s]

    Returns
    -------
    ndarray, shape (3, K, K)
        Cov(ȳ_j, ȳ_k) for each axis of the model. [units²: (rad/s)² | (m/s²)²]

    Raises
    ------
    InvalidInputError
        If shapes disagree, a duration is not positive, a value is not finite, or
        `reference_time_s` is after a window start.

    Examples
    --------
    >>> import numpy as np
    >>> C = compute_window_mean_covariance(NoiseModel(white_density=0.1), [0.0, 20.0], 10.0)
    >>> np.round(C[0], 6).tolist()                          # N²/T on the diagonal
    [[0.001, 0.0], [0.0, 0.001]]
    """
    start = as_array(window_start_s, "window_start_s")
    if start.ndim != 1 or start.size < 1:
        raise InvalidInputError(f"`window_start_s` must have shape (K,) with K ≥ 1; got "
                                f"{start.shape}")
    dur = as_array(window_duration_s, "window_duration_s")
    dur = np.full(start.shape, float(dur)) if dur.ndim == 0 else dur
    if dur.shape != start.shape:
        raise InvalidInputError(f"`window_duration_s` must be a scalar or have shape "
                                f"{start.shape}; got {dur.shape}")
    if np.any(dur <= 0):
        raise InvalidInputError(f"`window_duration_s` must be > 0; got min {dur.min():.6g}")
    t0 = float(start.min()) if reference_time_s is None else float(
        as_array(reference_time_s, "reference_time_s", shape=()))
    if np.any(start < t0):
        raise InvalidInputError(f"`reference_time_s` must be ≤ every window start "
                                f"({start.min():.9g} s); got {t0:.9g} s")
    a = start - t0
    b = a + dur
    norm = np.outer(dur, dur)
    m = noise_model
    k = start.size
    out = np.zeros((3, k, k))
    eye = np.eye(k)
    n_el = math.ceil(math.log10(m.bias_instability_corner_hz / m.bias_instability_low_hz)
                     - 1e-9) + 2
    taus = 1.0 / (2.0 * math.pi * m.bias_instability_corner_hz * 10.0 ** -np.arange(n_el))
    for ax in range(3):
        c = eye * (m.white_density[ax] ** 2 / dur + 2.0 * m.quantization[ax] ** 2 / dur**2)
        gm: list[tuple[float, float]] = []
        if m.bias_instability[ax] > 0:
            var = m.bias_instability[ax] ** 2 * math.log(10.0) / math.pi
            gm += [(var, float(tau)) for tau in taus]
        if m.markov_sigma[ax] > 0:
            gm.append((float(m.markov_sigma[ax] ** 2), float(m.markov_time_constant_s[ax])))
        for var, tau in gm:
            def phi(u: NDArray[np.float64], var: float = var, tau: float = tau
                    ) -> NDArray[np.float64]:
                x = np.abs(u)
                return var * tau * (x + tau * np.expm1(-x / tau))
            c = c + _pattern(a, b, phi) / norm
        if m.random_walk[ax] > 0:
            def psi(u: NDArray[np.float64]) -> NDArray[np.float64]:
                return np.abs(u) ** 3 / 6.0
            # ∫∫ min(s, t) = ½[T_k·∫s + T_j·∫t − ∫∫|s − t|]
            int_s = 0.5 * (b**2 - a**2)
            mins = 0.5 * (np.outer(int_s, dur) + np.outer(dur, int_s) - _pattern(a, b, psi))
            c = c + m.random_walk[ax] ** 2 * mins / norm
        out[ax] = 0.5 * (c + c.T)
    return out
