"""Twin scenarios: twin equipment plus a plan's steps, validated by pydantic.

A scenario is what ``imucalib simulate`` runs: the equipment of a twin station
(:class:`~imucalib.plan.equipment.TwinEquipment`: site, table, chamber, centrifuge, fixture,
IMUs) and a list of steps in the plan vocabulary (:data:`~imucalib.plan.schema.PlanStep`). It is
run as a plan (:meth:`Scenario.to_plan`) by the station runner on the simulated station, so a
scenario and a plan mean the same by every step. Loaded from TOML or taken from the built-in set
(:data:`BUILTIN_SCENARIOS`).

Contents
--------
:class:`Scenario`; :func:`load_scenario` (a built-in name or a TOML file);
:data:`BUILTIN_SCENARIOS`; :class:`ScenarioFormatWarning` and :func:`upgrade_scenario_data` (a
file written for the former scenario format: a soak's ``duration_s`` becomes ``stable_for_s``,
the centrifuge's unbalance coefficients take their unit-true names).

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
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

from pydantic import Field, ValidationError, model_validator

from imucalib.errors import ConfigurationError
from imucalib.plan.bounds import MAX_STEPS, MAX_TOTAL_S, format_validation_error
from imucalib.plan.equipment import (
    LEGACY_CENTRIFUGE_NAMES,
    CentrifugeConfig,
    ChamberConfig,
    FixtureConfig,
    ImuConfig,
    TableConfig,
    TwinEquipment,
)
from imucalib.plan.schema import (
    CentrifugeStep,
    GuardConfig,
    Plan,
    PlanLimits,
    PlanStep,
    PositionStep,
    RateStep,
    SoakStep,
    StaticStep,
    operator_check_problems,
    step_min_duration_s,
)

__all__ = [
    "BUILTIN_SCENARIOS",
    "Scenario",
    "ScenarioFormatWarning",
    "load_scenario",
    "upgrade_scenario_data",
]


class ScenarioFormatWarning(FutureWarning):
    """A scenario file uses a former field name; it is read with the current one."""


class Scenario(TwinEquipment):
    """A complete twin scenario: the equipment and a plan's steps to run on it."""

    name: str = Field(min_length=1, max_length=200)
    description: str = Field("", max_length=2000)
    steps: tuple[PlanStep, ...] = Field(min_length=1, max_length=MAX_STEPS)
    store_truth_streams: bool = False
    chunk_s: float = Field(10.0, ge=0.1, le=600.0,
                           description="longest span of virtual time generated at once [s]")

    @model_validator(mode="after")
    def _consistent(self) -> Scenario:
        n_axes = self.table_axes
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
        problems = operator_check_problems(self.steps, [imu.name for imu in self.imus],
                                           self.centrifuge.enabled)
        if problems:
            raise ValueError(problems[0])
        total = sum(step_min_duration_s(step) for step in self.steps)
        if total > MAX_TOTAL_S:
            raise ValueError(f"the steps take at least {total:.6g} s ({total / 86400:.3g} days); "
                             f"a scenario may last at most {MAX_TOTAL_S:.0f} s (14 days)")
        return self

    @property
    def equipment(self) -> TwinEquipment:
        """Return the twin equipment alone (what the simulated station is built from)."""
        return TwinEquipment.model_validate(
            self.model_dump(include=set(TwinEquipment.model_fields)))

    def to_plan(self, limits: PlanLimits | None = None) -> Plan:
        """Return the scenario as a plan: its steps, with the equipment as the plan's twin.

        Parameters
        ----------
        limits : PlanLimits, optional
            The plan's limits; by default the equipment's own
            (:meth:`imucalib.station.sim.SimStation.plan_limits` gives the twin's).

        The guards are the plan defaults, except that IMUs told to lose samples
        (``drop_probability`` > 0) may lose them inside a valid window: the scenario asks for
        those gaps, so they are recorded rather than tripped on.

        Raises
        ------
        pydantic.ValidationError
            When a step exceeds `limits`.
        """
        guards = GuardConfig()
        if any(imu.drop_probability > 0.0 for imu in self.imus):
            guards = guards.model_copy(update={"max_counter_gap_samples": 10**9})
        return Plan(name=self.name, description=self.description, procedure="",
                    limits=limits or PlanLimits(), guards=guards, twin=self.equipment,
                    steps=self.steps)


def upgrade_scenario_data(data: dict[str, Any]) -> tuple[dict[str, Any], list[str]]:
    """Map a scenario written for the former format onto the current one.

    The former scenario steps had their own vocabulary; now they are plan steps. Two names
    changed: a soak waited a fixed ``duration_s`` (now it waits until chamber and IMU are stable
    for ``stable_for_s``, up to ``timeout_s``), and the centrifuge's unbalance coefficients
    were named as if in m/s² (``unbalance_c0_m_s2``, ``unbalance_c_per_kg_m_s2_per_kg``).

    Returns
    -------
    data : dict
        The data with the current names (a copy where anything changed).
    notes : list of str
        One line per change, naming the old and the new field.
    """
    notes: list[str] = []
    steps = data.get("steps")
    if isinstance(steps, list):
        new_steps = []
        for i, step in enumerate(steps):
            if (isinstance(step, dict) and step.get("kind") == "soak" and "duration_s" in step
                    and "stable_for_s" not in step):
                step = {k: v for k, v in step.items() if k != "duration_s"}
                step["stable_for_s"] = steps[i]["duration_s"]
                notes.append(f"steps.{i} (soak): `duration_s` is now `stable_for_s` (the soak "
                             "waits until chamber and IMU temperatures are stable that long)")
            new_steps.append(step)
        data = {**data, "steps": new_steps}
    fuge = data.get("centrifuge")
    if isinstance(fuge, dict):
        for old, new in LEGACY_CENTRIFUGE_NAMES.items():
            if old in fuge:
                notes.append(f"centrifuge: `{old}` is now `{new}` (the unit is m/(rad/s)²)")
    return data, notes


def load_scenario(source: str | Path) -> Scenario:
    """Return a built-in scenario by name, or load and validate a TOML scenario file.

    A file written for the former scenario format is read with the current names
    (:func:`upgrade_scenario_data`), with a :class:`ScenarioFormatWarning` per change.

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
    data, notes = upgrade_scenario_data(data)
    for note in notes:
        warnings.warn(f"{path}: former scenario format: {note}; please update the file",
                      ScenarioFormatWarning, stacklevel=2)
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


#: P1's roles the built-in P1 scenario gives its steps: data, as a scenario file gives them
#: (the role strings of docs/p1.md; the layers keep ``sim`` below the procedures).
_P1_ACCEL_POSITION = "p1.accel-position"
_P1_GYRO_BIAS = "p1.gyro-bias"
_P1_GYRO_RATE = "p1.gyro-rate"


def _dual_axis_p1() -> Scenario:
    six = [(0, 0), (0, 180), (90, 0), (90, 180), (0, 90), (0, 270)]
    steps: list[Any] = [
        PositionStep(kind="position", angles_deg=a, settle_s=30.0, record_s=10.0,
                     label=f"position pitch={a[0]} roll={a[1]}", role=_P1_ACCEL_POSITION,
                     tags=("calibration", "six-position"))
        for a in six
    ]
    steps.append(PositionStep(kind="position", angles_deg=(0.0, 0.0), settle_s=30.0,
                              record_s=600.0, label="level static (gyro bias)",
                              role=_P1_GYRO_BIAS, tags=("calibration", "gyro-bias")))
    # rates about pitch (sensor Y), roll (sensor X), and pitch with the roll axis at 90°
    # (sensor Z): the triad's gyro scale factors and misalignments all need a rate
    for axis, roll_deg, about in ((0, 0.0, "pitch"), (1, 0.0, "roll"),
                                  (0, 90.0, "pitch, roll 90")):
        steps.append(PositionStep(kind="position", angles_deg=(0.0, roll_deg), settle_s=5.0,
                                  record_s=1.0, label=f"start of {about} rates"))
        for rate in (-100.0, -50.0, 0.0, 50.0, 100.0):
            revs = None if rate == 0 else 3
            steps.append(RateStep(kind="rate", axis=axis, rate_dps=rate, settle_s=20.0,
                                  revolutions=revs, record_s=10.0 if revs is None else None,
                                  label=f"rate about {about} {rate:+g} dps", role=_P1_GYRO_RATE,
                                  tags=("calibration", "rate")))
    steps.append(PositionStep(kind="position", angles_deg=(0.0, 0.0), settle_s=5.0,
                              record_s=1.0, label="return home"))
    return Scenario(
        name="dual-axis-p1",
        description="P1 on a dual-axis table: six positions, a level static record, "
        "±rate points about pitch, roll and (roll at 90°) the IMU's Z axis; the steps carry "
        "P1's roles, so `imucalib calibrate` runs P1 on the file (docs/p1.md).",
        seed=2,
        table=TableConfig(kind="dual-axis", grade="high"),
        imus=(ImuConfig(name="IMU-0001", grade="tactical", drift_ppm=20.0, jitter_s=2e-4),),
        steps=tuple(steps),
    )


def _chamber_array() -> Scenario:
    steps: list[Any] = []
    for temp in (-10.0, 20.0, 60.0):
        steps.append(SoakStep(kind="soak", temperature_degc=temp, stable_for_s=600.0,
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
        "single-axis table (P2, docs/procedures.md): soak, static and ±rate at three temperatures.",
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
    for rate in (120.0, 240.0, 300.0, 360.0):  # within the navigation gyro's ±400 °/s
        steps.append(CentrifugeStep(kind="centrifuge", rate_dps=rate, settle_s=10.0,
                                    revolutions=10, label=f"spin {rate:g} dps"))
    steps.append(CentrifugeStep(kind="centrifuge", rate_dps=0.0, settle_s=5.0, record_s=5.0,
                                label="stop"))
    return Scenario(
        name="centrifuge",
        description="A navigation-grade IMU on a precision centrifuge with dynamic unbalance "
        "(P3, docs/procedures.md): arm positions at rest, then four rates.",
        seed=4,
        centrifuge=CentrifugeConfig(enabled=True, static_radius_m=0.6,
                                    unbalance_c0_m_per_rps_sq=2e-7,
                                    unbalance_c_m_per_rps_sq_per_kg=5e-8,
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
