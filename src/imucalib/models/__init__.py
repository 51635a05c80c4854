"""Deterministic error models and stochastic noise models of IMU triads.

Each block below is one module's public API; see the module docstrings.

Contents
--------
:mod:`imucalib.models.triad`
    :class:`TriadModel`, :func:`apply_triad` (true → measured), :func:`correct_triad`
    (measured → true), :data:`PARAMETER_NAMES`, :data:`TriadKind`.
:mod:`imucalib.models.temperature`
    :class:`TemperatureDependence`, :func:`evaluate_parameter`.
"""

from __future__ import annotations

# --- triad ---
from imucalib.models.temperature import TemperatureDependence, evaluate_parameter
from imucalib.models.triad import (
    PARAMETER_NAMES,
    TriadKind,
    TriadModel,
    apply_triad,
    correct_triad,
)

# --- end triad ---

__all__ = [
    # --- triad ---
    "PARAMETER_NAMES",
    "TemperatureDependence",
    "TriadKind",
    "TriadModel",
    "apply_triad",
    "correct_triad",
    "evaluate_parameter",
    # --- end triad ---
]
