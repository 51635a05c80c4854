"""Deterministic error models and stochastic noise models of IMU triads.

Contents
--------
:mod:`imucalib.models.triad`
    :class:`TriadModel`, :func:`apply_triad` (true → measured), :func:`correct_triad`
    (measured → true), :data:`PARAMETER_NAMES`, :data:`TriadKind`.
:mod:`imucalib.models.temperature`
    :class:`TemperatureDependence`, :func:`evaluate_parameter`, :func:`hysteresis_state`.
:mod:`imucalib.models.noise`
    :class:`NoiseModel`, :func:`compute_theoretical_adev`.
:mod:`imucalib.models.noise_generator`
    :class:`NoiseGenerator`, :func:`simulate_noise` (samples of a model's noise).
:mod:`imucalib.models.sensor`
    :class:`SensorSpec` (range, resolution, bandwidth), :class:`OutputChain`.
:mod:`imucalib.models.imu`
    :class:`ImuModel`, :data:`GRADES`, :data:`THERMAL_GRADES`, :func:`sample_imu_model`.
:mod:`imucalib.models.earth`
    :class:`Site` (Earth rate, normal gravity, the table's heading), imported from its module.
:mod:`imucalib.models.correct`
    :func:`correct_imu`, :func:`correct_imu_frame` (a calibration result applied to data, at
    each sample's temperature when the result has temperature models), :func:`temperature_leg`,
    :class:`TemperatureRate`, imported from its module.
:mod:`imucalib.models.temperature_record`
    :class:`ParameterTemperatureModel` (one parameter's fitted temperature model, as a
    calibration result carries it), :class:`HeldOutOutcome`, imported from its module.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from imucalib._lazy import lazy_getattr

if TYPE_CHECKING:
    from imucalib.models.imu import GRADES, THERMAL_GRADES, GradeSpec, ImuModel, sample_imu_model
    from imucalib.models.noise import NoiseModel, compute_theoretical_adev
    from imucalib.models.noise_generator import NoiseGenerator, simulate_noise
    from imucalib.models.sensor import OutputChain, SensorSpec, apply_output_chain
    from imucalib.models.temperature import (
        TemperatureDependence,
        evaluate_parameter,
        hysteresis_state,
    )
    from imucalib.models.triad import (
        PARAMETER_NAMES,
        TriadKind,
        TriadModel,
        apply_triad,
        correct_triad,
    )

__all__ = [
    "GRADES",
    "PARAMETER_NAMES",
    "THERMAL_GRADES",
    "GradeSpec",
    "ImuModel",
    "NoiseGenerator",
    "NoiseModel",
    "OutputChain",
    "SensorSpec",
    "TemperatureDependence",
    "TriadKind",
    "TriadModel",
    "apply_output_chain",
    "apply_triad",
    "compute_theoretical_adev",
    "correct_triad",
    "evaluate_parameter",
    "hysteresis_state",
    "sample_imu_model",
    "simulate_noise",
]

_IMU, _NOISE, _SENSOR = "imucalib.models.imu", "imucalib.models.noise", "imucalib.models.sensor"
_GENERATOR = "imucalib.models.noise_generator"
_TEMPERATURE, _TRIAD = "imucalib.models.temperature", "imucalib.models.triad"

#: Module of each public name, imported on first access (PEP 562): importing one module of this
#: package (the result file's reader, a result) does not import the others.
__getattr__ = lazy_getattr(__name__, {
    **dict.fromkeys(("GRADES", "THERMAL_GRADES", "GradeSpec", "ImuModel", "sample_imu_model"),
                    _IMU),
    **dict.fromkeys(("NoiseModel", "compute_theoretical_adev"), _NOISE),
    **dict.fromkeys(("NoiseGenerator", "simulate_noise"), _GENERATOR),
    **dict.fromkeys(("OutputChain", "SensorSpec", "apply_output_chain"), _SENSOR),
    **dict.fromkeys(("TemperatureDependence", "evaluate_parameter", "hysteresis_state"),
                    _TEMPERATURE),
    **dict.fromkeys(("PARAMETER_NAMES", "TriadKind", "TriadModel", "apply_triad",
                     "correct_triad"), _TRIAD),
})
