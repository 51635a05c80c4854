"""The whole twin station in virtual time: the equipment, the fixture and the IMUs together.

:class:`TwinRig` owns the stateful twins (rate table or centrifuge, chamber, IMU synthesizers) and
produces every stream of the station for a span of virtual time. Commands go to the equipment
twins directly (``rig.table.command_position(...)``); generation is lazy, so a command issued at
time t changes everything generated after t. It is the one physical model behind the scenario
runner (:mod:`imucalib.sim.runner`), the simulated station of the station runtime and the
protocol simulator servers of the drivers; its methods are serialised by a lock so that
simulator servers in several threads can share one rig.

Contents
--------
:class:`TwinRig`
    The stateful rig.
:class:`RigChunk`, :class:`ChamberReadings`
    What one call of :meth:`TwinRig.generate` produces.
:func:`feedback_grid_s`
    The controller's sample times inside a span (shared grid, so chunks never repeat a row).

Streams
-------
- IMU samples at each IMU's own clock (:class:`~imucalib.sim.synth.ImuSynthesizer`), with true
  inputs from :func:`~imucalib.sim.kinematics.compute_imu_kinematics` (or the centrifuge's arm
  geometry) and the IMU temperature from :func:`~imucalib.sim.chamber.imu_temperature_degc`.
- Table and centrifuge feedback at ``feedback_rate_hz`` on the grid k / f
  (``SimRateTable.feedback``).
- Chamber air temperature and setpoint at ``chamber_rate_hz``.
"""

from __future__ import annotations

import dataclasses
import math
import threading
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from imucalib._checks import check_finite_scalar, check_positive
from imucalib.errors import ConfigurationError, InvalidInputError
from imucalib.models.earth import Site
from imucalib.sim.centrifuge import SimCentrifuge
from imucalib.sim.chamber import SimChamber, imu_temperature_degc
from imucalib.sim.fixture import Fixture
from imucalib.sim.kinematics import (
    ImuKinematics,
    PlatformMotion,
    compute_imu_kinematics,
    stationary_platform_motion,
)
from imucalib.sim.synth import ImuSamples, ImuSynthesizer, SimImu
from imucalib.sim.table import SimRateTable, TableFeedback

__all__ = ["ChamberReadings", "RigChunk", "TwinRig", "feedback_grid_s"]

_F64 = NDArray[np.float64]


def _at_rest(motion: PlatformMotion) -> bool:
    """Whether the platform holds one attitude with zero rate and acceleration throughout."""
    if np.any(motion.omega_tp_p_rps != 0.0) or np.any(motion.alpha_tp_p_rps2 != 0.0):
        return False
    q = motion.rot_tp.as_quat()
    return bool(np.all(q == q[0]))


def feedback_grid_s(t_start_s: float, t_end_s: float, rate_hz: float) -> _F64:
    """Return the grid times k / `rate_hz` in [`t_start_s`, `t_end_s`) [s].

    Consecutive spans share the grid, so a stream sampled span by span has no repeated or missing
    rows.
    """
    k0 = math.ceil(t_start_s * rate_hz - 1e-9)
    k1 = math.ceil(t_end_s * rate_hz - 1e-9)
    return np.arange(k0, max(k0, k1), dtype=np.float64) / rate_hz


@dataclass(frozen=True, eq=False)
class ChamberReadings:
    """Chamber air temperature [°C] and setpoint [°C] at ``time_s`` [s], each (n,)."""

    time_s: _F64
    temperature_degc: _F64
    setpoint_degc: _F64


@dataclass(frozen=True, eq=False)
class RigChunk:
    """Every stream of the rig over [``t_start_s``, ``t_end_s``) of virtual time.

    Attributes
    ----------
    imu : dict of str to ImuSamples
        Delivered samples of each IMU, by name.
    table, centrifuge : TableFeedback or None
        Controller feedback (None when the rig has no such device).
    chamber : ChamberReadings or None
        Chamber readings (None without a chamber).
    """

    t_start_s: float
    t_end_s: float
    imu: dict[str, ImuSamples] = field(default_factory=dict)
    table: TableFeedback | None = None
    centrifuge: TableFeedback | None = None
    chamber: ChamberReadings | None = None


class TwinRig:
    """The twin station: site, table or centrifuge, chamber, fixture and IMUs, in virtual time.

    Parameters
    ----------
    site : Site
        Latitude, heading and gravity.
    fixture : Fixture
        Mounts of the IMUs (names must match `imus`).
    imus : sequence of SimImu
        The units; each one's ``mount`` is taken from `fixture`.
    table : SimRateTable, optional
        The rate table carrying the fixture.
    centrifuge : SimCentrifuge, optional
        A centrifuge carrying the fixture on its arm (not together with `table`).
    chamber : SimChamber, optional
        A thermal chamber around the fixture; without one the IMUs sit in still air at
        `ambient_temperature_degc`.
    ambient_temperature_degc : float
        Air temperature without a chamber. [°C]
    feedback_rate_hz : float
        Rate of the table and centrifuge feedback streams. [Hz]
    chamber_rate_hz : float
        Rate of the chamber stream. [Hz]
    rng : numpy.random.Generator or int or None
        Source of the IMU synthesizers' randomness (one child generator per IMU).
    """

    def __init__(self, *, site: Site, fixture: Fixture, imus: Sequence[SimImu],
                 table: SimRateTable | None = None, centrifuge: SimCentrifuge | None = None,
                 chamber: SimChamber | None = None, ambient_temperature_degc: float = 20.0,
                 feedback_rate_hz: float = 100.0, chamber_rate_hz: float = 1.0,
                 rng: np.random.Generator | int | None = None) -> None:
        if table is not None and centrifuge is not None:
            raise ConfigurationError("a rig has a rate table or a centrifuge, not both")
        if not imus:
            raise ConfigurationError("a rig needs at least one IMU; got none")
        names = [imu.name for imu in imus]
        missing = sorted(set(names) - set(fixture.names))
        if missing:
            raise ConfigurationError(
                f"IMUs {missing} have no mount on the fixture; the fixture carries "
                f"{list(fixture.names)}"
            )
        self.site = site
        self.fixture = fixture
        self.table = table
        self.centrifuge = centrifuge
        self.chamber = chamber
        self.ambient_temperature_degc = check_finite_scalar(ambient_temperature_degc,
                                                            "ambient_temperature_degc")
        self.feedback_rate_hz = check_positive(feedback_rate_hz, "feedback_rate_hz")
        self.chamber_rate_hz = check_positive(chamber_rate_hz, "chamber_rate_hz")
        gens = np.random.default_rng(rng).spawn(len(imus))
        self.imus: dict[str, SimImu] = {}
        self._synth: dict[str, ImuSynthesizer] = {}
        for imu, gen in zip(imus, gens, strict=True):
            mounted = SimImu(imu.name, imu.model, imu.clock, imu.thermal,
                             fixture.mount(imu.name), imu.temperature_resolution_degc)
            self.imus[imu.name] = mounted
            self._synth[imu.name] = ImuSynthesizer(mounted, gen)
        self._imu_cursor_s = dict.fromkeys(self.imus, 0.0)
        self._still: dict[str, tuple[tuple[float, ...], ImuKinematics]] = {}
        self.now_s = 0.0
        self.lock = threading.RLock()

    @property
    def imu_names(self) -> tuple[str, ...]:
        """Names of the IMUs, in fixture order."""
        return tuple(self.imus)

    # --- remount -------------------------------------------------------------------------------
    def remount(self, rot_pm: Rotation | ArrayLike) -> None:
        """Place the fixture on the platform with another rotation ``rot_pm`` (a remount).

        Everything generated after the rig's current time :attr:`now_s` sees the fixture in the
        new pose; the IMUs' own mounts (``rot_mb``, lever arms in m) stay. Samples already
        generated keep the old pose (the operator remounts between steps, with nothing being
        recorded). The rotation is instantaneous in virtual time.

        Parameters
        ----------
        rot_pm : Rotation or array_like (3, 3)
            Maps fixture vectors into the platform frame
            (:func:`imucalib.plan.fixture_poses.rot_pm_for_pose`).

        Raises
        ------
        ConfigurationError
            If `rot_pm` is not a single proper rotation.
        """
        with self.lock:
            self.fixture = self.fixture.remounted(rot_pm)
            self._still.clear()  # cached still inputs belong to the old pose

    def swap_mounts(self, first: str, second: str) -> None:
        """Exchange the places of IMUs `first` and `second` on the fixture (a unit swap).

        Each IMU takes the other's position (``lever_arm_m_m``) and orientation (``rot_mb``)
        from the rig's current time :attr:`now_s` on, and keeps its own sensor errors, clock and
        noise; samples already generated keep the old places (the operator swaps the units
        between steps, with nothing being recorded).

        Raises
        ------
        InvalidInputError
            If a name is not an IMU of the rig, or both names are the same.
        """
        with self.lock:
            a, b = self._imu(first), self._imu(second)
            if first == second:
                raise InvalidInputError(f"a swap exchanges two different IMUs; got {first!r} "
                                        "twice")
            mount_a, mount_b = self.fixture.mount(first), self.fixture.mount(second)
            new_a = dataclasses.replace(mount_a, rot_mb=mount_b.rot_mb,
                                        lever_arm_m_m=mount_b.lever_arm_m_m.copy())
            new_b = dataclasses.replace(mount_b, rot_mb=mount_a.rot_mb,
                                        lever_arm_m_m=mount_a.lever_arm_m_m.copy())
            placed = {first: new_a, second: new_b}
            self.fixture = dataclasses.replace(
                self.fixture, mounts=tuple(placed.get(m.name, m) for m in self.fixture.mounts))
            for imu, mount in ((a, new_a), (b, new_b)):
                moved = dataclasses.replace(imu, mount=mount)
                self.imus[imu.name] = moved
                self._synth[imu.name].imu = moved  # the synthesizer keeps its state
            self._still.clear()  # cached still inputs belong to the old places

    # --- physics ------------------------------------------------------------------------------
    def imu_kinematics(self, name: str, true_time_s: _F64) -> ImuKinematics:
        """Return the true inputs of IMU `name` at true times `true_time_s` (shape (n,))."""
        imu = self._imu(name)
        assert imu.mount is not None  # set in __init__
        with self.lock:
            if self.centrifuge is not None:
                return self.centrifuge.imu_kinematics(true_time_s, self.site, imu.mount,
                                                      self.fixture.rot_pm)
            n = true_time_s.shape[0]
            if self.table is None and n > 1:  # a fixed plate: every sample alike
                first = compute_imu_kinematics(stationary_platform_motion(true_time_s[:1]),
                                               self.site, imu.mount, self.fixture.rot_pm)
                return first.repeat(n, time_s=true_time_s)
            if (self.table is not None and n > 1
                    and self.table.is_still(float(true_time_s[0]), float(true_time_s[-1]))):
                key = self.table.hold_pose(float(true_time_s[0]))
                cached = self._still.get(name)
                if cached is None or cached[0] != key:  # a new pose: its inputs once
                    cached = (key, compute_imu_kinematics(self.table.motion(true_time_s[:1]),
                                                          self.site, imu.mount,
                                                          self.fixture.rot_pm))
                    self._still[name] = cached
                return cached[1].repeat(n, time_s=true_time_s)
            motion = (self.table.motion(true_time_s) if self.table is not None
                      else stationary_platform_motion(true_time_s))
            if n > 1 and _at_rest(motion):
                # exact shortcut: a platform at rest gives every sample the inputs of the first
                first = compute_imu_kinematics(motion[:1], self.site, imu.mount,
                                               self.fixture.rot_pm)
                return first.repeat(len(motion), time_s=motion.time_s)
            return compute_imu_kinematics(motion, self.site, imu.mount, self.fixture.rot_pm)

    def imu_temperature(self, name: str, true_time_s: _F64) -> tuple[_F64, _F64]:
        """Return the temperature [°C] of IMU `name` and its rate [°C/s] at `true_time_s`."""
        imu = self._imu(name)
        with self.lock:
            if self.chamber is None:
                # still air: powered all along, the IMU sits in equilibrium at ambient + h
                # (imu_temperature_degc's solution for a constant ambient; exact)
                n = true_time_s.shape[0]
                level = self.ambient_temperature_degc + float(imu.thermal.self_heating_degc)
                return np.full(n, level), np.zeros(n)
            return imu_temperature_degc(self.chamber, imu.thermal, true_time_s)

    # --- generation ---------------------------------------------------------------------------
    def generate_imu(self, name: str, t_end_s: float) -> ImuSamples:
        """Generate IMU `name`'s samples from where it stopped up to true time `t_end_s`."""
        self._imu(name)
        with self.lock:
            samples = self._synth[name].synthesize(
                t_end_s,
                lambda t: self.imu_kinematics(name, t),
                lambda t: self.imu_temperature(name, t),
            )
            self._imu_cursor_s[name] = max(self._imu_cursor_s[name], t_end_s)
            return samples

    def motion_feedback(self, time_s: _F64) -> tuple[TableFeedback | None, TableFeedback | None]:
        """Return (table, centrifuge) feedback at `time_s` (None for an absent device)."""
        with self.lock:
            table = self.table.feedback(time_s) if self.table is not None else None
            fuge = self.centrifuge.feedback(time_s) if self.centrifuge is not None else None
            return table, fuge

    def chamber_readings(self, time_s: _F64) -> ChamberReadings | None:
        """Return the chamber's air temperature and setpoint at `time_s` (None without one)."""
        if self.chamber is None:
            return None
        with self.lock:
            return ChamberReadings(time_s=time_s,
                                   temperature_degc=self.chamber.air_temperature_degc(time_s),
                                   setpoint_degc=self.chamber.setpoint_degc(time_s))

    def generate(self, t_end_s: float) -> RigChunk:
        """Generate every stream from :attr:`now_s` up to `t_end_s` and advance :attr:`now_s`.

        Raises
        ------
        InvalidInputError
            If `t_end_s` is before :attr:`now_s`.
        """
        t_end = check_finite_scalar(t_end_s, "t_end_s")
        with self.lock:
            t0 = self.now_s
            if t_end < t0:
                raise InvalidInputError(
                    f"`t_end_s` must not be before the rig's current time {t0:g} s; got {t_end:g}"
                )
            fb_t = feedback_grid_s(t0, t_end, self.feedback_rate_hz)
            table, fuge = self.motion_feedback(fb_t)
            chamber = self.chamber_readings(feedback_grid_s(t0, t_end, self.chamber_rate_hz))
            imu = {name: self.generate_imu(name, t_end) for name in self.imus}
            self.now_s = t_end
            return RigChunk(t_start_s=t0, t_end_s=t_end, imu=imu, table=table, centrifuge=fuge,
                            chamber=chamber)

    def _imu(self, name: str) -> SimImu:
        try:
            return self.imus[name]
        except KeyError:
            raise InvalidInputError(
                f"no IMU named {name!r} on the rig; have {list(self.imus)}"
            ) from None
