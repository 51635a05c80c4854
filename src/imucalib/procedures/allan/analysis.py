"""The Allan procedure, analysis side: noise characterisation of the static records of a Recording.

Contents
--------
:func:`analyze_allan_recording` → :class:`NoiseCharacterization`
    For each static record: OADEV with confidence intervals and the noise-term fit of every gyro
    and accelerometer axis, streamed in bounded memory.
:func:`analyze_allan_arrays`
    The same for one record given as arrays (``imucalib allan DATA`` on a CSV).
:class:`SegmentNoise`, :class:`ChannelNoise`
    One record (step) and one channel of it.
:data:`FORMAT_VERSION`, :data:`STATIC_STEP_KINDS`

Which records
-------------
With ``steps=None``: every step whose kind is in :data:`STATIC_STEP_KINDS` (``"static"``,
``"allan"``), each analysed on its own (several static records, for example at several
temperatures, give several segments; they are never concatenated, since an Allan sum across a
gap is not defined). A step's valid window (after warm-up/settling) is used when it has one,
otherwise its whole span. A recording without steps is analysed whole. ``steps`` may instead
list step indices.

Channels are the canonical columns ``gyro_{x,y,z}_rps`` and ``accel_{x,y,z}_mps2`` present in
the stream; values in another physical unit (``deg/s``, ``g``, …) are converted to SI with
:func:`imucalib.units.parse_unit`; raw counts are refused. The time stamps must be uniform
(:class:`~imucalib.analysis.SamplingCheck`: gaps and jitter beyond `sampling_rtol` are errors).

The result has a versioned JSON form (:meth:`NoiseCharacterization.to_json`); a file from a
newer format version is refused.

The result contract
-------------------
:class:`NoiseCharacterization` is a :class:`~imucalib.models.procedure_result.ProcedureResult`
(docs/procedures.md, "The result contract"): its parameters are the detected noise terms
(:meth:`~NoiseCharacterization.parameter_rows`; their σ are those of the GLS fit against the
Allan covariance, not Birge-scaled, so ``std_noise`` = ``std``, a misfit named in the decision's
notes); it estimates no triad parameter and has no calibration; its decision is *no decision*
(:data:`NO_DECISION_REASON`): a noise characterisation has no acceptance limits (docs/noise.md).
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from imucalib import __version__
from imucalib.analysis import (
    FIT_TERMS,
    ONE_SIGMA,
    AllanStream,
    DeviationResult,
    NoiseFit,
    SamplingCheck,
    fit_noise_terms,
)
from imucalib.analysis.allan import TauSpec
from imucalib.analysis.noise_parameters import ImuNoiseParameters, noise_parameters_from_fits
from imucalib.conventions import ACCEL_COLUMNS, GYRO_COLUMNS, TEMPERATURE_COLUMN
from imucalib.errors import InvalidInputError
from imucalib.io.opening import open_recording
from imucalib.io.reader import Recording
from imucalib.models.decision import Decision, no_decision
from imucalib.models.fit_quality import FitQuality
from imucalib.models.procedure_result import ResultDefaults
from imucalib.models.reported import ReportedParameter
from imucalib.models.result import Provenance
from imucalib.plan.bounds import MAX_SAMPLE_RATE_HZ
from imucalib.units import parse_unit

__all__ = ["FORMAT_VERSION", "NO_DECISION_REASON", "STATIC_STEP_KINDS", "ChannelNoise",
           "NoiseCharacterization", "SegmentNoise", "analyze_allan_arrays",
           "analyze_allan_recording"]

#: Version of the JSON form of :class:`NoiseCharacterization`.
FORMAT_VERSION = 1
#: Step kinds analysed by default.
STATIC_STEP_KINDS = ("static", "allan")
_FORMAT_NAME = "imucalib-noise-characterization"
_SI_UNIT = {"gyro": "rad/s", "accel": "m/s^2"}
#: Why a noise characterisation decides nothing.
NO_DECISION_REASON = ("a noise characterisation has no acceptance limits: it reports each noise "
                      "term with its standard uncertainty and judges none; the unit's white-noise "
                      "limits ([imu.limits] gyro_arw_deg_rth, accel_vrw_ug_rthz) are judged by "
                      "P1 on its static record (docs/noise.md)")


@dataclass(frozen=True, eq=False)
class ChannelNoise:
    """One channel of one record: its deviations and its noise fit."""

    channel: str  # column name, e.g. "gyro_x_rps"
    sensor: str  # "gyro" or "accel"
    deviations: dict[str, DeviationResult]  # by estimator name; "oadev" always present
    fit: NoiseFit
    mean_si: float  # mean of the record [rad/s | m/s²] (Earth rate, gravity and bias)

    @property
    def axis_name(self) -> str:
        """``"gyro_x"`` … ``"accel_z"``."""
        return self.channel.rsplit("_", 1)[0]

    @property
    def oadev(self) -> DeviationResult:
        """The overlapping Allan deviation."""
        return self.deviations["oadev"]

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form."""
        return {"channel": self.channel, "sensor": self.sensor, "mean_si": self.mean_si,
                "deviations": {k: v.to_dict() for k, v in self.deviations.items()},
                "fit": self.fit.to_dict()}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> ChannelNoise:
        """Inverse of :meth:`to_dict`."""
        return cls(channel=data["channel"], sensor=data["sensor"], mean_si=data["mean_si"],
                   deviations={k: DeviationResult.from_dict(v)
                               for k, v in data["deviations"].items()},
                   fit=NoiseFit.from_dict(data["fit"]))


@dataclass(frozen=True, eq=False)
class SegmentNoise:
    """One analysed record (a static step, or the whole recording)."""

    label: str
    step_index: int | None
    t_start_s: float  # first sample [s]
    t_end_s: float  # last sample [s]
    n_samples: int
    sample_rate_hz: float  # [Hz]
    temperature_degc: float | None  # mean of the stream's temperature column, if any
    channels: tuple[ChannelNoise, ...]

    def channel(self, name: str) -> ChannelNoise:
        """Return a channel by column name (``"gyro_x_rps"``) or axis name (``"gyro_x"``)."""
        for c in self.channels:
            if name in (c.channel, c.axis_name):
                return c
        raise InvalidInputError(f"no channel {name!r}; channels: "
                                f"{[c.channel for c in self.channels]}")

    def fits(self, sensor: str | None = None) -> dict[str, NoiseFit]:
        """Noise fits by axis name (``"gyro_x"`` …), optionally of one sensor."""
        return {c.axis_name: c.fit for c in self.channels if sensor in (None, c.sensor)}

    def noise_parameters(self, *, combine: str = "max", noise_inflation: float = 1.0,
                         walk_inflation: float = 1.0) -> ImuNoiseParameters:
        """Return the Kalibr/OpenVINS densities (``noise_parameters_from_fits``) of this record."""
        return noise_parameters_from_fits(list(self.fits("gyro").values()),
                                          list(self.fits("accel").values()),
                                          self.sample_rate_hz, combine=combine,
                                          noise_inflation=noise_inflation,
                                          walk_inflation=walk_inflation)

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form."""
        return {"label": self.label, "step_index": self.step_index,
                "t_start_s": self.t_start_s, "t_end_s": self.t_end_s,
                "n_samples": self.n_samples, "sample_rate_hz": self.sample_rate_hz,
                "temperature_degc": self.temperature_degc,
                "channels": [c.to_dict() for c in self.channels]}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> SegmentNoise:
        """Inverse of :meth:`to_dict`."""
        return cls(label=data["label"], step_index=data["step_index"],
                   t_start_s=data["t_start_s"], t_end_s=data["t_end_s"],
                   n_samples=data["n_samples"], sample_rate_hz=data["sample_rate_hz"],
                   temperature_degc=data["temperature_degc"],
                   channels=tuple(ChannelNoise.from_dict(c) for c in data["channels"]))


@dataclass(frozen=True, eq=False)
class NoiseCharacterization(ResultDefaults):
    """Result of :func:`analyze_allan_recording`: one :class:`SegmentNoise` per record.

    A :class:`~imucalib.models.procedure_result.ProcedureResult` (module docstring, "The result
    contract"): no calibration, no triad parameters, *no decision*.
    """

    recording: str  # path of the recording
    device: str
    unit: str
    segments: tuple[SegmentNoise, ...]
    settings: dict[str, Any] = field(default_factory=dict)
    software_version: str = __version__
    created_utc: str = ""
    format_version: int = FORMAT_VERSION

    @property
    def procedure(self) -> str:
        """``"allan"``."""
        return "allan"

    @property
    def decision(self) -> Decision:
        """*No decision* (:data:`NO_DECISION_REASON`); each misfit noise fit in its notes."""
        return no_decision(NO_DECISION_REASON, notes=self.notes)

    @property
    def notes(self) -> tuple[str, ...]:
        """Each noise fit that is a misfit: its record, its axis and its χ²/ν."""
        several = len(self.segments) > 1
        return tuple(f"{f'record {k} ({seg.label}), ' if several else ''}{ch.axis_name} noise "
                     f"fit, {ch.fit.quality.summary()}"
                     for k, seg in enumerate(self.segments) for ch in seg.channels
                     if ch.fit.quality.misfit)

    @property
    def provenance(self) -> Provenance:
        """The recording analysed (its file name), the software and the time."""
        return Provenance(recording=Path(self.recording).name if self.recording else "",
                          software_version=self.software_version, created_utc=self.created_utc)

    @property
    def fit_quality(self) -> tuple[FitQuality, ...]:
        """Each channel's noise fit: χ²/ν against the Allan covariance, misfit verdict."""
        return tuple(ch.fit.quality for seg in self.segments for ch in seg.channels)

    def parameter_rows(self) -> list[ReportedParameter]:
        """Return every detected noise term with its standard uncertainty, for the records.

        One row per detected term of each channel's fit, named ``<axis>_<term>``
        (``gyro_x_white``; docs/noise.md), prefixed ``r<k>.`` by its record's index when the
        characterisation holds more than one record. The σ is the GLS fit's against the Allan
        covariance (not Birge-scaled), so ``std_noise`` = ``std``. A term whose σ is not known
        is left out (the noise JSON keeps it).
        """
        several = len(self.segments) > 1
        rows = []
        for k, seg in enumerate(self.segments):
            prefix = f"r{k}." if several else ""
            for ch in seg.channels:
                for term in ch.fit.terms:
                    if term.detected and math.isfinite(term.value_si) and \
                            math.isfinite(term.std_si):
                        std = float(term.std_si)
                        rows.append(ReportedParameter(f"{prefix}{ch.axis_name}_{term.name}",
                                                      float(term.value_si), std, term.unit_si,
                                                      std))
        return rows

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form (the body of :meth:`to_json`)."""
        return {"format": _FORMAT_NAME, "format_version": self.format_version,
                "recording": self.recording, "device": self.device, "unit": self.unit,
                "settings": self.settings, "software_version": self.software_version,
                "created_utc": self.created_utc,
                "segments": [s.to_dict() for s in self.segments]}

    def to_json(self) -> str:
        """Versioned, strict JSON text (NaN written as null); :meth:`from_json` rebuilds it."""
        return json.dumps(_strict(self.to_dict()), ensure_ascii=False, allow_nan=False)

    @classmethod
    def from_json(cls, text: str) -> NoiseCharacterization:
        """Rebuild a result from :meth:`to_json`.

        Raises
        ------
        InvalidInputError
            Not this format, or a newer ``format_version`` than this software reads.
        """
        data = json.loads(text)
        if not isinstance(data, dict) or data.get("format") != _FORMAT_NAME:
            raise InvalidInputError(f"not an {_FORMAT_NAME} document")
        version = data.get("format_version")
        if not isinstance(version, int) or version > FORMAT_VERSION:
            raise InvalidInputError(f"format_version {version!r} is newer than this software "
                                    f"reads ({FORMAT_VERSION}); upgrade imucalib")
        return cls(recording=data["recording"], device=data["device"], unit=data["unit"],
                   segments=tuple(SegmentNoise.from_dict(s) for s in data["segments"]),
                   settings=data["settings"], software_version=data["software_version"],
                   created_utc=data["created_utc"], format_version=version)

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write :meth:`to_json` to `path`; return the path."""
        out = Path(path)
        out.write_text(self.to_json(), encoding="utf-8")
        return out

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> NoiseCharacterization:
        """Read a file written by :meth:`save`."""
        return cls.from_json(Path(path).read_text(encoding="utf-8"))


def _strict(obj: Any) -> Any:
    """Replace non-finite floats by None (JSON has no NaN); readers turn None back into NaN."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _strict(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_strict(v) for v in obj]
    return obj


def _select_unit(rec: Recording, device: str, unit: str | None) -> str:
    units = [s.unit for s in rec.streams if s.device == device]
    if unit is not None:
        if unit not in units:
            raise InvalidInputError(f"no stream {device}/{unit} in {rec.path.name}; {device} "
                                    f"streams: {units or 'none'}")
        return unit
    if len(units) != 1:
        raise InvalidInputError(f"{rec.path.name} has {len(units)} {device} stream(s) "
                                f"{units}; pass `unit` to choose one")
    return units[0]


def _channels(rec: Recording, device: str, unit: str,
              channels: Sequence[str] | None) -> list[tuple[str, str, float]]:
    info = rec.stream_info(device, unit)
    wanted = list(channels) if channels is not None else [
        c for c in (*GYRO_COLUMNS, *ACCEL_COLUMNS) if c in info.columns]
    if not wanted:
        raise InvalidInputError(f"stream {device}/{unit} has none of the columns "
                                f"{list(GYRO_COLUMNS + ACCEL_COLUMNS)}; columns: "
                                f"{list(info.columns)}")
    out = []
    for name in wanted:
        if name not in info.columns:
            raise InvalidInputError(f"stream {device}/{unit} has no column {name!r}")
        spec = info.columns[name]
        sensor = "gyro" if name.startswith("gyro") else "accel" if name.startswith(
            "accel") else ""
        if not sensor:
            raise InvalidInputError(f"column {name!r} is neither a gyro nor an accelerometer "
                                    "column (names start with 'gyro' or 'accel')")
        if spec.quantity != "si":
            raise InvalidInputError(f"column {name!r} holds raw device output ({spec.unit}); "
                                    "apply the scale factor first (noise terms are in SI)")
        out.append((name, sensor, parse_unit(spec.unit)))
    return out


def _windows(rec: Recording, steps: Iterable[int] | None
             ) -> list[tuple[str, int | None, float | None, float | None]]:
    recorded = rec.steps
    if steps is None:
        if not recorded:
            return [("whole record", None, None, None)]
        chosen = [s for s in recorded if s.kind in STATIC_STEP_KINDS]
        if not chosen:
            kinds = sorted({s.kind for s in recorded})
            raise InvalidInputError(f"{rec.path.name} has no step of kind "
                                    f"{list(STATIC_STEP_KINDS)} (kinds: {kinds}); pass "
                                    "`steps` with the indices of the static records")
    else:
        chosen = [rec.step(int(i)) for i in steps]
    out: list[tuple[str, int | None, float | None, float | None]] = []
    for st in chosen:
        t0, t1 = rec.step_window(st.index, valid_only=st.has_valid_window)
        out.append((st.label or f"step {st.index}", st.index, t0, t1))
    return out


def analyze_allan_recording(recording: Recording | str | os.PathLike[str], *,
                            device: str = "imu", unit: str | None = None,
                            steps: Iterable[int] | None = None,
                            channels: Sequence[str] | None = None, taus: TauSpec = "octave",
                            kinds: Sequence[str] = ("oadev",),
                            confidence: float = ONE_SIGMA,
                            terms: Sequence[str] = FIT_TERMS,
                            chunk_samples: int = 1 << 18,
                            memory_limit_samples: int = 1 << 22,
                            scratch_dir: str | os.PathLike[str] | None = None,
                            sampling_rtol: float = 0.01,
                            tau_min_s: float | None = None,
                            progress: Callable[[float], None] | None = None
                            ) -> NoiseCharacterization:
    """Characterise the noise of an IMU from the static records of a Recording.

    Parameters
    ----------
    recording : Recording or path
        An open :class:`~imucalib.io.reader.Recording` or the path of one (opened and closed).
    device, unit : str
        The stream; `unit` may be omitted when the device has one stream.
    steps : iterable of int, optional
        Step indices to analyse (default: the static steps, or the whole record without steps;
        module docstring).
    channels : sequence of str, optional
        Columns (default: every canonical gyro/accelerometer column present).
    taus : str, int or array_like
        τ grid (:func:`imucalib.analysis.resolve_averaging_factors`); default octave.
    kinds : sequence of str
        Deviations to compute; ``"oadev"`` is always included (the fit uses it).
    confidence : float
        Probability content of the confidence intervals (default ±1σ).
    terms : sequence of str
        Noise terms to fit (:func:`imucalib.analysis.fit_noise_terms`).
    chunk_samples : int
        Rows read from the file at a time.
    memory_limit_samples : int
        Samples per channel kept in memory before spilling to a scratch file
        (:class:`~imucalib.analysis.AllanStream`); memory stays bounded for any record length.
    scratch_dir : path, optional
        Folder of the scratch files (default: the system temporary directory).
    sampling_rtol : float
        Allowed relative deviation of a sample interval from the nominal one.
    tau_min_s : float, optional
        Shortest τ the noise-term fit uses. By default 5 / bandwidth when the recording states
        the IMU's output bandwidth (``imu_identity_json``): an output low-pass lowers the Allan
        deviation at τ below a few filter time constants, which a white-noise term would
        otherwise be bent to follow (the twin's 90 Hz filter at 200 Hz made a fit from the
        first octave read the bias instability 3× too high). Without a bandwidth, every τ. [s]
    progress : callable, optional
        Called after each record with the fraction of the records analysed (increasing; the
        last call is 1.0).

    Returns
    -------
    NoiseCharacterization

    Raises
    ------
    InvalidInputError
        Unknown stream, column or step; no static step; raw counts; non-uniform time stamps,
        gaps or NaN samples (the message says where); a record too short for any τ.
    RecordingError
        If the file cannot be read.
    """
    if isinstance(recording, Recording):
        return _analyze(recording, device, unit, steps, channels, taus, kinds, confidence,
                        terms, chunk_samples, memory_limit_samples, scratch_dir, sampling_rtol,
                        tau_min_s, progress)
    with open_recording(recording) as rec:
        return _analyze(rec, device, unit, steps, channels, taus, kinds, confidence, terms,
                        chunk_samples, memory_limit_samples, scratch_dir, sampling_rtol,
                        tau_min_s, progress)


def _bandwidth_tau_min_s(rec: Recording, unit: str) -> float | None:
    """5 / bandwidth of the IMU's output filter, when the recording states the bandwidth."""
    ident = rec.metadata.get("imu_identity_json")
    info = ident.get(unit, {}) if isinstance(ident, dict) else {}
    bandwidth = info.get("bandwidth_hz") if isinstance(info, dict) else None
    if isinstance(bandwidth, int | float) and bandwidth > 0:
        return 5.0 / float(bandwidth)
    return None


def _analyze(rec: Recording, device: str, unit: str | None, steps: Iterable[int] | None,
             channels: Sequence[str] | None, taus: TauSpec, kinds: Sequence[str],
             confidence: float, terms: Sequence[str], chunk_samples: int,
             memory_limit_samples: int, scratch_dir: str | os.PathLike[str] | None,
             sampling_rtol: float, tau_min_s: float | None,
             progress: Callable[[float], None] | None = None) -> NoiseCharacterization:
    unit = _select_unit(rec, device, unit)
    if tau_min_s is None:
        tau_min_s = _bandwidth_tau_min_s(rec, unit)
    tau_range = None if tau_min_s is None else (float(tau_min_s), math.inf)
    chans = _channels(rec, device, unit, channels)
    all_kinds = tuple(dict.fromkeys(("oadev", *kinds)))
    has_temp = TEMPERATURE_COLUMN in rec.stream_info(device, unit).columns
    columns = [c for c, _, _ in chans] + ([TEMPERATURE_COLUMN] if has_temp else [])
    fit_options = _FitOptions(taus, all_kinds, confidence, tuple(terms), tau_range,
                              memory_limit_samples, scratch_dir, sampling_rtol)
    segments = []
    records = list(_windows(rec, steps))
    for done, (label, index, t0, t1) in enumerate(records, start=1):
        chunks = rec.iter_stream(device, unit, chunk_samples, columns, t0, t1)
        where = f"the window [{t0}, {t1}) s of {device}/{unit}"
        segments.append(_segment(label, index, chunks, chans, has_temp, where, fit_options,
                                 owned=True))
        if progress is not None:
            progress(done / len(records))
    return _characterization(str(rec.path), device, unit, segments, fit_options, tau_min_s)


def _characterization(source: str, device: str, unit: str, segments: Sequence[SegmentNoise],
                      opts: _FitOptions, tau_min_s: float | None) -> NoiseCharacterization:
    taus = opts.taus
    spec = taus if isinstance(taus, str | int) else [float(v) for v in np.ravel(taus)]
    settings = {"taus": spec,
                "kinds": list(opts.kinds), "confidence": opts.confidence,
                "terms": list(opts.terms), "sampling_rtol": opts.sampling_rtol,
                "tau_min_s": tau_min_s}
    return NoiseCharacterization(
        recording=source, device=device, unit=unit, segments=tuple(segments),
        settings=settings, created_utc=datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ"))


@dataclass(frozen=True)
class _FitOptions:
    """Settings shared by every record of one analysis."""

    taus: TauSpec
    kinds: tuple[str, ...]
    confidence: float
    terms: tuple[str, ...]
    tau_range: tuple[float, float] | None
    memory_limit_samples: int
    scratch_dir: str | os.PathLike[str] | None
    sampling_rtol: float


@dataclass(frozen=True)
class _Chunk:
    """A block of samples: what :meth:`Recording.iter_stream` yields, or a slice of arrays."""

    time_s: Any
    columns: Mapping[str, Any]


def _segment(label: str, index: int | None, chunks: Iterable[Any],
             chans: Sequence[tuple[str, str, float]], has_temp: bool, where: str,
             opts: _FitOptions, *, owned: bool = False) -> SegmentNoise:
    """Stream `chunks` (``time_s``, ``columns``) through the deviations and fit each channel.

    `owned`: the chunks' columns are arrays no one else holds (read from the recording), which
    the streams keep instead of copying them.
    """
    check = SamplingCheck(rtol=opts.sampling_rtol)
    streams: dict[str, AllanStream] = {}
    names = [c for c, _, _ in chans] + ([TEMPERATURE_COLUMN] if has_temp else [])
    sums = dict.fromkeys(names, 0.0)
    try:
        for chunk in chunks:
            check.update(chunk.time_s)
            if not streams:
                first = check.n_samples
                rate0 = 1.0 / float(np.median(np.diff(chunk.time_s))) if first > 1 else 1.0
                streams = {c: AllanStream(rate0, unit=_SI_UNIT[s], scratch_dir=opts.scratch_dir,
                                          memory_limit_samples=opts.memory_limit_samples)
                           for c, s, _ in chans}
            for c, _, factor in chans:
                values = np.asarray(chunk.columns[c], dtype=np.float64)
                if factor != 1.0:  # x·1 is x: no pass and no copy for SI columns
                    values = values * factor
                try:  # an array of our own (read, converted or scaled here) is kept, not copied
                    sums[c] += streams[c].append(
                        values, copy=not (owned or values is not chunk.columns[c]))
                except InvalidInputError as exc:
                    raise InvalidInputError(f"{label}, column {c}: {exc}") from exc
            if has_temp:
                sums[TEMPERATURE_COLUMN] += float(np.sum(chunk.columns[TEMPERATURE_COLUMN],
                                                         dtype=np.float64))
        n = check.n_samples
        if n < 3:
            raise InvalidInputError(f"{label}: {n} sample(s) in {where}; need at least 3")
        rate = check.sample_rate_hz()
        if not rate <= MAX_SAMPLE_RATE_HZ:
            raise InvalidInputError(
                f"{label}: the samples of {where} are {1.0 / rate:.3g} s apart ({rate:.4g} Hz); "
                f"an IMU samples at most {MAX_SAMPLE_RATE_HZ:g} Hz: is the time in seconds? "
                "(give its unit: `--time-unit ms`, or `time_s [ms]` in the header)")
        results = []
        for c, sensor, _ in chans:
            streams[c].sample_rate_hz = rate
            devs = streams[c].compute(opts.kinds, taus=opts.taus, confidence=opts.confidence)
            try:
                fit = fit_noise_terms(devs["oadev"], sensor=sensor, terms=opts.terms,
                                      tau_range_s=opts.tau_range)
            except InvalidInputError as exc:
                raise InvalidInputError(f"{label}, column {c}: {exc}") from exc
            results.append(ChannelNoise(c, sensor, devs, fit, sums[c] / n))
    finally:
        for s in streams.values():
            s.close()
    return SegmentNoise(
        label=label, step_index=index, t_start_s=check.t_first_s,
        t_end_s=check.t_last_s, n_samples=n, sample_rate_hz=rate,
        temperature_degc=sums[TEMPERATURE_COLUMN] / n if has_temp else None,
        channels=tuple(results))


def analyze_allan_arrays(time_s: ArrayLike, columns: Mapping[str, ArrayLike], *,
                         source: str, device: str = "imu", unit: str = "imu",
                         label: str = "whole record", taus: TauSpec = "octave",
                         kinds: Sequence[str] = ("oadev",), confidence: float = ONE_SIGMA,
                         terms: Sequence[str] = FIT_TERMS, chunk_samples: int = 1 << 18,
                         memory_limit_samples: int = 1 << 22,
                         scratch_dir: str | os.PathLike[str] | None = None,
                         sampling_rtol: float = 0.01,
                         tau_min_s: float | None = None) -> NoiseCharacterization:
    """Characterise the noise of one static record given as arrays (a CSV, no Recording).

    The same analysis as :func:`analyze_allan_recording` (one record, ``"whole record"``):
    `columns` maps canonical names (``gyro_x_rps`` …, ``accel_z_mps2``, optionally
    ``temperature_degc``) to SI samples at the times `time_s` [s]; gyro and accelerometer
    columns are analysed. `source` names the data in the result (its path).

    Raises
    ------
    InvalidInputError
        No gyro or accelerometer column, arrays of unequal length, non-uniform time stamps,
        or a record too short for any τ.
    """
    t = np.asarray(time_s, dtype=np.float64)
    chans = [(c, "gyro" if c in GYRO_COLUMNS else "accel", 1.0)
             for c in (*GYRO_COLUMNS, *ACCEL_COLUMNS) if c in columns]
    if not chans:
        raise InvalidInputError(f"{source}: none of the columns "
                                f"{list(GYRO_COLUMNS + ACCEL_COLUMNS)}; found {sorted(columns)}")
    data = {c: np.asarray(columns[c], dtype=np.float64) for c, _, _ in chans}
    has_temp = TEMPERATURE_COLUMN in columns
    if has_temp:
        data[TEMPERATURE_COLUMN] = np.asarray(columns[TEMPERATURE_COLUMN], dtype=np.float64)
    for c, v in data.items():
        if v.shape != t.shape:
            raise InvalidInputError(f"{source}: column {c} has {v.size} samples; time_s has "
                                    f"{t.size}")
    tau_range = None if tau_min_s is None else (float(tau_min_s), math.inf)
    opts = _FitOptions(taus, tuple(dict.fromkeys(("oadev", *kinds))), confidence, tuple(terms),
                       tau_range, memory_limit_samples, scratch_dir, sampling_rtol)
    step = max(int(chunk_samples), 1)
    chunks = (_Chunk(t[i:i + step], {c: v[i:i + step] for c, v in data.items()})
              for i in range(0, t.size, step))
    seg = _segment(label, None, chunks, chans, has_temp, source, opts)
    return _characterization(source, device, unit, [seg], opts, tau_min_s)
