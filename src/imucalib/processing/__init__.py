"""Signal processing between a Recording and the solvers (P1 processing rules 1–3, docs/p1.md).

Pure functions on arrays (no Recording access) returning frozen dataclasses. Algorithms,
equations and choices: ``docs/processing-estimation.md``.

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
    (→ :class:`TimeBase`), :func:`estimate_timestamp_jitter_s`,
    :data:`DEFAULT_MAX_ALIGNMENT_ERROR_S`.
:mod:`imucalib.processing.statistics`
    :func:`compute_window_statistics` (→ :class:`WindowStatistics`),
    :func:`compute_integer_revolution_window` (→ :class:`RevolutionWindow`).
:mod:`imucalib.processing.segmentation`
    :func:`detect_segments` (→ :class:`SegmentationResult` of :class:`Segment`).
:mod:`imucalib.processing.static_detector`
    :func:`detect_static_and_rotations` (→ :class:`StaticDetection`, with :class:`Rotation`):
    the variance detector of hand-held logs.
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
