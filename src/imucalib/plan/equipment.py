"""The equipment of a twin station: site, rate table, chamber, centrifuge, fixture and IMUs.

A plan may carry one as its ``[twin]`` table (to run it with ``--station sim``); a twin scenario
(:mod:`imucalib.sim.scenario`) is this description plus a plan's steps. The description belongs
to the plan layer: the twin (:mod:`imucalib.sim`) is built from it, never the reverse.

Contents
--------
:class:`TwinEquipment` and its parts :class:`SiteConfig`, :class:`TableConfig`,
:class:`ChamberConfig`, :class:`CentrifugeConfig`, :class:`FixtureConfig`, :class:`ImuConfig`;
:data:`LEGACY_CENTRIFUGE_NAMES`.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

from imucalib.plan.bounds import (
    MAX_CENTRIFUGE_RATE_DPS,
    MAX_IMUS,
    MAX_RAMP_DEGC_PER_MIN,
    MAX_SAMPLE_RATE_HZ,
    MAX_TABLE_RATE_DPS,
    MAX_TEMPERATURE_DEGC,
    MAX_TIME_CONSTANT_S,
    MIN_RAMP_DEGC_PER_MIN,
    MIN_SAMPLE_RATE_HZ,
    MIN_TEMPERATURE_DEGC,
    MIN_TIME_CONSTANT_S,
)

__all__ = [
    "LEGACY_CENTRIFUGE_NAMES",
    "CentrifugeConfig",
    "ChamberConfig",
    "FixtureConfig",
    "ImuConfig",
    "SiteConfig",
    "TableConfig",
    "TwinEquipment",
]

_ARM = Annotated[float, Field(ge=-5.0, le=5.0)]

#: Former names of the centrifuge's unbalance coefficients (their unit read as m/s²), mapped to
#: the unit-true names when a file written before the rename is read.
LEGACY_CENTRIFUGE_NAMES: dict[str, str] = {
    "unbalance_c0_m_s2": "unbalance_c0_m_per_rps_sq",
    "unbalance_c_per_kg_m_s2_per_kg": "unbalance_c_m_per_rps_sq_per_kg",
}


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class SiteConfig(_Model):
    """Where the station stands."""

    latitude_deg: float = Field(45.0, ge=-90.0, le=90.0)
    height_m: float = Field(0.0, ge=-500.0, le=9000.0)
    heading_deg: float = Field(0.0, ge=-360.0, le=360.0)
    gravity_mps2: float | None = Field(None, gt=9.7, lt=9.9)
    ambient_temperature_degc: float = Field(20.0, ge=-40.0, le=60.0)


class TableConfig(_Model):
    """The rate table: none, single axis (vertical) or dual axis (pitch outer, roll inner)."""

    kind: Literal["none", "single-axis", "dual-axis"] = "none"
    grade: Literal["ideal", "lab", "high"] = "high"
    max_rate_dps: float | None = Field(None, gt=0.0, le=MAX_TABLE_RATE_DPS)
    feedback_rate_hz: float = Field(100.0, ge=MIN_SAMPLE_RATE_HZ, le=10000.0,
                                    description="controller feedback rate [Hz]")


class ChamberConfig(_Model):
    """A thermal chamber around the fixture (absent when ``enabled`` is false)."""

    enabled: bool = False
    initial_temperature_degc: float = Field(25.0, ge=-70.0, le=180.0)
    min_temperature_degc: float = Field(-55.0, ge=MIN_TEMPERATURE_DEGC, le=MAX_TEMPERATURE_DEGC)
    max_temperature_degc: float = Field(125.0, ge=MIN_TEMPERATURE_DEGC, le=MAX_TEMPERATURE_DEGC)
    max_ramp_degc_per_min: float = Field(5.0, ge=MIN_RAMP_DEGC_PER_MIN, le=MAX_RAMP_DEGC_PER_MIN)
    air_time_constant_s: float = Field(120.0, ge=MIN_TIME_CONSTANT_S, le=MAX_TIME_CONSTANT_S)
    stability_noise_degc: float = Field(0.05, ge=0.0, le=5.0)

    @model_validator(mode="after")
    def _range(self) -> ChamberConfig:
        if self.min_temperature_degc >= self.max_temperature_degc:
            raise ValueError(f"min_temperature_degc ({self.min_temperature_degc:g}) must be "
                             f"below max_temperature_degc ({self.max_temperature_degc:g})")
        return self


class CentrifugeConfig(_Model):
    """A precision centrifuge carrying the test item on its arm.

    The dynamic unbalance shifts the radius by (c0 + c·load)·ω² with ω in rad/s, so both
    coefficients are metres per (rad/s)² (c per kilogram of load as well). Files written with
    the former names (:data:`LEGACY_CENTRIFUGE_NAMES`) are read with the new ones.
    """

    enabled: bool = False
    static_radius_m: float = Field(1.0, gt=0.0, le=20.0)
    unbalance_c0_m_per_rps_sq: float = Field(
        0.0, ge=-1e-3, le=1e-3, description="radius shift c0·ω² of the rotor [m/(rad/s)²]")
    unbalance_c_m_per_rps_sq_per_kg: float = Field(
        0.0, ge=-1e-3, le=1e-3, description="change of c0 per kg of load [m/(rad/s)²/kg]")
    load_kg: float = Field(0.0, ge=0.0, le=1000.0)
    max_rate_dps: float = Field(720.0, gt=0.0, le=MAX_CENTRIFUGE_RATE_DPS)

    @model_validator(mode="before")
    @classmethod
    def _legacy_names(cls, data: Any) -> Any:
        if isinstance(data, dict) and any(old in data for old in LEGACY_CENTRIFUGE_NAMES):
            data = dict(data)
            for old, new in LEGACY_CENTRIFUGE_NAMES.items():
                if old in data:
                    if new in data:
                        raise ValueError(f"give `{new}` only (`{old}` is its former name)")
                    data[new] = data.pop(old)
        return data


class FixtureConfig(_Model):
    """The fixture carrying the IMUs."""

    kind: Literal["single", "hexahedral", "array"] = "single"
    half_edge_m: float = Field(0.05, gt=0.0, le=1.0)
    lever_arm_m: tuple[_ARM, _ARM, _ARM] = Field((0.0, 0.0, 0.0), description="[m]")
    spacing_m: float = Field(0.05, gt=0.0, le=1.0)


class ImuConfig(_Model):
    """One IMU unit: its grade (its truth, thermal behaviour included, is drawn from it), clock."""

    name: str = Field(min_length=1, max_length=64)
    grade: Literal["consumer", "tactical", "navigation"] = "tactical"
    sample_rate_hz: float | None = Field(None, ge=MIN_SAMPLE_RATE_HZ, le=MAX_SAMPLE_RATE_HZ,
                                         description="output data rate [Hz]")
    seed: int | None = Field(None, ge=0, lt=2**63)
    drift_ppm: float = Field(0.0, ge=-1000.0, le=1000.0)
    jitter_s: float = Field(0.0, ge=0.0, le=0.1)
    latency_s: float = Field(0.0, ge=0.0, le=1.0)
    drop_probability: float = Field(0.0, ge=0.0, lt=1.0)
    thermal_time_constant_s: float = Field(600.0, ge=MIN_TIME_CONSTANT_S,
                                           le=MAX_TIME_CONSTANT_S)
    self_heating_degc: float = Field(0.0, ge=0.0, le=50.0)
    nonlinear: bool = True
    temperature_dependence: Literal["none", "typical"] = Field(
        "none", description="'typical': cubic temperature dependence of biases, scale factors "
        "and misalignments (imucalib.models.imu.sample_imu_model)")
    hysteresis_fraction: float = Field(
        0.0, ge=0.0, le=0.5, description="thermal hysteresis amplitude as a fraction of each "
        "parameter's swing over -40…85 °C (with 'typical') [–]")
    reference_temperature_degc: float = Field(
        25.0, ge=MIN_TEMPERATURE_DEGC, le=MAX_TEMPERATURE_DEGC,
        description="T0, where the drawn parameters hold (with 'typical') [°C]")

    @model_validator(mode="after")
    def _thermal(self) -> ImuConfig:
        if self.hysteresis_fraction > 0.0 and self.temperature_dependence == "none":
            raise ValueError("hysteresis_fraction > 0 needs temperature_dependence = 'typical'")
        return self


class TwinEquipment(_Model):
    """The twin station without a step list: site, equipment, fixture and IMUs.

    It is what a simulated station is built from (:func:`imucalib.sim.build.build_rig`); a twin
    scenario adds a plan's steps, and a test plan can carry one as its ``[twin]`` table.
    """

    seed: int = Field(0, ge=-(2**63), lt=2**63)
    site: SiteConfig = Field(default_factory=SiteConfig)
    table: TableConfig = Field(default_factory=TableConfig)
    chamber: ChamberConfig = Field(default_factory=ChamberConfig)
    centrifuge: CentrifugeConfig = Field(default_factory=CentrifugeConfig)
    fixture: FixtureConfig = Field(default_factory=FixtureConfig)
    imus: tuple[ImuConfig, ...] = Field(min_length=1, max_length=MAX_IMUS)

    @model_validator(mode="after")
    def _consistent_equipment(self) -> TwinEquipment:
        names = [imu.name for imu in self.imus]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ValueError(f"IMU names must be unique; repeated: {dup}")
        if self.fixture.kind == "hexahedral" and len(self.imus) > 6:
            raise ValueError(f"a hexahedral fixture carries at most 6 IMUs; got {len(self.imus)}")
        if self.fixture.kind == "single" and len(self.imus) > 1:
            raise ValueError(
                f"fixture kind 'single' carries one IMU; got {len(self.imus)} (use 'array')"
            )
        if self.centrifuge.enabled and self.table.kind != "none":
            raise ValueError("a twin station has either a rate table or a centrifuge, not both")
        return self

    @property
    def table_axes(self) -> int:
        """Return the number of rate-table axes (0 without a table)."""
        return {"none": 0, "single-axis": 1, "dual-axis": 2}[self.table.kind]
