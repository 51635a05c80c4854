"""The servo loop and the motion profile of one table axis, in closed form (private).

Each axis follows a reference angle r(t) (the commanded trapezoidal profile) through a type-2
closed loop with natural frequency ω (rad/s) and damping ζ:

    Y(s)/R(s) = T(s) = (2ζωs + ω²) / (s² + 2ζωs + ω²)

so the tracking error e = r − y obeys  ë + 2ζω ė + ω² e = r̈  (E/R = s²/(s² + 2ζωs + ω²)). The
loop has no steady error at constant rate and lags by r̈/ω² at constant acceleration; y, ẏ and ÿ
are continuous even where r̈ jumps. With r̈ piecewise constant (= a) the error on a piece is
e = a/ω² + x, x the free response of the homogeneous equation, evaluated here in closed form.

Functions
---------
:func:`free_response`
    x, ẋ, ẍ of ẍ + 2ζωẋ + ω²x = 0 from (x0, v0), vectorised over samples.
:func:`decay_rate`
    The slowest decay rate λ of the free response [1/s].
:func:`envelope`
    Bounds M_x, M_v with |x(τ)| ≤ M_x·e^{−λτ}, |ẋ(τ)| ≤ M_v·e^{−λτ}.
:func:`loop_norms`
    ‖g‖₁ (g the impulse response of T: the peak of |ÿ| is at most ‖g‖₁·max|r̈|) and ‖k‖₁
    (k that of s/(s² + 2ζωs + ω²): |ė| ≤ ‖k‖₁·max|r̈|).
:class:`Segment`, :class:`AxisProfile`
    The piecewise profile of one axis (reference polynomial, servo error state at each piece's
    start, rate ripple) and its vectorised evaluation.
:func:`plan_position`
    Time-optimal trapezoidal phases from a moving state to rest at a target.
:func:`settled_after`
    When the transient after the last command stays within tolerances.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "AxisProfile",
    "Segment",
    "decay_rate",
    "envelope",
    "free_response",
    "loop_norms",
    "plan_position",
    "settled_after",
]

_CRITICAL_TOL = 1e-6


def free_response(x0: NDArray[np.float64], v0: NDArray[np.float64], tau: NDArray[np.float64],
                  zeta: float, omega: float
                  ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Free response x(τ), ẋ(τ), ẍ(τ) of ẍ + 2ζωẋ + ω²x = 0 with x(0) = x0, ẋ(0) = v0."""
    if abs(zeta - 1.0) < _CRITICAL_TOL:
        decay = np.exp(-omega * tau)
        b = v0 + omega * x0
        x = (x0 + b * tau) * decay
        xd = (v0 - omega * b * tau) * decay
    elif zeta < 1.0:
        sigma = zeta * omega
        wd = omega * math.sqrt(1.0 - zeta * zeta)
        decay = np.exp(-sigma * tau)
        c, s = np.cos(wd * tau), np.sin(wd * tau)
        b = (v0 + sigma * x0) / wd
        x = decay * (x0 * c + b * s)
        xd = decay * (v0 * c - (sigma * v0 + omega * omega * x0) / wd * s)
    else:
        root = omega * math.sqrt(zeta * zeta - 1.0)
        s1, s2 = -zeta * omega + root, -zeta * omega - root
        c1 = (v0 - s2 * x0) / (s1 - s2)
        c2 = x0 - c1
        e1, e2 = np.exp(s1 * tau), np.exp(s2 * tau)
        x = c1 * e1 + c2 * e2
        xd = c1 * s1 * e1 + c2 * s2 * e2
    xdd = -2.0 * zeta * omega * xd - omega * omega * x
    return x, xd, xdd


def decay_rate(zeta: float, omega: float) -> float:
    """Slowest exponential decay rate λ of the free response [1/s]."""
    if abs(zeta - 1.0) < _CRITICAL_TOL:
        return 0.5 * omega  # (a + bτ)e^{−ωτ} ≤ (a + 2b/ω)e^{−ωτ/2}
    if zeta < 1.0:
        return zeta * omega
    return omega * (zeta - math.sqrt(zeta * zeta - 1.0))


def envelope(x0: float, v0: float, zeta: float, omega: float) -> tuple[float, float]:
    """Amplitudes (M_x, M_v) of exponential bounds on |x| and |ẋ| at rate :func:`decay_rate`."""
    if abs(zeta - 1.0) < _CRITICAL_TOL:
        b = v0 + omega * x0
        return abs(x0) + 2.0 * abs(b) / omega, abs(v0) + 2.0 * abs(b)
    if zeta < 1.0:
        sigma = zeta * omega
        wd = omega * math.sqrt(1.0 - zeta * zeta)
        mx = math.hypot(x0, (v0 + sigma * x0) / wd)
        mv = math.hypot(v0, (sigma * v0 + omega * omega * x0) / wd)
        return mx, mv
    root = omega * math.sqrt(zeta * zeta - 1.0)
    s1, s2 = -zeta * omega + root, -zeta * omega - root
    c1 = (v0 - s2 * x0) / (s1 - s2)
    c2 = x0 - c1
    return abs(c1) + abs(c2), abs(c1 * s1) + abs(c2 * s2)


@lru_cache(maxsize=64)
def loop_norms(zeta: float) -> tuple[float, float]:
    """(‖g‖₁, ω·‖k‖₁) of the loop, independent of ω; see the module docstring.

    Computed once per damping by trapezoidal integration of the closed-form impulse responses
    over 60 decay times, then enlarged by 10⁻⁴ relative so that they bound the true norms.
    """
    lam = decay_rate(zeta, 1.0)
    tau = np.linspace(0.0, 60.0 / lam, 400_001)
    x, xd, _ = free_response(np.zeros(1), np.ones(1), tau, zeta, 1.0)  # impulse of 1/(s²+2ζs+1)
    g = 2.0 * zeta * xd + x
    g_norm = float(np.trapezoid(np.abs(g), tau))
    k_norm = float(np.trapezoid(np.abs(xd), tau))
    return max(g_norm, 1.0) * (1.0 + 1e-4), k_norm * (1.0 + 1e-4)


@dataclass(slots=True)
class Segment:
    """One piece of an axis' profile: reference r = r0 + v0·τ + ½a·τ², servo error state at t0."""

    t0: float
    r0: float
    v0: float
    a: float
    e0: float
    ed0: float
    ripple_rps: float  # rate-ripple amplitude ρ·ω_c of a constant-rate piece
    mode: int  # index into the table's list of modes
    target: float  # target angle (position, stop, off) or rate (rate)


@dataclass(frozen=True)
class _Transient:
    """Per-segment servo-transient constants (:meth:`AxisProfile.servo_terms`)."""

    u: NDArray[np.float64]
    any_u: bool
    x0: NDArray[np.float64]
    v0e: NDArray[np.float64]
    active: NDArray[np.bool_]
    horizon_s: float


@dataclass(frozen=True)
class _ServoTerms:
    """The servo transient's constants (None for an ideal servo) and whether any ripple."""

    transient: _Transient | None
    ripple: bool


class AxisProfile:
    """Segments of one axis and their vectorised evaluation."""

    def __init__(self, omega_n_rps: float, damping: float, ripple_hz: float,
                 initial_angle_rad: float) -> None:
        self.omega = float(omega_n_rps)
        self.zeta = float(damping)
        self.ripple_w = 2.0 * math.pi * float(ripple_hz)
        self.segments = [Segment(0.0, initial_angle_rad, 0.0, 0.0, 0.0, 0.0, 0.0, 0,
                                 initial_angle_rad)]
        self._arrays: dict[str, NDArray[np.float64]] | None = None
        self._terms: _ServoTerms | None = None

    @property
    def t0s(self) -> list[float]:
        return [s.t0 for s in self.segments]

    def active_index(self, time_s: float) -> int:
        return max(bisect.bisect_right(self.t0s, time_s) - 1, 0)

    def arrays(self) -> dict[str, NDArray[np.float64]]:
        if self._arrays is None:
            names = ("t0", "r0", "v0", "a", "e0", "ed0", "ripple_rps", "mode", "target")
            self._arrays = {n: np.array([getattr(s, n) for s in self.segments], dtype=float)
                            for n in names}
        return self._arrays

    def servo_terms(self) -> _ServoTerms:
        """Return the per-segment constants of :meth:`evaluate` (cached until the next command).

        u = a/ω² is each piece's steady servo error, x0 = e0 − u and ė0 its transient's initial
        state (active where either is non-zero), dropped beyond the horizon 60/λ (λ:
        :func:`decay_rate`; e^{−60}: below 1e-26 rad); `ripple` tells whether any piece has
        rate ripple.
        """
        if self._terms is None:
            arr = self.arrays()
            omega = self.omega
            ripple = bool(np.any(arr["ripple_rps"] != 0.0))
            if math.isfinite(omega):
                u = arr["a"] / omega**2
                x0, v0e = arr["e0"] - u, arr["ed0"]
                self._terms = _ServoTerms(_Transient(
                    u=u, any_u=bool(np.any(u != 0.0)), x0=x0, v0e=v0e,
                    active=(x0 != 0.0) | (v0e != 0.0),
                    horizon_s=60.0 / decay_rate(self.zeta, omega)), ripple)
            else:
                self._terms = _ServoTerms(None, ripple)
        return self._terms

    def evaluate(self, t: NDArray[np.float64], *, with_jerk: bool = False) -> tuple[
            NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.intp],
            NDArray[np.float64] | None]:
        """Return true angle, rate, acceleration, segment index and (optionally) jerk at `t`."""
        arr = self.arrays()
        idx = np.searchsorted(arr["t0"], t, side="right") - 1
        np.maximum(idx, 0, out=idx)
        tau = np.maximum(t - arr["t0"][idx], 0.0)
        v0, a = arr["v0"][idx], arr["a"][idx]
        theta = arr["r0"][idx] + tau * (v0 + 0.5 * a * tau)
        rate = v0 + a * tau
        accel = a.copy()
        jerk = np.zeros_like(t) if with_jerk else None
        omega, zeta = self.omega, self.zeta
        terms = self.servo_terms()
        tr = terms.transient
        if tr is not None:
            if tr.any_u:
                theta -= tr.u[idx]
            x0, v0e = tr.x0, tr.v0e
            mask = tr.active[idx] & (tau < tr.horizon_s)
            if np.any(mask):
                im = idx[mask]
                x, xd, xdd = free_response(x0[im], v0e[im], tau[mask], zeta, omega)
                theta[mask] -= x
                rate[mask] -= xd
                accel[mask] -= xdd
                if jerk is not None:
                    jerk[mask] += 2.0 * zeta * omega * xdd + omega * omega * xd
        if terms.ripple:
            rip = arr["ripple_rps"]
            mask = rip[idx] != 0.0
            w = self.ripple_w
            amp, ph = rip[idx[mask]], w * tau[mask]
            theta[mask] += amp / w * (1.0 - np.cos(ph))
            rate[mask] += amp * np.sin(ph)
            accel[mask] += amp * w * np.cos(ph)
            if jerk is not None:
                jerk[mask] -= amp * w * w * np.sin(ph)
        return theta, rate, accel, idx, jerk

    def is_still(self, t_start_s: float, t_end_s: float) -> bool:
        """Whether :meth:`evaluate` gives one constant angle and zero rate on [start, end].

        True when one segment covers the span with no reference motion, no ripple, and a servo
        transient that is zero or, from `t_start_s` on, past the horizon beyond which
        :meth:`evaluate` drops it (so constant-valued evaluation is exact, not approximate).
        """
        i = self.active_index(t_start_s)
        if self.active_index(t_end_s) != i:
            return False
        s = self.segments[i]
        if s.v0 != 0.0 or s.a != 0.0 or s.ripple_rps != 0.0:
            return False
        if not math.isfinite(self.omega) or (s.e0 == 0.0 and s.ed0 == 0.0):
            return True
        horizon = 60.0 / decay_rate(self.zeta, self.omega)
        return t_start_s - s.t0 >= horizon

    def reference_state(self, time_s: float) -> tuple[float, float, float, float, int]:
        """Return (reference angle incl. ripple, its rate, servo error, its rate, index)."""
        i = self.active_index(time_s)
        s = self.segments[i]
        tau = max(time_s - s.t0, 0.0)
        r = s.r0 + tau * (s.v0 + 0.5 * s.a * tau)
        v = s.v0 + s.a * tau
        if s.ripple_rps:
            w = self.ripple_w
            r += s.ripple_rps / w * (1.0 - math.cos(w * tau))
            v += s.ripple_rps * math.sin(w * tau)
        e, ed = self._servo_step(s.e0, s.ed0, s.a, tau)
        return r, v, e, ed, i

    def _servo_step(self, e0: float, ed0: float, a: float, tau: float) -> tuple[float, float]:
        omega = self.omega
        if not math.isfinite(omega):
            return 0.0, 0.0
        u = a / omega**2
        x, xd, _ = free_response(np.array([e0 - u]), np.array([ed0]), np.array([tau]),
                                 self.zeta, omega)
        return u + float(x[0]), float(xd[0])

    def move_to(self, time_s: float, target: float, v_max: float, a_max: float,
                mode: int) -> float:
        """Plan a trapezoidal move to rest at `target` from the state at `time_s`."""
        r, v, _, _, _ = self.reference_state(time_s)
        phases = plan_position(r, v, target, v_max, a_max)
        return self.replace_future(time_s, phases, 0.0, target, 0.0, mode, target)

    def spin(self, time_s: float, rate: float, a_max: float, ripple_fraction: float,
             mode: int) -> float:
        """Ramp to a constant `rate` (rest, holding where it stops, when `rate` is 0)."""
        _, v, _, _, _ = self.reference_state(time_s)
        phases = [(abs(rate - v) / a_max, math.copysign(a_max, rate - v))]
        if rate == 0.0:
            return self.replace_future(time_s, phases, 0.0, None, 0.0, mode, None)
        return self.replace_future(time_s, phases, rate, None, ripple_fraction * rate, mode, rate)

    def replace_future(self, time_s: float, phases: list[tuple[float, float]],
                       final_v: float, final_r: float | None, ripple_rps: float, mode: int,
                       target: float | None) -> float:
        """Cut the profile at `time_s`, append `phases` (duration, accel), then a final piece.

        The final piece has rate `final_v` and angle `final_r` (None: the integrated angle). The
        new pieces get `mode` and `target` (None: the final piece's angle). Returns the time the
        phases end.
        """
        r, v, e, ed, i = self.reference_state(time_s)
        keep = i if self.segments[i].t0 < time_s else i - 1
        del self.segments[keep + 1:]
        t = time_s
        for duration, accel in phases:
            if duration <= 0.0:
                continue
            self.segments.append(Segment(t, r, v, accel, e, ed, 0.0, mode, 0.0))
            r += duration * (v + 0.5 * accel * duration)
            v += accel * duration
            e, ed = self._servo_step(e, ed, accel, duration)
            t += duration
        first_new = keep + 1
        final_r = r if final_r is None else final_r
        self.segments.append(Segment(t, final_r, final_v, 0.0, e, ed, ripple_rps, mode, 0.0))
        for seg in self.segments[first_new:]:
            seg.target = final_r if target is None else target
        self._arrays = None
        self._terms = None
        return t


def plan_position(x0: float, v0: float, x_target: float, v_max: float, a_max: float
                  ) -> list[tuple[float, float]]:
    """Time-optimal trapezoidal phases (duration, accel) from (x0, v0) to rest at `x_target`."""
    phases: list[tuple[float, float]] = []
    if v0 != 0.0:
        s = math.copysign(1.0, v0)
        if abs(v0) > v_max:  # slow down to the move's cruise limit first
            d = (abs(v0) - v_max) / a_max
            phases.append((d, -s * a_max))
            x0 += d * (v0 - 0.5 * s * a_max * d)
            v0 = s * v_max
        stop = v0 * abs(v0) / (2.0 * a_max)
        if s * (x_target - x0) < abs(stop):  # cannot stop in time: brake, then come back
            phases.append((abs(v0) / a_max, -s * a_max))
            x0 += stop
            v0 = 0.0
    dist = x_target - x0
    if v0 == 0.0 and dist == 0.0:
        return phases
    s = math.copysign(1.0, v0) if v0 != 0.0 else math.copysign(1.0, dist)
    dist, w0 = abs(dist), abs(v0)
    vp = min(v_max, math.sqrt(a_max * dist + 0.5 * w0 * w0))
    d1 = (vp * vp - w0 * w0) / (2.0 * a_max)
    d3 = vp * vp / (2.0 * a_max)
    phases += [((vp - w0) / a_max, s * a_max), (max(dist - d1 - d3, 0.0) / vp, 0.0),
               (vp / a_max, -s * a_max)]
    return phases


def settled_after(segment: Segment, zeta: float, omega: float, position_tol: float,
                  rate_tol: float, is_rate: bool) -> float:
    """Time from which the final `segment`'s servo transient stays within tolerance.

    Conservative, from :func:`envelope`; in rate mode the ripple amplitude is taken from
    `rate_tol` and the position tolerance is ignored; ``inf`` if the ripple alone exceeds it.
    """
    if is_rate:
        rate_tol -= abs(segment.ripple_rps)
        if rate_tol <= 0.0:
            return math.inf
        position_tol = math.inf
    if not math.isfinite(omega):
        return segment.t0
    mx, mv = envelope(segment.e0, segment.ed0, zeta, omega)
    lam = decay_rate(zeta, omega)
    tau = max(math.log(mx / position_tol) / lam if mx > position_tol else 0.0,
              math.log(mv / rate_tol) / lam if mv > rate_tol else 0.0)
    return segment.t0 + tau
