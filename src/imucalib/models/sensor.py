"""The output stage of a sensor triad: bandwidth low-pass, range saturation, resolution.

Contents
--------
:class:`SensorSpec`
    Range, resolution (bits or LSB) and bandwidth of one triad.
:class:`OutputChain`
    Stateful: applies the stage chunk by chunk, keeping the filter state.
:class:`OutputChainResult`
    Output values and per-sample saturation flags.
:func:`apply_output_chain`
    Pure wrapper: one record through a fresh chain.

Model
-----
Applied in this order at the output data rate fs, per axis (SI in, SI out):

1. **Low-pass**: a 2nd-order Butterworth filter with its −3 dB point at `bandwidth_hz`
   (``scipy.signal.butter(2, bandwidth_hz, fs=fs, output="sos")``, bilinear transform with
   pre-warping, so the −3 dB point is exact). The filter starts in the steady state of the first
   sample (no start-up transient) and keeps its state across chunks, so a record processed in
   chunks equals the record processed at once, bit for bit.
2. **Saturation** at ±`range` and 3. **quantization** to the grid k·LSB by round-half-to-even
   (``numpy.rint``; the error is uniform in ±LSB/2 and unbiased), done together as
   ``clip(rint(x/LSB), k_min, k_max)·LSB``. With `resolution_bits` = b the codes are those of a
   b-bit two's-complement converter, LSB = 2·range/2^b and k = −2^(b−1) … 2^(b−1) − 1, so the
   outputs span [−range, range − LSB]; with `lsb` alone they are symmetric, ±⌊range/LSB⌋; without
   a LSB the values are clipped at ±range.

A sample is flagged saturated on an axis when it was clipped: its filtered value rounds to a code
beyond the converter's codes, or (without quantization) lies beyond ±range.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib._checks import as_samples3, check_positive
from imucalib.errors import ConfigurationError, InvalidInputError

__all__ = ["OutputChain", "OutputChainResult", "SensorSpec", "apply_output_chain"]


@dataclass(frozen=True)
class SensorSpec:
    """Output stage of one triad.

    Parameters
    ----------
    range : float, optional
        Full scale ± [SI: rad/s | m/s²]; outputs clip there (saturation). None: no limit.
    resolution_bits : int, optional
        Converter word length b; LSB = 2·range/2^b (requires `range`).
    lsb : float, optional
        Alternatively the LSB directly [SI]; not together with `resolution_bits`.
    bandwidth_hz : float, optional
        −3 dB frequency of a 2nd-order Butterworth low-pass applied at the output data rate;
        must be below half the output data rate (checked by :class:`OutputChain`). [Hz]

    Raises
    ------
    ConfigurationError
        If a value is not positive and finite, `resolution_bits` is given without `range`, or
        both `resolution_bits` and `lsb` are given.
    """

    range: float | None = None
    resolution_bits: int | None = None
    lsb: float | None = None
    bandwidth_hz: float | None = None

    def __post_init__(self) -> None:
        for name in ("range", "lsb", "bandwidth_hz"):
            value = getattr(self, name)
            if value is not None:
                try:
                    checked = check_positive(value, name)
                except InvalidInputError as exc:
                    raise ConfigurationError(str(exc)) from None
                object.__setattr__(self, name, checked)
        bits = self.resolution_bits
        if bits is not None:
            if isinstance(bits, bool) or not isinstance(bits, int | np.integer) or not (
                1 <= bits <= 64
            ):
                raise ConfigurationError(
                    f"`resolution_bits` must be an integer in 1 … 64; got {bits!r}"
                )
            if self.range is None:
                raise ConfigurationError(
                    f"`resolution_bits` ({bits}) requires `range` (LSB = 2·range/2^bits); "
                    "got range None"
                )
            if self.lsb is not None:
                raise ConfigurationError(
                    f"give `resolution_bits` ({bits}) or `lsb` ({self.lsb}), not both"
                )
            object.__setattr__(self, "resolution_bits", int(bits))

    @property
    def effective_lsb(self) -> float | None:
        """The quantization step [SI], or None when the output is not quantized."""
        if self.resolution_bits is not None and self.range is not None:
            return 2.0 * self.range / 2.0**self.resolution_bits
        return self.lsb

    def code_limits(self) -> tuple[float, float] | None:
        """Return the lowest and highest output codes (in LSB), or None if unlimited."""
        lsb = self.effective_lsb
        if lsb is None or self.range is None:
            return None
        if self.resolution_bits is not None:
            top = 2.0 ** (self.resolution_bits - 1)
            return -top, top - 1.0
        top = math.floor(self.range / lsb * (1 + 1e-12))
        return -float(top), float(top)


@dataclass(frozen=True, eq=False)
class OutputChainResult:
    """What the output stage delivers.

    Parameters
    ----------
    values : ndarray, shape (n, 3)
        Filtered, saturated and quantized outputs [SI].
    saturated : ndarray of bool, shape (n, 3)
        True where an axis was clipped.
    """

    values: NDArray[np.float64]
    saturated: NDArray[np.bool_]


class OutputChain:
    """Apply a :class:`SensorSpec` chunk by chunk, keeping the low-pass state.

    Parameters
    ----------
    spec : SensorSpec
        The output stage.
    sample_rate_hz : float
        Output data rate fs. [Hz]

    Raises
    ------
    InvalidInputError
        If `spec` is not a SensorSpec or `sample_rate_hz` is not > 0.
    ConfigurationError
        If ``spec.bandwidth_hz`` ≥ fs/2.
    """

    def __init__(self, spec: SensorSpec, sample_rate_hz: float) -> None:
        if not isinstance(spec, SensorSpec):
            raise InvalidInputError(f"`spec` must be a SensorSpec; got {type(spec).__name__}")
        fs = check_positive(sample_rate_hz, "sample_rate_hz")
        if spec.bandwidth_hz is not None and spec.bandwidth_hz >= fs / 2:
            raise ConfigurationError(
                f"`bandwidth_hz` must be below half the output data rate ({fs / 2} Hz); "
                f"got {spec.bandwidth_hz} Hz"
            )
        self.spec = spec
        self.sample_rate_hz = fs
        self._sos: NDArray[np.float64] | None = None
        self._zi: NDArray[np.float64] | None = None

    def process(self, values: ArrayLike) -> OutputChainResult:
        """Pass the next chunk of samples through the output stage.

        Parameters
        ----------
        values : array_like, shape (n, 3)
            Sensor outputs before the output stage [SI], continuing the previous chunk.

        Returns
        -------
        OutputChainResult
            Delivered values and saturation flags, both (n, 3).

        Raises
        ------
        InvalidInputError
            If `values` is not finite or not of shape (n, 3).
        """
        x = _as_finite_samples(values)
        spec = self.spec
        if x.shape[0] == 0:
            return OutputChainResult(values=x.copy(), saturated=np.zeros(x.shape, dtype=bool))
        if spec.bandwidth_hz is not None:
            from scipy import signal  # imported when used: importing this module stays cheap

            if self._sos is None:
                self._sos = signal.butter(2, spec.bandwidth_hz, fs=self.sample_rate_hz,
                                          output="sos")
                # steady state for a constant input equal to the first sample: shape (1, 2, 3)
                self._zi = signal.sosfilt_zi(self._sos)[:, :, None] * x[0]
            x, self._zi = signal.sosfilt(self._sos, x, axis=0, zi=self._zi)  # a new array
        else:
            x = x.copy()
        limits = spec.code_limits()
        lsb = spec.effective_lsb
        if lsb is not None:
            np.divide(x, lsb, out=x)
            np.rint(x, out=x)
            if limits is None:
                saturated = np.zeros(x.shape, dtype=bool)
            else:
                lo, hi = limits
                saturated = x < lo
                saturated |= x > hi
                np.clip(x, lo, hi, out=x)
            np.multiply(x, lsb, out=x)
        elif spec.range is not None:
            saturated = x < -spec.range
            saturated |= x > spec.range
            np.clip(x, -spec.range, spec.range, out=x)
        else:
            saturated = np.zeros(x.shape, dtype=bool)
        return OutputChainResult(values=x, saturated=saturated)


def _as_finite_samples(values: ArrayLike) -> NDArray[np.float64]:
    """Return `values` as float64 (n, 3) without copying when possible; reject NaN and inf."""
    try:
        x = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        return as_samples3(values, "values")  # raises the standard message
    with np.errstate(invalid="ignore", over="ignore"):
        total = float(x.sum()) if x.ndim == 2 and x.shape[1] == 3 else math.nan
    if not math.isfinite(total):
        return as_samples3(x, "values")  # raises, or copes with a finite sum overflow
    return x


def apply_output_chain(values: ArrayLike, spec: SensorSpec,
                       sample_rate_hz: float) -> OutputChainResult:
    """Pass a whole record through a fresh :class:`OutputChain`.

    Parameters
    ----------
    values : array_like, shape (n, 3)
        Sensor outputs before the output stage. [SI]
    spec : SensorSpec
        The output stage.
    sample_rate_hz : float
        Output data rate. [Hz]

    Returns
    -------
    OutputChainResult
        Delivered values and saturation flags.
    """
    return OutputChain(spec, sample_rate_hz).process(values)
