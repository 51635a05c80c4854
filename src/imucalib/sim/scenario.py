"""Twin scenarios: what the digital twin is asked to simulate, validated by pydantic.

A scenario names a site, the equipment (table, chamber, centrifuge, fixture), the IMUs and a
sequence of steps. It is the twin's own description, loaded from TOML or taken from the built-in
set (:data:`BUILTIN_SCENARIOS`); test plans that drive real equipment are a separate, richer layer.

Contents
--------
:class:`Scenario` and its parts (:class:`SiteConfig`, :class:`TableConfig`, :class:`ChamberConfig`,
:class:`CentrifugeConfig`, :class:`FixtureConfig`, :class:`ImuConfig`, the step kinds
:class:`StaticStep`, :class:`PositionStep`, :class:`RateStep`, :class:`SoakStep`,
:class:`CentrifugeStep`); :func:`load_scenario` (a built-in name or a TOML file);
:data:`BUILTIN_SCENARIOS`.

Example TOML
------------
.. code-block:: toml

    name = "my-static"
    seed = 7
    [site]
    latitude_deg = 52.0
    [[imus]]
    name = "IMU-0001"
    grade = "tactical"
    [[steps]]
    kind = "static"
    duration_s = 600
"""

from __future__ import annotations

import tomllib
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from imucalib.errors import ConfigurationError

__all__ = [
    "BUILTIN_SCENARIOS",
    "CentrifugeConfig",
    "CentrifugeStep",
    "ChamberConfig",
    "FixtureConfig",
    "ImuConfig",
    "PositionStep",
    "RateStep",
    "Scenario",
    "SiteConfig",
    "SoakStep",
    "StaticStep",
    "TableConfig",
    "TwinEquipment",
    "format_validation_error",
    "load_scenario",
]


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
    max_rate_dps: float | None = Field(None, gt=0.0)
    feedback_rate_hz: float = Field(100.0, gt=0.0, le=10000.0)


class ChamberConfig(_Model):
    """A thermal chamber around the fixture (absent when ``enabled`` is false)."""

    enabled: bool = False
    initial_temperature_degc: float = Field(25.0, ge=-70.0, le=180.0)
    min_temperature_degc: float = -55.0
    max_temperature_degc: float = 125.0
    max_ramp_degc_per_min: float = Field(5.0, gt=0.0)
    air_time_constant_s: float = Field(120.0, gt=0.0)
    stability_noise_degc: float = Field(0.05, ge=0.0, le=5.0)


class CentrifugeConfig(_Model):
    """A precision centrifuge carrying the test item on its arm."""

    enabled: bool = False
    static_radius_m: float = Field(1.0, gt=0.0, le=20.0)
    unbalance_c0_m_s2: float = 0.0
    unbalance_c_per_kg_m_s2_per_kg: float = 0.0
    load_kg: float = Field(0.0, ge=0.0)
    max_rate_dps: float = Field(720.0, gt=0.0)


class FixtureConfig(_Model):
    """The fixture carrying the IMUs."""

    kind: Literal["single", "hexahedral", "array"] = "single"
    half_edge_m: float = Field(0.05, gt=0.0, le=1.0)
    lever_arm_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    spacing_m: float = Field(0.05, gt=0.0, le=1.0)


class ImuConfig(_Model):
    """One IMU unit: its grade (the truth is drawn from it) and its clock."""

    name: str = Field(min_length=1, max_length=64)
    grade: Literal["consumer", "tactical", "navigation"] = "tactical"
    sample_rate_hz: float | None = Field(None, gt=0.0, le=100000.0)
    seed: int | None = None
    drift_ppm: float = Field(0.0, ge=-1000.0, le=1000.0)
    jitter_s: float = Field(0.0, ge=0.0, le=0.1)
    latency_s: float = Field(0.0, ge=0.0, le=1.0)
    drop_probability: float = Field(0.0, ge=0.0, lt=1.0)
    thermal_time_constant_s: float = Field(600.0, gt=0.0)
    self_heating_degc: float = Field(0.0, ge=0.0, le=50.0)
    nonlinear: bool = True


class _Step(_Model):
    label: str = ""


class StaticStep(_Step):
    """Record with nothing moving."""

    kind: Literal["static"]
    duration_s: float = Field(gt=0.0)


class PositionStep(_Step):
    """Move the table to angles, settle, record."""

    kind: Literal["position"]
    angles_deg: tuple[float, ...] = Field(min_length=1, max_length=2)
    settle_s: float = Field(30.0, ge=0.0)
    record_s: float = Field(10.0, gt=0.0)


class RateStep(_Step):
    """Spin one table axis at a constant rate, settle, record whole revolutions or a duration."""

    kind: Literal["rate"]
    axis: int = Field(0, ge=0, le=1)
    rate_dps: float
    settle_s: float = Field(20.0, ge=0.0)
    revolutions: int | None = Field(None, ge=1)
    record_s: float | None = Field(None, gt=0.0)

    @model_validator(mode="after")
    def _one_length(self) -> RateStep:
        if self.revolutions is not None and self.rate_dps == 0.0:
            raise ValueError("`revolutions` needs a non-zero `rate_dps`; use `record_s` at 0 °/s")
        if self.revolutions is None and self.record_s is None:
            raise ValueError("give `revolutions` or `record_s`")
        return self


class SoakStep(_Step):
    """Set the chamber temperature and wait."""

    kind: Literal["soak"]
    temperature_degc: float
    duration_s: float = Field(gt=0.0)
    ramp_degc_per_min: float | None = Field(None, gt=0.0)


class CentrifugeStep(_Step):
    """Run the centrifuge at a rate (or position its arm at rest), settle, record."""

    kind: Literal["centrifuge"]
    rate_dps: float = 0.0
    arm_position_deg: float | None = None
    settle_s: float = Field(10.0, ge=0.0)
    revolutions: int | None = Field(None, ge=1)
    record_s: float | None = Field(None, gt=0.0)

    @model_validator(mode="after")
    def _one_length(self) -> CentrifugeStep:
        if self.revolutions is not None and self.rate_dps == 0.0:
            raise ValueError("`revolutions` needs a non-zero `rate_dps`; use `record_s` at rest")
        if self.revolutions is None and self.record_s is None:
            raise ValueError("give `revolutions` or `record_s`")
        return self


Step = Annotated[
    StaticStep | PositionStep | RateStep | SoakStep | CentrifugeStep,
    Field(discriminator="kind"),
]


class TwinEquipment(_Model):
    """The twin station without a step list: site, equipment, fixture and IMUs.

    It is what a simulated station is built from (:func:`imucalib.sim.build.build_rig`); a
    :class:`Scenario` adds the steps, and a test plan can carry one as its ``[twin]`` table.
    """

    seed: int = 0
    site: SiteConfig = Field(default_factory=SiteConfig)
    table: TableConfig = Field(default_factory=TableConfig)
    chamber: ChamberConfig = Field(default_factory=ChamberConfig)
    centrifuge: CentrifugeConfig = Field(default_factory=CentrifugeConfig)
    fixture: FixtureConfig = Field(default_factory=FixtureConfig)
    imus: tuple[ImuConfig, ...] = Field(min_length=1)

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


class Scenario(TwinEquipment):
    """A complete twin scenario: the equipment and the steps to run on it."""

    name: str = Field(min_length=1)
    description: str = ""
    steps: tuple[Step, ...] = Field(min_length=1)
    store_truth_streams: bool = False
    chunk_s: float = Field(10.0, gt=0.0, le=600.0)

    @model_validator(mode="after")
    def _consistent(self) -> Scenario:
        n_axes = {"none": 0, "single-axis": 1, "dual-axis": 2}[self.table.kind]
        for i, step in enumerate(self.steps):
            where = f"steps[{i}] ({step.kind})"
            if isinstance(step, PositionStep) and len(step.angles_deg) != n_axes:
                raise ValueError(
                    f"{where}: `angles_deg` needs {n_axes} value(s) for table kind "
                    f"{self.table.kind!r}; got {len(step.angles_deg)}"
                )
            if isinstance(step, RateStep) and step.axis >= n_axes:
                raise ValueError(
                    f"{where}: `axis` {step.axis} does not exist on table kind {self.table.kind!r}"
                )
            if isinstance(step, SoakStep) and not self.chamber.enabled:
                raise ValueError(f"{where}: a soak step needs `chamber.enabled = true`")
            if isinstance(step, CentrifugeStep) and not self.centrifuge.enabled:
                raise ValueError(f"{where}: a centrifuge step needs `centrifuge.enabled = true`")
        return self


def format_validation_error(exc: ValidationError, source: str, what: str = "scenario") -> str:
    """Render a pydantic error as one line per problem, naming the field path."""
    lines = [f"invalid {what} {source}:"]
    for err in exc.errors():
        loc = ".".join(str(p) for p in err["loc"]) or "(top level)"
        got = err.get("input")
        got_txt = "" if isinstance(got, dict | list) else f" (got {got!r})"
        lines.append(f"  {loc}: {err['msg']}{got_txt}")
    return "\n".join(lines)


def load_scenario(source: str | Path) -> Scenario:
    """Return a built-in scenario by name, or load and validate a TOML scenario file.

    Raises
    ------
    ConfigurationError
        If the file is missing, is not valid TOML, or does not match the schema; the message
        names each offending field, what was expected and what was found.
    """
    key = str(source)
    if key in BUILTIN_SCENARIOS:
        return BUILTIN_SCENARIOS[key]()
    path = Path(source)
    if not path.is_file():
        raise ConfigurationError(
            f"scenario {key!r} is neither a built-in ({', '.join(sorted(BUILTIN_SCENARIOS))}) "
            "nor an existing file"
        )
    try:
        data: dict[str, Any] = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ConfigurationError(f"scenario file {path} is not valid TOML: {exc}") from exc
    try:
        return Scenario.model_validate(data)
    except ValidationError as exc:
        raise ConfigurationError(format_validation_error(exc, str(path))) from exc


def _static_hour() -> Scenario:
    return Scenario(
        name="static-hour",
        description="One tactical IMU static and level for an hour at 1 kHz "
        "(Allan-variance record).",
        seed=1,
        imus=(ImuConfig(name="IMU-0001", grade="tactical"),),
        steps=(StaticStep(kind="static", duration_s=3600.0, label="static hour"),),
        chunk_s=60.0,
    )


def _dual_axis_p1() -> Scenario:
    six = [(0, 0), (0, 180), (90, 0), (90, 180), (0, 90), (0, 270)]
    steps: list[Any] = [
        PositionStep(kind="position", angles_deg=a, settle_s=30.0, record_s=10.0,
                     label=f"position pitch={a[0]} roll={a[1]}")
        for a in six
    ]
    steps.append(PositionStep(kind="position", angles_deg=(0.0, 0.0), settle_s=30.0,
                              record_s=600.0, label="level static (gyro bias)"))
    for axis in (0, 1):
        for rate in (-100.0, -50.0, 0.0, 50.0, 100.0):
            revs = None if rate == 0 else 3
            steps.append(RateStep(kind="rate", axis=axis, rate_dps=rate, settle_s=20.0,
                                  revolutions=revs, record_s=10.0 if revs is None else None,
                                  label=f"rate axis {axis} {rate:+g} dps"))
        steps.append(PositionStep(kind="position", angles_deg=(0.0, 0.0), settle_s=5.0,
                                  record_s=1.0, label="return home"))
    return Scenario(
        name="dual-axis-p1",
        description="P1 on a dual-axis table: six positions, a level static record, "
        "±rate points about pitch and roll (SPEC.md P1).",
        seed=2,
        table=TableConfig(kind="dual-axis", grade="high"),
        imus=(ImuConfig(name="IMU-0001", grade="tactical", drift_ppm=20.0, jitter_s=2e-4),),
        steps=tuple(steps),
    )


def _chamber_array() -> Scenario:
    steps: list[Any] = []
    for temp in (-10.0, 20.0, 60.0):
        steps.append(SoakStep(kind="soak", temperature_degc=temp, duration_s=1800.0,
                              label=f"soak {temp:+g} °C"))
        for angle in (0.0, 90.0, 180.0, 270.0):
            steps.append(PositionStep(kind="position", angles_deg=(angle,), settle_s=10.0,
                                      record_s=20.0, label=f"{temp:+g} °C static {angle:g}°"))
        for rate in (60.0, -60.0):
            steps.append(RateStep(kind="rate", axis=0, rate_dps=rate, settle_s=10.0,
                                  revolutions=2, label=f"{temp:+g} °C rate {rate:+g} dps"))
    imus = tuple(
        ImuConfig(name=f"IMU-{i + 1:04d}", grade="consumer", sample_rate_hz=200.0,
                  self_heating_degc=3.0, thermal_time_constant_s=300.0)
        for i in range(6)
    )
    return Scenario(
        name="chamber-array",
        description="Six consumer IMUs on a hexahedral fixture in a thermal chamber on a "
        "single-axis table (SPEC.md P2): soak, static and ±rate at three temperatures.",
        seed=3,
        table=TableConfig(kind="single-axis", grade="lab"),
        chamber=ChamberConfig(enabled=True, initial_temperature_degc=20.0),
        fixture=FixtureConfig(kind="hexahedral", half_edge_m=0.06),
        imus=imus,
        steps=tuple(steps),
        chunk_s=30.0,
    )


def _centrifuge() -> Scenario:
    steps: list[Any] = [
        CentrifugeStep(kind="centrifuge", rate_dps=0.0, arm_position_deg=a, settle_s=5.0,
                       record_s=10.0, label=f"rest, arm at {a:g}°")
        for a in (0.0, 90.0, 180.0, 270.0)
    ]
    for rate in (120.0, 240.0, 360.0, 480.0):
        steps.append(CentrifugeStep(kind="centrifuge", rate_dps=rate, settle_s=10.0,
                                    revolutions=10, label=f"spin {rate:g} dps"))
    steps.append(CentrifugeStep(kind="centrifuge", rate_dps=0.0, settle_s=5.0, record_s=5.0,
                                label="stop"))
    return Scenario(
        name="centrifuge",
        description="A navigation-grade IMU on a precision centrifuge with dynamic unbalance "
        "(SPEC.md P3): arm positions at rest, then four rates.",
        seed=4,
        centrifuge=CentrifugeConfig(enabled=True, static_radius_m=0.6,
                                    unbalance_c0_m_s2=2e-7, unbalance_c_per_kg_m_s2_per_kg=5e-8,
                                    load_kg=2.0),
        imus=(ImuConfig(name="IMU-0001", grade="navigation"),),
        steps=tuple(steps),
    )


#: Built-in scenarios by name.
BUILTIN_SCENARIOS: dict[str, Callable[[], Scenario]] = {
    "static-hour": _static_hour,
    "dual-axis-p1": _dual_axis_p1,
    "chamber-array": _chamber_array,
    "centrifuge": _centrifuge,
}
