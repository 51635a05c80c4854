"""Procedures: the shared part (:mod:`.common`) and one folder per procedure.

Each procedure folder holds its plan generator, its analysis and a ``procedure`` module whose
``PROCEDURE`` implements :class:`~imucalib.procedures.common.procedure.Procedure`; the
:mod:`~imucalib.procedures.registry` finds them by name (docs/procedures.md).

Contents
--------
:mod:`imucalib.procedures.registry`
    :func:`~imucalib.procedures.registry.get`, :func:`~imucalib.procedures.registry.names`,
    :func:`~imucalib.procedures.registry.register`,
    :func:`~imucalib.procedures.registry.identify`.
:mod:`imucalib.procedures.common`
    The :class:`Procedure` and :class:`ProcedureResult` protocols; window statistics, reference
    inputs, the noise model of window means and the triad design builder.
:mod:`imucalib.procedures.p1`
    P1: :mod:`.p1.plan` (:func:`generate_p1_plan`), :mod:`.p1.observations`, :mod:`.p1.fit`,
    :mod:`.p1.analysis` (:func:`~imucalib.procedures.p1.analysis.analyze_p1`).
:mod:`imucalib.procedures.allan`
    The Allan procedure: :mod:`.allan.plan` (:func:`generate_allan_plan`), :mod:`.allan.analysis`
    (:func:`analyze_allan_recording`, :class:`NoiseCharacterization`, :class:`SegmentNoise`,
    :class:`ChannelNoise`, :data:`STATIC_STEP_KINDS`).

The names listed under p1 and allan are also attributes of this package, imported on first
access (importing the package imports no analysis).
"""

from __future__ import annotations

from imucalib._lazy import lazy_getattr

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

_LAZY = {
    "P1_HELD_OUT_POSITIONS_DEG": "imucalib.procedures.p1.plan",
    "P1_SIX_POSITIONS_DEG": "imucalib.procedures.p1.plan",
    "generate_p1_plan": "imucalib.procedures.p1.plan",
    "generate_allan_plan": "imucalib.procedures.allan.plan",
    "STATIC_STEP_KINDS": "imucalib.procedures.allan.analysis",
    "ChannelNoise": "imucalib.procedures.allan.analysis",
    "NoiseCharacterization": "imucalib.procedures.allan.analysis",
    "SegmentNoise": "imucalib.procedures.allan.analysis",
    "analyze_allan_recording": "imucalib.procedures.allan.analysis",
}

__getattr__ = lazy_getattr(__name__, _LAZY)
