"""Analysis: verification of calibrations (and, with the noise toolkit, Allan-family deviations).

Contents
--------
:mod:`imucalib.analysis.verification`
    :func:`check_residuals`, :func:`check_accuracy`, :func:`check_repeatability`,
    :func:`decide`, :class:`Check`, :class:`CheckRow`, :class:`Decision`,
    :data:`DECISION_RULE`.
"""

from __future__ import annotations

# --- verification ---
from imucalib.analysis.verification import (
    DECISION_RULE,
    Check,
    CheckRow,
    Decision,
    check_accuracy,
    check_repeatability,
    check_residuals,
    decide,
)

__all__ = [
    "DECISION_RULE",
    "Check",
    "CheckRow",
    "Decision",
    "check_accuracy",
    "check_repeatability",
    "check_residuals",
    "decide",
]
# --- end verification ---
