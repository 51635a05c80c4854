"""Allan-family deviations of rate or angle data, with EDF confidence intervals.

Contents
--------
:class:`DeviationResult`
    τ, deviation, number of terms, EDF, confidence interval and identified noise type per τ.
:func:`compute_deviation`
    Any estimator by name; :func:`compute_adev`, :func:`compute_oadev`, :func:`compute_mdev`,
    :func:`compute_tdev`, :func:`compute_hdev`, :func:`compute_ohdev`, :func:`compute_totdev`
    are the same with the name fixed (one signature for all, as in allantools).
:func:`resolve_averaging_factors`
    The τ grid: ``"octave"``, ``"decade"``, ``"all"``, an int (log-spaced, that many per decade)
    or explicit τ values [s].
:func:`check_uniform_sampling`, :class:`SamplingCheck`
    Sample rate from time stamps (all at once, or chunk by chunk), refusing gaps and jitter.
:data:`DEVIATION_KINDS`

Data
----
``data_type="rate"``: samples y_k of a rate (gyro [rad/s], accelerometer [m/s²]; the
"fractional frequency" of NIST SP 1065 [1]_). The angle (phase) is x_0 = 0,
x_k = τ0·Σ_{j<k}(y_j − ȳ) (eq. (2); the mean is removed for precision and cancels in every
difference). ``data_type="angle"``: the integrated samples x_k themselves [rad | m/s]. Deviations
are in rate units; TDEV is in angle units.

Estimators (NIST SP 1065 equation numbers): ADEV (7), OADEV (11), MDEV (14), TDEV (15),
HDEV (18), OHDEV (20), TOTDEV (25). Sums are listed in :mod:`._allan_engine`; kernels and their
rounding in :mod:`._allan_kernels`. Each τ's confidence interval comes from the EDF of
Greenhall and Riley (total deviation: SP 1065 Table 7) for the noise type identified at that τ by
the lag-1 autocorrelation (:mod:`.edf`). Agreement with NIST's published NBS14 values and with
allantools is tested.

Bad input: NaN or infinite samples raise :class:`~imucalib.errors.InvalidInputError` naming the
first bad index (split the record at gaps: an Allan sum across a gap is not defined); so do an
explicit τ that the record is too short for, and fewer than 3 samples.

References
----------
.. [1] W. J. Riley, "Handbook of Frequency Stability Analysis", NIST SP 1065, 2008.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib._checks import check_positive
from imucalib.analysis import _allan_engine as eng
from imucalib.analysis.edf import (
    NOISE_TYPES,
    ONE_SIGMA,
    compute_confidence_interval,
    compute_edf,
    identify_noise_lag1,
)
from imucalib.errors import InvalidInputError

__all__ = [
    "DEVIATION_KINDS",
    "DeviationResult",
    "SamplingCheck",
    "TauSpec",
    "check_uniform_sampling",
    "compute_adev",
    "compute_deviation",
    "compute_hdev",
    "compute_mdev",
    "compute_oadev",
    "compute_ohdev",
    "compute_tdev",
    "compute_totdev",
    "resolve_averaging_factors",
]

#: Estimator names accepted by :func:`compute_deviation`.
DEVIATION_KINDS: tuple[str, ...] = eng.KINDS
TauSpec = str | int | ArrayLike
DataType = Literal["rate", "angle"]

_MEAN_CHUNK = 1 << 20  # samples per partial sum of the mean (streaming uses the same)
_NOISE_ID_POINTS = 1 << 13  # τ-averages used per noise identification (from mid-record)
_NOISE_ID_MIN = 30


@dataclass(frozen=True, eq=False)
class DeviationResult:
    """A deviation per τ with its confidence interval.

    Arrays have one entry per τ. ``noise_alpha`` is the exponent α of the rate PSD
    S_y ∝ f^α identified at that τ (:data:`imucalib.analysis.edf.NOISE_TYPES`);
    ``noise_id_method`` says how: ``"lag1-acf"``, ``"nearest"`` (too few τ-averages: taken
    from the nearest τ that had enough) or ``"assumed"`` (white rate, α = 0).
    """

    kind: str
    taus_s: NDArray[np.float64]  # [s]
    deviation: NDArray[np.float64]  # [unit] (tdev: [unit·s])
    averaging_factors: NDArray[np.int64]  # m, τ = m/sample_rate_hz
    n_terms: NDArray[np.int64]
    edf: NDArray[np.float64]
    ci_low: NDArray[np.float64]  # [unit]
    ci_high: NDArray[np.float64]  # [unit]
    noise_alpha: NDArray[np.int64]
    noise_id_method: tuple[str, ...]
    confidence: float
    sample_rate_hz: float  # [Hz]
    n_samples: int  # rate samples (angle data: phase points − 1)
    data_type: str
    unit: str = ""

    @property
    def variance(self) -> NDArray[np.float64]:
        """The deviation squared [unit²]."""
        out: NDArray[np.float64] = self.deviation**2
        return out

    @property
    def noise_types(self) -> tuple[str, ...]:
        """Names of the identified noise types."""
        return tuple(NOISE_TYPES[int(a)] for a in self.noise_alpha)

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form; :meth:`from_dict` rebuilds it exactly."""
        out: dict[str, Any] = {}
        for f in fields(self):
            v = getattr(self, f.name)
            out[f.name] = v.tolist() if isinstance(v, np.ndarray) else (
                list(v) if isinstance(v, tuple) else v)
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> DeviationResult:
        """Rebuild a result written by :meth:`to_dict` (InvalidInputError on missing keys)."""
        names = {f.name for f in fields(cls)}
        missing = sorted(names - set(data) - {"unit"})
        if missing:
            raise InvalidInputError(f"deviation result is missing {missing}")
        ints = {"averaging_factors", "n_terms", "noise_alpha"}
        floats = {"taus_s", "deviation", "edf", "ci_low", "ci_high"}
        kw: dict[str, Any] = {}
        for name in names & set(data):
            v = data[name]
            if name in ints:
                kw[name] = np.asarray(v, dtype=np.int64)
            elif name in floats:
                kw[name] = np.asarray(v, dtype=np.float64)
            elif name == "noise_id_method":
                kw[name] = tuple(str(s) for s in v)
            else:
                kw[name] = v
        return cls(**kw)


class SamplingCheck:
    """Check time stamps chunk by chunk for gaps and jitter; the sample rate at the end.

    The nominal interval is the median interval of the first chunk given. A gap is an interval
    longer than 1.5 nominal intervals; jitter an interval off the nominal by more than `rtol`
    (relative); both raise :class:`~imucalib.errors.InvalidInputError` giving the time, as do
    non-increasing or non-finite stamps.
    """

    def __init__(self, *, rtol: float = 0.01) -> None:
        self.rtol = rtol
        self._first: float | None = None
        self._last: float | None = None
        self._nominal: float | None = None
        self._count = 0

    def update(self, time_s: ArrayLike) -> None:
        """Check the next stamps (1-D) [s]; raise InvalidInputError on a gap or jitter."""
        t = np.asarray(time_s, dtype=np.float64).ravel()
        if t.size == 0:
            return
        if not self._within(t):
            self._check(t)  # the stamp-by-stamp checks name what is wrong
        if self._first is None:
            self._first = float(t[0])
        self._last = float(t[-1])
        self._count += t.size

    def _within(self, t: NDArray[np.float64]) -> bool:
        """Whether every interval of `t` passes the checks, from the extreme intervals alone.

        Finite stamps have finite intervals; an interval is out of order, a gap or off the
        nominal exactly when the shortest or the longest one is (|dt/T − 1| is monotonic in dt
        on either side of T, in floating point too), so the smallest and largest interval
        decide, with the nominal interval taken from the first chunk as :meth:`_check` does.
        False sends the chunk to :meth:`_check`, which raises or accepts it.
        """
        dt = np.empty(t.size - (1 if self._last is None else 0))
        if dt.size == 0 or not math.isfinite(float(t[0])):
            return False
        if self._last is not None:
            dt[0] = t[0] - self._last
        np.subtract(t[1:], t[:-1], out=dt[dt.size - (t.size - 1):])
        lo, hi = float(dt.min()), float(dt.max())
        if not (math.isfinite(lo) and math.isfinite(hi)):
            return False
        nominal = float(np.median(dt)) if self._nominal is None else self._nominal
        if not (lo > 0 and nominal > 0 and hi <= 1.5 * nominal):
            return False
        if max(abs(lo / nominal - 1), abs(hi / nominal - 1)) > self.rtol:
            return False
        self._nominal = nominal
        return True

    def _check(self, t: NDArray[np.float64]) -> None:
        """Check the stamps `t` one by one against the previous chunk's; raise on a defect."""
        if not np.all(np.isfinite(t)):
            raise InvalidInputError("`time_s` must be finite; got NaN or infinite stamps")
        full = t if self._last is None else np.concatenate([[self._last], t])
        dt = np.diff(full)
        if self._nominal is None and dt.size:
            self._nominal = float(np.median(dt))
        if dt.size and self._nominal is not None:
            nominal = self._nominal
            bad_order = dt <= 0
            if bad_order.any() or not nominal > 0:
                i = int(np.argmax(bad_order))
                raise InvalidInputError(f"`time_s` must be strictly increasing; "
                                        f"{float(full[i + 1])!r} s follows {float(full[i])!r} s")
            gap = dt > 1.5 * nominal
            if gap.any():
                i = int(np.argmax(gap))
                raise InvalidInputError(
                    f"non-uniform sampling: a gap of {dt[i]:.6g} s (nominal interval "
                    f"{nominal:.6g} s) after t = {full[i]:.6f} s; Allan deviations need gap-free "
                    "data: analyse the pieces separately")
            dev = np.abs(dt / nominal - 1)
            if np.any(dev > self.rtol):
                i = int(np.argmax(dev))
                raise InvalidInputError(
                    f"non-uniform sampling: the interval after t = {full[i]:.6f} s is "
                    f"{dt[i]:.6g} s, {dev[i]:.2%} off the nominal {nominal:.6g} s (tolerance "
                    f"{self.rtol:.2%}); resample onto a uniform grid first")

    @property
    def n_samples(self) -> int:
        """Stamps seen so far."""
        return self._count

    @property
    def t_first_s(self) -> float:
        """First stamp [s] (NaN before any)."""
        return math.nan if self._first is None else self._first

    @property
    def t_last_s(self) -> float:
        """Last stamp [s] (NaN before any)."""
        return math.nan if self._last is None else self._last

    def sample_rate_hz(self) -> float:
        """(n − 1)/(t_last − t_first) [Hz]; InvalidInputError before two stamps."""
        if self._count < 2 or self._first is None or self._last is None:
            raise InvalidInputError(f"need at least 2 time stamps; got {self._count}")
        return (self._count - 1) / (self._last - self._first)


def check_uniform_sampling(time_s: ArrayLike, *, rtol: float = 0.01) -> float:
    """Return the sample rate [Hz] of uniformly spaced time stamps `time_s` [s].

    (n − 1)/(t_last − t_first), after the checks of :class:`SamplingCheck` on the whole array.

    Raises
    ------
    InvalidInputError
        Fewer than 2 stamps or not 1-D, non-finite or non-increasing stamps, a gap or jitter
        (the message says where).
    """
    t = np.asarray(time_s, dtype=np.float64)
    if t.ndim != 1 or t.size < 2:
        raise InvalidInputError(f"`time_s` must be 1-D with ≥ 2 stamps; got shape {t.shape}")
    check = SamplingCheck(rtol=rtol)
    check.update(t)
    return check.sample_rate_hz()


def resolve_averaging_factors(taus: TauSpec, n_phase: int, sample_rate_hz: float,
                              kind: str = "oadev") -> NDArray[np.int64]:
    """Averaging factors m (τ = m/sample_rate_hz) of a τ specification, for estimator `kind`.

    ``"octave"``: m = 1, 2, 4, …; ``"decade"``: 1, 2, 4, 10, 20, 40, …; ``"all"``: every m;
    an int k: log-spaced, k per decade (rounded, duplicates removed); an array: τ [s], each
    rounded to the nearest multiple of the sample interval. Automatic grids keep the m that give
    at least 2 terms (total deviation: m ≤ (n − 1)/2).

    Raises
    ------
    InvalidInputError
        Unknown specification; an explicit τ shorter than half a sample interval or longer than
        the record allows (the message gives the longest τ possible); no valid τ at all.
    """
    if kind not in DEVIATION_KINDS:
        raise InvalidInputError(f"unknown deviation kind {kind!r}; expected one of "
                                f"{list(DEVIATION_KINDS)}")
    if isinstance(taus, str):
        top = max(n_phase, 1)
        if taus == "octave":
            cand = 2 ** np.arange(math.floor(math.log2(top)) + 1, dtype=np.int64)
        elif taus == "decade":
            dec = 10 ** np.arange(math.floor(math.log10(top)) + 1, dtype=np.int64)
            cand = (np.array([1, 2, 4], dtype=np.int64)[None, :] * dec[:, None]).ravel()
        elif taus == "all":
            cand = np.arange(1, top, dtype=np.int64)
        else:
            raise InvalidInputError(f"`taus` must be 'octave', 'decade', 'all', an int or τ "
                                    f"values [s]; got {taus!r}")
        explicit = False
    elif isinstance(taus, int | np.integer) and not isinstance(taus, bool):
        if taus < 1:
            raise InvalidInputError(f"`taus` per decade must be ≥ 1; got {taus}")
        k = np.arange(math.ceil(taus * math.log10(max(n_phase, 2))) + 1)
        cand = np.unique(np.round(10.0 ** (k / int(taus))).astype(np.int64))
        explicit = False
    else:
        arr = np.atleast_1d(np.asarray(taus, dtype=np.float64))
        if arr.ndim != 1 or arr.size == 0 or not np.all(np.isfinite(arr)):
            raise InvalidInputError(f"`taus` values must be a non-empty 1-D finite array [s]; "
                                    f"got {taus!r}")
        cand = np.round(arr * sample_rate_hz).astype(np.int64)
        if np.any(cand < 1):
            bad = float(arr[int(np.argmax(cand < 1))])
            raise InvalidInputError(f"τ = {bad:g} s is shorter than the sample interval "
                                    f"{1 / sample_rate_hz:g} s")
        cand = np.unique(cand)
        explicit = True
    count = eng.n_terms(kind, cand, n_phase)
    ok = count >= 2
    if explicit and not ok.all():
        bad_m = int(cand[~ok][0])
        longest = cand_max(kind, n_phase)
        limit = (f"the longest τ is {longest / sample_rate_hz:g} s" if longest >= 1
                 else "no τ is possible")
        raise InvalidInputError(
            f"τ = {bad_m / sample_rate_hz:g} s is too long for `{kind}` on {n_phase - 1} "
            f"samples at {sample_rate_hz:g} Hz ({limit})")
    out = cand[ok]
    if out.size == 0:
        raise InvalidInputError(f"data too short: `{kind}` needs at least "
                                f"{min_samples(kind)} samples for one τ; got {n_phase - 1}")
    return out.astype(np.int64)


def cand_max(kind: str, n_phase: int) -> int:
    """Largest m with at least 2 terms for estimator `kind` (0 if none)."""
    m = max(n_phase, 1)
    lo, hi = 0, m
    while lo < hi:  # n_terms is non-increasing in m
        mid = (lo + hi + 1) // 2
        if int(eng.n_terms(kind, mid, n_phase)) >= 2:
            lo = mid
        else:
            hi = mid - 1
    return lo


def min_samples(kind: str) -> int:
    """Fewest rate samples giving one τ (m = 1) with 2 terms."""
    n = 2
    while int(eng.n_terms(kind, 1, n + 1)) < 2:
        n += 1
    return n


def canonical_mean(values: NDArray[np.float64]) -> float:
    """Mean as Σ over 2^20-sample chunks of np.sum(chunk), added in order (streaming-exact)."""
    acc = 0.0
    for a in range(0, values.size, _MEAN_CHUNK):
        acc += float(np.sum(values[a:a + _MEAN_CHUNK]))
    return acc / values.size


def _validate(data: ArrayLike,
              sample_rate_hz: float) -> tuple[NDArray[np.float64], float, float]:
    """Return (samples, sample rate, canonical mean); the mean's sum is the finiteness check."""
    rate = check_positive(sample_rate_hz, "sample_rate_hz")
    try:
        y = np.asarray(data, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"`data` must be numeric; got {type(data).__name__}") from exc
    if y.ndim != 1:
        raise InvalidInputError(f"`data` must be 1-D (one channel); got shape {y.shape}")
    with np.errstate(over="ignore", invalid="ignore"):
        mean = canonical_mean(y) if y.size else 0.0
    if not math.isfinite(mean):  # a NaN or infinity anywhere makes the sum non-finite
        bad = ~np.isfinite(y)
        if not bad.any():
            raise InvalidInputError(
                f"`data` is too large to sum in float64 (largest magnitude "
                f"{float(np.max(np.abs(y))):g}): rescale it")
        i = int(np.argmax(bad))
        raise InvalidInputError(
            f"`data` has {int(bad.sum())} NaN or infinite sample(s), the first at index {i} "
            f"(t = {i / rate:g} s); an Allan sum across a gap is not defined: split the record "
            "at the gap and analyse the pieces")
    return y, rate, mean


def phase_from_rate(y: NDArray[np.float64], sample_rate_hz: float,
                    mean: float | None = None) -> NDArray[np.float64]:
    """x_0 = 0, x_k = τ0·Σ_{j<k}(y_j − ȳ) with the canonical mean (module docstring) [angle].

    `mean` is :func:`canonical_mean` of `y` when the caller has it already.
    """
    x = np.empty(y.size + 1)
    x[0] = 0.0
    y_bar = canonical_mean(y) if mean is None else mean
    eng.integrate_phase(np.ascontiguousarray(y), y_bar, 1.0 / sample_rate_hz, x[1:])
    return x


def deviations_from_source(source: eng.PhaseSource, kinds: tuple[str, ...], taus: TauSpec,
                           sample_rate_hz: float, *, confidence: float, identify_noise: bool,
                           data_type: str, unit: str) -> dict[str, DeviationResult]:
    """Every estimator of `kinds` from one phase source (the shared core; streaming uses it)."""
    n = source.n_phase
    tau0 = 1.0 / sample_rate_hz
    out: dict[str, DeviationResult] = {}
    alpha_cache: dict[tuple[int, int], tuple[int, str]] = {}
    for kind in kinds:
        ms = resolve_averaging_factors(taus, n, sample_rate_hz, kind)
        count = eng.n_terms(kind, ms, n)
        tau = (ms * tau0).astype(np.float64)
        if kind == "oadev":
            var = eng.sum_overlapping(source, ms, count, 2) / (2 * count * tau**2)
        elif kind == "ohdev":
            var = eng.sum_overlapping(source, ms, count, 3) / (6 * count * tau**2)
        elif kind == "adev":
            var = eng.sum_nonoverlapping(source, ms, 2) / (2 * count * tau**2)
        elif kind == "hdev":
            var = eng.sum_nonoverlapping(source, ms, 3) / (6 * count * tau**2)
        elif kind in ("mdev", "tdev"):
            var = eng.sums_mdev(source, ms) / (2 * ms.astype(np.float64) ** 2 * tau**2 * count)
            if kind == "tdev":
                var = var * tau**2 / 3
        else:  # totdev
            var = eng.sums_totdev(source, ms) / (2 * tau**2 * (n - 2))
        dev = np.sqrt(var)
        d_max = 3 if kind in ("hdev", "ohdev") else 2
        alphas = np.zeros(ms.size, dtype=np.int64)
        methods: list[str] = []
        last: int | None = None
        for i, m in enumerate(ms.tolist()):
            key = (m, d_max)
            if not identify_noise:
                alphas[i], how = 0, "assumed"
            elif key in alpha_cache:
                alphas[i], how = alpha_cache[key]
            else:
                avg = eng.decimated_averages(source, m, tau0, _NOISE_ID_POINTS)
                if avg.size >= _NOISE_ID_MIN:
                    alphas[i] = identify_noise_lag1(avg, max_differences=d_max).alpha
                    how = "lag1-acf"
                elif last is not None:
                    alphas[i], how = last, "nearest"
                else:
                    alphas[i], how = 0, "assumed"
                alpha_cache[key] = (int(alphas[i]), how)
            if how == "lag1-acf":
                last = int(alphas[i])
            methods.append(how)
        edf = np.array([compute_edf(kind, int(a), int(m), n) for a, m in zip(alphas, ms,
                                                                            strict=True)])
        lo, hi = compute_confidence_interval(dev, edf, confidence)
        out[kind] = DeviationResult(
            kind=kind, taus_s=tau, deviation=dev, averaging_factors=ms, n_terms=count, edf=edf,
            ci_low=lo, ci_high=hi, noise_alpha=alphas, noise_id_method=tuple(methods),
            confidence=float(confidence), sample_rate_hz=float(sample_rate_hz),
            n_samples=int(n - 1), data_type=data_type, unit=unit)
    return out


def compute_deviation(kind: str, data: ArrayLike, sample_rate_hz: float, *,
                      data_type: DataType = "rate", taus: TauSpec = "octave",
                      confidence: float = ONE_SIGMA, identify_noise: bool = True,
                      unit: str = "") -> DeviationResult:
    """Compute one Allan-family deviation with confidence intervals.

    Parameters
    ----------
    kind : str
        ``"adev"``, ``"oadev"``, ``"mdev"``, ``"tdev"``, ``"hdev"``, ``"ohdev"``, ``"totdev"``.
    data : array_like, shape (n,)
        Rate samples [unit] (``data_type="rate"``) or integrated angle samples [unit·s]
        (``"angle"``), uniformly sampled, finite.
    sample_rate_hz : float
        1/τ0. [Hz]
    data_type : {"rate", "angle"}
        What `data` holds (module docstring).
    taus : str, int or array_like
        τ grid (:func:`resolve_averaging_factors`); explicit values in [s].
    confidence : float
        Probability content of the interval (default ±1σ, 0.6827).
    identify_noise : bool
        Identify the noise type per τ for the EDF (otherwise white rate noise is assumed).
    unit : str
        Label of the rate unit, stored in the result (e.g. ``"rad/s"``).

    Returns
    -------
    DeviationResult

    Raises
    ------
    InvalidInputError
        NaN/infinite samples (the message gives the first index), not 1-D, too short for any τ
        or for an explicit τ, bad `taus`, `kind`, `data_type` or `confidence`.
    """
    y, rate, mean = _validate(data, sample_rate_hz)
    if data_type not in ("rate", "angle"):
        raise InvalidInputError(f"`data_type` must be 'rate' or 'angle'; got {data_type!r}")
    if kind not in DEVIATION_KINDS:
        raise InvalidInputError(f"unknown deviation kind {kind!r}; expected one of "
                                f"{list(DEVIATION_KINDS)}")
    n_min = min_samples(kind) + (1 if data_type == "angle" else 0)
    if y.size < n_min:
        raise InvalidInputError(f"data too short: `{kind}` needs at least {n_min} samples; "
                                f"got {y.size}")
    x = phase_from_rate(y, rate, mean) if data_type == "rate" else np.ascontiguousarray(y)
    res = deviations_from_source(eng.ArrayPhase(x), (kind,), taus, rate, confidence=confidence,
                                 identify_noise=identify_noise, data_type=data_type, unit=unit)
    return res[kind]


def compute_adev(data: ArrayLike, sample_rate_hz: float, **kwargs: Any) -> DeviationResult:
    """Compute the non-overlapping Allan deviation, NIST SP 1065 eq. (7)."""
    return compute_deviation("adev", data, sample_rate_hz, **kwargs)


def compute_oadev(data: ArrayLike, sample_rate_hz: float, **kwargs: Any) -> DeviationResult:
    """Compute the overlapping Allan deviation, NIST SP 1065 eq. (11)."""
    return compute_deviation("oadev", data, sample_rate_hz, **kwargs)


def compute_mdev(data: ArrayLike, sample_rate_hz: float, **kwargs: Any) -> DeviationResult:
    """Compute the modified Allan deviation, NIST SP 1065 eq. (14) (see compute_deviation)."""
    return compute_deviation("mdev", data, sample_rate_hz, **kwargs)


def compute_tdev(data: ArrayLike, sample_rate_hz: float, **kwargs: Any) -> DeviationResult:
    """Compute the time (angle) deviation τ·MDEV/√3, NIST SP 1065 eq. (15) [unit·s]."""
    return compute_deviation("tdev", data, sample_rate_hz, **kwargs)


def compute_hdev(data: ArrayLike, sample_rate_hz: float, **kwargs: Any) -> DeviationResult:
    """Compute the non-overlapping Hadamard deviation, NIST SP 1065 eq. (18)."""
    return compute_deviation("hdev", data, sample_rate_hz, **kwargs)


def compute_ohdev(data: ArrayLike, sample_rate_hz: float, **kwargs: Any) -> DeviationResult:
    """Compute the overlapping Hadamard deviation, NIST SP 1065 eq. (20)."""
    return compute_deviation("ohdev", data, sample_rate_hz, **kwargs)


def compute_totdev(data: ArrayLike, sample_rate_hz: float, **kwargs: Any) -> DeviationResult:
    """Compute the total deviation (reflected ends), NIST SP 1065 eq. (25); m ≤ (n − 1)/2."""
    return compute_deviation("totdev", data, sample_rate_hz, **kwargs)
