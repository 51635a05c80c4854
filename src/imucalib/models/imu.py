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
:class:`ThermalGradeSpec`, :data:`THERMAL_GRADES`, :data:`THERMAL_RANGE_DEGC`
    Typical temperature swings of the biases, scale factors and misalignments per grade
    (docs/equations.md §13), used to draw temperature-dependent truths.
:func:`sample_imu_model`
    Draw a random IMU of a grade (every random function takes ``rng``), optionally with a
    temperature dependence and thermal hysteresis of its biases, scale factors and misalignments.

Typical temperature dependence
------------------------------
With ``temperature_dependence="typical"`` every bias b_i, scale factor M_ii and misalignment
M_ij (i ≠ j) of both triads gets a cubic in (T − T0) (docs/equations.md §4)::

    p(T) = p0 + c1·(T − T0) + c2·(T − T0)² + c3·(T − T0)³ + h·s

Its swing (max − min over :data:`THERMAL_RANGE_DEGC`, −40 … +85 °C) is drawn uniformly in
[0.5, 1.5] × the grade's typical swing below, and its shape at random with a real cubic part: the
Legendre P3 component over the range (the part no quadratic in T represents) spans at least 25 %
of the swing, so a quadratic fit leaves visible residuals. The hysteresis amplitude is
h = ``hysteresis_fraction`` × swing with a random sign, width w = 5 °C.

============  ===========  ==========  ==============  =============  =====================
grade         gyro bias    accel bias  gyro scale      accel scale    misalignments
============  ===========  ==========  ==============  =============  =====================
consumer      0.3 °/s      20 mg       10000 ppm       10000 ppm      2 mrad (σ/4)
tactical      10 °/h       0.5 mg      300 ppm         300 ppm        0.125 mrad (σ/4)
navigation    0.05 °/h     30 µg       5 ppm           100 ppm        0.005 mrad (σ/4)
============  ===========  ==========  ==============  =============  =====================

The coefficients come from a child generator spawned from the IMU's generator after its other
draws, so the truth drawn with ``temperature_dependence="none"`` is unchanged.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
from numpy.polynomial import Legendre, Polynomial
from numpy.typing import NDArray

from imucalib import units
from imucalib._checks import check_finite_scalar, check_positive
from imucalib.errors import ConfigurationError, InvalidInputError
from imucalib.models.noise import NoiseModel
from imucalib.models.sensor import SensorSpec
from imucalib.models.temperature import TemperatureDependence, evaluate_parameter
from imucalib.models.triad import TriadModel

__all__ = ["GRADES", "THERMAL_GRADES", "THERMAL_RANGE_DEGC", "GradeName", "GradeSpec",
           "ImuModel", "TemperatureDependenceKind", "ThermalGradeSpec", "sample_imu_model"]

GradeName = Literal["consumer", "tactical", "navigation"]
#: Temperature dependence drawn by :func:`sample_imu_model`.
TemperatureDependenceKind = Literal["none", "typical"]
_AXES = "xyz"


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

    def parameters_at(self, temperature_degc: float,
                      hysteresis_state: float = 0.0) -> dict[str, float]:
        """Return the true value of every calibration parameter at a temperature and state.

        Parameters
        ----------
        temperature_degc : float
            Sensor temperature T. [°C]
        hysteresis_state : float
            Thermal hysteresis state s in [−1, 1]: +1 after heating, −1 after cooling by several
            hysteresis widths, 0 without thermal history (docs/equations.md §4). [–]

        Returns
        -------
        dict of str to float
            ``<triad>_bias_<i>`` [rad/s | m/s²], ``<triad>_M_<ij>`` (y = b + (I + M)·x, row i the
            sensor axis, column j the input axis) [–] for ``gyro`` and ``accel``, and
            ``gyro_G_<ij>`` [rad/s per m/s²]: the names of
            :func:`~imucalib.models.result.triad_parameter_names`.

        Raises
        ------
        InvalidInputError
            If the temperature is not finite or the state is outside [−1, 1].
        """
        temp = check_finite_scalar(temperature_degc, "temperature_degc")
        state = check_finite_scalar(hysteresis_state, "hysteresis_state")
        if abs(state) > 1.0:
            raise InvalidInputError(f"`hysteresis_state` must be within [-1, 1]; got {state}")
        out: dict[str, float] = {}
        for triad, tm in (("gyro", self.gyro), ("accel", self.accel)):
            def at(name: str, tm: TriadModel = tm) -> NDArray[np.float64]:
                value = evaluate_parameter(getattr(tm, name), name, tm.temperature, temp, None,
                                           state)
                return value.reshape(getattr(tm, name).shape)
            bias, mat = at("bias"), at("scale_misalignment")
            for i, a in enumerate(_AXES):
                out[f"{triad}_bias_{a}"] = float(bias[i])
            for i, a in enumerate(_AXES):
                for j, b in enumerate(_AXES):
                    out[f"{triad}_M_{a}{b}"] = float(mat[i, j])
            if triad == "gyro":
                g = at("g_sensitivity")
                for i, a in enumerate(_AXES):
                    for j, b in enumerate(_AXES):
                        out[f"gyro_G_{a}{b}"] = float(g[i, j])
        return out

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


#: The temperature range over which :data:`THERMAL_GRADES` gives the swings. [°C]
THERMAL_RANGE_DEGC: tuple[float, float] = (-40.0, 85.0)


@dataclass(frozen=True)
class ThermalGradeSpec:
    """Typical swing (max − min over :data:`THERMAL_RANGE_DEGC`) of parameters with temperature.

    Biases swing by about the grade's bias σ, scale factors by its scale σ and misalignments by a
    quarter of its misalignment σ (docs/equations.md §13), in the units of their names.
    """

    gyro_bias_dph: float
    accel_bias_ug: float
    gyro_scale_ppm: float
    accel_scale_ppm: float
    gyro_misalignment_mrad: float
    accel_misalignment_mrad: float


#: Typical temperature swings per grade (module docstring's table).
THERMAL_GRADES: dict[str, ThermalGradeSpec] = {
    "consumer": ThermalGradeSpec(
        gyro_bias_dph=1080.0,  # 0.3 °/s
        accel_bias_ug=20000.0,  # 20 mg
        gyro_scale_ppm=10000.0,
        accel_scale_ppm=10000.0,
        gyro_misalignment_mrad=2.0,
        accel_misalignment_mrad=2.0,
    ),
    "tactical": ThermalGradeSpec(
        gyro_bias_dph=10.0,
        accel_bias_ug=500.0,
        gyro_scale_ppm=300.0,
        accel_scale_ppm=300.0,
        gyro_misalignment_mrad=0.125,
        accel_misalignment_mrad=0.125,
    ),
    "navigation": ThermalGradeSpec(
        gyro_bias_dph=0.05,
        accel_bias_ug=30.0,
        gyro_scale_ppm=5.0,
        accel_scale_ppm=100.0,
        gyro_misalignment_mrad=0.005,
        accel_misalignment_mrad=0.005,
    ),
}

_SWING_GRID_POINTS = 501  # temperatures at which a drawn curve's swing is evaluated
_MIN_CUBIC_SHARE = 0.25  # least span of the Legendre P3 part, as a fraction of the swing
_HYSTERESIS_WIDTH_DEGC = 5.0


def _draw_curve(gen: np.random.Generator, swing: float, t0_degc: float,
                hysteresis_fraction: float) -> tuple[NDArray[np.float64], float]:
    """Draw (c1, c2, c3) in (T − T0) and a hysteresis amplitude for one parameter entry."""
    lo, hi = THERMAL_RANGE_DEGC
    grid = np.linspace(lo - t0_degc, hi - t0_degc, _SWING_GRID_POINTS)
    while True:  # a cubic whose P3 part spans ≥ _MIN_CUBIC_SHARE of the swing (P3 spans 2)
        beta = gen.normal(0.0, 1.0, 3)
        poly = Legendre(np.concatenate([[0.0], beta]),
                        domain=[lo - t0_degc, hi - t0_degc]).convert(kind=Polynomial)
        coef = np.zeros(4)
        coef[: poly.coef.size] = poly.coef
        coef[0] = 0.0  # p(T0) = p0
        values = Polynomial(coef)(grid)
        span = float(values.max() - values.min())
        if span > 0.0 and 2.0 * abs(beta[2]) >= _MIN_CUBIC_SHARE * span:
            break
    target = swing * gen.uniform(0.5, 1.5)
    sign = 1.0 if gen.random() < 0.5 else -1.0
    return coef[1:] * (target / span), sign * hysteresis_fraction * target


def _typical_dependence(gen: np.random.Generator, bias_swing: float, scale_swing: float,
                        misalignment_swing: float, t0_degc: float,
                        hysteresis_fraction: float) -> TemperatureDependence:
    """Draw a triad's typical dependence: bias (3 entries), then M row by row (9 entries)."""
    bias_c, bias_h = np.zeros((3, 3)), np.zeros(3)
    for i in range(3):
        bias_c[:, i], bias_h[i] = _draw_curve(gen, bias_swing, t0_degc, hysteresis_fraction)
    mat_c, mat_h = np.zeros((3, 3, 3)), np.zeros((3, 3))
    for i in range(3):
        for j in range(3):
            swing = scale_swing if i == j else misalignment_swing
            mat_c[:, i, j], mat_h[i, j] = _draw_curve(gen, swing, t0_degc, hysteresis_fraction)
    hysteresis = ({"bias": bias_h, "scale_misalignment": mat_h} if hysteresis_fraction > 0.0
                  else {})
    return TemperatureDependence(
        reference_temperature_degc=t0_degc,
        coefficients={"bias": bias_c, "scale_misalignment": mat_c},
        hysteresis=hysteresis,
        hysteresis_width_degc=_HYSTERESIS_WIDTH_DEGC,
    )


def sample_imu_model(
    grade: str,
    rng: np.random.Generator | int | None = None,
    *,
    sample_rate_hz: float | None = None,
    nonlinear: bool = True,
    temperature_dependence: TemperatureDependenceKind = "none",
    hysteresis_fraction: float = 0.0,
    reference_temperature_degc: float = 25.0,
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
    temperature_dependence : {"none", "typical"}
        ``"typical"`` draws a cubic temperature dependence of every bias, scale factor and
        misalignment of both triads with the grade's :data:`THERMAL_GRADES` swing (module
        docstring); ``"none"`` draws none.
    hysteresis_fraction : float
        With ``"typical"``: thermal hysteresis amplitude h of each of those parameters as a
        fraction of its swing, in [0, 0.5] (random sign, width 5 °C). [–]
    reference_temperature_degc : float
        T0, the temperature at which the drawn biases, scale factors and misalignments hold
        (with ``"typical"``). [°C]

    Returns
    -------
    ImuModel
        Biases, scale factors and misalignments drawn as N(0, σ²) with the grade's σ (their
        values at T0 with ``"typical"``); noise coefficients at the grade's nominal values.

    Raises
    ------
    ConfigurationError
        If `grade` or `temperature_dependence` is not one of the known ones.
    InvalidInputError
        If `hysteresis_fraction` is outside [0, 0.5] or given without ``"typical"``, or
        `reference_temperature_degc` is not finite.
    """
    if grade not in GRADES:
        raise ConfigurationError(f"unknown IMU grade {grade!r}; expected one of {sorted(GRADES)}")
    if temperature_dependence not in ("none", "typical"):
        raise ConfigurationError(
            f"`temperature_dependence` must be 'none' or 'typical'; got {temperature_dependence!r}"
        )
    fraction = check_finite_scalar(hysteresis_fraction, "hysteresis_fraction")
    if not 0.0 <= fraction <= 0.5:
        raise InvalidInputError(f"`hysteresis_fraction` must be in [0, 0.5]; got {fraction}")
    if fraction > 0.0 and temperature_dependence == "none":
        raise InvalidInputError(
            "`hysteresis_fraction` > 0 needs temperature_dependence='typical'"
        )
    t0 = check_finite_scalar(reference_temperature_degc, "reference_temperature_degc")
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
    if temperature_dependence == "typical":
        # a child generator spawned after every other draw: the draws above stay as they were
        tgen = gen.spawn(1)[0]
        th = THERMAL_GRADES[grade]
        gyro = gyro.replace(temperature=_typical_dependence(
            tgen, th.gyro_bias_dph * units.DEG_PER_H, th.gyro_scale_ppm * units.PPM,
            th.gyro_misalignment_mrad * units.MRAD, t0, fraction))
        accel = accel.replace(temperature=_typical_dependence(
            tgen, th.accel_bias_ug * units.UG, th.accel_scale_ppm * units.PPM,
            th.accel_misalignment_mrad * units.MRAD, t0, fraction))
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
