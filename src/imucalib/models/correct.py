"""Apply a calibration to data: measured → corrected (estimated true) gyro and accelerometer.

Contents
--------
:func:`correct_imu`
    Array form: ``(gyro_rps, accel_mps2)`` in, corrected pair out.
:func:`correct_imu_frame`
    DataFrame form over the canonical columns (``gyro_x_rps`` … ``accel_z_mps2``).

Both refuse data whose units differ from the result's ``input_units`` (a result made from SI data
applied to raw counts is an error, not a silent mistake). The accelerometer is corrected first
(exact inverse of y = b + (I + M)·x); a gyro g-sensitivity is then removed with the corrected
specific force (:func:`~imucalib.models.triad.correct_triad`).

Temperature
-----------
A result with temperature models (format version 3) is applied sample by sample: every
parameter is evaluated at the sample's temperature T, its rate Ṫ and leg ℓ
(:meth:`~imucalib.models.result.CalibrationResult.values_at`, docs/processing-estimation.md,
Eq. (T1)) and the same exact inverse is solved per sample. :func:`correct_imu_frame` takes T from
the ``temperature_degc`` column, Ṫ from :class:`TemperatureRate` (the least-squares slope of T
over the trailing :data:`RATE_WINDOW_S`, state carried from chunk to chunk) and ℓ from
:func:`temperature_leg` (the sign of Ṫ outside a dead band of :data:`LEG_DEAD_BAND_DEGC_PS`).
:data:`EXTRAPOLATION_MARGIN_DEGC` is how far outside the fitted temperature range ``imucalib
apply`` corrects without a warning.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib._checks import as_samples3
from imucalib.conventions import ACCEL_COLUMNS, AXES, GYRO_COLUMNS, TEMPERATURE_COLUMN, TIME_COLUMN
from imucalib.errors import InvalidInputError, UnitError
from imucalib.models.result import CalibrationResult
from imucalib.models.triad import correct_triad

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "EXTRAPOLATION_MARGIN_DEGC",
    "LEG_DEAD_BAND_DEGC_PS",
    "RATE_WINDOW_S",
    "TemperatureRate",
    "correct_imu",
    "correct_imu_frame",
    "temperature_leg",
]

_F64 = NDArray[np.float64]

#: Dead band of the leg rule: |Ṫ| at or below it counts as neither heating nor cooling. [°C/s]
LEG_DEAD_BAND_DEGC_PS: Final = 0.002
#: Length of the trailing window over which Ṫ is the least-squares slope of T. [s]
RATE_WINDOW_S: Final = 60.0
#: How far outside a result's fitted temperature range data count as extrapolated. [°C]
EXTRAPOLATION_MARGIN_DEGC: Final = 5.0
#: Samples per block of :class:`TemperatureRate` (keeps its running sums well conditioned).
_RATE_BLOCK: Final = 4096


def temperature_leg(temperature_rate_degc_ps: ArrayLike,
                    dead_band_degc_ps: float = LEG_DEAD_BAND_DEGC_PS) -> _F64:
    """Return the hysteresis leg ℓ of each sample from its temperature rate.

    ``ℓ = sign(Ṫ)`` where ``|Ṫ| > dead band``, else ``ℓ = 0``: +1 on a heating leg, −1 on a
    cooling leg, 0 (the mean of both legs, h·ℓ = 0 in Eq. (T1) of
    docs/processing-estimation.md) while the temperature is steady within the dead band.

    Parameters
    ----------
    temperature_rate_degc_ps : float or array_like
        Ṫ. [°C/s]
    dead_band_degc_ps : float
        The dead band, ≥ 0. [°C/s]

    Returns
    -------
    ndarray
        ℓ ∈ {−1.0, 0.0, +1.0}, the shape of the rate (at least one dimension).

    Raises
    ------
    InvalidInputError
        A rate that is not finite, or a negative or non-finite dead band.
    """
    rate = np.atleast_1d(np.asarray(temperature_rate_degc_ps, dtype=np.float64))
    if not np.all(np.isfinite(rate)):
        raise InvalidInputError("`temperature_rate_degc_ps` must be finite")
    band = float(dead_band_degc_ps)
    if not (np.isfinite(band) and band >= 0.0):
        raise InvalidInputError(f"`dead_band_degc_ps` must be finite and ≥ 0; got {band!r}")
    return np.where(np.abs(rate) > band, np.sign(rate), 0.0)


class TemperatureRate:
    """Ṫ of a temperature record fed in chunks: a trailing-window least-squares slope.

    For sample i, Ṫ_i is the slope of the straight line fitted by least squares to the samples
    (t_j, T_j) with t_i − W < t_j ≤ t_i (W = `window_s`), earlier chunks included: the state kept
    between calls is the last W seconds of samples (bounded memory). The estimate is causal and
    lags a changing rate by about W/2. Edge: until the window spans at least W/2 (the start of
    the record, or after a gap longer than W), Ṫ_i = 0, so the leg is 0 there
    (:func:`temperature_leg`).

    Parameters
    ----------
    window_s : float
        W, > 0. [s]

    Raises
    ------
    InvalidInputError
        A window that is not positive and finite.
    """

    def __init__(self, window_s: float = RATE_WINDOW_S) -> None:
        w = float(window_s)
        if not (np.isfinite(w) and w > 0.0):
            raise InvalidInputError(f"`window_s` must be finite and > 0; got {window_s!r}")
        self.window_s = w
        self._t: _F64 = np.empty(0)
        self._temp: _F64 = np.empty(0)

    def __call__(self, time_s: ArrayLike, temperature_degc: ArrayLike) -> _F64:
        """Return Ṫ [°C/s] at each sample of the next chunk (times [s], temperatures [°C]).

        Raises
        ------
        InvalidInputError
            Arrays of different shapes or not one-dimensional, non-finite values, or times that
            decrease (within the chunk or from the previous one).
        """
        t = np.asarray(time_s, dtype=np.float64)
        temp = np.asarray(temperature_degc, dtype=np.float64)
        if t.ndim != 1 or t.shape != temp.shape:
            raise InvalidInputError(f"`time_s` and `temperature_degc` must have the same shape "
                                    f"(n,); got {t.shape} and {temp.shape}")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(temp))):
            raise InvalidInputError("`time_s` and `temperature_degc` must be finite")
        out = np.empty(t.size)
        for start in range(0, t.size, _RATE_BLOCK):
            stop = start + _RATE_BLOCK
            out[start:stop] = self._block(t[start:stop], temp[start:stop])
        return out

    def _block(self, t_new: _F64, temp_new: _F64) -> _F64:
        t = np.concatenate([self._t, t_new])
        temp = np.concatenate([self._temp, temp_new])
        if np.any(np.diff(t) < 0):
            raise InvalidInputError("`time_s` must not decrease (within a chunk or from the "
                                    "previous chunk)")
        m = self._t.size
        x, y = t - t[0], temp - temp[0]  # a local origin keeps the sums small
        zero = np.zeros(1)
        s1 = np.concatenate([zero, np.cumsum(np.ones_like(x))])
        sx = np.concatenate([zero, np.cumsum(x)])
        sy = np.concatenate([zero, np.cumsum(y)])
        sxx = np.concatenate([zero, np.cumsum(x * x)])
        sxy = np.concatenate([zero, np.cumsum(x * y)])
        i = np.arange(m, t.size)
        j = np.searchsorted(t, t[i] - self.window_s, side="right")
        n = s1[i + 1] - s1[j]
        mx, my = (sx[i + 1] - sx[j]) / n, (sy[i + 1] - sy[j]) / n
        vxx = (sxx[i + 1] - sxx[j]) / n - mx * mx
        vxy = (sxy[i + 1] - sxy[j]) / n - mx * my
        enough = (t[i] - t[j]) >= 0.5 * self.window_s
        rate = np.where(enough, vxy / np.where(enough & (vxx > 0), vxx, 1.0), 0.0)
        keep = t > t[-1] - self.window_s
        self._t, self._temp = t[keep], temp[keep]
        return rate


def _check_units(result: CalibrationResult, gyro_unit: str, accel_unit: str) -> None:
    for triad, unit in (("gyro", gyro_unit), ("accel", accel_unit)):
        expected = result.input_units.get(triad)
        if result.has_triad(triad) and expected is not None and unit != expected:
            raise UnitError(f"the result for {result.sensor_id} was made from {triad} data in "
                            f"{expected!r}; the data given are in {unit!r}")


def correct_imu(gyro_rps: ArrayLike | None, accel_mps2: ArrayLike | None,
                result: CalibrationResult, *, gyro_unit: str = "rad/s",
                accel_unit: str = "m/s^2", temperature_degc: ArrayLike | None = None,
                temperature_rate_degc_ps: ArrayLike | None = None,
                leg: ArrayLike | None = None) -> tuple[_F64 | None, _F64 | None]:
    """Correct measured outputs with a calibration result.

    Parameters
    ----------
    gyro_rps : array_like, shape (n, 3), or None
        Measured gyro output, sensor frame. [rad/s]
    accel_mps2 : array_like, shape (n, 3), or None
        Measured accelerometer output, sensor frame. [m/s²]
    result : CalibrationResult
        The calibration; a triad it does not calibrate is passed through unchanged.
    gyro_unit, accel_unit : str
        The units the data are in; they must equal ``result.input_units``.
    temperature_degc : float or array_like, shape (n,), optional
        The sensor's temperature T per sample; required when the result has temperature
        models, ignored otherwise. [°C]
    temperature_rate_degc_ps : float or array_like, shape (n,), optional
        Ṫ per sample; 0 when omitted. [°C/s]
    leg : float or array_like, shape (n,), optional
        ℓ ∈ {−1, 0, +1} per sample; when omitted, :func:`temperature_leg` of the rate.

    Returns
    -------
    gyro_rps, accel_mps2 : ndarray, shape (n, 3), or None
        Corrected (estimated true) angular rate [rad/s] and specific force [m/s²], body frame.

    Raises
    ------
    UnitError
        If the data units differ from the result's.
    InvalidInputError
        For arrays of the wrong shape, non-finite values (temperatures included), a gyro
        g-sensitivity without accelerometer data, or a result with temperature models and no
        temperature.

    Notes
    -----
    With temperature models each sample is corrected with the parameters at its (T, Ṫ, ℓ),
    Eq. (T1) of docs/processing-estimation.md: x = (I + M(T))⁻¹·h⁻¹(y − b(T) − G(T)·f), with
    h(u)_i = u_i + K2_i(T)·u_i² + K3_i(T)·u_i³ inverted on its branch through 0: in closed
    form without K3 (Eq. (C3) of docs/c-runtime.md), by Newton's method from that root with
    K3 (Eq. (C3′)); or x_i = y_i/K_i(T) − b_i(T) for a per-axis result. Without temperature
    models :func:`~imucalib.models.triad.correct_triad` inverts the same h (Newton from the
    same start, safeguarded by bisection).
    """
    _check_units(result, gyro_unit, accel_unit)
    accel = None if accel_mps2 is None else as_samples3(accel_mps2, "accel_mps2")
    gyro = None if gyro_rps is None else as_samples3(gyro_rps, "gyro_rps")
    if accel is not None and gyro is not None and accel.shape != gyro.shape:
        raise InvalidInputError(f"`gyro_rps` and `accel_mps2` must have the same shape; got "
                                f"{gyro.shape} and {accel.shape}")
    if result.temperature_models:
        values = _values_per_sample(result, gyro if accel is None else accel, temperature_degc,
                                    temperature_rate_degc_ps, leg)
        if accel is not None and result.has_triad("accel"):
            accel = _correct_per_sample(result, "accel", values, accel, None)
        if gyro is not None and result.has_triad("gyro"):
            gyro = _correct_per_sample(result, "gyro", values, gyro, accel)
        return gyro, accel
    if accel is not None and result.has_triad("accel"):
        zeros = np.zeros_like(accel)
        accel = correct_triad(result.triad_model("accel"), accel, rate_b_rps=zeros,
                              angular_accel_b_rps2=zeros)
    if gyro is not None and result.has_triad("gyro"):
        model = result.triad_model("gyro")
        if np.any(model.g_sensitivity != 0.0) and accel is None:
            raise InvalidInputError("this result has a gyro g-sensitivity: correcting the gyro "
                                    "needs the accelerometer data too")
        gyro = correct_triad(model, gyro, specific_force_b_mps2=accel)
    return gyro, accel


def _values_per_sample(result: CalibrationResult, samples: _F64 | None,
                       temperature_degc: ArrayLike | None,
                       temperature_rate_degc_ps: ArrayLike | None, leg: ArrayLike | None
                       ) -> _F64:
    """Return every parameter at each sample's (T, Ṫ, ℓ), shape (n, k)."""
    n = 0 if samples is None else samples.shape[0]
    if temperature_degc is None:
        raise InvalidInputError(
            f"`temperature_degc` is required: the result for {result.sensor_id} has temperature "
            f"models of {', '.join(tm.name for tm in result.temperature_models)}")

    def per_sample(value: ArrayLike, name: str) -> _F64:
        arr = np.atleast_1d(np.asarray(value, dtype=np.float64))
        if arr.ndim != 1 or arr.size not in (1, n):
            raise InvalidInputError(f"`{name}` must be a scalar or have shape ({n},), one per "
                                    f"sample; got {arr.shape}")
        bad = int(np.count_nonzero(~np.isfinite(arr)))
        if bad:
            raise InvalidInputError(f"`{name}` must be finite; got {bad} NaN or infinite "
                                    "value(s)")
        return np.broadcast_to(arr, (n,))

    temp = per_sample(temperature_degc, "temperature_degc")
    rate = np.zeros(n) if temperature_rate_degc_ps is None else per_sample(
        temperature_rate_degc_ps, "temperature_rate_degc_ps")
    ell = temperature_leg(rate) if leg is None else per_sample(leg, "leg")
    if not np.all(np.isin(ell, (-1.0, 0.0, 1.0))):
        raise InvalidInputError("`leg` must be -1, 0 or +1")
    values, _ = result.values_at(temp, rate, ell)
    return values


def _correct_per_sample(result: CalibrationResult, triad: str, values: _F64, y: _F64,
                        specific_force: _F64 | None) -> _F64:
    """Invert y = b + h((I + M)·x) + G·f (or y_i = K_i·(x_i + b_i)), per-sample parameters.

    h(u)_i = u_i + K2_i·u_i² + K3_i·u_i³ (Eq. (C2)); inverted by Eq. (C3), or (C3′) with K3.
    """
    index = {name: i for i, name in enumerate(result.param_names)}

    def cols(names: list[str]) -> _F64:
        return values[:, [index[name] for name in names]]

    n = y.shape[0]
    if result.model == "per-axis":
        k = cols([f"{triad}_K_{a}" for a in AXES])
        if np.any(k == 0.0):
            raise InvalidInputError(f"the {triad} scale factor K is zero at some temperature")
        return np.asarray(y / k - cols([f"{triad}_b_{a}" for a in AXES]), dtype=np.float64)
    rest = y - cols([f"{triad}_bias_{a}" for a in AXES])
    if f"{triad}_G_xx" in index:
        g = cols([f"{triad}_G_{i}{j}" for i in AXES for j in AXES]).reshape(n, 3, 3)
        if np.any(g != 0.0):
            if specific_force is None:
                raise InvalidInputError("this result has a gyro g-sensitivity: correcting the "
                                        "gyro needs the accelerometer data too")
            rest = rest - np.einsum("nij,nj->ni", g, specific_force)
    k2, k3 = (cols([f"{triad}_{symbol}_{a}" for a in AXES]) if f"{triad}_{symbol}_x" in index
              else None for symbol in ("K2", "K3"))
    if k3 is not None and np.any(k3 != 0.0):
        rest = _k3_inverse(np.zeros_like(k3) if k2 is None else k2, k3, rest, triad)
    elif k2 is not None:
        rest = _k2_inverse(k2, rest, triad)
    a = cols([f"{triad}_M_{i}{j}" for i in AXES for j in AXES]).reshape(n, 3, 3) + np.eye(3)
    try:
        return np.asarray(np.linalg.solve(a, rest[..., None])[..., 0], dtype=np.float64)
    except np.linalg.LinAlgError as exc:
        raise InvalidInputError(f"I + M of the {triad} triad is singular at some "
                                "temperature") from exc


def _k2_inverse(k2: _F64, r: _F64, triad: str) -> _F64:
    """Solve u + K2·u² = r per axis on the branch through 0: u = 2r / (1 + √(1 + 4·K2·r)).

    The root :func:`~imucalib.models.triad.correct_triad` converges to when K3, Koq and the
    asymmetry are 0 (docs/c-runtime.md, Eq. (C3)).
    """
    if not np.any(k2 != 0.0):
        return r
    disc = 1.0 + 4.0 * k2 * r
    bad = ~(disc >= 0.0)
    if np.any(bad):
        raise InvalidInputError(
            f"cannot invert the {triad} K2 model u + K2·u² for {int(np.count_nonzero(bad))} "
            f"value(s) (largest |measured - bias| {float(np.max(np.abs(r[bad]))):g}): outside "
            "its monotonic range")
    return np.asarray(2.0 * r / (1.0 + np.sqrt(disc)), dtype=np.float64)


#: Most Newton steps of :func:`_k3_inverse` (from the K2 root it needs two or three). [–]
K3_MAX_ITER: Final = 20
#: :func:`_k3_inverse` has converged where a Newton step is at most this times |u|. [–]
_K3_STEP_RTOL: Final = 4.0 * float(np.finfo(np.float64).eps)


def _k3_inverse(k2: _F64, k3: _F64, r: _F64, triad: str) -> _F64:
    """Solve u + K2·u² + K3·u³ = r per axis on the branch through 0 (Eq. (C3′), docs/c-runtime.md).

    Newton's method from the closed-form root of the quadratic part (Eq. (C3), with
    1 + 4·K2·r clipped at 0), at most :data:`K3_MAX_ITER` steps, each stopping where a step is
    within 4 ε·|u|. An axis whose K3 is 0 keeps the closed-form root (no step: bit for bit what
    :func:`_k2_inverse` gives). The root is accepted only on the branch through 0: the slope
    1 + 2·K2·t + 3·K3·t² is > 0 for every t between 0 and u. It is the root
    :func:`~imucalib.models.triad.correct_triad` converges to (Koq and the asymmetry being 0).

    Raises
    ------
    InvalidInputError
        A value whose Newton iteration does not converge, or whose root leaves the branch
        through 0 (outside the range where h is monotonic); also, on an axis with K3 = 0,
        1 + 4·K2·r < 0 (as :func:`_k2_inverse`).
    """
    disc = 1.0 + 4.0 * k2 * r
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        u = 2.0 * r / (1.0 + np.sqrt(np.maximum(disc, 0.0)))
        active = k3 != 0.0
        for _ in range(K3_MAX_ITER):
            slope = 1.0 + u * (2.0 * k2 + 3.0 * k3 * u)
            step = np.where(active, (u + u * u * (k2 + k3 * u) - r) / slope, 0.0)
            u = u - step
            active &= ~(np.abs(step) <= _K3_STEP_RTOL * np.abs(u))
            if not active.any():
                break
        # g'(t) = 1 + 2 K2 t + 3 K3 t² > 0 on [0, u]: at both ends and at the vertex inside
        lowest = np.minimum(1.0, 1.0 + u * (2.0 * k2 + 3.0 * k3 * u))
        vertex = np.where(k3 != 0.0, -k2 / (3.0 * np.where(k3 != 0.0, k3, 1.0)), 0.0)
        inside = (k3 > 0.0) & (vertex * (vertex - u) < 0.0)
        lowest = np.where(inside, np.minimum(lowest, 1.0 + k2 * vertex), lowest)
        failed = active | ~(lowest > 0.0) | ((k3 == 0.0) & ~(disc >= 0.0))
    if np.any(failed):
        raise InvalidInputError(
            f"cannot invert the {triad} K2/K3 model u + K2·u² + K3·u³ for "
            f"{int(np.count_nonzero(failed))} value(s) (largest |measured - bias| "
            f"{float(np.max(np.abs(r[failed]))):g}): outside its monotonic range (the root "
            f"leaves the branch through 0) or no convergence in {K3_MAX_ITER} Newton steps")
    return np.asarray(u, dtype=np.float64)


def correct_imu_frame(df: pd.DataFrame, result: CalibrationResult, *,
                      temperature_rate: TemperatureRate | None = None) -> pd.DataFrame:
    """Correct the canonical columns of a DataFrame (others are kept as they are).

    Parameters
    ----------
    df : pandas.DataFrame
        The canonical columns, indexed by ``time_s`` (or with a ``time_s`` column), with a
        ``temperature_degc`` column when the result has temperature models.
    result : CalibrationResult
        The calibration.
    temperature_rate : TemperatureRate, optional
        Ṫ's estimator; pass the same one to each chunk of a record so that its window runs on
        across them. A new one (:data:`RATE_WINDOW_S`) when omitted.

    Returns
    -------
    pandas.DataFrame
        A copy with the canonical columns corrected.

    Raises
    ------
    InvalidInputError
        If a triad's columns are only partly present, or the result has temperature models and
        the frame has no ``temperature_degc`` column, NaN temperatures or no times.
    UnitError
        If ``df.attrs["units"]`` names units that differ from the result's.
    """
    units = df.attrs.get("units", {})
    out = df.copy()
    cols = {}
    for triad, names in (("gyro", GYRO_COLUMNS), ("accel", ACCEL_COLUMNS)):
        present = [c for c in names if c in df.columns]
        if present and len(present) != 3:
            raise InvalidInputError(f"{triad} columns must all be present ({list(names)}); got "
                                    f"{present}")
        cols[triad] = df[list(names)].to_numpy(dtype=np.float64) if present else None
    gyro_unit = units.get(GYRO_COLUMNS[0], "rad/s")
    accel_unit = units.get(ACCEL_COLUMNS[0], "m/s^2")
    temperature: dict[str, _F64] = {}
    if result.temperature_models:
        temperature = _frame_temperature(df, result, temperature_rate)
    gyro, accel = correct_imu(cols["gyro"], cols["accel"], result, gyro_unit=gyro_unit,
                              accel_unit=accel_unit, **temperature)
    if gyro is not None:
        out[list(GYRO_COLUMNS)] = gyro
    if accel is not None:
        out[list(ACCEL_COLUMNS)] = accel
    return out


def _frame_temperature(df: pd.DataFrame, result: CalibrationResult,
                       estimator: TemperatureRate | None) -> dict[str, _F64]:
    """T and Ṫ of a frame for a result with temperature models (``correct_imu`` arguments)."""
    if TEMPERATURE_COLUMN not in df.columns:
        raise InvalidInputError(
            f"the result for {result.sensor_id} has temperature models; the data have no "
            f"{TEMPERATURE_COLUMN!r} column (the sensor's temperature) to apply them with")
    temp = df[TEMPERATURE_COLUMN].to_numpy(dtype=np.float64)
    bad = ~np.isfinite(temp)
    if bad.any():
        raise InvalidInputError(
            f"{int(bad.sum())} of {temp.size} temperatures ({TEMPERATURE_COLUMN!r}) are NaN or "
            f"infinite (the first at row {int(np.argmax(bad))}); the result's temperature "
            "models need every sample's temperature")
    if df.index.name == TIME_COLUMN:
        time = df.index.to_numpy(dtype=np.float64)
    elif TIME_COLUMN in df.columns:
        time = df[TIME_COLUMN].to_numpy(dtype=np.float64)
    else:
        raise InvalidInputError(f"the data need times ({TIME_COLUMN!r}) to estimate the "
                                "temperature rate")
    rate = (estimator or TemperatureRate())(time, temp)
    return {"temperature_degc": temp, "temperature_rate_degc_ps": rate}
