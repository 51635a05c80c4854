"""Signal processing between the data and the solvers: samples in, window values out.

Pure functions on arrays (no Recording access) returning frozen dataclasses. Algorithms,
equations and choices: ``docs/processing-estimation.md``. The outlier, low-pass and
synchronisation modules are P1's processing rules 1–3 (docs/p1.md); the window statistics serve
every procedure (``procedures/common/windows.py``); segmentation and the static detector find
intervals in data without step records (``imucalib segments``, docs/import.md; the ``field``
procedure, docs/field.md).

Contents
--------
:mod:`imucalib.processing.outliers`
    :func:`reject_outliers_robust` (P1's default), :func:`reject_outliers_3sigma`,
    :func:`reject_outliers_grubbs` (→ :class:`OutlierResult`), :func:`robust_threshold`,
    :func:`grubbs_critical_value`.
:mod:`imucalib.processing.filtering`
    :func:`lowpass_zero_phase` (→ :class:`LowpassResult`), :func:`compute_effective_cutoff_hz`,
    :data:`SPEC_CUTOFF_FRACTION_RANGE`.
:mod:`imucalib.processing.sync`
    :func:`synchronize` (→ :class:`SyncResult`), :func:`reconstruct_time_base`
    (→ :class:`TimeBase`: device time on the host clock from the sample counter),
    :func:`estimate_timestamp_jitter_s`, :data:`DEFAULT_MAX_ALIGNMENT_ERROR_S`.
:mod:`imucalib.processing.statistics`
    :func:`compute_window_statistics` (→ :class:`WindowStatistics`: the standard error of a
    window mean with correlated noise), :func:`compute_integer_revolution_window`
    (→ :class:`RevolutionWindow`).
:mod:`imucalib.processing.segmentation`
    :func:`detect_segments` (→ :class:`SegmentationResult` of :class:`Segment`;
    :data:`SEGMENT_LABELS`): static and constant-rate intervals of a table run
    (``imucalib segments --detector table``).
:mod:`imucalib.processing.static_detector`
    :func:`detect_static_and_rotations` (→ :class:`StaticDetection`, with :class:`Rotation`):
    the variance detector of hand-held logs (``--detector variance``; the ``field``
    procedure).
"""

from __future__ import annotations

from imucalib.processing.filtering import (
    SPEC_CUTOFF_FRACTION_RANGE,
    LowpassResult,
    compute_effective_cutoff_hz,
    lowpass_zero_phase,
)
from imucalib.processing.outliers import (
    OutlierResult,
    grubbs_critical_value,
    reject_outliers_3sigma,
    reject_outliers_grubbs,
    reject_outliers_robust,
    robust_threshold,
)
from imucalib.processing.segmentation import (
    SEGMENT_LABELS,
    Segment,
    SegmentationResult,
    detect_segments,
)
from imucalib.processing.static_detector import (
    Rotation,
    StaticDetection,
    detect_static_and_rotations,
)
from imucalib.processing.statistics import (
    RevolutionWindow,
    WindowStatistics,
    compute_integer_revolution_window,
    compute_window_statistics,
)
from imucalib.processing.sync import (
    DEFAULT_MAX_ALIGNMENT_ERROR_S,
    SyncResult,
    TimeBase,
    estimate_timestamp_jitter_s,
    reconstruct_time_base,
    synchronize,
)

__all__ = [
    "DEFAULT_MAX_ALIGNMENT_ERROR_S",
    "SEGMENT_LABELS",
    "SPEC_CUTOFF_FRACTION_RANGE",
    "LowpassResult",
    "OutlierResult",
    "RevolutionWindow",
    "Rotation",
    "Segment",
    "SegmentationResult",
    "StaticDetection",
    "SyncResult",
    "TimeBase",
    "WindowStatistics",
    "compute_effective_cutoff_hz",
    "compute_integer_revolution_window",
    "compute_window_statistics",
    "detect_segments",
    "detect_static_and_rotations",
    "estimate_timestamp_jitter_s",
    "grubbs_critical_value",
    "lowpass_zero_phase",
    "reconstruct_time_base",
    "reject_outliers_3sigma",
    "reject_outliers_grubbs",
    "reject_outliers_robust",
    "robust_threshold",
    "synchronize",
]
