"""Procedures: one module per calibration procedure (plan generator and analysis).

Each block below is one procedure's public API; see the module docstrings.

Contents
--------
:mod:`imucalib.procedures.allan`
    :func:`analyze_allan_recording`, :class:`NoiseCharacterization`, :class:`SegmentNoise`,
    :class:`ChannelNoise`, :data:`STATIC_STEP_KINDS`.
"""

from __future__ import annotations

# --- allan ---
from imucalib.procedures.allan import (
    STATIC_STEP_KINDS,
    ChannelNoise,
    NoiseCharacterization,
    SegmentNoise,
    analyze_allan_recording,
)

# --- end allan ---

__all__ = [
    # --- allan ---
    "STATIC_STEP_KINDS",
    "ChannelNoise",
    "NoiseCharacterization",
    "SegmentNoise",
    "analyze_allan_recording",
    # --- end allan ---
]
