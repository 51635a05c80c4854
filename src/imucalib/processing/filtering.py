"""Zero-phase Butterworth low-pass filter (P1 processing rule 2, docs/p1.md).

Contents
--------
:class:`LowpassResult`
    Filtered samples, the design cut-off and the effective −3 dB frequency of the two passes.
:func:`lowpass_zero_phase`
    Butterworth design (second-order sections) run forward and backward.
:func:`compute_effective_cutoff_hz`
    The −3 dB frequency of the forward–backward response, Eq. (2).

Method
------
A digital Butterworth low-pass of order N and cut-off f_c (``scipy.signal.butter``, bilinear
transform with pre-warping, second-order sections for numerical robustness) has [1]_::

    |H(f)|² = 1 / (1 + (tan(πf/f_s) / tan(πf_c/f_s))^{2N})                      (1)

Running it forward then backward (what ``scipy.signal.sosfiltfilt`` does, odd extension at both
ends; here its values bit for bit from the compiled :mod:`~imucalib.processing._sos_kernel`)
cancels the phase exactly — no delay, no phase distortion, as P1 requires — but *squares*
the magnitude: the overall response is |H(f)|², −6 dB (gain ½) at f_c, with roll-off 2N·20 dB
per decade. Its −3 dB point is lower than f_c::

    f_3dB = (f_s/π)·atan( tan(πf_c/f_s) · (√2 − 1)^{1/(2N)} )                   (2)

(0.896·f_c for N = 4 well below Nyquist). The cut-off is set as a fraction of the IMU's
bandwidth, 1/5–1/3 by P1's rule 2 (default ¼); other fractions need ``allow_any_fraction=True``.
The filter has unit gain at DC, so window means are unchanged up to end effects; the first and
last ~1/f_c seconds carry the start-up transient of the odd extension — filter whole records and
cut windows afterwards.

References
----------
.. [1] A. V. Oppenheim and R. W. Schafer, *Discrete-Time Signal Processing*, 3rd ed., 2010,
   §7.3 (Butterworth design by bilinear transformation), §5.1 / problem 5.64 (zero-phase
   forward–backward filtering).
.. [2] F. Gustafsson, "Determining the initial states in forward-backward filtering", IEEE Trans.
   Signal Process. 44(4):988–992, 1996.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import signal

from imucalib._checks import check_positive
from imucalib.errors import InvalidInputError
from imucalib.processing._common import as_columns, restore_shape
from imucalib.processing._sos_kernel import sosfiltfilt_columns

__all__ = [
    "SPEC_CUTOFF_FRACTION_RANGE",
    "LowpassResult",
    "compute_effective_cutoff_hz",
    "lowpass_zero_phase",
]

#: Allowed cut-off / bandwidth fractions of P1 processing rule 2 (docs/p1.md).
SPEC_CUTOFF_FRACTION_RANGE: tuple[float, float] = (1.0 / 5.0, 1.0 / 3.0)
_MAX_ORDER = 10


@dataclass(frozen=True, eq=False)
class LowpassResult:
    """Result of :func:`lowpass_zero_phase`.

    Attributes
    ----------
    values : ndarray, shape like the input
        Filtered samples (read-only). [units of the input]
    cutoff_hz : float
        Design cut-off f_c of each pass (−3 dB of one pass, −6 dB overall). [Hz]
    effective_cutoff_hz : float
        −3 dB frequency of the forward–backward response, Eq. (2). [Hz]
    order : int
        Order N of each pass (the overall response has order 2N).
    sample_rate_hz : float
        Sample rate used. [Hz]
    """

    values: NDArray[np.float64]
    cutoff_hz: float
    effective_cutoff_hz: float
    order: int
    sample_rate_hz: float


def compute_effective_cutoff_hz(cutoff_hz: float, sample_rate_hz: float, order: int) -> float:
    """Return the −3 dB frequency of the forward–backward Butterworth response, Eq. (2). [Hz]

    Parameters
    ----------
    cutoff_hz : float
        Design cut-off f_c, 0 < f_c < f_s/2. [Hz]
    sample_rate_hz : float
        Sample rate f_s. [Hz]
    order : int
        Order N of each pass.

    Returns
    -------
    float
        f_3dB. [Hz]

    Examples
    --------
    >>> round(compute_effective_cutoff_hz(50.0, 1000.0, 4), 2)
    44.86
    """
    fs = check_positive(sample_rate_hz, "sample_rate_hz")
    fc = check_positive(cutoff_hz, "cutoff_hz")
    n = _check_order(order)
    warped = math.tan(math.pi * fc / fs) * (math.sqrt(2.0) - 1.0) ** (1.0 / (2 * n))
    return fs / math.pi * math.atan(warped)  # Eq. (2)


def lowpass_zero_phase(
    values: ArrayLike,
    sample_rate_hz: float,
    *,
    bandwidth_hz: float,
    cutoff_fraction: float = 0.25,
    order: int = 4,
    allow_any_fraction: bool = False,
) -> LowpassResult:
    """Low-pass filter each column with a zero-phase Butterworth filter (module docstring).

    Parameters
    ----------
    values : array_like, shape (n,) or (n, k)
        Uniformly sampled signal, time along axis 0. [any unit]
    sample_rate_hz : float
        f_s. [Hz]
    bandwidth_hz : float
        The IMU's bandwidth (its datasheet or :class:`~imucalib.models.sensor.SensorSpec`
        ``bandwidth_hz``). [Hz]
    cutoff_fraction : float
        f_c / bandwidth, within [1/5, 1/3] (docs/p1.md, rule 2) unless `allow_any_fraction`.
    order : int
        Order N of each pass, 1 … 10.
    allow_any_fraction : bool
        Accept a `cutoff_fraction` outside [1/5, 1/3] (any value in (0, ∞) with f_c < f_s/2).

    Returns
    -------
    LowpassResult
        Filtered values and the cut-off frequencies.

    Raises
    ------
    InvalidInputError
        If the fraction is outside [1/5, 1/3] without `allow_any_fraction`, f_c ≥ f_s/2 (Nyquist),
        the order is not an integer in 1 … 10, the record is not longer than the filter's padding
        (3·(2·sections + 1) samples), or `values` holds NaN or infinite values.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(2000) / 1000.0
    >>> x = np.sin(2 * np.pi * 5 * t) + np.sin(2 * np.pi * 200 * t)
    >>> res = lowpass_zero_phase(x, 1000.0, bandwidth_hz=200.0)        # f_c = 50 Hz
    >>> bool(np.abs(res.values[500:1500] - np.sin(2 * np.pi * 5 * t[500:1500])).max() < 1e-3)
    True
    """
    fs = check_positive(sample_rate_hz, "sample_rate_hz")
    bw = check_positive(bandwidth_hz, "bandwidth_hz")
    frac = check_positive(cutoff_fraction, "cutoff_fraction")
    lo, hi = SPEC_CUTOFF_FRACTION_RANGE
    if not allow_any_fraction and not (lo - 1e-12 <= frac <= hi + 1e-12):
        raise InvalidInputError(
            f"`cutoff_fraction` must be within 1/5–1/3 of the IMU bandwidth (procedure P1, "
            f"processing rule 2, docs/p1.md); got {frac:.6g} "
            f"(pass allow_any_fraction=True to override)"
        )
    n_ord = _check_order(order)
    fc = frac * bw
    nyquist = 0.5 * fs
    if fc >= nyquist:
        raise InvalidInputError(
            f"the cut-off {frac:.6g} × {bw:.6g} Hz = {fc:.6g} Hz must be below the Nyquist "
            f"frequency {nyquist:.6g} Hz (sample rate {fs:.6g} Hz)"
        )
    cols, one_d = as_columns(values, "values", copy=False)  # sosfiltfilt only reads it
    sos, padlen = _butter_lowpass(n_ord, 2.0 * fc / fs)  # butter(fs=fs) normalises the same way
    if cols.shape[0] <= padlen:
        raise InvalidInputError(
            f"`values` must have more than {padlen} samples for an order-{n_ord} zero-phase "
            f"filter; got {cols.shape[0]}"
        )
    # scipy.signal.sosfiltfilt(sos, cols, axis=0), bit for bit, all columns at once
    out = sosfiltfilt_columns(sos, _steady_state(n_ord, 2.0 * fc / fs), cols, padlen)
    res = restore_shape(out, one_d)
    res.setflags(write=False)
    return LowpassResult(values=res, cutoff_hz=fc,
                         effective_cutoff_hz=compute_effective_cutoff_hz(fc, fs, n_ord),
                         order=n_ord, sample_rate_hz=fs)


@lru_cache(maxsize=64)
def _butter_lowpass(order: int, wn: float) -> tuple[NDArray[np.float64], int]:
    """Return the Butterworth low-pass of Eq. (1) as second-order sections and its padding.

    Parameters
    ----------
    order : int
        N.
    wn : float
        Cut-off as a fraction of the Nyquist frequency, 2·f_c/f_s (what ``butter`` computes from
        ``fs``), 0 < wn < 1.

    Returns
    -------
    sos : ndarray, shape (⌈N/2⌉, 6)
        ``scipy.signal.butter(order, wn, output="sos")``; shared by every call: never modify.
    padlen : int
        ``sosfiltfilt``'s default odd-extension length 3·(2·sections + 1 − z), z the sections
        whose b₂ and a₂ are both zero.

    Notes
    -----
    The design (bilinear transform, pole pairing) costs as much as filtering a few thousand
    samples, and every window of an analysis asks for the same one: it is cached per
    (N, wn).
    """
    # left writable: scipy's compiled sosfilt takes a writable buffer (it never writes sos)
    sos = np.asarray(signal.butter(order, wn, btype="low", output="sos"), dtype=np.float64)
    n_zero = min(int(np.sum(sos[:, 2] == 0)), int(np.sum(sos[:, 5] == 0)))
    return sos, 3 * (2 * sos.shape[0] + 1 - n_zero)  # sosfiltfilt's default


@lru_cache(maxsize=64)
def _steady_state(order: int, wn: float) -> NDArray[np.float64]:
    """Return ``scipy.signal.sosfilt_zi`` of :func:`_butter_lowpass` (the same cache key)."""
    return np.asarray(signal.sosfilt_zi(_butter_lowpass(order, wn)[0]), dtype=np.float64)


def _check_order(order: object) -> int:
    if isinstance(order, bool) or not isinstance(order, int | np.integer) or not (
        1 <= int(order) <= _MAX_ORDER
    ):
        raise InvalidInputError(f"`order` must be an integer in 1 … {_MAX_ORDER}; got {order!r}")
    return int(order)
