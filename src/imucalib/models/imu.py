"""A whole IMU: two triads, their noise, their output stages, and grade presets.

Contents
--------
:class:`ImuModel`
    Gyro and accelerometer :class:`~imucalib.models.triad.TriadModel`, their
    :class:`~imucalib.models.noise.NoiseModel`, their :class:`~imucalib.models.sensor.SensorSpec`
    and the output data rate.
:class:`GradeSpec`, :data:`GRADES`
    One-sigma spreads of the error parameters of consumer-MEMS, tactical and navigation-grade IMUs
    (docs/equations.md §13), used to draw realistic truths for the twin.
:func:`sample_imu_model`
    Draw a random IMU of a grade (every random function takes ``rng``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from imucalib import units
from imucalib._checks import check_positive
from imucalib.errors import ConfigurationError
from imucalib.models.noise import NoiseModel
from imucalib.models.sensor import SensorSpec
from imucalib.models.triad import TriadModel

__all__ = ["GRADES", "GradeName", "GradeSpec", "ImuModel", "sample_imu_model"]

GradeName = Literal["consumer", "tactical", "navigation"]


@dataclass(frozen=True, eq=False)
class ImuModel:
    """The truth (or nominal model) of one IMU.

    Parameters
    ----------
    gyro, accel : TriadModel
        Deterministic errors of the gyro triad [rad/s] and accelerometer triad [m/s²].
    gyro_noise, accel_noise : NoiseModel
        Stochastic errors (two-sided density convention, see :mod:`imucalib.models.noise`).
    gyro_output, accel_output : SensorSpec
        Output stage: range, resolution, bandwidth.
    sample_rate_hz : float
        Output data rate (nominal; the twin's clock model adds drift). [Hz]
    """

    gyro: TriadModel
    accel: TriadModel
    gyro_noise: NoiseModel = field(default_factory=NoiseModel)
    accel_noise: NoiseModel = field(default_factory=NoiseModel)
    gyro_output: SensorSpec = field(default_factory=SensorSpec)
    accel_output: SensorSpec = field(default_factory=SensorSpec)
    sample_rate_hz: float = 1000.0

    def __post_init__(self) -> None:
        check_positive(self.sample_rate_hz, "sample_rate_hz")
        if self.gyro.kind != "gyro":
            raise ConfigurationError(
                f"`gyro` must be a gyro TriadModel; got kind {self.gyro.kind!r}"
            )
        if self.accel.kind != "accel":
            raise ConfigurationError(
                f"`accel` must be an accel TriadModel; got kind {self.accel.kind!r}"
            )
        for name, spec in (("gyro_output", self.gyro_output), ("accel_output", self.accel_output)):
            bw = spec.bandwidth_hz
            if bw is not None and bw >= self.sample_rate_hz / 2:
                raise ConfigurationError(
                    f"`{name}.bandwidth_hz` must be below the Nyquist frequency "
                    f"{self.sample_rate_hz / 2} Hz; got {bw} Hz"
                )

    @classmethod
    def ideal(cls, sample_rate_hz: float = 1000.0) -> ImuModel:
        """Return an error-free, noise-free IMU."""
        return cls(
            gyro=TriadModel.ideal("gyro"),
            accel=TriadModel.ideal("accel"),
            sample_rate_hz=sample_rate_hz,
        )

    def to_dict(self) -> dict[str, Any]:
        """Return a JSON-able description (exact round trip through :meth:`from_dict`)."""
        return {
            "gyro": self.gyro.to_dict(),
            "accel": self.accel.to_dict(),
            "gyro_noise": self.gyro_noise.to_dict(),
            "accel_noise": self.accel_noise.to_dict(),
            "gyro_output": _spec_to_dict(self.gyro_output),
            "accel_output": _spec_to_dict(self.accel_output),
            "sample_rate_hz": self.sample_rate_hz,
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> ImuModel:
        """Rebuild a model written by :meth:`to_dict`."""
        return cls(
            gyro=TriadModel.from_dict(data["gyro"]),
            accel=TriadModel.from_dict(data["accel"]),
            gyro_noise=NoiseModel.from_dict(data["gyro_noise"]),
            accel_noise=NoiseModel.from_dict(data["accel_noise"]),
            gyro_output=SensorSpec(**data["gyro_output"]),
            accel_output=SensorSpec(**data["accel_output"]),
            sample_rate_hz=float(data["sample_rate_hz"]),
        )


def _spec_to_dict(spec: SensorSpec) -> dict[str, Any]:
    return {
        "range": spec.range,
        "resolution_bits": spec.resolution_bits,
        "lsb": spec.lsb,
        "bandwidth_hz": spec.bandwidth_hz,
    }


@dataclass(frozen=True)
class GradeSpec:
    """One-sigma spreads of an IMU grade's errors, in the units of their names.

    Values follow the grade ranges of docs/equations.md §13 (El-Sheimy & Youssef 2020, Groves
    2013, and indicative datasheets such as HG9900, HG1700, MPU-6050/BMI160 class parts).
    """

    gyro_bias_dph: float
    gyro_scale_ppm: float
    gyro_misalignment_mrad: float
    gyro_g_sensitivity_dph_per_g: float
    gyro_arw_deg_rth: float
    gyro_bias_instability_dph: float
    gyro_rrw_deg_h_rth: float
    accel_bias_ug: float
    accel_scale_ppm: float
    accel_misalignment_mrad: float
    accel_k2_ug_per_g2: float
    accel_vrw_ug_rthz: float
    accel_bias_instability_ug: float
    gyro_range_dps: float
    accel_range_g: float
    resolution_bits: int | None
    bandwidth_hz: float
    sample_rate_hz: float
    lever_arm_mm: float


#: The three grades of the project's closed-loop tests.
GRADES: dict[str, GradeSpec] = {
    "consumer": GradeSpec(
        gyro_bias_dph=1800.0,  # 0.5 °/s
        gyro_scale_ppm=10000.0,
        gyro_misalignment_mrad=8.0,
        gyro_g_sensitivity_dph_per_g=360.0,  # 0.1 (°/s)/g
        gyro_arw_deg_rth=0.3,
        gyro_bias_instability_dph=8.0,
        gyro_rrw_deg_h_rth=30.0,
        accel_bias_ug=40000.0,
        accel_scale_ppm=10000.0,
        accel_misalignment_mrad=8.0,
        accel_k2_ug_per_g2=1000.0,
        accel_vrw_ug_rthz=150.0,
        accel_bias_instability_ug=60.0,
        gyro_range_dps=2000.0,
        accel_range_g=16.0,
        resolution_bits=16,
        bandwidth_hz=200.0,
        sample_rate_hz=1000.0,
        lever_arm_mm=3.0,
    ),
    "tactical": GradeSpec(
        gyro_bias_dph=5.0,
        gyro_scale_ppm=300.0,
        gyro_misalignment_mrad=0.5,
        gyro_g_sensitivity_dph_per_g=1.0,
        gyro_arw_deg_rth=0.125,
        gyro_bias_instability_dph=1.0,
        gyro_rrw_deg_h_rth=0.5,
        accel_bias_ug=1000.0,
        accel_scale_ppm=300.0,
        accel_misalignment_mrad=0.5,
        accel_k2_ug_per_g2=50.0,
        accel_vrw_ug_rthz=50.0,
        accel_bias_instability_ug=20.0,
        gyro_range_dps=1000.0,
        accel_range_g=30.0,
        resolution_bits=24,
        bandwidth_hz=200.0,
        sample_rate_hz=1000.0,
        lever_arm_mm=5.0,
    ),
    "navigation": GradeSpec(
        gyro_bias_dph=0.003,
        gyro_scale_ppm=5.0,
        gyro_misalignment_mrad=0.02,
        gyro_g_sensitivity_dph_per_g=0.0,  # ring-laser / fibre gyros: nominally none
        gyro_arw_deg_rth=0.002,
        gyro_bias_instability_dph=0.003,
        gyro_rrw_deg_h_rth=0.0005,
        accel_bias_ug=25.0,
        accel_scale_ppm=100.0,
        accel_misalignment_mrad=0.02,
        accel_k2_ug_per_g2=10.0,
        accel_vrw_ug_rthz=10.0,
        accel_bias_instability_ug=2.0,
        gyro_range_dps=400.0,
        accel_range_g=30.0,
        resolution_bits=None,
        bandwidth_hz=200.0,
        sample_rate_hz=1000.0,
        lever_arm_mm=10.0,
    ),
}


def sample_imu_model(
    grade: str,
    rng: np.random.Generator | int | None = None,
    *,
    sample_rate_hz: float | None = None,
    nonlinear: bool = True,
) -> ImuModel:
    """Draw a random IMU of a grade: the truth the twin simulates.

    Parameters
    ----------
    grade : {"consumer", "tactical", "navigation"}
        Row of :data:`GRADES`.
    rng : numpy.random.Generator or int or None
        Random source (seed).
    sample_rate_hz : float, optional
        Output data rate; the grade's default when omitted. [Hz]
    nonlinear : bool
        Draw accelerometer K2 (quadratic) terms too.

    Returns
    -------
    ImuModel
        Biases, scale factors and misalignments drawn as N(0, σ²) with the grade's σ; noise
        coefficients at the grade's nominal values.

    Raises
    ------
    ConfigurationError
        If `grade` is not one of the known grades.
    """
    if grade not in GRADES:
        raise ConfigurationError(f"unknown IMU grade {grade!r}; expected one of {sorted(GRADES)}")
    spec = GRADES[grade]
    gen = np.random.default_rng(rng)
    fs = spec.sample_rate_hz if sample_rate_hz is None else check_positive(
        sample_rate_hz, "sample_rate_hz"
    )

    def scale_mis(scale_ppm: float, mis_mrad: float) -> np.ndarray:
        m = gen.normal(0.0, mis_mrad * units.MRAD, (3, 3))
        m[np.diag_indices(3)] = gen.normal(0.0, scale_ppm * units.PPM, 3)
        return m

    gyro = TriadModel(
        kind="gyro",
        bias=gen.normal(0.0, spec.gyro_bias_dph * units.DEG_PER_H, 3),
        scale_misalignment=scale_mis(spec.gyro_scale_ppm, spec.gyro_misalignment_mrad),
        g_sensitivity=gen.normal(
            0.0, spec.gyro_g_sensitivity_dph_per_g * units.DEG_PER_H / units.G0_MPS2, (3, 3)
        ),
    )
    k2 = (
        gen.normal(0.0, spec.accel_k2_ug_per_g2 * units.UG / units.G0_MPS2**2, 3)
        if nonlinear
        else np.zeros(3)
    )
    arms = gen.normal(0.0, spec.lever_arm_mm * 1e-3, (3, 3))
    arms[np.diag_indices(3)] = 0.0  # each accelerometer's offset along its own axis is zero
    accel = TriadModel(
        kind="accel",
        bias=gen.normal(0.0, spec.accel_bias_ug * units.UG, 3),
        scale_misalignment=scale_mis(spec.accel_scale_ppm, spec.accel_misalignment_mrad),
        k2=k2,
        lever_arms_b_m=arms,
    )
    gyro_noise = NoiseModel(
        white_density=spec.gyro_arw_deg_rth * units.DEG_PER_RTH,
        bias_instability=spec.gyro_bias_instability_dph * units.DEG_PER_H,
        random_walk=spec.gyro_rrw_deg_h_rth * units.DEG_PER_H_RTH,
    )
    accel_noise = NoiseModel(
        white_density=spec.accel_vrw_ug_rthz * units.UG_PER_RTHZ,
        bias_instability=spec.accel_bias_instability_ug * units.UG,
    )
    bw = min(spec.bandwidth_hz, 0.45 * fs)
    gyro_range = spec.gyro_range_dps * units.DEG_PER_S
    accel_range = spec.accel_range_g * units.G0_MPS2
    return ImuModel(
        gyro=gyro,
        accel=accel,
        gyro_noise=gyro_noise,
        accel_noise=accel_noise,
        gyro_output=SensorSpec(
            range=gyro_range, resolution_bits=spec.resolution_bits, bandwidth_hz=bw
        ),
        accel_output=SensorSpec(
            range=accel_range, resolution_bits=spec.resolution_bits, bandwidth_hz=bw
        ),
        sample_rate_hz=fs,
    )
