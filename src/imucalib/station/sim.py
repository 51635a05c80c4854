"""The digital twin as a station: the runner's device protocols over a :class:`TwinRig`.

:class:`SimStation` implements :class:`~imucalib.station.devices.Station` in virtual time: its
clock's ``sleep`` advances the rig, which generates every stream into the devices' buffers; the
devices' ``poll``/``read`` drain them. A full P1 plan with its 60-minute static record runs in
seconds. Each device can be made to fail on purpose (the fault hooks below) so that the runner's
guards are tested on the same code path as with real equipment.

Contents
--------
:class:`SimStation`, :class:`SimClock`, :class:`SimMotionDevice`, :class:`SimChamberDevice`,
:class:`SimImuSource`.

Time base
---------
Station time = ``start_time_s`` + the rig's virtual time. A resumed run builds a new station whose
``start_time_s`` lies after the last sample of the recording (the equipment restarted: the table
at its home angles, the chamber at its initial temperature, the IMUs' counters from zero).

Remounts
--------
:meth:`SimStation.remount` places the fixture in another pose (an axis up, a yaw): the runner
calls it when a remount operator check is confirmed, and a resumed run calls it with the pose of
the recording's last completed remount (the rebuilt twin starts in the ``+z`` pose otherwise).
:meth:`SimStation.swap_units` (two units exchange their places on the fixture) and
:meth:`SimStation.set_centrifuge_load` (the test load on the centrifuge arm) are the twin's side
of the other operator checks; a resumed run re-applies the recording's completed swaps, in order,
and its last load.

Devices and their fault hooks
-----------------------------
The devices (:class:`SimClock`, :class:`SimMotionDevice`, :class:`SimChamberDevice`,
:class:`SimImuSource`) and the faults each can be made to show are in
:mod:`imucalib.station.sim_devices`; :meth:`SimStation.at` schedules any fault at a station time.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imucalib import units
from imucalib._checks import check_nonnegative
from imucalib.errors import InvalidInputError
from imucalib.io import StreamSpec
from imucalib.io.streams import imu_truth_stream_spec
from imucalib.plan.bounds import (
    MAX_CENTRIFUGE_RATE_DPS,
    MAX_TABLE_ACCEL_DPS2,
    MAX_TABLE_RATE_DPS,
)
from imucalib.plan.equipment import TwinEquipment
from imucalib.plan.fixture_poses import rot_pm_for_pose
from imucalib.plan.schema import CentrifugeStep, PlanLimits, PlanStep, RateStep, SoakStep
from imucalib.sim.build import build_rig
from imucalib.sim.rig import RigChunk
from imucalib.sim.synth import ImuSamples
from imucalib.station.sim_devices import (
    SimChamberDevice,
    SimClock,
    SimImuSource,
    SimMotionDevice,
)

__all__ = ["SimChamberDevice", "SimClock", "SimImuSource", "SimMotionDevice", "SimStation"]

_F64 = NDArray[np.float64]


@dataclass(order=True)
class _Scheduled:
    at_s: float
    seq: int
    action: Callable[[], None] = field(compare=False)


class SimStation:
    """The twin station in virtual time (implements the Station protocol).

    Parameters
    ----------
    equipment : TwinEquipment
        Site, table or centrifuge, chamber, fixture and IMUs (the ``[twin]`` table of a plan);
        the IMUs' truths are drawn from its seed, so the same equipment gives the same IMUs.
    start_time_s : float
        Station time of the rig's time 0 (after the last sample of a resumed recording). [s]
    truth_streams : bool
        Keep every IMU's true rate, specific force, temperature and sample instant for
        :meth:`drain_truth` (the runner writes them as ``/truth`` streams when this station is
        its ``RunOptions.truth_source``).
    """

    def __init__(self, equipment: TwinEquipment, *, start_time_s: float = 0.0,
                 truth_streams: bool = False) -> None:
        built = build_rig(equipment)
        self.equipment = equipment
        self.rig = built.rig
        self.truth = built.truth
        self.imu_models = built.imu_models
        self.start_time_s = float(start_time_s)
        self.latitude_deg = equipment.site.latitude_deg
        self.heading_deg = equipment.site.heading_deg
        self.grades = {imu.name: imu.grade for imu in equipment.imus}
        self.clock = SimClock(self)
        self.fault_rng = np.random.default_rng(equipment.seed + 7919)
        self.table = (SimMotionDevice(self, self.rig.table, "main")
                      if self.rig.table is not None else None)
        self.centrifuge = (
            SimMotionDevice(self, self.rig.centrifuge.table, "main", centrifuge=self.rig.centrifuge,
                            imbalance_alarm_m=equipment.centrifuge.imbalance_alarm_um * 1e-6)
            if self.rig.centrifuge is not None else None)
        self.chamber = SimChamberDevice(self, "main") if self.rig.chamber is not None else None
        self.imus = [SimImuSource(self, name) for name in self.rig.imu_names]
        self._schedule: list[_Scheduled] = []
        self.truth_streams = truth_streams
        self._truth: dict[str, list[ImuSamples]] = {name: [] for name in self.rig.imu_names}
        #: The fixture's pose (axis up, yaw [°]) and every remount as (station time, up, yaw).
        self.pose: tuple[str, float] = ("+z", 0.0)
        self.remounts: list[tuple[float, str, float]] = []
        #: Every unit swap as (station time, first, second) and load change as (time, kg).
        self.swaps: list[tuple[float, str, str]] = []
        self.load_changes: list[tuple[float, float]] = []

    # --- what the twin can do, before anything moves ------------------------------------------
    def plan_limits(self) -> PlanLimits:
        """Return plan limits equal to the twin's own.

        They are its axes' rate and acceleration limits and its chamber's temperature range: a
        plan within them never asks a device for more.
        """
        values: dict[str, float] = {}
        table, fuge, chamber = self.rig.table, self.rig.centrifuge, self.rig.chamber
        axes = (table.spec.axes if table is not None
                else fuge.table.spec.axes if fuge is not None else ())
        if table is not None:
            values["max_rate_dps"] = min(min(ax.max_rate_rps for ax in axes) / units.DEG,
                                         MAX_TABLE_RATE_DPS)
        if fuge is not None:
            values["max_centrifuge_rate_dps"] = min(fuge.spec.max_rate_rps / units.DEG,
                                                    MAX_CENTRIFUGE_RATE_DPS)
        if axes:
            values["max_accel_dps2"] = min(min(ax.max_accel_rps2 for ax in axes) / units.DEG,
                                           MAX_TABLE_ACCEL_DPS2)
        if chamber is not None:
            values["min_temperature_degc"] = chamber.spec.min_temp_degc
            values["max_temperature_degc"] = chamber.spec.max_temp_degc
        return PlanLimits.model_validate(values)

    def position_tolerance_arcsec(self) -> float:
        """Return the table deviation this twin's encoders let a held position show. [″]

        It is 3 × (encoder error (an RMS) + resolution + position noise) of the worst axis: a
        lab-grade table (15″ encoder error) cannot show 5″, however long it settles.
        """
        table = self.rig.table or (self.rig.centrifuge.table if self.rig.centrifuge else None)
        if table is None:
            return 0.0
        worst = max(ax.encoder_error_rad + ax.encoder_resolution_rad + ax.position_noise_rad
                    for ax in table.spec.axes)
        return 3.0 * worst / units.ARCSEC

    def check_steps(self, steps: Sequence[PlanStep]) -> None:
        """Refuse, before anything moves, a step that asks the twin for more than it can do.

        Raises
        ------
        LimitExceededError
            A rate beyond a table or centrifuge axis's limit, a soak outside the chamber's
            range or faster than its ramp limit (the devices' own messages).
        """
        for step in steps:
            if isinstance(step, RateStep) and self.rig.table is not None:
                self.rig.table.check_rate(step.axis, step.rate_dps * units.DEG)
            elif isinstance(step, CentrifugeStep) and self.rig.centrifuge is not None:
                self.rig.centrifuge.table.check_rate(0, step.rate_dps * units.DEG)
            elif isinstance(step, SoakStep) and self.rig.chamber is not None:
                ramp = None if step.ramp_degc_per_min is None else step.ramp_degc_per_min / 60.0
                self.rig.chamber.check_setpoint(step.temperature_degc, ramp)

    # --- truth --------------------------------------------------------------------------------
    def truth_stream_specs(self) -> list[StreamSpec]:
        """Return the layouts of the truth streams (one per IMU; none without `truth_streams`)."""
        if not self.truth_streams:
            return []
        return [imu_truth_stream_spec(name) for name in self.rig.imu_names]

    def drain_truth(self) -> dict[str, dict[str, Any]]:
        """Return, per IMU, the truth columns generated since the previous call."""
        out: dict[str, dict[str, Any]] = {}
        for name, blocks in self._truth.items():
            if not blocks:
                continue
            self._truth[name] = []
            cols: dict[str, Any] = {
                "time_s": np.concatenate([b.time_s for b in blocks]) + self.start_time_s,
                "true_time_s": np.concatenate([b.true_time_s for b in blocks])
                + self.start_time_s,
                "true_temperature_degc": np.concatenate(
                    [b.true_temperature_degc for b in blocks])}
            rate = np.concatenate([b.true_rate_b_rps for b in blocks])
            force = np.concatenate([b.true_specific_force_b_mps2 for b in blocks])
            for j, axis in enumerate("xyz"):
                cols[f"true_rate_{axis}_rps"] = rate[:, j]
                cols[f"true_force_{axis}_mps2"] = force[:, j]
            out[name] = cols
        return out

    def describe(self) -> dict[str, Any]:
        """Return a JSON-able description of the station."""
        return {"kind": "digital-twin", "twin": self.equipment.model_dump(mode="json"),
                "start_time_s": self.start_time_s}

    def remount(self, up: str, yaw_deg: float = 0.0) -> None:
        """Place the fixture with its axis `up` pointing up, turned `yaw_deg` about the vertical.

        The twin's side of a remount operator check (``OperatorCheckStep.remount``): the rig's
        fixture takes the pose's rotation (:func:`imucalib.plan.fixture_poses.rot_pm_for_pose`)
        from the current station time on. A real station has no such method; there the operator
        moved the fixture.

        Raises
        ------
        InvalidInputError
            If `up` is not a pose name or `yaw_deg` is not finite.
        """
        try:
            rot_pm = rot_pm_for_pose(up, yaw_deg)
        except ValueError as exc:
            raise InvalidInputError(f"remount: {exc}") from None
        self.rig.remount(rot_pm)
        self.pose = (up, float(yaw_deg))
        self.remounts.append((self.clock.now_s(), up, float(yaw_deg)))

    def swap_units(self, first: str, second: str) -> None:
        """Exchange units `first` and `second` on the fixture (each takes the other's place).

        The twin's side of a swap operator check (``OperatorCheckStep.swap_units``): from the
        current station time on, each unit sits where the other sat, in its orientation, and
        keeps its own sensor errors (:meth:`imucalib.sim.rig.TwinRig.swap_mounts`). A real
        station has no such method; there the operator exchanged the units.

        Raises
        ------
        InvalidInputError
            If a name is not a unit of the twin, or both are the same.
        """
        self.rig.swap_mounts(first, second)
        self.swaps.append((self.clock.now_s(), first, second))

    def set_centrifuge_load(self, load_kg: float) -> None:
        """Put a test load of `load_kg` on the centrifuge arm; it sets the unbalance c. [kg]

        The twin's side of an operator check with ``centrifuge_load_kg``: everything generated
        from the current station time on sees c = c0 + c_per_kg·load.

        Raises
        ------
        InvalidInputError
            If the twin has no centrifuge, or `load_kg` is negative or not finite.
        """
        fuge = self.rig.centrifuge
        if fuge is None:
            raise InvalidInputError(f"centrifuge load {load_kg!r} kg: the twin has no centrifuge")
        with self.rig.lock:  # c is read from load_kg at every evaluation; nothing caches it
            fuge.load_kg = check_nonnegative(load_kg, "load_kg")
        self.load_changes.append((self.clock.now_s(), fuge.load_kg))

    def imu(self, name: str) -> SimImuSource:
        """Return the IMU source called `name`."""
        for src in self.imus:
            if src.name == name:
                return src
        raise InvalidInputError(f"no IMU named {name!r}; have {[s.name for s in self.imus]}")

    def at(self, time_s: float, action: Callable[[], None]) -> None:
        """Run `action` (a fault hook) when the station clock reaches `time_s`."""
        entry = _Scheduled(float(time_s), len(self._schedule), action)
        bisect.insort(self._schedule, entry)

    def advance(self, duration_s: float) -> None:
        """Generate `duration_s` of every stream into the device buffers, running due actions."""
        end = self.rig.now_s + duration_s
        while True:
            due = self._schedule[0].at_s - self.start_time_s if self._schedule else math.inf
            if due > end:
                break
            self._deliver(self.rig.generate(max(due, self.rig.now_s)))
            self._schedule.pop(0).action()
        self._deliver(self.rig.generate(end))

    def _deliver(self, chunk: RigChunk) -> None:
        if self.table is not None:
            self.table._push(chunk.table)
        if self.centrifuge is not None:
            self.centrifuge._push(chunk.centrifuge)
        if self.chamber is not None and chunk.chamber is not None and chunk.chamber.time_s.size:
            self.chamber._buffer.append(chunk.chamber)
        for src in self.imus:
            samples = chunk.imu[src.name]
            if len(samples):
                src._buffer.append(samples)
                if self.truth_streams:
                    self._truth[src.name].append(samples)
