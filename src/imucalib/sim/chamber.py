"""Thermal chamber and the IMU's thermal response.

Contents
--------
:class:`ChamberSpec`
    Range, ramp limit, air time constant and stability of a chamber.
:class:`SimChamber`
    The stateful twin of the chamber controller in virtual time: setpoint ramps, air temperature.
:class:`ImuThermalSpec`
    The IMU's thermal time constant and self-heating.
:func:`imu_temperature_degc`
    The IMU's temperature and its rate, in a chamber or at a constant ambient temperature.

Model
-----
The setpoint s(t) is piecewise linear: each command ramps it from its current value to the new
target at the requested rate (at most ``max_ramp_degc_ps``), then holds it. The air follows with a
first-order lag, and the IMU follows the air with its own first-order lag plus self-heating h
(switched on at power-on)::

    τ_a·dA/dt = s − A,        τ_i·dT/dt = A + h − T

Both are solved in closed form on each linear piece of s (exact, no time stepping): with s = s0 + kτ
on a piece, A = s0 − kτ_a + kτ + C·e^{−τ/τ_a} (C = A0 − s0 + kτ_a) and
T = s0 − kτ_a + h + k(τ − τ_i) + C·G(τ) + D·e^{−τ/τ_i}, G(τ) = τ_a/(τ_a − τ_i)·(e^{−τ/τ_a} −
e^{−τ/τ_i}) (→ τ/τ_i·e^{−τ/τ_i} when τ_a = τ_i), D = T0 − (s0 − kτ_a + h − kτ_i). At time 0 the
chamber air rests at its initial temperature and the IMU is in equilibrium with it.

The chamber's stability (controller cycling) is a deterministic sum of six sinusoids with periods
from 60 s to 1800 s, random phases and amplitudes, scaled so that its RMS is
``stability_noise_degc``; it is added to the air temperature, and the IMU sees it through its lag
(steady-state filtered sinusoids), so repeated evaluations are consistent.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib._checks import as_array, check_finite_scalar, check_nonnegative, check_positive
from imucalib.errors import ConfigurationError, InvalidInputError, LimitExceededError

__all__ = ["ChamberSpec", "ImuThermalSpec", "SimChamber", "imu_temperature_degc"]

_F64 = NDArray[np.float64]
_N_SINES = 6


@dataclass(frozen=True)
class ChamberSpec:
    """A thermal chamber.

    Parameters
    ----------
    min_temp_degc, max_temp_degc : float
        Setpoint range. [°C]
    max_ramp_degc_ps : float
        Fastest setpoint ramp. [°C/s]
    air_time_constant_s : float
        First-order lag of the air temperature behind the setpoint. [s]
    stability_noise_degc : float
        RMS of the air temperature's fluctuation about its mean. [°C]
    """

    min_temp_degc: float = -55.0
    max_temp_degc: float = 125.0
    max_ramp_degc_ps: float = 5.0 / 60.0
    air_time_constant_s: float = 120.0
    stability_noise_degc: float = 0.0

    def __post_init__(self) -> None:
        lo = check_finite_scalar(self.min_temp_degc, "min_temp_degc")
        hi = check_finite_scalar(self.max_temp_degc, "max_temp_degc")
        if not lo < hi:
            raise ConfigurationError(
                f"`min_temp_degc` must be below `max_temp_degc`; got {lo}, {hi}"
            )
        check_positive(self.max_ramp_degc_ps, "max_ramp_degc_ps")
        check_positive(self.air_time_constant_s, "air_time_constant_s")
        check_nonnegative(self.stability_noise_degc, "stability_noise_degc")


@dataclass(frozen=True)
class ImuThermalSpec:
    """Thermal behaviour of an IMU.

    Parameters
    ----------
    time_constant_s : float
        First-order lag of the IMU temperature behind the surrounding air. [s]
    self_heating_degc : float
        Steady-state rise of the IMU above the air while powered. [°C]
    """

    time_constant_s: float = 600.0
    self_heating_degc: float = 0.0

    def __post_init__(self) -> None:
        check_positive(self.time_constant_s, "time_constant_s")
        check_finite_scalar(self.self_heating_degc, "self_heating_degc")


class SimChamber:
    """The twin of a thermal-chamber controller, in virtual time.

    Parameters
    ----------
    spec : ChamberSpec
        The chamber.
    initial_temp_degc : float
        Setpoint and (settled) air temperature at time 0. [°C]
    rng : numpy.random.Generator or int or None
        Source of the stability fluctuation's phases and amplitudes (drawn once, lazily).

    Examples
    --------
    >>> chamber = SimChamber(ChamberSpec(max_ramp_degc_ps=0.1), initial_temp_degc=20.0)
    >>> chamber.command_setpoint(60.0, at_time_s=0.0)
    400.0
    """

    def __init__(self, spec: ChamberSpec, initial_temp_degc: float = 20.0,
                 rng: np.random.Generator | int | None = None) -> None:
        if not isinstance(spec, ChamberSpec):
            raise ConfigurationError(f"`spec` must be a ChamberSpec; got {type(spec).__name__}")
        self.spec = spec
        temp = self._check_range(initial_temp_degc, "initial_temp_degc")
        self._segments: list[tuple[float, float, float]] = [(0.0, temp, 0.0)]  # (t0, s0, slope)
        self._rng = rng
        self._sines: tuple[_F64, _F64, _F64] | None = None
        #: _lagged_sines of the fluctuation per lag [s] (constants of the chamber and the IMUs)
        self._lagged: dict[float, tuple[_F64, _F64, _F64, _F64]] = {}
        self._last_command_s = 0.0

    def _check_range(self, value: float, name: str) -> float:
        temp = check_finite_scalar(value, name)
        lo, hi = self.spec.min_temp_degc, self.spec.max_temp_degc
        if not lo <= temp <= hi:
            raise LimitExceededError(
                f"chamber: `{name}` {temp:g} °C is outside the range [{lo:g}, {hi:g}] °C"
            )
        return temp

    def check_setpoint(self, temp_degc: float, ramp_degc_ps: float | None = None
                       ) -> tuple[float, float]:
        """Return (setpoint, ramp) of a command, checked against the chamber's limits.

        Raises
        ------
        LimitExceededError
            If the setpoint is outside the chamber's range or the ramp exceeds its limit.
        """
        target = self._check_range(temp_degc, "temp_degc")
        limit = self.spec.max_ramp_degc_ps
        ramp = limit if ramp_degc_ps is None else check_positive(ramp_degc_ps, "ramp_degc_ps")
        if ramp > limit:
            raise LimitExceededError(
                f"chamber: ramp {ramp:.6g} °C/s ({ramp * 60:.4g} °C/min) exceeds the limit "
                f"{limit:.6g} °C/s ({limit * 60:.4g} °C/min)"
            )
        return target, ramp

    def command_setpoint(self, temp_degc: float, at_time_s: float,
                         ramp_degc_ps: float | None = None) -> float:
        """Ramp the setpoint from its current value to `temp_degc`, then hold it.

        Parameters
        ----------
        temp_degc : float
            New setpoint. [°C]
        at_time_s : float
            Time of the command, ≥ 0 and not before the previous command. [s]
        ramp_degc_ps : float, optional
            Ramp rate, at most (and by default) ``max_ramp_degc_ps``. [°C/s]

        Returns
        -------
        float
            Time at which the setpoint reaches `temp_degc`. [s]

        Raises
        ------
        LimitExceededError
            If the setpoint is outside the chamber's range or the ramp exceeds its limit.
        InvalidInputError
            For a non-finite value or a command earlier than the previous one.
        """
        target, ramp = self.check_setpoint(temp_degc, ramp_degc_ps)
        t = check_finite_scalar(at_time_s, "at_time_s")
        if t < self._last_command_s:
            raise InvalidInputError(
                f"commands must be issued in non-decreasing time (from 0 s); got at_time_s={t:g} "
                f"after a command at {self._last_command_s:g} s"
            )
        self._last_command_s = t
        now = float(self.setpoint_degc(np.array([t]))[0])
        del self._segments[bisect.bisect_left([s[0] for s in self._segments], t):]
        duration = abs(target - now) / ramp
        if duration > 0.0:
            self._segments.append((t, now, math.copysign(ramp, target - now)))
        self._segments.append((t + duration, target, 0.0))
        return t + duration

    def setpoint_degc(self, time_s: ArrayLike) -> _F64:
        """Return the setpoint at `time_s` (shape (n,)) [°C]."""
        t = as_array(time_s, "time_s", shape=(None,))
        t0, s0, k = (np.array(c) for c in zip(*self._segments, strict=True))
        idx = np.maximum(np.searchsorted(t0, t, side="right") - 1, 0)
        return s0[idx] + k[idx] * np.maximum(t - t0[idx], 0.0)

    def air_temperature_degc(self, time_s: ArrayLike) -> _F64:
        """Return the air temperature at `time_s` (n,): lagged setpoint plus fluctuation [°C]."""
        t = as_array(time_s, "time_s", shape=(None,))
        air, _, _, _ = _cascade(self._segments, self.spec.air_time_constant_s, None, 0.0, None, t)
        noise, _ = self._fluctuation(t, 0.0)
        return air + noise

    def _fluctuation(self, t: _F64, lag_s: float) -> tuple[_F64 | float, _F64 | float]:
        """Return the stability fluctuation seen through a first-order lag `lag_s`, and its rate."""
        sigma = float(self.spec.stability_noise_degc)
        if sigma == 0.0:
            return 0.0, 0.0
        if self._sines is None:
            rng = np.random.default_rng(self._rng)
            w = 2.0 * np.pi / np.geomspace(60.0, 1800.0, _N_SINES)
            amp = rng.rayleigh(1.0, _N_SINES)
            amp *= sigma * math.sqrt(2.0) / np.linalg.norm(amp)  # RMS of Σ a·sin = |a|/√2
            self._sines = (w, amp, rng.uniform(0.0, 2.0 * np.pi, _N_SINES))
        lagged = self._lagged.get(lag_s)
        if lagged is None:
            lagged = self._lagged[lag_s] = _lagged_sines(*self._sines, lag_s)
        w, shift, sin_gain, cos_gain = lagged
        arg = np.outer(t, w) + shift
        return np.sin(arg) @ sin_gain, np.cos(arg) @ cos_gain


def _growth(tau: _F64, tau_a: float, tau_i: float) -> _F64:
    """G(τ) = τ_a/(τ_a − τ_i)·(e^{−τ/τ_a} − e^{−τ/τ_i}), stable for τ_a ≈ τ_i."""
    delta = 1.0 / tau_i - 1.0 / tau_a
    if delta == 0.0:
        return np.asarray(tau / tau_i * np.exp(-tau / tau_i), dtype=np.float64)
    x = tau * delta
    small = np.abs(x) < 1.0
    with np.errstate(over="ignore", invalid="ignore"):
        near = np.exp(-tau / tau_i) * np.expm1(np.where(small, x, 0.0))
        far = np.exp(-tau / tau_a) - np.exp(-tau / tau_i)
    return np.asarray(np.where(small, near, far) / (tau_i * delta), dtype=np.float64)


def _cascade(segments: list[tuple[float, float, float]], tau_a: float, tau_i: float | None,
             heating: float, power_on_s: float | None, t: _F64
             ) -> tuple[_F64, _F64, _F64, _F64]:
    """Air A, dA/dt and IMU T, dT/dt at times `t` (module equations; T uses τ_i = 1 s if None).

    `heating` applies from `power_on_s` (None: always on, the IMU starting in equilibrium).
    """
    key = repr((segments, tau_a, tau_i, heating, power_on_s))  # exact: repr round-trips, ±0
    cached = _STARTS_CACHE.get(key)
    if cached is None:
        if len(_STARTS_CACHE) >= _STARTS_CACHE_SIZE:
            _STARTS_CACHE.clear()
        cached = _STARTS_CACHE[key] = _piece_starts(segments, tau_a, tau_i, heating, power_on_s)
    pieces, starts, t0s = cached
    tau_ii = 1.0 if tau_i is None else tau_i
    idx = np.maximum(np.searchsorted(t0s, t, side="right") - 1, 0)
    if idx.size and idx.min() == idx.max():  # one piece (the usual chunk): no masking
        t0, s0, k, on = pieces[int(idx[0])]
        a_start, t_start = starts[int(idx[0])]
        return _piece(s0, k, heating if on else 0.0, a_start, t_start, tau_a, tau_ii,
                      np.maximum(t - t0, 0.0))
    air, air_rate = np.empty_like(t), np.empty_like(t)
    imu, imu_rate = np.empty_like(t), np.empty_like(t)
    for n in np.unique(idx):
        sel = idx == n
        t0, s0, k, on = pieces[n]
        tau = np.maximum(t[sel] - t0, 0.0)
        a_start, t_start = starts[n]
        air[sel], air_rate[sel], imu[sel], imu_rate[sel] = _piece(
            s0, k, heating if on else 0.0, a_start, t_start, tau_a, tau_ii, tau)
    return air, air_rate, imu, imu_rate


#: _piece_starts results by the exact text of their arguments (a chamber's history changes only
#: at a command, so every chunk of every IMU between two commands shares one entry)
_STARTS_CACHE: dict[str, tuple[list[tuple[float, float, float, bool]],
                               list[tuple[float, float]], _F64]] = {}
_STARTS_CACHE_SIZE = 256


def _piece_starts(segments: list[tuple[float, float, float]], tau_a: float,
                  tau_i: float | None, heating: float, power_on_s: float | None
                  ) -> tuple[list[tuple[float, float, float, bool]], list[tuple[float, float]],
                             _F64]:
    """Return the cascade's linear pieces, the (A, T) state at each one's start, their starts.

    Pieces are (t0, s0, k, heating on); the states follow the module equations and depend on the
    setpoint history only. Pure; :func:`_cascade` caches it (:data:`_STARTS_CACHE`).
    """
    pieces = [(t0, s0, k, True) for t0, s0, k in segments]
    if tau_i is not None and power_on_s is not None and power_on_s > pieces[0][0]:
        pieces = [(t0, s0, k, t0 >= power_on_s) for t0, s0, k, _ in pieces]
        j = bisect.bisect_right([p[0] for p in pieces], power_on_s) - 1
        t0, s0, k, _ = pieces[j]
        if t0 < power_on_s:
            pieces.insert(j + 1, (power_on_s, s0 + k * (power_on_s - t0), k, True))
    # State at the start of each piece.
    a_state = segments[0][1]
    t_state = a_state + (heating if pieces[0][3] else 0.0)
    starts = []
    tau_ii = 1.0 if tau_i is None else tau_i
    for n, (t0, s0, k, on) in enumerate(pieces):
        starts.append((a_state, t_state))
        if n + 1 < len(pieces):
            d = np.array([pieces[n + 1][0] - t0])
            a_val, _, t_val, _ = _piece(s0, k, heating if on else 0.0, a_state, t_state, tau_a,
                                        tau_ii, d)
            a_state, t_state = float(a_val[0]), float(t_val[0])
    t0s = np.array([p[0] for p in pieces])
    t0s.flags.writeable = False
    return pieces, starts, t0s


def _lagged_sines(w: _F64, amp: _F64, phase: _F64, lag_s: float
                  ) -> tuple[_F64, _F64, _F64, _F64]:
    """Return the fluctuation's frequencies, phases and sine/cosine weights through a lag.

    A sinusoid a·sin(ωt + φ) through a first-order lag τ becomes a·g·sin(ωt + φ − atan ωτ),
    g = 1/√(1 + (ωτ)²); its rate has weight a·g·ω on the cosine (module docstring).
    """
    gain = 1.0 / np.sqrt(1.0 + (w * lag_s) ** 2)
    return w, phase - np.arctan(w * lag_s), amp * gain, amp * gain * w


def _piece(s0: float, k: float, h: float, a0: float, t0: float, tau_a: float, tau_i: float,
           tau: _F64) -> tuple[_F64, _F64, _F64, _F64]:
    """Closed-form air and IMU temperatures on one linear piece of the setpoint."""
    c = a0 - s0 + k * tau_a
    air = s0 - k * tau_a + k * tau + c * np.exp(-tau / tau_a)
    lin0 = s0 - k * tau_a + h - k * tau_i
    imu = lin0 + k * tau + c * _growth(tau, tau_a, tau_i) + (t0 - lin0) * np.exp(-tau / tau_i)
    setpoint = s0 + k * tau
    return air, (setpoint - air) / tau_a, imu, (air + h - imu) / tau_i


def imu_temperature_degc(chamber: SimChamber | float, thermal: ImuThermalSpec,
                         time_s: ArrayLike, *, power_on_time_s: float | None = None
                         ) -> tuple[_F64, _F64]:
    """Temperature of an IMU and its rate of change (module equations).

    Parameters
    ----------
    chamber : SimChamber or float
        The chamber around the IMU, or a constant ambient air temperature [°C] when there is none.
    thermal : ImuThermalSpec
        The IMU's lag and self-heating.
    time_s : array_like, shape (n,)
        Times. [s]
    power_on_time_s : float, optional
        When the IMU is switched on (self-heating starts; before it the IMU follows the air).
        None: powered all along, in thermal equilibrium at time 0. [s]

    Returns
    -------
    temperature_degc : ndarray, shape (n,)
        IMU temperature. [°C]
    rate_degc_ps : ndarray, shape (n,)
        Its time derivative. [°C/s]
    """
    if not isinstance(thermal, ImuThermalSpec):
        raise InvalidInputError(
            f"`thermal` must be an ImuThermalSpec; got {type(thermal).__name__}"
        )
    t = as_array(time_s, "time_s", shape=(None,))
    power_on = None if power_on_time_s is None else check_finite_scalar(power_on_time_s,
                                                                       "power_on_time_s")
    tau_i, heat = float(thermal.time_constant_s), float(thermal.self_heating_degc)
    if isinstance(chamber, SimChamber):
        _, _, imu, rate = _cascade(chamber._segments, chamber.spec.air_time_constant_s, tau_i,
                                   heat, power_on, t)
        noise, noise_rate = chamber._fluctuation(t, tau_i)
        return imu + noise, rate + noise_rate
    ambient = check_finite_scalar(chamber, "chamber (ambient temperature)")
    _, _, imu, rate = _cascade([(0.0, ambient, 0.0)], 1.0, tau_i, heat, power_on, t)
    return imu, rate
