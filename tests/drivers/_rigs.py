"""Small twin rigs for the driver tests (one tactical IMU; a fast chamber when asked)."""

from __future__ import annotations

from typing import Any

from imucalib.plan.equipment import (
    CentrifugeConfig,
    ChamberConfig,
    ImuConfig,
    TableConfig,
    TwinEquipment,
)
from imucalib.sim.build import build_rig
from imucalib.sim.rig import TwinRig

SPEED = 20.0


def make_rig(*, table: str = "dual-axis", chamber: bool = False, centrifuge: bool = False,
             sample_rate_hz: float = 200.0, grade: str = "high", seed: int = 11,
             **imu: Any) -> TwinRig:
    """A rig with one tactical IMU at `sample_rate_hz` (a fast chamber when asked)."""
    sc = TwinEquipment(
        seed=seed,
        table=TableConfig(kind=table, grade=grade),  # type: ignore[arg-type]
        chamber=ChamberConfig(enabled=chamber, initial_temperature_degc=20.0,
                              max_ramp_degc_per_min=120.0, air_time_constant_s=10.0,
                              stability_noise_degc=0.0, min_temperature_degc=-40.0,
                              max_temperature_degc=120.0),
        centrifuge=CentrifugeConfig(enabled=centrifuge, static_radius_m=0.5),
        imus=(ImuConfig(name="IMU-T1", grade="tactical", sample_rate_hz=sample_rate_hz, **imu),),
    )
    return build_rig(sc).rig
