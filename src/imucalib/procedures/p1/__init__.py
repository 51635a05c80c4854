"""Procedure P1: two-dimensional calibration of an IMU on a dual-axis table.

Modules: :mod:`.plan` (the default plan), :mod:`.observations` (recording → window means),
:mod:`.fit` (the triad and per-axis models), :mod:`.analysis` (fit, verification, decision).
"""
