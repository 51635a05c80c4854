"""Analysis: Allan-family deviations and IMU noise-term fits; verification of calibrations.

Contents
--------
:mod:`imucalib.analysis.allan`
    :class:`DeviationResult`, :func:`compute_deviation` and :func:`compute_adev`,
    :func:`compute_oadev`, :func:`compute_mdev`, :func:`compute_tdev`, :func:`compute_hdev`,
    :func:`compute_ohdev`, :func:`compute_totdev`; :func:`resolve_averaging_factors`,
    :func:`check_uniform_sampling`, :class:`SamplingCheck`, :data:`DEVIATION_KINDS`.
:mod:`imucalib.analysis.streaming`
    :class:`AllanStream`, :func:`compute_deviations_streaming` (exact results in bounded
    memory).
:mod:`imucalib.analysis.edf`
    :func:`compute_edf`, :func:`compute_edf_greenhall`, :func:`compute_edf_totdev`,
    :func:`compute_confidence_interval`, :func:`identify_noise_lag1`,
    :class:`NoiseIdentification`, :data:`NOISE_TYPES`, :data:`ONE_SIGMA`.
:mod:`imucalib.analysis.noise_fit`
    :func:`fit_noise_terms`, :class:`NoiseFit`, :class:`NoiseTerm`, :func:`read_slope_lines`,
    :func:`term_avar`, :func:`make_noise_term`, :data:`FIT_TERMS`, :data:`FLICKER_FACTOR`.
:mod:`imucalib.analysis.bias_instability`
    :func:`read_allan_minimum`, :class:`AllanMinimum` (the Allan minimum over the usable τ, its
    detection test and upper bound; imported from its module).
:mod:`imucalib.analysis.noise_parameters`
    :class:`ImuNoiseParameters`, :func:`noise_parameters_from_fits` (the densities a VIO filter
    takes; imported from its module).
:mod:`imucalib.analysis.noise_units`
    :func:`convert_noise_term`, :class:`UnitValue`, :data:`DENSITY_CONVENTION`.
:func:`kernel_backend`, :func:`set_kernel_backend`
    Which compiled kernels run (numba, or the bit-identical numpy twin).
:mod:`imucalib.analysis.verification`
    :func:`check_residuals`, :func:`check_accuracy`, :func:`check_repeatability`,
    :func:`decide`, :class:`Check`, :class:`CheckRow`, :class:`Decision`,
    :data:`DECISION_RULE`.
"""

from __future__ import annotations

from imucalib.analysis._allan_kernels import backend_name as kernel_backend
from imucalib.analysis._allan_kernels import set_backend as set_kernel_backend
from imucalib.analysis.allan import (
    DEVIATION_KINDS,
    DeviationResult,
    SamplingCheck,
    check_uniform_sampling,
    compute_adev,
    compute_deviation,
    compute_hdev,
    compute_mdev,
    compute_oadev,
    compute_ohdev,
    compute_tdev,
    compute_totdev,
    resolve_averaging_factors,
)
from imucalib.analysis.edf import (
    NOISE_TYPES,
    ONE_SIGMA,
    NoiseIdentification,
    compute_confidence_interval,
    compute_edf,
    compute_edf_greenhall,
    compute_edf_totdev,
    identify_noise_lag1,
)
from imucalib.analysis.noise_fit import (
    FIT_TERMS,
    FLICKER_FACTOR,
    NoiseFit,
    NoiseTerm,
    fit_noise_terms,
    make_noise_term,
    read_slope_lines,
    term_avar,
)
from imucalib.analysis.noise_units import DENSITY_CONVENTION, UnitValue, convert_noise_term
from imucalib.analysis.streaming import AllanStream, compute_deviations_streaming
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
    "DENSITY_CONVENTION",
    "DEVIATION_KINDS",
    "FIT_TERMS",
    "FLICKER_FACTOR",
    "NOISE_TYPES",
    "ONE_SIGMA",
    "AllanStream",
    "Check",
    "CheckRow",
    "Decision",
    "DeviationResult",
    "NoiseFit",
    "NoiseIdentification",
    "NoiseTerm",
    "SamplingCheck",
    "UnitValue",
    "check_accuracy",
    "check_repeatability",
    "check_residuals",
    "check_uniform_sampling",
    "compute_adev",
    "compute_confidence_interval",
    "compute_deviation",
    "compute_deviations_streaming",
    "compute_edf",
    "compute_edf_greenhall",
    "compute_edf_totdev",
    "compute_hdev",
    "compute_mdev",
    "compute_oadev",
    "compute_ohdev",
    "compute_tdev",
    "compute_totdev",
    "convert_noise_term",
    "decide",
    "fit_noise_terms",
    "identify_noise_lag1",
    "kernel_backend",
    "make_noise_term",
    "read_slope_lines",
    "resolve_averaging_factors",
    "set_kernel_backend",
    "term_avar",
]
