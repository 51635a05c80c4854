"""Samples of a :class:`~imucalib.models.noise.NoiseModel`'s noise: a fast, stateful generator.

Contents: :class:`NoiseGenerator` (stateful, continues every process across calls),
:func:`simulate_noise` (pure wrapper). The model, its units and its Allan deviation are
:mod:`imucalib.models.noise`'s.

Generation method
-----------------
Sample k is the value at t = k·Δt (t = 0 at the generator's first sample). Slow processes are
point-sampled, so within a few Δt their Allan deviation departs from the continuous formulas
(a sampled random walk has σ(Δt) = √(3/2)·K·√(Δt/3)): read coefficients at τ ≥ 10·Δt.

- White noise plus quantization form one Gaussian MA(1) process θ0·u_k + θ1·u_{k−1}, u i.i.d.
  N(0, 1), with the autocovariance of N/√Δt·w_k + (e_k − e_{k−1})/Δt, e_k i.i.d. N(0, Q²):
  r0 = a² + 2b², r1 = −b² (a = N/√Δt, b = Q/Δt). Its minimum-phase factor θ0 = (s + a)/2,
  θ1 = −(s − a)/2, s = √(a² + 4b²), gives the same Gaussian process for one deviate per sample.
  Deviates come from a vectorised Box–Muller transform [4]_ (about 2× numpy's ziggurat here).
- Bias instability: a bank of first-order Gauss–Markov processes [2]_, [3]_ with corners
  f0·10^(−i), one per decade from f0 down to f_low/10, each of variance B²·ln 10/π; their
  Lorentzians 2σ²T/(1 + (2πfT)²) sum to B²/(2πf) within ±5 %. The Allan deviation is within
  ±1.5 % of the IEEE closed form (plateau 0.6643·B) for τ in [2/f0, 0.1/f_low]. The elements
  start stationary, so the term carries a random offset of standard deviation
  B·√(0.733·(number of elements)) (2.3·B for f0 = 1 Hz, f_low = 1e-5 Hz).
- Random walk: increments of standard deviation K·√h, cumulated from zero.
- Rate ramp: a **deterministic** slope R·t per axis (sign kept): σ_Allan(τ) = |R|·τ/√2 exactly.
- Markov: exact discretisation x_{j+1} = φ·x_j + w, φ = exp(−h/T_c), var(w) = σ²(1 − φ²),
  stationary start. At the full rate it joins the MA(1) of its axis: (1 − φz⁻¹)·y is then an
  MA(2) process, factorised in closed form, so y = β(z)/(1 − φz⁻¹)·u (``lfilter``, filter state
  drawn from its stationary covariance) again needs one deviate per sample.

Flicker, random walk, ramp and slow Markov terms are computed exactly on a grid of step
h = D·Δt and interpolated linearly; D keeps the interpolation out of the Allan deviation:
h ≤ 0.1/f0 (0.63 of the fastest flicker time constant; the flicker term is specified for
τ ≥ 2/f0 = 20·h); h ≤ √3·N/(10·K) per axis (below τ = 10·h the random-walk AVAR K²τ/3 is < 1 % of
the white AVAR N²/τ; D = 1 when N = 0); Markov terms go on the grid if T_c ≥ 20·h, the others
run at the full rate. The tests compare this choice of D with D = 1. Samples are made in fixed
blocks with a fixed order of draws: for a generator owning its ``Generator``, any chunking of a
record gives the same values bit for bit.

References
----------
.. [1] IEEE Std 952-1997 (R2008), Annex C; docs/equations.md §1 and §8.
.. [2] M. S. Keshner, "1/f noise", Proc. IEEE 70(3):212–218, 1982.
.. [3] N. J. Kasdin, "Discrete simulation of colored noise and stochastic processes and 1/f^α
   power law noise generation", Proc. IEEE 83(5):802–827, 1995.
.. [4] G. E. P. Box and M. E. Muller, "A note on the generation of random normal deviates",
   Ann. Math. Statist. 29(2):610–611, 1958.
"""

from __future__ import annotations

import cmath
import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imucalib._checks import check_positive
from imucalib.errors import ConfigurationError, InvalidInputError
from imucalib.models.noise import NoiseModel

__all__ = ["NoiseGenerator", "simulate_noise"]

_GRID_MAX_DECIMATION = 256  # coarsest slow grid, in samples
_BLOCK_TARGET = 1 << 15  # samples per generated block (about 0.8 MB per (3, n) array)
_MARKOV_GRID_RATIO = 20.0  # a Markov term goes on the slow grid when T_c ≥ 20·h


class _NormalSource:
    """Standard normal deviates by a vectorised Box–Muller transform into preallocated scratch.

    The radius uses a 53-bit uniform (tails to 8.5σ); the angle a 24-bit float32 uniform and
    float32 sine/cosine (relative error ~1e-7 on each deviate).
    """

    _TWO_PI = np.float32(2 * np.pi)

    def __init__(self, rng: np.random.Generator, capacity: int) -> None:
        half = (capacity + 1) // 2
        self._rng = rng
        self._radius = np.empty(half)
        self._angle = np.empty(half, dtype=np.float32)
        self._trig = np.empty(half, dtype=np.float32)

    def fill(self, out: NDArray[np.float64]) -> None:
        """Fill the contiguous 1-D array `out` with N(0, 1) deviates."""
        n = out.size
        half, rest = (n + 1) // 2, n // 2
        r, a, t = self._radius[:half], self._angle[:half], self._trig[:half]
        self._rng.random(out=r)
        np.negative(r, out=r)
        np.log1p(r, out=r)  # log(1 − U) with 1 − U in (0, 1]
        np.multiply(r, -2.0, out=r)
        np.sqrt(r, out=r)
        self._rng.random(out=a, dtype=np.float32)
        np.multiply(a, self._TWO_PI, out=a)
        np.cos(a, out=t)
        np.multiply(r, t, out=out[:half])
        np.sin(a[:rest], out=t[:rest])
        np.multiply(r[:rest], t[:rest], out=out[half:])


def _check_count(value: Any, name: str, minimum: int) -> int:
    """Return `value` as an int ≥ `minimum` (numpy integers accepted, bool not)."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < minimum:
        raise InvalidInputError(f"`{name}` must be an integer ≥ {minimum}; got {value!r}")
    return int(value)


def _ma_factor(A: float, a: float, B: float, b: float, c2: float) -> NDArray[np.float64]:
    """Return the minimum-phase MA(2) coefficients β (3,) with the spectrum (A + a·x)(B + b·x) + c2.

    x = 2 − 2·cos ω, so S(x) is the spectrum of (1 − φz⁻¹)·(θ0 + θ1·z⁻¹)·u + c·g with
    A = (θ0 + θ1)², a = −θ0·θ1, B = (1 − φ)², b = φ: all ≥ 0 and free of cancellation. Each root
    x_i of S gives the root z_i = 2/(w + √(w² − 4)) of β (w = 2 − x_i, w² − 4 = −x_i·(4 − x_i),
    |z_i| < 1); on the unit circle |β|² = β0²·Πz_i·Π(x − x_i), so β0² = (lead coefficient)/Πz_i.
    """
    q2, q1, q0 = a * b, a * B + b * A, A * B + c2
    if q2 > 1e-15 * (q1 + q0):
        disc = cmath.sqrt(q1 * q1 - 4 * q2 * q0)
        big = -(q1 + disc) / 2  # q1 ≥ 0: no cancellation
        roots, lead = [big / q2, q0 / big], q2
    elif q1 > 1e-15 * q0:
        roots, lead = [complex(-q0 / q1)], q1
    else:
        return np.array([math.sqrt(q0), 0.0, 0.0])
    poly, prod = np.ones(1, dtype=complex), 1.0 + 0j
    for x in roots:
        w, rt = 2 - x, cmath.sqrt(-x * (4 - x))
        z = 2 / (w + rt if abs(w + rt) >= abs(w - rt) else w - rt)
        poly, prod = np.convolve(poly, [1.0, -z]), prod * z
    beta = np.zeros(3)
    beta[: poly.size] = poly.real * math.sqrt(lead / prod.real)
    return beta


class NoiseGenerator:
    """Generate the noise of a :class:`NoiseModel`, continuing every process across calls.

    Parameters
    ----------
    model : NoiseModel
        The noise coefficients.
    sample_interval_s : float
        Δt between samples. [s]
    rng : numpy.random.Generator or int or None
        Random source (seed); ``np.random.default_rng(rng)`` is called once.
    decimation : int, optional
        Force the slow-grid factor D (h = D·Δt) instead of the automatic choice described in the
        module docstring; ``decimation=1`` runs every process at the full rate (slow, exact).

    Raises
    ------
    InvalidInputError
        If `model` is not a NoiseModel, `sample_interval_s` is not > 0, or `decimation` < 1.
    ConfigurationError
        If the flicker corner f0 is at or above the Nyquist frequency 1/(2Δt).

    Notes
    -----
    Nothing is computed before the first :meth:`generate`. Samples come in fixed blocks of about
    32 k, so memory stays bounded and any chunking gives the same record (module docstring).
    """

    def __init__(self, model: NoiseModel, sample_interval_s: float,
                 rng: np.random.Generator | int | None = None, *,
                 decimation: int | None = None) -> None:
        if not isinstance(model, NoiseModel):
            raise InvalidInputError(f"`model` must be a NoiseModel; got {type(model).__name__}")
        dt = check_positive(sample_interval_s, "sample_interval_s")
        if np.any(model.bias_instability > 0) and model.bias_instability_corner_hz >= 0.5 / dt:
            raise ConfigurationError(
                f"`bias_instability_corner_hz` must be below the Nyquist frequency {0.5 / dt} Hz;"
                f" got {model.bias_instability_corner_hz} Hz"
            )
        self._decimation = None if decimation is None else _check_count(decimation, "decimation", 1)
        self.model = model
        self.sample_interval_s = dt
        self._rng = np.random.default_rng(rng)
        self._zero: bool | None = None
        self._ready = False

    @property
    def decimation(self) -> int:
        """The slow-grid factor D (h = D·Δt) this generator uses."""
        self._setup()
        return self._d

    def generate(self, n_samples: int) -> NDArray[np.float64]:
        """Return the next `n_samples` samples of noise, continuing the previous call.

        Returns
        -------
        ndarray, shape (n_samples, 3)
            Noise in the sensor axes [rad/s | m/s²]: a transposed view of a channel-major
            (3, n_samples) buffer (Fortran order). `n_samples` must be an integer ≥ 0.
        """
        n = _check_count(n_samples, "n_samples", 0)
        if self._zero is None:
            self._zero = self.model.is_zero()
        zero = self._zero
        out = np.zeros((3, n)) if zero else np.empty((3, n))
        if n == 0 or zero:
            return out.T
        self._setup()
        done, size = 0, self._block.shape[1]
        while done < n:
            if self._pos == size:
                self._next_block()
            take = min(n - done, size - self._pos)
            out[:, done:done + take] = self._block[:, self._pos:self._pos + take]
            self._pos += take
            done += take
        return out.T

    # -- set-up: coefficients and initial (stationary) states --------------------------------
    def _setup(self) -> None:
        if self._ready:
            return
        m, dt, rng = self.model, self.sample_interval_s, self._rng
        # white + quantization as one MA(1): closed-form minimum-phase factor (module docstring)
        a = m.white_density / math.sqrt(dt)
        s = np.sqrt(a**2 + 4 * (m.quantization / dt) ** 2)
        self._theta0, self._theta1 = (s + a) / 2, -(s - a) / 2
        self._has_quant = bool(np.any(self._theta1 != 0))
        # slow grid step h = D·Δt (rules in the module docstring)
        flicker, rw, markov = m.bias_instability > 0, m.random_walk > 0, m.markov_sigma > 0
        f0, f_low = m.bias_instability_corner_hz, m.bias_instability_low_hz
        limits = [0.1 / f0] if flicker.any() else []
        if rw.any():
            crossover = math.sqrt(3) * m.white_density[rw] / m.random_walk[rw]  # N²/τ = K²τ/3
            limits.append(float(np.min(crossover)) / 10)
        if not limits and markov.any():
            limits.append(float(np.min(m.markov_time_constant_s[markov])) / _MARKOV_GRID_RATIO)
        d = self._decimation
        if d is None:
            d = int(min(limits) / dt * (1 + 1e-12)) if limits else _GRID_MAX_DECIMATION
            d = max(1, min(d, _GRID_MAX_DECIMATION))
        h = d * dt
        self._d, self._h = d, h
        tc = np.where(markov, m.markov_time_constant_s, 1.0)
        on_grid = markov & ((tc >= _MARKOV_GRID_RATIO * h) | (d == 1))
        # a full-rate Markov term joins its axis' MA(1): (1 − φz⁻¹)·y is MA(2), factorised so
        # that y = β(z)/(1 − φz⁻¹)·u needs one deviate per sample; stationary filter state
        self._arma: list[tuple[int, NDArray[np.float64], NDArray[np.float64],
                               NDArray[np.float64]]] = []
        for ax in np.flatnonzero(markov & ~on_grid).tolist():
            phi, gap = math.exp(-dt / tc[ax]), -math.expm1(-dt / tc[ax])  # φ, 1 − φ
            beta = _ma_factor(a[ax] ** 2, (m.quantization[ax] / dt) ** 2, gap**2, phi,
                              m.markov_sigma[ax] ** 2 * -math.expm1(-2 * dt / tc[ax]))
            # lfilter's state s' = F·s + G·u (transposed direct form II); P = F·P·Fᵀ + G·Gᵀ
            grow = np.array([beta[1] + phi * beta[0], beta[2]])
            from scipy import linalg  # imported when used: importing this module stays cheap

            cov = linalg.solve_discrete_lyapunov(np.array([[phi, 1.0], [0.0, 0.0]]),
                                                 np.outer(grow, grow))
            val, vec = np.linalg.eigh(cov)
            state = vec @ (np.sqrt(np.clip(val, 0.0, None)) * rng.standard_normal(2))
            self._arma.append((ax, beta, np.array([1.0, -phi]), state))
        # grid rows x_j = e^(−rate)·x_{j−1} + c·w_j, rate = h/T: (axis, rate, stationary σ)
        rows: list[tuple[int, float, float]] = []
        n_el = math.ceil(math.log10(f0 / f_low) - 1e-9) + 2  # flicker: f0 … f_low/10 [2], [3]
        for k in range(n_el if flicker.any() else 0):
            rows += [(ax, h * 2 * math.pi * f0 * 10.0**-k,
                      m.bias_instability[ax] * math.sqrt(math.log(10) / math.pi))
                     for ax in np.flatnonzero(flicker).tolist()]
        rows += [(ax, 0.0, 0.0) for ax in np.flatnonzero(rw).tolist()]  # random walk, starts at 0
        rows += [(ax, h / tc[ax], m.markov_sigma[ax]) for ax in np.flatnonzero(on_grid).tolist()]
        axis = np.array([r[0] for r in rows], dtype=np.intp)
        rate = np.array([r[1] for r in rows]).reshape(-1, 1)
        sigma = np.array([r[2] for r in rows])
        self._grid_c = np.where(rate[:, 0] > 0, sigma * np.sqrt(-np.expm1(-2 * rate[:, 0])),
                                m.random_walk[axis] * math.sqrt(h)).reshape(-1, 1)
        n_rows = axis.size
        self._grid_sum = np.zeros((3, n_rows))  # grid value per axis = Σ of its rows
        self._grid_sum[axis, np.arange(n_rows)] = 1.0
        self._has_ramp = bool(np.any(m.rate_ramp != 0))
        self._has_grid = n_rows > 0 or self._has_ramp
        # sub-blocks keep φ^(−l) below e^600; scaled-cumsum factors φ^(∓l), l = 1 … L
        block = d * max(1, round(_BLOCK_TARGET / d))
        m_grid = block // d
        fastest = float(rate.max(initial=0.0))
        length = m_grid if fastest == 0 else max(1, min(m_grid, int(600 / fastest)))
        steps = np.arange(1, length + 1) * rate
        self._grow, self._decay = np.exp(steps), np.exp(-steps)
        # initial states, drawn in a fixed order: stationary except the random walks (0)
        self._u_prev = rng.standard_normal(3)
        self._grid_x = sigma * rng.standard_normal(n_rows)
        self._g_last, self._j = self._grid_sum @ self._grid_x, 0
        # fixed blocks and preallocated scratch
        self._block, self._z = np.empty((3, block)), np.empty((3, block))
        self._pos = block
        self._normals = _NormalSource(rng, max(3 * block, n_rows * m_grid))
        self._grid_w = np.empty((n_rows, m_grid))
        self._interp_basis = np.vstack([np.ones(d), np.arange(d) / d])  # value, slope·frac
        self._interp_coef = np.empty((3, m_grid, 2))
        self._interp = np.empty((3 * m_grid, d))
        self._ready = True

    # -- one block of samples -----------------------------------------------------------------
    def _next_block(self) -> None:
        blk, z = self._block, self._z
        self._normals.fill(z.reshape(-1))
        arma = []  # axes with a full-rate Markov term: ARMA(1, 2) on the same deviates
        if self._arma:
            from scipy import signal  # imported when used: importing this module stays cheap
        for ax, b, a, state in self._arma:
            y, state[:] = signal.lfilter(b, a, z[ax], zi=state)
            arma.append((ax, y))
        np.multiply(z, self._theta0[:, None], out=blk)
        if self._has_quant:  # y_k = θ0·u_k + θ1·u_{k−1}
            blk[:, 0] += self._theta1 * self._u_prev
            tail = z[:, :-1]
            np.multiply(tail, self._theta1[:, None], out=tail)  # z is scratch: overwrite
            blk[:, 1:] += tail
        self._u_prev = z[:, -1].copy()
        for ax, y in arma:
            blk[ax] = y
        if self._has_grid:
            self._add_slow(blk)
        self._pos = 0

    def _add_slow(self, blk: NDArray[np.float64]) -> None:
        """Add the slow terms: grid values at j0 … j0+m, interpolated linearly to the block."""
        d = self._d
        m = blk.shape[1] // d
        w = self._grid_w
        self._normals.fill(w.reshape(-1))
        w *= self._grid_c
        # x_j = φ^j·(x_0 + Σ_{l≤j} φ^(−l)·c·w_l), vectorised over rows, in sub-blocks of length L
        length = self._grow.shape[1]
        for start in range(0, m, length):
            seg = w[:, start:start + length]
            k = seg.shape[1]
            seg *= self._grow[:, :k]
            np.cumsum(seg, axis=1, out=seg)
            seg += self._grid_x[:, None]
            seg *= self._decay[:, :k]
            self._grid_x = seg[:, -1].copy()
        g = np.empty((3, m + 1))
        g[:, 0] = self._g_last
        np.matmul(self._grid_sum, w, out=g[:, 1:])
        if self._has_ramp:  # deterministic: R·t at the grid times
            g[:, 1:] += self.model.rate_ramp[:, None] * (np.arange(self._j + 1, self._j + m + 1)
                                                         * self._h)
        self._g_last = g[:, -1].copy()
        self._j += m
        if d == 1:
            blk += g[:, :-1]
            return
        coef = self._interp_coef  # value g_j and slope g_{j+1} − g_j of each segment
        coef[:, :, 0] = g[:, :-1]
        np.subtract(g[:, 1:], g[:, :-1], out=coef[:, :, 1])
        np.matmul(coef.reshape(-1, 2), self._interp_basis, out=self._interp)
        view = blk.reshape(3 * m, d)
        view += self._interp


def simulate_noise(model: NoiseModel, n_samples: int, sample_interval_s: float,
                   rng: np.random.Generator | int | None = None) -> NDArray[np.float64]:
    """Return `n_samples` samples (shape (n_samples, 3)) of the noise of `model` [rad/s | m/s²].

    A fresh :class:`NoiseGenerator` with interval `sample_interval_s` [s] and random source `rng`.
    """
    return NoiseGenerator(model, sample_interval_s, rng).generate(n_samples)
