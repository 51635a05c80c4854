"""Pure estimators: weighted and nonlinear least squares, Kalman filter, Cramér–Rao bounds.

Everything here works on arrays (no Recording access) and returns frozen dataclasses; a design
that cannot determine its parameters raises
:class:`~imucalib.errors.InsufficientExcitationError` naming them. Algorithms, equations and
choices: ``docs/processing-estimation.md``.

Contents
--------
:mod:`imucalib.estimation.linear`
    :func:`solve_weighted_lsq` → :class:`LsqSolution`: the one weighted least-squares solver of
    every linear fit (σ, weights or a full covariance; the misfit rule of
    :mod:`imucalib.models.fit_quality` and the Birge-scaled covariance).
:mod:`imucalib.estimation.nonlinear`
    :func:`solve_nonlinear_lsq` → :class:`NlsSolution`.
:mod:`imucalib.estimation.kalman`
    :func:`kf_predict`, :func:`kf_update` (→ :class:`KalmanUpdate`), :class:`KalmanFilter`,
    :func:`refine_with_kalman` → :class:`KalmanRefinement`.
:mod:`imucalib.estimation.crlb`
    :func:`compute_crlb` → :class:`CrlbResult`; closed forms
    :func:`compute_six_position_accel_crlb`, :func:`compute_sphere_accel_crlb` (→
    :class:`TriadCrlb`), :func:`compute_rate_table_gyro_crlb` (→ :class:`RateTableCrlb`).
:mod:`imucalib.estimation.noise_covariance`
    :func:`compute_window_mean_covariance` (coloured-noise covariance of window means).
:mod:`imucalib.estimation.observability`
    :func:`compute_observability` → :class:`ObservabilityReport`.
:mod:`imucalib.estimation.temperature_model`
    :func:`fit_temperature_model` → :class:`TemperatureModelFit`, :func:`check_held_out`,
    :func:`predict_temperature_model`, :func:`to_temperature_dependence`.
:mod:`imucalib.estimation.designs`
    :func:`build_design` (the one triad design builder, by model term) and its 12-parameter
    case :func:`build_triad_design` → :class:`LinearDesign`, :data:`SIX_POSITION_UP_B`,
    :data:`TRIAD_PARAMETER_NAMES`.
:mod:`imucalib.estimation.gravity_norm` (imported on its own)
    :func:`~imucalib.estimation.gravity_norm.fit_gravity_norm` (the accelerometer triad from
    static poses of unknown orientation), :func:`~imucalib.estimation.gravity_norm.pose_coverage`.
:mod:`imucalib.estimation.gyro_rotations` (imported on its own)
    :func:`~imucalib.estimation.gyro_rotations.fit_gyro_rotations` (the gyro's M from hand
    rotations between static poses and known turns),
    :func:`~imucalib.estimation.gyro_rotations.fit_turns_linear`.
"""

from __future__ import annotations

from imucalib.estimation.crlb import (
    CrlbResult,
    RateTableCrlb,
    TriadCrlb,
    compute_crlb,
    compute_rate_table_gyro_crlb,
    compute_six_position_accel_crlb,
    compute_sphere_accel_crlb,
)
from imucalib.estimation.designs import (
    SIX_POSITION_UP_B,
    TRIAD_PARAMETER_NAMES,
    LinearDesign,
    build_design,
    build_triad_design,
)
from imucalib.estimation.kalman import (
    KalmanFilter,
    KalmanRefinement,
    KalmanUpdate,
    kf_predict,
    kf_update,
    refine_with_kalman,
)
from imucalib.estimation.linear import LsqSolution, solve_weighted_lsq
from imucalib.estimation.noise_covariance import compute_window_mean_covariance
from imucalib.estimation.nonlinear import NlsSolution, solve_nonlinear_lsq
from imucalib.estimation.observability import (
    DEFAULT_COND_LIMIT,
    ObservabilityReport,
    compute_observability,
)
from imucalib.estimation.temperature_forms import (
    from_temperature_dependence,
    to_temperature_dependence,
)
from imucalib.estimation.temperature_model import (
    HeldOutCheck,
    TemperatureModelFit,
    TemperaturePolynomial,
    TemperaturePrediction,
    check_held_out,
    fit_temperature_model,
    predict_temperature_model,
)

__all__ = [
    "DEFAULT_COND_LIMIT",
    "SIX_POSITION_UP_B",
    "TRIAD_PARAMETER_NAMES",
    "CrlbResult",
    "HeldOutCheck",
    "KalmanFilter",
    "KalmanRefinement",
    "KalmanUpdate",
    "LinearDesign",
    "LsqSolution",
    "NlsSolution",
    "ObservabilityReport",
    "RateTableCrlb",
    "TemperatureModelFit",
    "TemperaturePolynomial",
    "TemperaturePrediction",
    "TriadCrlb",
    "build_design",
    "build_triad_design",
    "check_held_out",
    "compute_crlb",
    "compute_observability",
    "compute_rate_table_gyro_crlb",
    "compute_six_position_accel_crlb",
    "compute_sphere_accel_crlb",
    "compute_window_mean_covariance",
    "fit_temperature_model",
    "from_temperature_dependence",
    "kf_predict",
    "kf_update",
    "predict_temperature_model",
    "refine_with_kalman",
    "solve_nonlinear_lsq",
    "solve_weighted_lsq",
    "to_temperature_dependence",
]
