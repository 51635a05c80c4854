"""The attitude of an IMU turned by hand between static poses, with its exact rate and acceleration.

A hand-held calibration session (:mod:`imucalib.sim.handheld`) alternates static poses on a desk
and hand rotations between them. This module is the motion alone: a sequence of segments, each
static (a fixed attitude) or a hand rotation, evaluated at any times into the attitude R_tb of the
IMU body b relative to the Earth-fixed frame t (z up, :mod:`imucalib.conventions`), its angular
rate ω_tb and angular acceleration ω̇_tb, both in b. The rate and acceleration are the analytic
derivatives of the attitude, so that the gyro's true input integrates to the attitude change
exactly (up to the integrator's own error).

Equations
---------
A rotation from R_0 to R_1 = R_0·exp([φ]×) (φ the rotation vector in the start body frame: the
shortest arc φ = log(R_0ᵀR_1), or ±2π·u_up for a full turn on the desk) follows

    R_tb(t) = R_0 · exp(s(t)·[φ]×) · exp(a(t)·[u]×)                                   (H.1)

where s goes from 0 to 1 (the slerp parameter) and a(t) is a hand tremor about the unit axis u.
With ṡ, s̈, ȧ, ä the time derivatives and T = exp(a·[u]×), the body rate and its derivative are

    ω_tb^b = Tᵀ·φ·ṡ + u·ȧ                                                              (H.2)
    ω̇_tb^b = Tᵀ·φ·s̈ − (u·ȧ) × (Tᵀ·φ·ṡ) + u·ä                                         (H.3)

(dTᵀ/dt = −[u·ȧ]×·Tᵀ; exp(s·[φ]×) turns about φ, which it leaves unchanged). The rate profile of
one move from s_a to s_b over [t_a, t_a + D], with τ = (t − t_a)/D and the peak at τ = c
(c ∈ (0, 1), a skewed raised cosine), is

    ṡ = (Δs/D)·(1 − cos(πτ/c))              for τ ≤ c
    ṡ = (Δs/D)·(1 + cos(π(τ − c)/(1 − c)))  for τ > c                                   (H.4)

which starts and ends at zero rate and zero acceleration and integrates to Δs = s_b − s_a. A
rotation is one move, or two moves with a pause between them (the hand hesitates). The tremor
is a(t) = A·E(τ)·sin(2πf·(t − t_0) + ψ) with E(τ) = sin³(πτ) over the whole rotation
(τ = (t − t_0)/(t_1 − t_0)), so that a, ȧ and ä vanish at both ends: statics stay static and
the rate and acceleration are continuous.

Contents
--------
:class:`HandMove`, :class:`HandSegment`, :class:`HandMotion` (:meth:`HandMotion.evaluate`,
:meth:`HandMotion.platform_motion`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from imucalib._checks import as_array
from imucalib.errors import InvalidInputError
from imucalib.sim.kinematics import PlatformMotion

__all__ = ["HandMotion", "HandMove", "HandSegment"]

_F64 = NDArray[np.float64]


@dataclass(frozen=True)
class HandMove:
    """One move of a rotation's slerp parameter, (H.4).

    Attributes
    ----------
    start_time_s, stop_time_s : float
        The move's span. [s]
    s_start, s_stop : float
        The slerp parameter at its ends. [–]
    peak_fraction : float
        c: where in the move the rate peaks, in (0, 1) (0.5 symmetric). [–]
    """

    start_time_s: float
    stop_time_s: float
    s_start: float
    s_stop: float
    peak_fraction: float

    def profile(self, time_s: _F64) -> tuple[_F64, _F64, _F64]:
        """Return s, ṡ, s̈ of (H.4) at times inside the move. [–], [1/s], [1/s²]"""
        dur = self.stop_time_s - self.start_time_s
        c, ds = self.peak_fraction, self.s_stop - self.s_start
        tau = np.clip((time_s - self.start_time_s) / dur, 0.0, 1.0)
        rise = tau <= c
        x = np.where(rise, math.pi * tau / c, math.pi * (tau - c) / (1.0 - c))
        s = np.where(rise, tau - c / math.pi * np.sin(x), tau + (1.0 - c) / math.pi * np.sin(x))
        sd = np.where(rise, 1.0 - np.cos(x), 1.0 + np.cos(x))
        sdd = np.where(rise, math.pi / c * np.sin(x), -math.pi / (1.0 - c) * np.sin(x))
        return self.s_start + ds * s, ds / dur * sd, ds / dur**2 * sdd


@dataclass(frozen=True, eq=False)
class HandSegment:
    """A static pose (``moves`` empty) or a hand rotation (H.1) over [start, stop).

    Attributes
    ----------
    start_time_s, stop_time_s : float
        The segment's span. [s]
    rot_start : Rotation
        R_0: the attitude at the start (for a static, throughout).
    rotvec_b_rad : ndarray, shape (3,)
        φ of (H.1) (zeros for a static). [rad]
    moves : tuple of HandMove
        The moves of s from 0 to 1, in time order; a gap between two is a pause.
    tremor_rad : float
        A, the tremor amplitude. [rad]
    tremor_hz : float
        f, its frequency. [Hz]
    tremor_phase_rad : float
        ψ. [rad]
    tremor_axis_b : ndarray, shape (3,)
        u, a unit vector in b.
    """

    start_time_s: float
    stop_time_s: float
    rot_start: Rotation
    rotvec_b_rad: _F64
    moves: tuple[HandMove, ...] = ()
    tremor_rad: float = 0.0
    tremor_hz: float = 8.0
    tremor_phase_rad: float = 0.0
    tremor_axis_b: _F64 = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))

    @property
    def is_static(self) -> bool:
        """True for a static pose."""
        return not self.moves

    @property
    def rot_stop(self) -> Rotation:
        """R_1 = R_0·exp([φ]×): the attitude at the end."""
        return self.rot_start * Rotation.from_rotvec(self.rotvec_b_rad)

    def _slerp(self, t: _F64) -> tuple[_F64, _F64, _F64]:
        s, sd, sdd = np.zeros_like(t), np.zeros_like(t), np.zeros_like(t)
        s[t >= self.moves[0].start_time_s] = self.moves[0].s_start
        for move in self.moves:
            inside = (t >= move.start_time_s) & (t < move.stop_time_s)
            s[inside], sd[inside], sdd[inside] = move.profile(t[inside])
            s[t >= move.stop_time_s] = move.s_stop
        return s, sd, sdd

    def _tremor(self, t: _F64) -> tuple[_F64, _F64, _F64]:
        dur = self.stop_time_s - self.start_time_s
        k = math.pi / dur
        x = np.clip(t - self.start_time_s, 0.0, dur) * k
        sx, cx = np.sin(x), np.cos(x)
        env, env_d, env_dd = sx**3, 3.0 * sx**2 * cx * k, (6.0 * sx * cx**2 - 3.0 * sx**3) * k**2
        w = 2.0 * math.pi * self.tremor_hz
        arg = w * (t - self.start_time_s) + self.tremor_phase_rad
        osc, osc_d, osc_dd = np.sin(arg), w * np.cos(arg), -w * w * np.sin(arg)
        amp = self.tremor_rad
        return (amp * env * osc, amp * (env_d * osc + env * osc_d),
                amp * (env_dd * osc + 2.0 * env_d * osc_d + env * osc_dd))

    def evaluate(self, time_s: _F64) -> tuple[Rotation, _F64, _F64]:
        """Return R_tb, ω_tb^b, ω̇_tb^b at times inside the segment, (H.1)–(H.3)."""
        n = time_s.shape[0]
        if self.is_static:
            return (Rotation.from_quat(np.tile(self.rot_start.as_quat(), (n, 1))),
                    np.zeros((n, 3)), np.zeros((n, 3)))
        phi, u = self.rotvec_b_rad, self.tremor_axis_b
        s, sd, sdd = self._slerp(time_s)
        a, ad, add = self._tremor(time_s)
        rot_t = Rotation.from_rotvec(a[:, None] * u)
        rot = self.rot_start * Rotation.from_rotvec(s[:, None] * phi) * rot_t
        turn_b = rot_t.inv().apply(np.tile(phi, (n, 1)))  # Tᵀ·φ
        tremor_rate = ad[:, None] * u
        rate = turn_b * sd[:, None] + tremor_rate
        accel = (turn_b * sdd[:, None] - np.cross(tremor_rate, turn_b * sd[:, None])
                 + add[:, None] * u)
        return rot, rate, accel


@dataclass(frozen=True, eq=False)
class HandMotion:
    """A hand-held session's motion: contiguous segments from time 0.

    Attributes
    ----------
    segments : tuple of HandSegment
        In time order, each starting where the one before stops.
    """

    segments: tuple[HandSegment, ...]

    def __post_init__(self) -> None:
        if not self.segments:
            raise InvalidInputError("a HandMotion needs at least one segment")
        for before, after in zip(self.segments[:-1], self.segments[1:], strict=True):
            if after.start_time_s != before.stop_time_s:
                raise InvalidInputError(
                    f"hand segments must be contiguous; one stops at {before.stop_time_s} s and "
                    f"the next starts at {after.start_time_s} s")

    @property
    def duration_s(self) -> float:
        """End of the last segment. [s]"""
        return self.segments[-1].stop_time_s

    def evaluate(self, time_s: ArrayLike) -> tuple[Rotation, _F64, _F64]:
        """Return the attitude and motion at `time_s`, (H.1)–(H.3).

        Parameters
        ----------
        time_s : array_like, shape (n,)
            Times; before the first segment the first attitude holds, after the last the last.
            [s]

        Returns
        -------
        rot_tb : Rotation, length n
            Attitude of the body relative to the Earth-fixed frame t (``v_t = rot_tb.apply(v_b)``).
        rate_b_rps : ndarray, shape (n, 3)
            ω_tb in b (no Earth rate). [rad/s]
        accel_b_rps2 : ndarray, shape (n, 3)
            ω̇_tb in b. [rad/s²]
        """
        t = as_array(time_s, "time_s", shape=(None,))
        n = t.shape[0]
        starts = np.array([seg.start_time_s for seg in self.segments])
        which = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(self.segments) - 1)
        quat = np.empty((n, 4))
        rate, accel = np.zeros((n, 3)), np.zeros((n, 3))
        for k in np.unique(which):
            seg = self.segments[k]
            rows = np.flatnonzero(which == k)
            tk = np.clip(t[rows], seg.start_time_s, seg.stop_time_s)
            rot, rate[rows], accel[rows] = seg.evaluate(tk)
            quat[rows] = rot.as_quat()
        return Rotation.from_quat(quat), rate, accel

    def platform_motion(self, time_s: ArrayLike) -> PlatformMotion:
        """Return the motion as a :class:`~imucalib.sim.kinematics.PlatformMotion`.

        The platform frame is the IMU body at its own origin (rot_tp = R_tb, no table axes), the
        input of :func:`~imucalib.sim.kinematics.compute_imu_kinematics`.
        """
        t = as_array(time_s, "time_s", shape=(None,))
        rot, rate, accel = self.evaluate(t)
        z0 = np.zeros((t.shape[0], 0))
        return PlatformMotion(time_s=t, angle_rad=z0, rate_rps=z0.copy(), accel_rps2=z0.copy(),
                              rot_tp=rot, omega_tp_p_rps=rate, alpha_tp_p_rps2=accel)
