"""Procedures: one module per calibration procedure (plan generator and analysis).

Contents
--------
:mod:`imucalib.procedures.allan.analysis`
    :func:`analyze_allan_recording`, :class:`NoiseCharacterization`, :class:`SegmentNoise`,
    :class:`ChannelNoise`, :data:`STATIC_STEP_KINDS`.
:mod:`imucalib.procedures.allan.plan`
    :func:`generate_allan_plan`: warm-up, soaks and long static records.
:mod:`imucalib.procedures.p1.plan`
    :func:`generate_p1_plan`: SPEC.md P1's plan (six positions, static bias, rates, held-out
    checks, repetitions).
:mod:`imucalib.procedures.p1.analysis`
    :func:`~imucalib.procedures.p1.analysis.analyze_p1` (imported from its module: it pulls in the
    whole analysis chain).
"""

from __future__ import annotations

from imucalib.procedures.allan.analysis import (
    STATIC_STEP_KINDS,
    ChannelNoise,
    NoiseCharacterization,
    SegmentNoise,
    analyze_allan_recording,
)
from imucalib.procedures.allan.plan import generate_allan_plan
from imucalib.procedures.p1.plan import (
    P1_HELD_OUT_POSITIONS_DEG,
    P1_SIX_POSITIONS_DEG,
    generate_p1_plan,
)

__all__ = [
    "P1_HELD_OUT_POSITIONS_DEG",
    "P1_SIX_POSITIONS_DEG",
    "STATIC_STEP_KINDS",
    "ChannelNoise",
    "NoiseCharacterization",
    "SegmentNoise",
    "analyze_allan_recording",
    "generate_allan_plan",
    "generate_p1_plan",
]
