"""Guards and settling criteria: pure checks on the data a station delivers.

Each ``check_*`` function returns None when all is well, or a sentence that says what was found and
what was allowed (it becomes the trip reason in the event log and the step's note). The runner
applies them to every block it acquires while a step records (data-quality guards) or waits to
settle (settling criteria); it never lets a block that failed a guard count as valid.

Contents
--------
:func:`wrap_angle_rad`, :func:`check_position_hold`, :func:`check_rate_hold`,
:func:`check_saturation`, :func:`check_jumps`, :func:`check_counter`, :func:`check_chamber_band`,
:func:`check_overspeed`, :func:`accel_fluctuation_g`, :class:`RollingWindow`.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from imucalib import units

__all__ = [
    "RollingWindow",
    "accel_fluctuation_g",
    "check_chamber_band",
    "check_counter",
    "check_jumps",
    "check_overspeed",
    "check_position_hold",
    "check_rate_hold",
    "check_saturation",
    "wrap_angle_rad",
]

_F64 = NDArray[np.float64]


def wrap_angle_rad(angle_rad: _F64) -> _F64:
    """Return angles wrapped into (−π, π]. [rad]"""
    return np.asarray(np.angle(np.exp(1j * np.asarray(angle_rad))), dtype=np.float64)


def check_position_hold(angle_rad: _F64, target_rad: Sequence[float], axis_names: Sequence[str],
                        tolerance_rad: float) -> str | None:
    """Every row of measured angles (n, k) within `tolerance_rad` of the targets (mod 2π)."""
    if angle_rad.shape[0] == 0:
        return None
    for i, (target, name) in enumerate(zip(target_rad, axis_names, strict=False)):
        err = np.abs(wrap_angle_rad(angle_rad[:, i] - target))
        worst = float(err.max())
        if worst > tolerance_rad:
            return (f"table axis {name!r} is {worst / units.ARCSEC:.2f}″ from its target "
                    f"(limit {tolerance_rad / units.ARCSEC:.2f}″)")
    return None


def check_rate_hold(rate_rps: _F64, commanded_rps: float, axis: int, axis_name: str,
                    tolerance_rps: float) -> str | None:
    """Every measured rate of `axis` within `tolerance_rps` of the commanded rate."""
    if rate_rps.shape[0] == 0:
        return None
    err = np.abs(rate_rps[:, axis] - commanded_rps)
    worst = float(err.max())
    if worst > tolerance_rps:
        return (f"table axis {axis_name!r} rate is {worst / units.DEG:.4g} °/s off the commanded "
                f"{commanded_rps / units.DEG:.6g} °/s (limit {tolerance_rps / units.DEG:.4g} °/s)")
    return None


def check_overspeed(rate_rps: _F64, limit_rps: float, name: str) -> str | None:
    """No measured centrifuge rate (any row, any axis) beyond ±`limit_rps`.

    Parameters
    ----------
    rate_rps : ndarray
        Measured spin rates, any shape. [rad/s]
    limit_rps : float
        The plan's limit (``limits.max_centrifuge_rate_dps``). [rad/s]
    name : str
        The centrifuge's name.
    """
    rates = np.abs(np.asarray(rate_rps, dtype=np.float64))
    if rates.size == 0:
        return None
    worst = float(rates.max())
    if worst > limit_rps:
        return (f"centrifuge {name!r} over-speed: {worst / units.DEG:.1f} °/s measured, limit "
                f"{limit_rps / units.DEG:g} °/s")
    return None


def check_saturation(name: str, gyro_rps: _F64, accel_mps2: _F64, flags: NDArray[np.bool_],
                     gyro_range_rps: float | None, accel_range_mps2: float | None
                     ) -> str | None:
    """No sample flagged over-range by the device or within 0.1 % of a known range."""
    n_flag = int(np.count_nonzero(flags))
    if n_flag:
        return f"IMU {name}: {n_flag} sample(s) flagged saturated by the device"
    for what, values, limit, unit, scale in (("gyro", gyro_rps, gyro_range_rps, "°/s", units.DEG),
                                             ("accel", accel_mps2, accel_range_mps2, "g",
                                              units.G0_MPS2)):
        if limit is not None and values.size:
            peak = float(np.abs(values).max())
            if peak >= 0.999 * limit:
                return (f"IMU {name}: {what} output {peak / scale:.6g} {unit} at its range "
                        f"±{limit / scale:.6g} {unit} (saturated)")
    return None


def check_jumps(name: str, gyro_rps: _F64, accel_mps2: _F64, gyro_jump_rps: float,
                accel_jump_mps2: float) -> str | None:
    """No sample-to-sample change above the jump thresholds (abnormal output)."""
    for what, values, limit, unit, scale in (("gyro", gyro_rps, gyro_jump_rps, "°/s", units.DEG),
                                             ("accel", accel_mps2, accel_jump_mps2, "g",
                                              units.G0_MPS2)):
        if values.shape[0] > 1:
            jump = float(np.abs(np.diff(values, axis=0)).max())
            if jump > limit:
                return (f"IMU {name}: {what} output jumped by {jump / scale:.4g} {unit} between "
                        f"samples (limit {limit / scale:.4g} {unit})")
    return None


def check_counter(name: str, missing_samples: int, crc_errors: int, max_missing: int,
                  max_crc: int) -> str | None:
    """Lost samples and CRC failures within their allowances."""
    if crc_errors > max_crc:
        return f"IMU {name}: {crc_errors} frame(s) failed their CRC (allowed {max_crc})"
    if missing_samples > max_missing:
        return (f"IMU {name}: sample counter shows {missing_samples} lost sample(s) "
                f"(allowed {max_missing})")
    return None


def check_chamber_band(temperature_degc: _F64, setpoint_degc: float, band_degc: float
                       ) -> str | None:
    """Chamber air within ±`band_degc` of the setpoint."""
    if temperature_degc.size == 0:
        return None
    worst = float(np.abs(temperature_degc - setpoint_degc).max())
    if worst > band_degc:
        return (f"chamber air {worst:.3g} °C from the setpoint {setpoint_degc:g} °C "
                f"(band ±{band_degc:g} °C)")
    return None


def accel_fluctuation_g(time_s: _F64, accel_mps2: _F64, average_s: float) -> float:
    """Return the fluctuation of the accelerometer output (P1's "signal fluctuation"). [g]

    It is the largest per-axis standard deviation of the output's means over consecutive blocks of
    `average_s`; P1 settles until it is within 0.001 g (docs/p1.md, calibration step 1).
    Block means, rather than samples, are compared so that white noise at a high output rate
    (a consumer part's per-sample noise exceeds 0.001 g) does not mask a table at rest.
    """
    if time_s.size < 2:
        return float("inf")
    blocks = np.floor((time_s - time_s[0]) / average_s).astype(np.int64)
    n_blocks = int(blocks[-1]) + 1
    if n_blocks < 2:
        return float("inf")
    counts = np.bincount(blocks, minlength=n_blocks).astype(np.float64)
    used = counts > 0
    means = np.stack([np.bincount(blocks, weights=accel_mps2[:, j], minlength=n_blocks)[used]
                      / counts[used] for j in range(3)], axis=1)
    return float(means.std(axis=0).max() / units.G0_MPS2)


class RollingWindow:
    """The rows of the last `span_s` of a stream (time (n,) and values (n, k))."""

    def __init__(self, span_s: float) -> None:
        self.span_s = float(span_s)
        self._blocks: deque[tuple[_F64, _F64]] = deque()
        # the kept blocks joined, once :meth:`rows` has asked for them (None: not joined yet);
        # kept up to date by push, so a guard asking every tick joins two arrays, not hundreds
        self._joined: tuple[_F64, _F64] | None = None

    def clear(self) -> None:
        """Forget everything."""
        self._blocks.clear()
        self._joined = None

    def push(self, time_s: _F64, values: _F64) -> None:
        """Add rows and drop those older than `span_s` before the newest."""
        if time_s.size == 0:
            return
        self._blocks.append((time_s, values))
        if self._joined is not None:
            self._joined = (np.concatenate((self._joined[0], time_s)),
                            np.concatenate((self._joined[1], values)))
        newest = float(time_s[-1])
        while self._blocks and float(self._blocks[0][0][-1]) < newest - self.span_s:
            dropped = len(self._blocks.popleft()[0])
            if self._joined is not None:
                self._joined = (self._joined[0][dropped:], self._joined[1][dropped:])

    def rows(self, since_s: float | None = None) -> tuple[_F64, _F64]:
        """Return the rows kept (those at or after `since_s` when given)."""
        if not self._blocks:
            return np.zeros(0), np.zeros((0, 0))
        if self._joined is None:
            self._joined = (np.concatenate([b[0] for b in self._blocks]),
                            np.concatenate([b[1] for b in self._blocks]))
        t, v = self._joined
        keep = t >= (t[-1] - self.span_s if since_s is None else max(since_s, t[-1] - self.span_s))
        return t[keep], v[keep]

    def covers(self, start_s: float) -> bool:
        """Whether the kept rows reach back to `start_s`."""
        return bool(self._blocks) and float(self._blocks[0][0][0]) <= start_s
