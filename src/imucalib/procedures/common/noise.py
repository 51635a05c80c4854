"""The noise model of window means: fitted once on the long static records, used for all.

The overlapping Allan variance of each long static window is fitted with
σ²(τ) ≈ N²/τ + C_B + K²τ/3 (white, flicker and random-walk terms; docs/noise.md §4) and
B = √(C_B/(2 ln 2/π)) (IEEE Std 952-1997 Annex C). When a run holds several records about as
long as the longest (a P1 plan's repetitions), their fitted N², C_B and K² are averaged,
weighted by duration (:func:`estimate_noise`). The standard error of a window mean of
duration T is then the model's Allan deviation at τ = T (:func:`window_mean_se`), and the
covariance of several windows' means
:func:`~imucalib.estimation.compute_window_mean_covariance` (docs/processing-estimation.md).

A record too short to show the flicker floor (its Allan fit's longest cluster, the largest power
of two ≤ n/2 samples, below :data:`FLICKER_CORNERS_MIN` (8) flicker corners τ_c = N²/C_B of the
unit's declared noise, the τ where the white and flicker Allan variances are equal) cannot
determine the flicker and random-walk terms that the biases of a run of hours rest on. Their
Allan fit then spreads the white noise's scatter over all three terms, clipped at zero: on the
twin, four 120-s records of a tactical unit gave flicker 0.9–2.0× and the gyro's random walk
up to 37× the unit's, and reported the biases' σ 16× too large. For such records
:func:`with_declared_floor` takes, per axis, the declared (the grade's,
:func:`~imucalib.procedures.common.grade.grade_noise`) bias instability and random walk — a
Type B input (JCGM 100:2008 §4.3) — and keeps the fitted white density (docs/p1.md, "Noise
model of the window means"). Long records keep the fit unchanged.

The procedures of long records (P3, the classical tests) use instead the white-noise density
from the scatter of block means, pooled over a unit's records (:func:`block_variance`,
:func:`pooled_white_density`): N² = Σ (K_i − 1)·s_i²·τ / Σ (K_i − 1), s_i² the variance of
record i's K_i block means of length τ (1 s). Blocks much longer than the output filter's memory
keep N free of its bias, and the Allan fit's flicker and random-walk terms of one-minute records
(poorly determined, clipped at zero, so biased upwards) stay out; noise correlated over longer
times shows in the fits' χ² instead (docs/p3.md, "On the twin").

Contents
--------
:func:`estimate_noise`, :func:`with_declared_floor`, :func:`noise_records`,
:func:`longest_cluster_s`, :func:`flicker_corner_s`, :func:`window_mean_se`,
:class:`StaticWindow`, :func:`block_variance`, :func:`pooled_white_density`
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from imucalib.models.noise import NoiseModel, compute_theoretical_adev
from imucalib.processing.moments import block_means

__all__ = ["FLICKER_CORNERS_MIN", "FLICKER_FACTOR", "NOISE_RECORD_MIN_S", "StaticWindow",
           "block_variance", "estimate_noise", "flicker_corner_s", "longest_cluster_s",
           "noise_records", "pooled_white_density", "window_mean_se", "with_declared_floor"]

_F64 = NDArray[np.float64]

#: Allan plateau² of flicker noise per B² (IEEE 952): 2 ln 2/π.
FLICKER_FACTOR = 2.0 * math.log(2.0) / math.pi


class StaticWindow(Protocol):
    """What :func:`estimate_noise` reads of a window."""

    @property
    def kind(self) -> str:
        """``"static"`` for a window the fit may use."""
        ...

    @property
    def duration_s(self) -> float:
        """Length of the averaged span. [s]"""
        ...

    @property
    def allan_fit(self) -> _F64 | None:
        """Per channel (gyro x, y, z, accel x, y, z) the fitted N̂, Ĉ_B, K̂, shape (3, 6)."""
        ...


#: The shortest static record :func:`estimate_noise` fits a noise model to. [s]
NOISE_RECORD_MIN_S = 120.0

#: A record whose averaged span falls short of :data:`NOISE_RECORD_MIN_S` by no more than this
#: fraction still counts (a 120-s static step averages 119.98 s at 100 Hz: its edge samples).
_RECORD_TOLERANCE = 1e-3

#: The Allan fit's longest cluster must reach this many flicker corners (τ_max ≥ 8·τ_c: flicker
#: carries ≥ 89 % of the Allan variance there) for the record to determine the flicker floor.
#: At 4 corners the fit still comes out high: four 232-s records of a tactical accelerometer
#: (τ_max = 5.8·τ_c) gave B 1.06–1.44× the unit's on all six axes of two twin seeds. The default
#: tactical plan's 60-min static reaches 8.2 corners of the gyro's (1 kHz).
FLICKER_CORNERS_MIN = 8.0


def noise_records(windows: Sequence[StaticWindow], *,
                  min_duration_s: float = NOISE_RECORD_MIN_S) -> list[StaticWindow]:
    """Return the static records :func:`estimate_noise` pools.

    Static windows with an Allan fit lasting at least `min_duration_s` (less 0.1 %: a step of
    exactly that length, less its edge samples) [s], and at least half the longest of them.
    """
    floor = min_duration_s * (1.0 - _RECORD_TOLERANCE)
    static = [w for w in windows if w.kind == "static" and w.allan_fit is not None
              and w.duration_s >= floor]
    if not static:
        return []
    longest = max(w.duration_s for w in static)
    return [w for w in static if w.duration_s >= 0.5 * longest]


def longest_cluster_s(duration_s: float, sample_rate_hz: float) -> float:
    """Return the Allan fit's longest cluster τ_max of a record: the largest 2^k ≤ n/2 samples. [s]

    n = round(`duration_s`·`sample_rate_hz`) (at least 8), as
    :func:`~imucalib.processing.statistics.compute_window_statistics` chooses its octaves.
    """
    n = max(round(duration_s * sample_rate_hz), 8)
    return float(1 << max((n // 2).bit_length() - 1, 0)) / sample_rate_hz


def flicker_corner_s(noise: NoiseModel) -> _F64:
    """Return τ_c = N²/C_B per axis, C_B = (2 ln 2/π)·B²: where flicker equals white. [s]

    0 for an axis without flicker (nothing to determine); ∞ for flicker without white noise.
    """
    n2 = np.asarray(noise.white_density, dtype=float) ** 2
    c_b = FLICKER_FACTOR * np.asarray(noise.bias_instability, dtype=float) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        tau = np.where(c_b > 0.0, np.where(n2 > 0.0, n2 / np.where(c_b > 0.0, c_b, 1.0),
                                           np.inf), 0.0)
    return np.asarray(np.broadcast_to(tau, (3,)), dtype=np.float64)


def with_declared_floor(fitted: Mapping[str, NoiseModel], declared: Mapping[str, NoiseModel],
                        tau_max_s: float, *, corners: float = FLICKER_CORNERS_MIN,
                        source: str = "declared") -> tuple[dict[str, NoiseModel], str | None]:
    """Return the noise model with the declared flicker floor where the records cannot show it.

    An axis whose pooled records' longest Allan cluster `tau_max_s` [s] is shorter than
    `corners` flicker corners of the declared model (:func:`flicker_corner_s`) takes the
    declared bias instability and random walk, a Type B input (JCGM 100:2008 §4.3); its white
    density stays the fitted one (the record's many samples determine it). The fitted flicker
    and random walk of such an axis are not used: they are not determined (module docstring).
    The note (None when nothing changed) says which axes and why, with the fitted values set
    aside; `source` names the declared model in it.
    """
    out = dict(fitted)
    parts: list[str] = []
    for triad, fit in fitted.items():
        dec = declared.get(triad)
        if dec is None:
            continue
        tau_c = flicker_corner_s(dec)
        short = tau_max_s < corners * tau_c
        if not short.any():
            continue
        b_fit = np.broadcast_to(np.asarray(fit.bias_instability, dtype=float), (3,))
        b_dec = np.broadcast_to(np.asarray(dec.bias_instability, dtype=float), (3,))
        k_fit = np.broadcast_to(np.asarray(fit.random_walk, dtype=float), (3,))
        k_dec = np.broadcast_to(np.asarray(dec.random_walk, dtype=float), (3,))
        b = np.where(short, b_dec, b_fit)
        k = np.where(short, k_dec, k_fit)
        if np.array_equal(b, b_fit) and np.array_equal(k, k_fit):
            continue
        out[triad] = NoiseModel(white_density=fit.white_density, bias_instability=b,
                                random_walk=k)
        axes = "".join(a for a, s_ in zip("xyz", short, strict=True) if s_)
        parts.append(f"{triad} {axes} (τ_c {float(np.max(tau_c[short])):.3g} s; fitted B/declared"
                     f" {_ratios(b_fit[short], b_dec[short])}, K/declared "
                     f"{_ratios(k_fit[short], k_dec[short])})")
    if not parts:
        return out, None
    return out, (f"noise model: the static records' longest Allan cluster ({tau_max_s:.3g} s) is "
                 f"shorter than {corners:g} flicker corners τ_c = N²/C_B of the {source} noise"
                 f" for {', '.join(parts)}: the flicker floor is not determined, so these "
                 f"axes take the {source} bias instability and random walk (Type B) with the "
                 "fitted white noise")


def _ratios(fit: _F64, dec: _F64) -> str:
    """Fitted/declared per axis, "–" where nothing is declared."""
    return "/".join(f"{f / d:.2g}" if d > 0 else "–" for f, d in zip(fit, dec, strict=True))


def estimate_noise(windows: Sequence[StaticWindow], *,
                   min_duration_s: float = NOISE_RECORD_MIN_S) -> dict[str, NoiseModel]:
    """Fit gyro and accelerometer noise models to the long static records.

    Each record's overlapping Allan variance is fitted with σ²(τ) ≈ N²/τ + C_B + K²τ/3 (the
    ``allan_fit`` of :func:`~imucalib.processing.statistics.compute_window_statistics`);
    B = √(C_B/(2 ln 2/π)). The records at least half as long as the longest are pooled: their
    N², C_B and K² averaged with weights proportional to duration (each term is linear in
    the Allan variance it describes). One record's flicker and random-walk terms are uncertain
    by a factor of about two (a 600 s record at 1 kHz: B differed by 2× between four
    repetitions of the same twin run); taking just "the longest" of several equally long
    records let the last bits of their durations choose among those estimates. Empty when no
    static window lasts `min_duration_s` (:func:`noise_records`). [s]
    """
    pooled = noise_records(windows, min_duration_s=min_duration_s)
    if not pooled:
        return {}
    weights = np.array([w.duration_s for w in pooled]) / sum(w.duration_s for w in pooled)
    squares = np.array([1.0, 0.0, 1.0])[:, None]  # N and K are densities, C_B a variance
    fit = np.zeros((3, 6))
    for wt, w in zip(weights, pooled, strict=True):
        assert w.allan_fit is not None
        f = np.nan_to_num(w.allan_fit, nan=0.0)
        fit += wt * np.where(squares > 0, f * f, f)
    fit = np.where(squares > 0, np.sqrt(fit), fit)
    out = {}
    for triad, cols in (("gyro", slice(0, 3)), ("accel", slice(3, 6))):
        n, c_b, k = fit[0, cols], fit[1, cols], fit[2, cols]
        out[triad] = NoiseModel(white_density=np.maximum(n, 0.0),
                                bias_instability=np.sqrt(np.maximum(c_b, 0.0) / FLICKER_FACTOR),
                                random_walk=np.maximum(k, 0.0))
    return out


def window_mean_se(noise: Mapping[str, NoiseModel], duration_s: float) -> tuple[_F64, _F64]:
    """Return the (gyro, accel) standard errors of a window mean of `duration_s` [s].

    The noise model's Allan deviation at τ = duration (at least 1 ms), floored at 1e-300 so a
    weight never divides by zero. [rad/s], [m/s²]
    """
    tau = np.array([max(duration_s, 1e-3)])
    gyro = compute_theoretical_adev(noise["gyro"], tau)[0]
    accel = compute_theoretical_adev(noise["accel"], tau)[0]
    return np.maximum(gyro, 1e-300), np.maximum(accel, 1e-300)


def block_variance(values: NDArray[np.float64], period_s: float, block_s: float
                   ) -> tuple[int, _F64]:
    """Return (K − 1, s²·τ) of the K block means of length τ of each column (module docstring).

    τ is `block_s` rounded to whole sample periods `period_s`; fewer than three blocks give
    (0, NaN). s²·τ estimates N², the white-noise density squared, per column.
    """
    per_block = max(round(block_s / period_s), 1)
    cols = values.reshape(values.shape[0], -1)
    k = cols.shape[0] // per_block
    if k < 3:
        return 0, np.full(cols.shape[1], math.nan)
    means = block_means(cols, per_block)  # the reshaped mean(axis=1), bit for bit
    return k - 1, np.asarray(np.var(means, axis=0, ddof=1) * per_block * period_s,
                             dtype=np.float64)


def pooled_white_density(blocks: Sequence[tuple[int, _F64]]) -> _F64 | None:
    """Return N per column pooled over records' :func:`block_variance`, or None if none counts.

    N² = Σ (K_i − 1)·s_i²·τ / Σ (K_i − 1) over the records with blocks (module docstring).
    """
    dof = np.array([b[0] for b in blocks], dtype=float)
    ok = dof > 0
    if not ok.any():
        return None
    var = np.array([np.nan_to_num(np.asarray(b[1], dtype=float)) for b in blocks])
    return np.asarray(np.sqrt(np.maximum(dof[ok] @ var[ok] / dof[ok].sum(), 1e-300)),
                      dtype=np.float64)
