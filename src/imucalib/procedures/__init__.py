"""Procedures: one module per procedure, with its default plan and its analysis.

Contents
--------
:mod:`imucalib.procedures.p1_plan`
    :func:`generate_p1_plan`: SPEC.md P1's plan (six positions, static bias, rates, held-out
    checks, repetitions).
"""

from __future__ import annotations

# --- p1 ---
from imucalib.procedures.p1_plan import (
    P1_HELD_OUT_POSITIONS_DEG,
    P1_SIX_POSITIONS_DEG,
    generate_p1_plan,
)

__all__ = [
    "P1_HELD_OUT_POSITIONS_DEG",
    "P1_SIX_POSITIONS_DEG",
    "generate_p1_plan",
]
# --- end p1 ---
