"""Synthetic P2 window means from a known truth (fast Monte Carlo without the twin).

The means follow docs/p2.md Eqs. (P2.1)–(P2.3) exactly (with the gyro g-sensitivity and the
accelerometer K2), with Gaussian noise of the stated standard errors; the truth of every
parameter is a cubic in (T − 25 °C) plus a hysteresis term h·ℓ (ℓ = +1 heating, −1 cooling).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from imucalib.procedures.p2.observations import P2Window, UnitObservations
from imucalib.procedures.p2.reduction import ORIENTATIONS, PARAM_NAMES, up_vector

G = 9.80665
EARTH_UP = 7.292115e-5 * np.sin(np.radians(45.0))


@dataclass
class Truth:
    """Polynomial coefficients (4, 36) in (T − 25) and hysteresis h (36,), lever arm r (3,)."""

    coefficients: np.ndarray
    hysteresis: np.ndarray
    lever_arm_m: np.ndarray

    def at(self, temperature_degc: float, leg: str) -> np.ndarray:
        dt = temperature_degc - 25.0
        powers = np.array([1.0, dt, dt**2, dt**3])
        sign = 1.0 if leg == "heating" else -1.0
        return np.asarray(powers @ self.coefficients + sign * self.hysteresis)


def draw_truth(rng: np.random.Generator, *, cubic: bool = True, hysteresis: float = 0.0,
               lever_arm_m: Sequence[float] = (0.0, 0.0, 0.0)) -> Truth:
    """A consumer-like truth: biases and M with cubic temperature dependence."""
    scale = np.array([1e-2] * 3 + [3e-3] * 9 + [1e-4] * 9 + [5e-2] * 3 + [3e-3] * 9
                     + [5e-5] * 3)
    c = np.zeros((4, 36))
    c[0] = rng.normal(0.0, scale)
    swing = rng.normal(0.0, scale)                       # the change over ±62.5 °C
    c[1] = swing / 62.5
    c[2] = 0.3 * rng.normal(0.0, scale) / 62.5**2
    if cubic:
        c[3] = 0.5 * swing / 62.5**3
    h = hysteresis * np.abs(swing) * rng.choice([-1.0, 1.0], 36)
    return Truth(c, h, np.asarray(lever_arm_m, dtype=float))


def point_windows(truth: Truth, point: int, temperature_degc: float, leg: str, held_out: bool,
                  rng: np.random.Generator, *, rate_rps: float = np.radians(60.0),
                  gyro_se: float = 2e-4, accel_se: float = 3e-3,
                  drop: Sequence[tuple[str, str]] = (), noise: bool = True) -> list[P2Window]:
    """The windows of one point: per orientation, static at 0°/180° and turns at ±ω."""
    p = truth.at(temperature_degc, leg)
    bg, mg, gs = p[:3], p[3:12].reshape(3, 3), p[12:21].reshape(3, 3)
    ba, ma, k2 = p[21:24], p[24:33].reshape(3, 3), p[33:36]
    r = truth.lever_arm_m
    k = 1.0 if noise else 0.0
    out = []
    idx = 0
    for o in ORIENTATIONS:
        u = up_vector(o)
        proj = np.eye(3) - np.outer(u, u)
        for kind, rate in (("static", 0.0), ("static", 0.0), ("rate", rate_rps),
                           ("rate", -rate_rps)):
            if (o, kind if rate == 0 else ("+" if rate > 0 else "-")) in drop:
                continue
            w_true = rate * (1.0 + k * rng.normal(0.0, 1e-6)) if rate else 0.0
            force = G * u - w_true**2 * (proj @ r)
            gyro = bg + (np.eye(3) + mg) @ (u * (w_true + EARTH_UP)) + gs @ force
            if rate == 0.0:
                gyro = gyro + rng.normal(0.0, 5e-5, 3)     # not used by P2 (horizontal Ω)
            accel = ba + (np.eye(3) + ma) @ force + k2 * force**2
            se_g = np.full(3, gyro_se)
            se_a = np.full(3, accel_se)
            out.append(P2Window(
                step_index=idx, label=f"{o} {kind} {rate:+.3f}", point=point, leg=leg,
                held_out=held_out, pose=o, kind=kind, table_rate_rps=w_true,
                n_revolutions=2 if rate else 0,
                gyro_mean_rps=gyro + k * rng.normal(0.0, se_g), accel_mean_mps2=accel
                + k * rng.normal(0.0, se_a), gyro_se_rps=se_g, accel_se_mps2=se_a,
                temperature_degc=temperature_degc + rng.normal(0.0, 0.02),
                temperature_rate_degc_ps=float(rng.normal(0.0, 2e-3)), duration_s=10.0,
                n_samples=1000, n_lost=0))
            idx += 1
    return out


def unit_observations(truth: Truth, rng: np.random.Generator, *,
                      temperatures: Sequence[float] = (-40.0, -20.0, 0.0, 25.0, 45.0, 65.0, 85.0),
                      held_out: Sequence[float] = (-10.0, 55.0), hysteresis: bool = False,
                      unit: str = "U1", **kwargs: object) -> UnitObservations:
    """Every point of a sweep (heating, and cooling with `hysteresis`)."""
    every = sorted([(t, False) for t in temperatures] + [(t, True) for t in held_out])
    order = [(t, "heating", h) for t, h in every]
    if hysteresis:
        order += [(t, "cooling", h) for t, h in reversed(every[:-1])]
    windows = []
    for k, (t, leg, held) in enumerate(order):
        windows += point_windows(truth, k, t, leg, held, rng, **kwargs)  # type: ignore[arg-type]
    return UnitObservations(unit=unit, windows=tuple(windows), gravity_mps2=G,
                            earth_rate_up_rps=EARTH_UP, latitude_deg=45.0, sample_rate_hz=100.0)


__all__ = [
    "EARTH_UP",
    "PARAM_NAMES",
    "G",
    "Truth",
    "draw_truth",
    "point_windows",
    "unit_observations",
]
