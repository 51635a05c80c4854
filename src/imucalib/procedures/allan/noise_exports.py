"""Exports of IMU noise parameters: Kalibr / OpenVINS YAML and a datasheet-style table.

Contents
--------
:func:`format_kalibr_yaml`, :func:`write_kalibr_yaml`
    Kalibr's ``imu.yaml``.
:func:`format_openvins_yaml`, :func:`write_openvins_yaml`
    OpenVINS' ``kalibr_imu_chain.yaml`` (``%YAML:1.0``, ``imu0`` block, model ``kalibr`` with
    identity intrinsics unless given).
:func:`format_noise_table`
    Datasheet-style table (``"text"``, ``"csv"`` or ``"markdown"``), from
    :mod:`imucalib.report.noise_table` (the report shows it too).

Conversions (docs/noise.md §5; :mod:`imucalib.analysis.noise_units`)
-------------------------------------------------------------------
Kalibr and OpenVINS model the white noise as a continuous-time process of density σ_c and
discretise it as σ_d = σ_c/√Δt; the bias as a random walk ḃ = σ_b·w(t). So

==============================  ==============================  ==============================
YAML key                        value                           unit
==============================  ==============================  ==============================
``gyroscope_noise_density``     N_gyro (two-sided; σ_Allan(1 s)) rad/s/√Hz = rad/√s
``gyroscope_random_walk``       K_gyro (σ_Allan(3 s) = K)        rad/s²/√Hz = rad/s/√s
``accelerometer_noise_density`` N_accel                          m/s²/√Hz = m/s/√s
``accelerometer_random_walk``   K_accel                          m/s³/√Hz = m/s²/√s
``update_rate``                 sample rate                      Hz
==============================  ==============================  ==============================

The densities (:class:`~imucalib.analysis.noise_parameters.ImuNoiseParameters`) come from
:func:`~imucalib.analysis.noise_parameters.noise_parameters_from_fits`. No factor √2 enters:
Kalibr's σ_c *is* the two-sided N (a one-sided datasheet density ND is √2·N, and
ARW[°/√h] = 60·N[°/√s]). A triad gives one number per key: the largest axis by default
(``combine="max"``, conservative) or the RMS over axes. A random walk that the fit did not detect
is exported as its 1σ scale (the uncertainty of the absent term) and flagged in a YAML comment;
Kalibr and OpenVINS need a non-zero value. Their authors advise inflating Allan values for real
motion (vibration, temperature); `noise_inflation`/`walk_inflation` do that explicitly.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from imucalib.analysis.noise_parameters import ImuNoiseParameters
from imucalib.errors import InvalidInputError
from imucalib.report.noise_table import TABLE_ROWS, format_noise_table

__all__ = [
    "TABLE_ROWS",
    "format_kalibr_yaml",
    "format_noise_table",
    "format_openvins_yaml",
    "write_kalibr_yaml",
    "write_openvins_yaml",
]


def _header(params: ImuNoiseParameters) -> list[str]:
    lines = ["# Written by imucalib from an Allan-variance noise characterisation.",
             "# Continuous-time densities, two-sided (Kalibr sigma_c = N = sigma_Allan(1 s));",
             "# a one-sided datasheet density is sqrt(2) times larger."]
    lines += [f"# {n}" for n in params.notes]
    return lines


def format_kalibr_yaml(params: ImuNoiseParameters, *, rostopic: str = "/imu0") -> str:
    """Return Kalibr's ``imu.yaml`` text for `params`."""
    p = params
    return "\n".join([
        *_header(p),
        "",
        "#Accelerometers",
        f"accelerometer_noise_density: {p.accelerometer_noise_density:.6e}   "
        "#Noise density (continuous-time) [m/s^2/sqrt(Hz)]",
        f"accelerometer_random_walk:   {p.accelerometer_random_walk:.6e}   "
        "#Bias random walk [m/s^3/sqrt(Hz)]",
        "",
        "#Gyroscopes",
        f"gyroscope_noise_density:     {p.gyroscope_noise_density:.6e}   "
        "#Noise density (continuous-time) [rad/s/sqrt(Hz)]",
        f"gyroscope_random_walk:       {p.gyroscope_random_walk:.6e}   "
        "#Bias random walk [rad/s^2/sqrt(Hz)]",
        "",
        f"rostopic:                    {rostopic}   #the IMU ROS topic",
        f"update_rate:                 {p.update_rate_hz:.6g}   "
        "#Hz (for discretization of the values above)",
        "",
    ])


def _matrix(rows: ArrayLike, indent: str) -> list[str]:
    arr = np.asarray(rows, dtype=np.float64)
    return [f"{indent}- [{', '.join(f'{v:.9g}' for v in row)}]" for row in arr]


def format_openvins_yaml(params: ImuNoiseParameters, *, rostopic: str = "/imu0",
                         time_offset_s: float = 0.0, t_i_b: ArrayLike | None = None,
                         intrinsics: Mapping[str, ArrayLike] | None = None) -> str:
    """Return OpenVINS' ``kalibr_imu_chain.yaml`` text (``imu0``, model ``kalibr``).

    `t_i_b` is the 4×4 IMU-to-body transform (identity by default); `intrinsics` may give the
    3×3 matrices ``Tw``, ``R_IMUtoGYRO``, ``Ta``, ``R_IMUtoACC``, ``Tg`` (identity, and zero
    for ``Tg``, by default: an IMU whose intrinsics are already applied).
    """
    p = params
    eye = np.eye(3)
    mats: dict[str, ArrayLike] = {"Tw": eye, "R_IMUtoGYRO": eye, "Ta": eye, "R_IMUtoACC": eye,
                                  "Tg": np.zeros((3, 3))}
    if intrinsics:
        unknown = sorted(set(intrinsics) - set(mats))
        if unknown:
            raise InvalidInputError(f"unknown intrinsics {unknown}; expected {sorted(mats)}")
        mats.update(intrinsics)
    tib = np.eye(4) if t_i_b is None else np.asarray(t_i_b, dtype=np.float64)
    if tib.shape != (4, 4):
        raise InvalidInputError(f"`t_i_b` must be 4x4; got shape {tib.shape}")
    lines = ["%YAML:1.0 # need to specify the file type at the top!", *_header(p), "", "imu0:",
             "  T_i_b:", *_matrix(tib, "    "),
             f"  accelerometer_noise_density: {p.accelerometer_noise_density:.6e}  "
             "# [ m / s^2 / sqrt(Hz) ]   ( accel \"white noise\" )",
             f"  accelerometer_random_walk: {p.accelerometer_random_walk:.6e}  "
             "# [ m / s^3 / sqrt(Hz) ].  ( accel bias diffusion )",
             f"  gyroscope_noise_density: {p.gyroscope_noise_density:.6e}  "
             "# [ rad / s / sqrt(Hz) ]   ( gyro \"white noise\" )",
             f"  gyroscope_random_walk: {p.gyroscope_random_walk:.6e}  "
             "# [ rad / s^2 / sqrt(Hz) ] ( gyro bias diffusion )",
             f"  rostopic: {rostopic}",
             f"  time_offset: {float(time_offset_s):.9g}",
             f"  update_rate: {p.update_rate_hz:.6g}",
             "  model: \"kalibr\""]
    for name, value in mats.items():
        arr = np.asarray(value, dtype=np.float64)
        if arr.shape != (3, 3):
            raise InvalidInputError(f"intrinsic `{name}` must be 3x3; got shape {arr.shape}")
        lines += [f"  {name}:", *_matrix(arr, "    ")]
    return "\n".join(lines) + "\n"


def write_kalibr_yaml(path: str | os.PathLike[str], params: ImuNoiseParameters,
                      **kwargs: str) -> Path:
    """Write :func:`format_kalibr_yaml` to `path`; return the path."""
    out = Path(path)
    out.write_text(format_kalibr_yaml(params, **kwargs), encoding="utf-8")
    return out


def write_openvins_yaml(path: str | os.PathLike[str], params: ImuNoiseParameters,
                        **kwargs: object) -> Path:
    """Write :func:`format_openvins_yaml` to `path`; return the path."""
    out = Path(path)
    out.write_text(format_openvins_yaml(params, **kwargs), encoding="utf-8")  # type: ignore[arg-type]
    return out
