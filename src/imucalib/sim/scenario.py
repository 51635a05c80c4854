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
    "MAX_ANGLE_DEG",
    "MAX_CENTRIFUGE_RATE_DPS",
    "MAX_IMUS",
    "MAX_RAMP_DEGC_PER_MIN",
    "MAX_RECORD_S",
    "MAX_REVOLUTIONS",
    "MAX_SAMPLE_RATE_HZ",
    "MAX_SETTLE_S",
    "MAX_STEPS",
    "MAX_TABLE_ACCEL_DPS2",
    "MAX_TABLE_RATE_DPS",
    "MAX_TEMPERATURE_DEGC",
    "MAX_TIME_CONSTANT_S",
    "MAX_TOTAL_S",
    "MAX_WAIT_S",
    "MIN_RAMP_DEGC_PER_MIN",
    "MIN_SAMPLE_RATE_HZ",
    "MIN_TEMPERATURE_DEGC",
    "MIN_TIME_CONSTANT_S",
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
    "step_min_duration_s",
]

# --- Bounds of every duration, count, rate and temperature (docs/twin.md, docs/station.md) ---
# Plans (imucalib.plan.schema) use the same numbers. Each is a physical or station limit with
# margin, so that no input can ask for an absurd run: a file of terabytes, a wait of centuries.

#: Longest settle (dwell) before a record: an hour; tables settle in seconds. [s]
MAX_SETTLE_S = 3600.0
#: Longest single record or static step: 7 days (an Allan record of a navigation IMU is 1–3). [s]
MAX_RECORD_S = 7 * 86400.0
#: Longest wait or time-out (soak, warm-up, stability): 2 days. [s]
MAX_WAIT_S = 2 * 86400.0
#: Longest plan or scenario, summed least step durations: 14 days. [s]
MAX_TOTAL_S = 14 * 86400.0
#: Longest thermal time constant (chamber air, IMU): a day. [s]
MAX_TIME_CONSTANT_S = 86400.0
#: Shortest thermal time constant: a second (shorter ones overflow the closed-form chamber model
#: and no chamber or IMU housing is that fast). [s]
MIN_TIME_CONSTANT_S = 1.0
#: Most steps in a plan or scenario (the default P1 plan has 110).
MAX_STEPS = 10_000
#: Most IMUs on one fixture.
MAX_IMUS = 64
#: Most whole revolutions one step records.
MAX_REVOLUTIONS = 100_000
#: Fastest rate-table rate (real tables: a few thousand °/s at most). [°/s]
MAX_TABLE_RATE_DPS = 10_000.0
#: Highest rate-table acceleration. [°/s²]
MAX_TABLE_ACCEL_DPS2 = 100_000.0
#: Fastest centrifuge rate (about 1700 rpm). [°/s]
MAX_CENTRIFUGE_RATE_DPS = 10_000.0
#: Largest commanded table or arm angle in magnitude (a turn either way). [°]
MAX_ANGLE_DEG = 360.0
#: Temperature range of thermal chambers (real ones: about −75 … +180 °C). [°C]
MIN_TEMPERATURE_DEGC = -100.0
MAX_TEMPERATURE_DEGC = 200.0
#: Fastest chamber ramp: 10 °C/s (thermal-shock chambers move an item between zones in seconds;
#: the driver tests' fast chamber ramps at 2 °C/s). [°C/min]
MAX_RAMP_DEGC_PER_MIN = 600.0
#: Slowest chamber ramp asked for: 0.01 °C/min (a degree in 100 minutes; real controllers
#: stop at about 0.1). [°C/min]
MIN_RAMP_DEGC_PER_MIN = 0.01
#: IMU output data rates accepted. [Hz]
MIN_SAMPLE_RATE_HZ = 1.0
MAX_SAMPLE_RATE_HZ = 100_000.0

_ANGLE = Annotated[float, Field(ge=-MAX_ANGLE_DEG, le=MAX_ANGLE_DEG)]
_ARM = Annotated[float, Field(ge=-5.0, le=5.0)]


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
    max_ramp_degc_per_min: float = Field(5.0, gt=0.0, le=MAX_RAMP_DEGC_PER_MIN)
    air_time_constant_s: float = Field(120.0, ge=MIN_TIME_CONSTANT_S, le=MAX_TIME_CONSTANT_S)
    stability_noise_degc: float = Field(0.05, ge=0.0, le=5.0)

    @model_validator(mode="after")
    def _range(self) -> ChamberConfig:
        if self.min_temperature_degc >= self.max_temperature_degc:
            raise ValueError(f"min_temperature_degc ({self.min_temperature_degc:g}) must be "
                             f"below max_temperature_degc ({self.max_temperature_degc:g})")
        return self


class CentrifugeConfig(_Model):
    """A precision centrifuge carrying the test item on its arm."""

    enabled: bool = False
    static_radius_m: float = Field(1.0, gt=0.0, le=20.0)
    unbalance_c0_m_s2: float = Field(0.0, ge=-1e-3, le=1e-3,
                                     description="shift c0·ω² of the rotor [m·s²]")
    unbalance_c_per_kg_m_s2_per_kg: float = Field(0.0, ge=-1e-3, le=1e-3,
                                                  description="[m·s²/kg]")
    load_kg: float = Field(0.0, ge=0.0, le=1000.0)
    max_rate_dps: float = Field(720.0, gt=0.0, le=MAX_CENTRIFUGE_RATE_DPS)


class FixtureConfig(_Model):
    """The fixture carrying the IMUs."""

    kind: Literal["single", "hexahedral", "array"] = "single"
    half_edge_m: float = Field(0.05, gt=0.0, le=1.0)
    lever_arm_m: tuple[_ARM, _ARM, _ARM] = Field((0.0, 0.0, 0.0), description="[m]")
    spacing_m: float = Field(0.05, gt=0.0, le=1.0)


class ImuConfig(_Model):
    """One IMU unit: its grade (the truth is drawn from it) and its clock."""

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


class _Step(_Model):
    label: str = Field("", max_length=200)


class StaticStep(_Step):
    """Record with nothing moving."""

    kind: Literal["static"]
    duration_s: float = Field(gt=0.0, le=MAX_RECORD_S)


class PositionStep(_Step):
    """Move the table to angles, settle, record."""

    kind: Literal["position"]
    angles_deg: tuple[_ANGLE, ...] = Field(min_length=1, max_length=2)
    settle_s: float = Field(30.0, ge=0.0, le=MAX_SETTLE_S)
    record_s: float = Field(10.0, gt=0.0, le=MAX_RECORD_S)


class RateStep(_Step):
    """Spin one table axis at a constant rate, settle, record whole revolutions or a duration."""

    kind: Literal["rate"]
    axis: int = Field(0, ge=0, le=1)
    rate_dps: float = Field(ge=-MAX_TABLE_RATE_DPS, le=MAX_TABLE_RATE_DPS)
    settle_s: float = Field(20.0, ge=0.0, le=MAX_SETTLE_S)
    revolutions: int | None = Field(None, ge=1, le=MAX_REVOLUTIONS)
    record_s: float | None = Field(None, gt=0.0, le=MAX_RECORD_S)

    @model_validator(mode="after")
    def _one_length(self) -> RateStep:
        if self.revolutions is not None and self.rate_dps == 0.0:
            raise ValueError("`revolutions` needs a non-zero `rate_dps`; use `record_s` at 0 °/s")
        if self.revolutions is None and self.record_s is None:
            raise ValueError("give `revolutions` or `record_s`")
        check_record_length(self.revolutions, self.record_s, self.rate_dps)
        return self


class SoakStep(_Step):
    """Set the chamber temperature and wait."""

    kind: Literal["soak"]
    temperature_degc: float = Field(ge=MIN_TEMPERATURE_DEGC, le=MAX_TEMPERATURE_DEGC)
    duration_s: float = Field(gt=0.0, le=MAX_WAIT_S)
    ramp_degc_per_min: float | None = Field(None, ge=MIN_RAMP_DEGC_PER_MIN,
                                            le=MAX_RAMP_DEGC_PER_MIN)


class CentrifugeStep(_Step):
    """Run the centrifuge at a rate (or position its arm at rest), settle, record."""

    kind: Literal["centrifuge"]
    rate_dps: float = Field(0.0, ge=-MAX_CENTRIFUGE_RATE_DPS, le=MAX_CENTRIFUGE_RATE_DPS)
    arm_position_deg: _ANGLE | None = None
    settle_s: float = Field(10.0, ge=0.0, le=MAX_SETTLE_S)
    revolutions: int | None = Field(None, ge=1, le=MAX_REVOLUTIONS)
    record_s: float | None = Field(None, gt=0.0, le=MAX_RECORD_S)

    @model_validator(mode="after")
    def _one_length(self) -> CentrifugeStep:
        if self.revolutions is not None and self.rate_dps == 0.0:
            raise ValueError("`revolutions` needs a non-zero `rate_dps`; use `record_s` at rest")
        if self.revolutions is None and self.record_s is None:
            raise ValueError("give `revolutions` or `record_s`")
        check_record_length(self.revolutions, self.record_s, self.rate_dps)
        return self


Step = Annotated[
    StaticStep | PositionStep | RateStep | SoakStep | CentrifugeStep,
    Field(discriminator="kind"),
]


def check_record_length(revolutions: int | None, record_s: float | None, rate_dps: float
                        ) -> None:
    """Refuse a record of whole revolutions longer than :data:`MAX_RECORD_S` (a slow rate)."""
    if revolutions is not None and rate_dps != 0.0:
        length = revolutions * 360.0 / abs(rate_dps)
        if length > MAX_RECORD_S:
            raise ValueError(f"{revolutions} revolution(s) at {rate_dps:g} °/s take "
                             f"{length:.4g} s; a record may last at most {MAX_RECORD_S:.0f} s "
                             "(7 days)")


def step_min_duration_s(step: StaticStep | PositionStep | RateStep | SoakStep
                        | CentrifugeStep) -> float:
    """Return the least time a scenario step takes (moves and settling excluded). [s]"""
    if isinstance(step, StaticStep | SoakStep):
        return step.duration_s
    if isinstance(step, PositionStep):
        return step.settle_s + step.record_s
    if step.revolutions is not None and step.rate_dps != 0.0:
        return step.settle_s + step.revolutions * 360.0 / abs(step.rate_dps)
    return step.settle_s + (step.record_s or 0.0)


class TwinEquipment(_Model):
    """The twin station without a step list: site, equipment, fixture and IMUs.

    It is what a simulated station is built from (:func:`imucalib.sim.build.build_rig`); a
    :class:`Scenario` adds the steps, and a test plan can carry one as its ``[twin]`` table.
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


class Scenario(TwinEquipment):
    """A complete twin scenario: the equipment and the steps to run on it."""

    name: str = Field(min_length=1, max_length=200)
    description: str = Field("", max_length=2000)
    steps: tuple[Step, ...] = Field(min_length=1, max_length=MAX_STEPS)
    store_truth_streams: bool = False
    chunk_s: float = Field(10.0, ge=0.1, le=600.0,
                           description="simulated time generated per chunk [s]")

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
            if isinstance(step, SoakStep) and not (
                    self.chamber.min_temperature_degc <= step.temperature_degc
                    <= self.chamber.max_temperature_degc):
                raise ValueError(
                    f"{where}: temperature_degc {step.temperature_degc:g} is outside the "
                    f"chamber's range [{self.chamber.min_temperature_degc:g}, "
                    f"{self.chamber.max_temperature_degc:g}] °C")
            if isinstance(step, CentrifugeStep) and not self.centrifuge.enabled:
                raise ValueError(f"{where}: a centrifuge step needs `centrifuge.enabled = true`")
            if isinstance(step, CentrifugeStep) and \
                    abs(step.rate_dps) > self.centrifuge.max_rate_dps:
                raise ValueError(f"{where}: rate_dps {step.rate_dps:g} exceeds "
                                 f"centrifuge.max_rate_dps {self.centrifuge.max_rate_dps:g}")
        total = sum(step_min_duration_s(step) for step in self.steps)
        if total > MAX_TOTAL_S:
            raise ValueError(f"the steps take at least {total:.6g} s ({total / 86400:.3g} days); "
                             f"a scenario may last at most {MAX_TOTAL_S:.0f} s (14 days)")
        return self


def format_validation_error(exc: ValidationError, source: str, what: str = "scenario") -> str:
    """Render a pydantic error naming the field path: one line, or one line per problem."""
    lines = [f"invalid {what} {source}:"]
    errors = exc.errors()
    for err in errors:
        if err["type"] == "too_short" and any(
                len(e["loc"]) > len(err["loc"]) and e["loc"][:len(err["loc"])] == err["loc"]
                for e in errors):
            continue  # pydantic's echo of an invalid item: "at least 1 item … not 0"
        loc = ".".join(str(p) for p in err["loc"])
        got = err.get("input")
        msg = err["msg"].removeprefix("Value error, ")
        if err["type"] == "value_error":  # a model check: its message names the fields
            lines.append(f"  {loc + ': ' if loc else ''}{msg}")
            continue
        got_txt = "" if isinstance(got, dict | list | tuple) else f" (got {got!r})"
        lines.append(f"  {loc or '(top level)'}: {msg}{got_txt}")
    if len(lines) == 2:
        return f"{lines[0]} {lines[1].strip()}"
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
