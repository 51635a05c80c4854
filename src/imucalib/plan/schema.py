"""Test plans: the schema of a plan file, validated by pydantic.

A plan is what a station run executes: limits, guard thresholds, the IMU's specification, an
optional description of the twin station to run it on, and the list of steps. Defaults are the
numbers of SPEC.md P1 (settle ≥30 s within 5″ and 0.001 g; rate within 0.5 °/s; record ≥10 s;
temperature steady within 0.2 °C).

Contents
--------
:class:`Plan` and its parts :class:`PlanLimits`, :class:`GuardConfig`, :class:`ImuSpecConfig`;
the step kinds :class:`SoakStep`, :class:`WarmUpStep`, :class:`PositionStep`, :class:`RateStep`,
:class:`CentrifugeStep`, :class:`StaticStep`, :class:`OperatorCheckStep`; :data:`PlanStep`.

Example
-------
.. code-block:: toml

    name = "p1-example"
    procedure = "p1"
    [limits]
    max_rate_dps = 300
    [[steps]]
    kind = "operator-check"
    item = "IMU mounted, X along the roll axis, Z up"
    [[steps]]
    kind = "position"
    angles_deg = [0, 180]
    settle_s = 30
    record_s = 10
    tags = ["calibration"]
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

from imucalib.sim.scenario import TwinEquipment

__all__ = [
    "CentrifugeStep",
    "EquipmentConfig",
    "GuardConfig",
    "ImuSpecConfig",
    "OperatorCheckStep",
    "Plan",
    "PlanLimits",
    "PlanStep",
    "PositionStep",
    "RateStep",
    "SoakStep",
    "StaticStep",
    "WarmUpStep",
    "step_min_duration_s",
]


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class PlanLimits(_Model):
    """Limits no command of the plan may exceed (checked before anything moves)."""

    max_rate_dps: float = Field(500.0, gt=0.0, description="table rate limit [°/s]")
    max_accel_dps2: float = Field(100.0, gt=0.0, description="table acceleration limit [°/s²]")
    max_centrifuge_rate_dps: float = Field(720.0, gt=0.0, description="centrifuge limit [°/s]")
    min_temperature_degc: float = Field(-55.0, ge=-100.0, le=200.0)
    max_temperature_degc: float = Field(125.0, ge=-100.0, le=200.0)

    @model_validator(mode="after")
    def _range(self) -> PlanLimits:
        if self.min_temperature_degc >= self.max_temperature_degc:
            raise ValueError(
                f"min_temperature_degc ({self.min_temperature_degc}) must be below "
                f"max_temperature_degc ({self.max_temperature_degc})"
            )
        return self


class GuardConfig(_Model):
    """Settling criteria and guard thresholds; the defaults are SPEC.md P1's."""

    position_tolerance_arcsec: float = Field(5.0, gt=0.0, description="table deviation [″]")
    hold_rate_tolerance_dps: float = Field(
        0.01, gt=0.0, description="rate of an axis holding a position [°/s]")
    rate_tolerance_dps: float = Field(0.5, gt=0.0, description="rate deviation [°/s]")
    settle_fluctuation_g: float = Field(
        0.001, gt=0.0, description="IMU accelerometer fluctuation allowed when settled [g]")
    settle_average_s: float = Field(
        0.1, gt=0.0, description="block length whose means the fluctuation is taken over [s]")
    settle_check_s: float = Field(
        1.0, gt=0.0, description="span over which the settling criteria must hold [s]")
    settle_timeout_s: float = Field(300.0, gt=0.0, description="give up settling after [s]")
    accel_jump_g: float = Field(0.5, gt=0.0, description="sample-to-sample output jump [g]")
    gyro_jump_dps: float = Field(20.0, gt=0.0, description="sample-to-sample jump [°/s]")
    max_counter_gap_samples: int = Field(
        0, ge=0, description="lost samples tolerated inside a valid window")
    max_crc_errors: int = Field(0, ge=0, description="CRC failures tolerated in a valid window")
    trip_on_saturation: bool = True
    chamber_band_degc: float = Field(
        1.0, gt=0.0, description="chamber air vs setpoint while recording, after a soak [°C]")
    device_timeout_s: float = Field(5.0, gt=0.0, description="device time-out [s]")
    recover_timeout_s: float = Field(
        60.0, gt=0.0, description="after a trip, wait this long for healthy devices [s]")
    on_trip: Literal["retry", "stop"] = "retry"
    max_retries: int = Field(2, ge=0, le=10)


class ImuSpecConfig(_Model):
    """What the IMU under test claims: identity and the accuracy verification checks against."""

    model: str = ""
    maker: str = ""
    grade: Literal["consumer", "tactical", "navigation", ""] = ""
    accel_accuracy_g: float = Field(0.01, gt=0.0, description="held-out accuracy spec [g]")
    gyro_accuracy_dps: float = Field(0.5, gt=0.0, description="held-out accuracy spec [°/s]")
    gyro_noise_dps: float | None = Field(None, gt=0.0, description="gyro noise spec [°/s]")


class EquipmentConfig(_Model):
    """What the plan requires of the equipment (SPEC.md P1 preparation).

    The analysis also uses these as Type B uncertainties (uniform, u = a/√3) of the quantities
    they limit: table angle errors tilt the reference gravity (accelerometer misalignments),
    a non-perpendicular axis pair tilts the reference rates (gyro misalignments).
    """

    table_position_accuracy_arcsec: float = Field(10.0, ge=0.0, description="[″]")
    table_orthogonality_arcsec: float = Field(5.0, ge=0.0, description="[″]")
    acquisition_rate_min_hz: float = Field(100.0, gt=0.0, description="[Hz]")


class _Step(_Model):
    label: str = Field("", max_length=200)
    tags: tuple[str, ...] = ()


class SoakStep(_Step):
    """Set the chamber, then wait until chamber and IMU temperatures are stable."""

    kind: Literal["soak"]
    temperature_degc: float
    ramp_degc_per_min: float | None = Field(None, gt=0.0)
    band_degc: float = Field(0.5, gt=0.0, description="chamber air within ± of the setpoint")
    imu_band_degc: float = Field(0.2, gt=0.0, description="IMU temperature span when stable")
    stable_for_s: float = Field(600.0, gt=0.0)
    timeout_s: float = Field(7200.0, gt=0.0)


class WarmUpStep(_Step):
    """Power-on warm-up: at least `duration_s`, and until the IMU output has stopped drifting."""

    kind: Literal["warm-up"]
    duration_s: float = Field(gt=0.0)
    window_s: float = Field(60.0, gt=0.0, description="window whose means are compared")
    max_gyro_drift_dps: float = Field(0.01, gt=0.0, description="change of consecutive means")
    max_accel_drift_g: float = Field(0.001, gt=0.0, description="change of consecutive means")
    timeout_s: float = Field(7200.0, gt=0.0)


class PositionStep(_Step):
    """Move the table to angles (one per axis), settle, record."""

    kind: Literal["position"]
    angles_deg: tuple[float, ...] = Field(min_length=1, max_length=2)
    settle_s: float = Field(30.0, ge=0.0)
    record_s: float = Field(10.0, gt=0.0)


class RateStep(_Step):
    """Spin one table axis at a rate, settle, record whole revolutions (or a duration)."""

    kind: Literal["rate"]
    axis: int = Field(0, ge=0, le=1)
    rate_dps: float
    settle_s: float = Field(20.0, ge=0.0)
    revolutions: int | None = Field(None, ge=1)
    record_s: float | None = Field(None, gt=0.0)

    @model_validator(mode="after")
    def _length(self) -> RateStep:
        if self.revolutions is not None and self.rate_dps == 0.0:
            raise ValueError("`revolutions` needs a non-zero `rate_dps`; use `record_s` at 0 °/s")
        if (self.revolutions is None) == (self.record_s is None):
            raise ValueError("give exactly one of `revolutions` and `record_s`")
        return self


class CentrifugeStep(_Step):
    """Spin the centrifuge (or position its arm at rest), settle, record."""

    kind: Literal["centrifuge"]
    rate_dps: float = 0.0
    arm_position_deg: float | None = None
    settle_s: float = Field(10.0, ge=0.0)
    revolutions: int | None = Field(None, ge=1)
    record_s: float | None = Field(None, gt=0.0)

    @model_validator(mode="after")
    def _length(self) -> CentrifugeStep:
        if self.revolutions is not None and self.rate_dps == 0.0:
            raise ValueError("`revolutions` needs a non-zero `rate_dps`; use `record_s` at rest")
        if (self.revolutions is None) == (self.record_s is None):
            raise ValueError("give exactly one of `revolutions` and `record_s`")
        if self.arm_position_deg is not None and self.rate_dps != 0.0:
            raise ValueError("`arm_position_deg` positions the arm at rest; `rate_dps` must be 0")
        return self


class StaticStep(_Step):
    """Record where the table is, nothing moving (the long static record of P1 step 2)."""

    kind: Literal["static"]
    duration_s: float = Field(gt=0.0)


class OperatorCheckStep(_Step):
    """An item the operator confirms (mounting, alignment, remount); who and when are recorded."""

    kind: Literal["operator-check"]
    item: str = Field(min_length=1, max_length=500)


PlanStep = Annotated[
    SoakStep | WarmUpStep | PositionStep | RateStep | CentrifugeStep | StaticStep
    | OperatorCheckStep,
    Field(discriminator="kind"),
]


class Plan(_Model):
    """A test plan."""

    name: str = Field(min_length=1, max_length=200)
    description: str = ""
    procedure: str = Field("", description="analysis that applies: p1, allan, …")
    imu: ImuSpecConfig = Field(default_factory=ImuSpecConfig)
    limits: PlanLimits = Field(default_factory=PlanLimits)
    guards: GuardConfig = Field(default_factory=GuardConfig)
    equipment: EquipmentConfig = Field(default_factory=EquipmentConfig)
    twin: TwinEquipment | None = Field(
        None, description="the twin station to run this plan on with --station sim")
    steps: tuple[PlanStep, ...] = Field(min_length=1)

    @model_validator(mode="after")
    def _within_limits(self) -> Plan:
        lim = self.limits
        for i, step in enumerate(self.steps):
            where = f"steps.{i} ({step.kind}{' ' + repr(step.label) if step.label else ''})"
            if isinstance(step, RateStep) and abs(step.rate_dps) > lim.max_rate_dps:
                raise ValueError(f"{where}: rate_dps {step.rate_dps:g} exceeds "
                                 f"limits.max_rate_dps {lim.max_rate_dps:g}")
            if isinstance(step, CentrifugeStep) and abs(step.rate_dps) > \
                    lim.max_centrifuge_rate_dps:
                raise ValueError(f"{where}: rate_dps {step.rate_dps:g} exceeds "
                                 f"limits.max_centrifuge_rate_dps {lim.max_centrifuge_rate_dps:g}")
            if isinstance(step, SoakStep) and not (
                    lim.min_temperature_degc <= step.temperature_degc <= lim.max_temperature_degc):
                raise ValueError(
                    f"{where}: temperature_degc {step.temperature_degc:g} is outside limits "
                    f"[{lim.min_temperature_degc:g}, {lim.max_temperature_degc:g}] °C")
        return self

    def step_label(self, index: int) -> str:
        """Return the label of step `index`, or ``"<kind> <index>"`` when it has none."""
        step = self.steps[index]
        return step.label or f"{step.kind} {index}"


def step_min_duration_s(step: PlanStep) -> float:
    """Return the least time a step can take (moves and waits for stability excluded). [s]"""
    if isinstance(step, SoakStep):
        return step.stable_for_s
    if isinstance(step, WarmUpStep | StaticStep):
        return step.duration_s
    if isinstance(step, PositionStep):
        return step.settle_s + step.record_s
    if isinstance(step, RateStep | CentrifugeStep):
        if step.revolutions is not None:
            return step.settle_s + step.revolutions * 360.0 / abs(step.rate_dps)
        return step.settle_s + (step.record_s or 0.0)
    return 0.0
