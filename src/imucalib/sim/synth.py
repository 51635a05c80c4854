"""IMU synthesis at each IMU's own sample clock.

An IMU on the twin samples at its own (drifting) oscillator, timestamps with its own counter, and
its packets reach the station with latency and jitter; some may be lost. Its outputs are the truth
passed through the error model (:func:`~imucalib.models.triad.apply_triad`), plus noise
(:class:`~imucalib.models.noise_generator.NoiseGenerator`), through the output stage
(:class:`~imucalib.models.sensor.OutputChain`: bandwidth, saturation, resolution).

Contents
--------
:class:`ClockSpec`
    Oscillator drift, transport latency and jitter, dropped samples.
:class:`SimImu`
    One IMU unit on the twin: its name (serial), true :class:`~imucalib.models.imu.ImuModel`,
    clock, thermal behaviour and mount.
:class:`ImuSamples`
    One chunk of synthesised output (with the truth it came from).
:class:`ImuSynthesizer`
    Stateful generator, continuing noise, filters and clock across chunks (bounded memory).

Timing model
------------
Sample k is taken at true time t_k = φ + k / (f_s·(1 + δ)) where f_s is the nominal output data
rate, δ the oscillator error (``drift_ppm``·1e-6) and φ the phase. The device stamps it
``device_time_s = k / f_s`` and ``counter = k mod 2**counter_bits``; the station receives it at
``time_s = t_k + latency + jitter·ε_k`` (ε standard normal), made non-decreasing as a host clock
stamping a serial stream would. A dropped sample (probability ``drop_probability``) is generated
(its noise is part of the physical process) but not delivered, so the counter shows a gap.

Thermal hysteresis
------------------
When a triad's temperature dependence has hysteresis terms, its state s
(:func:`~imucalib.models.temperature.hysteresis_state`, docs/equations.md §4) follows the IMU's
true temperature at its samples, from s = 0 at the first sample, and is carried from one chunk to
the next (the last temperature and state), so that the record does not depend on the chunking.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from imucalib._checks import check_finite_scalar, check_nonnegative
from imucalib.errors import ConfigurationError, InvalidInputError
from imucalib.models.imu import ImuModel
from imucalib.models.noise_generator import NoiseGenerator
from imucalib.models.sensor import OutputChain
from imucalib.models.temperature import hysteresis_state
from imucalib.models.triad import TriadModel, apply_triad
from imucalib.sim.chamber import ImuThermalSpec
from imucalib.sim.fixture import MountedImu
from imucalib.sim.kinematics import ImuKinematics

__all__ = ["ClockSpec", "ImuSamples", "ImuSynthesizer", "SimImu"]

#: Returns the IMU's true kinematics at the given true times.
KinematicsSource = Callable[[NDArray[np.float64]], ImuKinematics]
#: Returns (temperature [°C], temperature rate [°C/s]) of the IMU at the given true times.
TemperatureSource = Callable[[NDArray[np.float64]], tuple[NDArray[np.float64], NDArray[np.float64]]]


@dataclass(frozen=True)
class ClockSpec:
    """Sample clock and transport of one IMU.

    Parameters
    ----------
    drift_ppm : float
        Oscillator frequency error; the true rate is f_s·(1 + drift_ppm·1e-6). [ppm]
    jitter_s : float
        Standard deviation of the receive-time jitter. [s]
    latency_s : float
        Mean transport latency. [s]
    drop_probability : float
        Probability that a sample is lost in transport, in [0, 1).
    phase_s : float
        True time of sample 0. [s]
    counter_bits : int
        Width of the sample counter (it wraps at 2**counter_bits).
    """

    drift_ppm: float = 0.0
    jitter_s: float = 0.0
    latency_s: float = 0.0
    drop_probability: float = 0.0
    phase_s: float = 0.0
    counter_bits: int = 32

    def __post_init__(self) -> None:
        check_finite_scalar(self.drift_ppm, "drift_ppm")
        if abs(self.drift_ppm) >= 1e5:
            raise InvalidInputError(f"`drift_ppm` must be within ±1e5; got {self.drift_ppm}")
        check_nonnegative(self.jitter_s, "jitter_s")
        check_nonnegative(self.latency_s, "latency_s")
        check_finite_scalar(self.phase_s, "phase_s")
        p = check_finite_scalar(self.drop_probability, "drop_probability")
        if not 0.0 <= p < 1.0:
            raise InvalidInputError(f"`drop_probability` must be in [0, 1); got {p}")
        if not 8 <= int(self.counter_bits) <= 63:
            raise InvalidInputError(f"`counter_bits` must be in [8, 63]; got {self.counter_bits}")


@dataclass(frozen=True)
class SimImu:
    """One IMU unit on the twin.

    Parameters
    ----------
    name : str
        Serial number or name; the Recording's stream unit.
    model : ImuModel
        The truth this unit follows.
    clock : ClockSpec
        Sample clock and transport.
    thermal : ImuThermalSpec
        Thermal lag behind the surrounding air and self-heating.
    mount : MountedImu or None
        Where it sits on the fixture; ``None`` means at the fixture origin, axes aligned.
    temperature_resolution_degc : float
        Resolution of the internal temperature sensor. [°C]
    """

    name: str
    model: ImuModel
    clock: ClockSpec = field(default_factory=ClockSpec)
    thermal: ImuThermalSpec = field(default_factory=ImuThermalSpec)
    mount: MountedImu | None = None
    temperature_resolution_degc: float = 1.0 / 256.0

    def __post_init__(self) -> None:
        if not self.name or not self.name.strip():
            raise ConfigurationError("`name` of a SimImu must be a non-empty string")
        check_nonnegative(self.temperature_resolution_degc, "temperature_resolution_degc")


@dataclass(frozen=True)
class ImuSamples:
    """A chunk of IMU output as the station receives it, with the truth behind it.

    Attributes
    ----------
    time_s : ndarray, shape (n,)
        Station receive time. [s]
    device_time_s : ndarray, shape (n,)
        The IMU's own timestamp, counter / nominal rate. [s]
    counter : ndarray of int64, shape (n,)
        Sample counter (wraps at 2**counter_bits; gaps show dropped samples).
    gyro_rps : ndarray, shape (n, 3)
        Gyro output in the sensor frame. [rad/s]
    accel_mps2 : ndarray, shape (n, 3)
        Accelerometer output in the sensor frame. [m/s²]
    temperature_degc : ndarray, shape (n,)
        Internal temperature sensor reading. [°C]
    saturated : ndarray of bool, shape (n,)
        True where any channel hit its range.
    true_time_s : ndarray, shape (n,)
        True sampling time (truth). [s]
    true_rate_b_rps, true_specific_force_b_mps2 : ndarray, shape (n, 3)
        True inputs (truth). [rad/s], [m/s²]
    true_temperature_degc : ndarray, shape (n,)
        True IMU temperature (truth). [°C]
    """

    time_s: NDArray[np.float64]
    device_time_s: NDArray[np.float64]
    counter: NDArray[np.int64]
    gyro_rps: NDArray[np.float64]
    accel_mps2: NDArray[np.float64]
    temperature_degc: NDArray[np.float64]
    saturated: NDArray[np.bool_]
    true_time_s: NDArray[np.float64]
    true_rate_b_rps: NDArray[np.float64]
    true_specific_force_b_mps2: NDArray[np.float64]
    true_temperature_degc: NDArray[np.float64]

    def __len__(self) -> int:
        return int(self.time_s.shape[0])


class ImuSynthesizer:
    """Generate an IMU's output chunk by chunk, continuing its clock, noise and filters.

    Parameters
    ----------
    imu : SimImu
        The unit to synthesise.
    rng : numpy.random.Generator or int or None
        Random source; independent child generators feed the gyro noise, the accelerometer
        noise, the jitter and the drops, so any chunking of a record gives the same values.
    """

    def __init__(self, imu: SimImu, rng: np.random.Generator | int | None = None) -> None:
        self.imu = imu
        # one child generator per process, so that any chunking gives the same record
        gyro_rng, accel_rng, self._jitter_rng, self._drop_rng = np.random.default_rng(rng).spawn(4)
        model = imu.model
        dt = 1.0 / model.sample_rate_hz
        self._gyro_noise = NoiseGenerator(model.gyro_noise, dt, gyro_rng)
        self._accel_noise = NoiseGenerator(model.accel_noise, dt, accel_rng)
        self._gyro_out = OutputChain(model.gyro_output, model.sample_rate_hz)
        self._accel_out = OutputChain(model.accel_output, model.sample_rate_hz)
        self._next_index = 0
        self._last_time_s = -np.inf
        # per triad: (true temperature [°C], hysteresis state) at the last sample generated
        self._hysteresis: dict[str, tuple[float, float]] = {}

    @property
    def hysteresis_states(self) -> dict[str, float]:
        """Thermal hysteresis state at the last sample generated, per triad with hysteresis.

        Keys ``"gyro"`` and ``"accel"``; a triad without hysteresis terms, or one not yet
        sampled, has no entry. [–]
        """
        return {kind: state for kind, (_, state) in self._hysteresis.items()}

    def _hysteresis_state(self, triad: TriadModel,
                          temp_degc: NDArray[np.float64]) -> NDArray[np.float64] | None:
        """Advance `triad`'s hysteresis state over this chunk's true temperatures."""
        dep = triad.temperature
        if dep is None or not dep.has_hysteresis:
            return None
        last = self._hysteresis.get(triad.kind)
        if last is None:  # the first sample: state 0
            states, final = hysteresis_state(temp_degc, 0.0, dep.hysteresis_width_degc)
        else:
            history = np.concatenate([[last[0]], temp_degc])
            states, final = hysteresis_state(history, last[1], dep.hysteresis_width_degc)
            states = states[1:]
        self._hysteresis[triad.kind] = (float(temp_degc[-1]), final)
        return states

    @property
    def true_period_s(self) -> float:
        """True sampling interval, including the oscillator error. [s]"""
        return 1.0 / (self.imu.model.sample_rate_hz * (1.0 + self.imu.clock.drift_ppm * 1e-6))

    def sample_indices_before(self, t_end_s: float) -> NDArray[np.int64]:
        """Return the indices of the samples still to generate with true time before `t_end_s`."""
        clock = self.imu.clock
        last = int(np.ceil((t_end_s - clock.phase_s) / self.true_period_s))  # first index ≥ t_end
        last = max(last, self._next_index)
        return np.arange(self._next_index, last, dtype=np.int64)

    def synthesize(
        self,
        t_end_s: float,
        kinematics: KinematicsSource,
        temperature: TemperatureSource,
    ) -> ImuSamples:
        """Generate every sample whose true time falls before `t_end_s`.

        Parameters
        ----------
        t_end_s : float
            End of the chunk (exclusive), true time. [s]
        kinematics : callable
            ``kinematics(true_time_s) -> ImuKinematics`` of this IMU.
        temperature : callable
            ``temperature(true_time_s) -> (temperature_degc, rate_degc_ps)`` of this IMU.

        Returns
        -------
        ImuSamples
            The delivered samples (dropped ones removed) and their truth.
        """
        idx = self.sample_indices_before(t_end_s)
        n = idx.size
        model, clock = self.imu.model, self.imu.clock
        if n == 0:
            return _empty_samples()
        self._next_index = int(idx[-1]) + 1
        t_true: NDArray[np.float64] = clock.phase_s + idx * np.float64(self.true_period_s)
        kin = kinematics(t_true)
        temp_degc, temp_rate = temperature(t_true)
        temp_arg = temp_degc if model.gyro.temperature or model.accel.temperature else None
        rate_arg = temp_rate if temp_arg is not None else None
        true_temp = np.asarray(temp_degc, dtype=np.float64).reshape(-1)
        gyro_state = self._hysteresis_state(model.gyro, true_temp)
        accel_state = self._hysteresis_state(model.accel, true_temp)
        # exact shortcut: inputs known to be constant (a platform at rest) and no temperature
        # dependence give every sample the deterministic output of the first
        rows = slice(0, 1) if n > 1 and temp_arg is None and kin.constant else slice(None)
        gyro = apply_triad(
            model.gyro,
            kin.rate_b_rps[rows],
            specific_force_b_mps2=kin.specific_force_b_mps2[rows],
            temperature_degc=temp_arg,
            temperature_rate_degc_ps=rate_arg,
            hysteresis_state=gyro_state,
        )
        accel = apply_triad(
            model.accel,
            kin.specific_force_b_mps2[rows],
            rate_b_rps=kin.rate_b_rps[rows],
            angular_accel_b_rps2=kin.angular_accel_b_rps2[rows],
            temperature_degc=temp_arg,
            temperature_rate_degc_ps=rate_arg,
            hysteresis_state=accel_state,
        )
        if gyro.shape[0] != n:
            gyro, accel = np.repeat(gyro, n, axis=0), np.repeat(accel, n, axis=0)
        gyro += self._gyro_noise.generate(n)
        accel += self._accel_noise.generate(n)
        gyro_res = self._gyro_out.process(gyro)
        accel_res = self._accel_out.process(accel)
        saturated: NDArray[np.bool_] = np.asarray(
            gyro_res.saturated.any(axis=1) | accel_res.saturated.any(axis=1)
        )

        res = self.imu.temperature_resolution_degc
        temp_meas = np.round(temp_degc / res) * res if res > 0 else temp_degc.copy()
        host: NDArray[np.float64] = t_true + clock.latency_s
        if clock.jitter_s > 0:
            host = host + clock.jitter_s * self._jitter_rng.standard_normal(n)
            host = np.maximum.accumulate(np.maximum(host, self._last_time_s))
        self._last_time_s = float(host[-1])
        keep: NDArray[np.bool_] | slice = (
            np.asarray(self._drop_rng.random(n) >= clock.drop_probability)
            if clock.drop_probability > 0
            else slice(None)  # every sample delivered: views, no copies
        )
        counter = idx % (1 << clock.counter_bits)
        return ImuSamples(
            time_s=host[keep],
            device_time_s=(idx / model.sample_rate_hz)[keep],
            counter=counter[keep],
            gyro_rps=gyro_res.values[keep],
            accel_mps2=accel_res.values[keep],
            temperature_degc=temp_meas[keep],
            saturated=saturated[keep],
            true_time_s=t_true[keep],
            true_rate_b_rps=kin.rate_b_rps[keep],
            true_specific_force_b_mps2=kin.specific_force_b_mps2[keep],
            true_temperature_degc=np.asarray(temp_degc, dtype=np.float64)[keep],
        )


def _empty_samples() -> ImuSamples:
    z1 = np.zeros(0)
    z3 = np.zeros((0, 3))
    return ImuSamples(
        time_s=z1,
        device_time_s=z1,
        counter=np.zeros(0, dtype=np.int64),
        gyro_rps=z3,
        accel_mps2=z3,
        temperature_degc=z1,
        saturated=np.zeros(0, dtype=bool),
        true_time_s=z1,
        true_rate_b_rps=z3,
        true_specific_force_b_mps2=z3,
        true_temperature_degc=z1,
    )
