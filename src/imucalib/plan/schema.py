"""Test plans: the schema of a plan file, validated by pydantic.

A plan is what a station run executes: limits, guard thresholds, the IMU's specification, an
optional description of the twin station to run it on, and the list of steps. Defaults are the
numbers of P1 (docs/p1.md, calibration steps 1–3: settle ≥30 s within 5″ and 0.001 g; rate within
0.5 °/s; record ≥10 s; temperature steady within 0.2 °C).

Contents
--------
:class:`Plan` and its parts :class:`PlanLimits`, :class:`GuardConfig`, :class:`ImuSpecConfig`
(with :class:`ImuNoiseConfig`, the unit's declared noise);
the step kinds :class:`SoakStep`, :class:`WarmUpStep`, :class:`PositionStep`, :class:`RateStep`,
:class:`CentrifugeStep`, :class:`StaticStep`, :class:`OperatorCheckStep`; :data:`PlanStep`;
:func:`operator_check_problems` (unit swaps and load changes a station cannot do).

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

from collections.abc import Sequence
from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

from imucalib.plan.bounds import (
    MAX_ANGLE_DEG,
    MAX_CENTRIFUGE_RATE_DPS,
    MAX_RAMP_DEGC_PER_MIN,
    MAX_RECORD_S,
    MAX_REVOLUTIONS,
    MAX_SAMPLE_RATE_HZ,
    MAX_SETTLE_S,
    MAX_STEPS,
    MAX_TABLE_ACCEL_DPS2,
    MAX_TABLE_RATE_DPS,
    MAX_TEMPERATURE_DEGC,
    MAX_TOTAL_S,
    MAX_WAIT_S,
    MIN_RAMP_DEGC_PER_MIN,
    MIN_SAMPLE_RATE_HZ,
    MIN_TEMPERATURE_DEGC,
    check_record_length,
)
from imucalib.plan.equipment import TwinEquipment
from imucalib.plan.fixture_poses import FixtureAxis

__all__ = [
    "AcceptanceConfig",
    "CentrifugeStep",
    "EquipmentConfig",
    "GuardConfig",
    "ImuNoiseConfig",
    "ImuSpecConfig",
    "OperatorCheckStep",
    "Plan",
    "PlanLimits",
    "PlanStep",
    "PositionStep",
    "RateStep",
    "SoakStep",
    "SpecLimits",
    "StaticStep",
    "WarmUpStep",
    "operator_check_problems",
    "plan_min_duration_s",
    "step_min_duration_s",
]

_ANGLE = Annotated[float, Field(ge=-MAX_ANGLE_DEG, le=MAX_ANGLE_DEG)]


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class PlanLimits(_Model):
    """Limits no command of the plan may exceed (checked before anything moves)."""

    max_rate_dps: float = Field(500.0, gt=0.0, le=MAX_TABLE_RATE_DPS,
                                description="table rate limit [°/s]")
    max_accel_dps2: float = Field(100.0, gt=0.0, le=MAX_TABLE_ACCEL_DPS2,
                                  description="table acceleration limit [°/s²]")
    max_centrifuge_rate_dps: float = Field(720.0, gt=0.0, le=MAX_CENTRIFUGE_RATE_DPS,
                                           description="centrifuge limit [°/s]")
    min_temperature_degc: float = Field(-55.0, ge=MIN_TEMPERATURE_DEGC,
                                        le=MAX_TEMPERATURE_DEGC, description="[°C]")
    max_temperature_degc: float = Field(125.0, ge=MIN_TEMPERATURE_DEGC,
                                        le=MAX_TEMPERATURE_DEGC, description="[°C]")

    @model_validator(mode="after")
    def _range(self) -> PlanLimits:
        if self.min_temperature_degc >= self.max_temperature_degc:
            raise ValueError(
                f"min_temperature_degc ({self.min_temperature_degc}) must be below "
                f"max_temperature_degc ({self.max_temperature_degc})"
            )
        return self


class GuardConfig(_Model):
    """Settling criteria and guard thresholds; the defaults are P1's (docs/p1.md, steps 1–3)."""

    position_tolerance_arcsec: float = Field(5.0, gt=0.0, le=3600.0,
                                             description="table deviation [″]")
    hold_rate_tolerance_dps: float = Field(
        0.01, gt=0.0, le=10.0, description="rate of an axis holding a position [°/s]")
    rate_tolerance_dps: float = Field(0.5, gt=0.0, le=100.0, description="rate deviation [°/s]")
    settle_fluctuation_g: float = Field(
        0.001, gt=0.0, le=1.0,
        description="IMU accelerometer fluctuation allowed when settled [g]")
    settle_average_s: float = Field(
        0.1, gt=0.0, le=60.0,
        description="block length whose means the fluctuation is taken over [s]")
    settle_check_s: float = Field(
        1.0, gt=0.0, le=MAX_SETTLE_S,
        description="span over which the settling criteria must hold [s]")
    settle_timeout_s: float = Field(300.0, gt=0.0, le=MAX_SETTLE_S,
                                    description="give up settling after [s]")
    accel_jump_g: float = Field(0.5, gt=0.0, le=1000.0,
                                description="sample-to-sample output jump [g]")
    gyro_jump_dps: float = Field(20.0, gt=0.0, le=100_000.0,
                                 description="sample-to-sample jump [°/s]")
    max_counter_gap_samples: int = Field(
        0, ge=0, le=10**9, description="lost samples tolerated inside a valid window")
    max_crc_errors: int = Field(0, ge=0, le=10**9,
                                description="CRC failures tolerated in a valid window")
    trip_on_saturation: bool = True
    chamber_band_degc: float = Field(
        1.0, gt=0.0, le=50.0,
        description="chamber air vs setpoint while recording, after a soak [°C]")
    device_timeout_s: float = Field(5.0, gt=0.0, le=600.0, description="device time-out [s]")
    recover_timeout_s: float = Field(
        60.0, gt=0.0, le=MAX_SETTLE_S,
        description="after a trip, wait this long for healthy devices [s]")
    on_trip: Literal["retry", "stop"] = "retry"
    max_retries: int = Field(2, ge=0, le=10)

    @model_validator(mode="after")
    def _blocks(self) -> GuardConfig:
        if self.settle_average_s > self.settle_check_s:
            raise ValueError(f"settle_average_s ({self.settle_average_s:g} s) must not exceed "
                             f"settle_check_s ({self.settle_check_s:g} s): the fluctuation is "
                             "taken over block means inside that span")
        return self


class SpecLimits(_Model):
    """The unit's specification: the largest error each parameter may have (docs/p1.md).

    Each limit bounds |value| of the calibrated parameter (a scale factor: its deviation from
    1); None: not specified, not checked. The noise limits bound the white-noise coefficients
    of the noise model fitted to the static record.
    """

    accel_bias_ug: float | None = Field(None, ge=0.0, le=1e7, description="[µg]")
    accel_scale_ppm: float | None = Field(None, ge=0.0, le=1e6, description="[ppm]")
    accel_misalignment_urad: float | None = Field(None, ge=0.0, le=1e6, description="[µrad]")
    gyro_bias_dph: float | None = Field(None, ge=0.0, le=1e7, description="[°/h]")
    gyro_scale_ppm: float | None = Field(None, ge=0.0, le=1e6, description="[ppm]")
    gyro_misalignment_urad: float | None = Field(None, ge=0.0, le=1e6, description="[µrad]")
    gyro_g_sensitivity_dph_per_g: float | None = Field(None, ge=0.0, le=1e7,
                                                       description="[(°/h)/g]")
    gyro_arw_deg_rth: float | None = Field(None, ge=0.0, le=1e4, description="[°/√h]")
    accel_vrw_ug_rthz: float | None = Field(None, ge=0.0, le=1e7, description="[µg/√Hz]")


#: One non-negative coefficient per axis (x, y, z), SI.
_PER_AXIS = tuple[Annotated[float, Field(ge=0.0, le=1e3)],
                  Annotated[float, Field(ge=0.0, le=1e3)],
                  Annotated[float, Field(ge=0.0, le=1e3)]]


class ImuNoiseConfig(_Model):
    """The unit's declared noise: the fitted terms of its noise characterisation, per axis, SI.

    The terms of the overlapping Allan variance σ²(τ) = N²/τ + (2 ln 2/π)·B² + K²·τ/3 (IEEE
    Std 952-1997 Annex C; docs/noise.md §4) as the noise JSON ``imucalib allan`` writes gives
    them for its longest record (two-sided densities): white density N, bias instability B and
    random walk K, for the gyro and the accelerometer. The plan carries the values, so that it
    and the recording that copies it need no file later, and the file's name, record and
    SHA-256 for traceability (docs/test-design.md, "A noise characterisation in place of the
    grade's"). The prediction and the analysis's declared flicker floor take it instead of the
    grade's noise (docs/p1.md, "Noise model of the window means").
    """

    source: str = Field(min_length=1, max_length=255,
                        description="file name of the noise characterisation")
    source_sha256: str = Field(pattern=r"^[0-9a-f]{64}$",
                               description="SHA-256 (hex) of the file's bytes")
    record: str = Field("", max_length=200, description="label of the record read")
    record_duration_s: float = Field(0.0, ge=0.0, le=1e9,
                                     description="length of the record read [s]")
    gyro_white_rps_rthz: _PER_AXIS = Field(description="gyro N [rad/s/√Hz = rad/√s]")
    gyro_bias_instability_rps: _PER_AXIS = Field(description="gyro B [rad/s]")
    gyro_random_walk_rps_rts: _PER_AXIS = Field(description="gyro K [rad/s/√s]")
    accel_white_mps2_rthz: _PER_AXIS = Field(description="accelerometer N [m/s²/√Hz]")
    accel_bias_instability_mps2: _PER_AXIS = Field(description="accelerometer B [m/s²]")
    accel_random_walk_mps2_rts: _PER_AXIS = Field(description="accelerometer K [m/s²/√s]")


class ImuSpecConfig(_Model):
    """The IMU under test: identity, specification, held-out limits (docs/p1.md, "Acceptance").

    ``noise`` (optional, the ``[imu.noise]`` table): the unit's declared noise from its noise
    characterisation (:class:`ImuNoiseConfig`); without it the unit's grade's.
    """

    serial: str = Field("", max_length=100, description="serial number")
    model: str = Field("", max_length=200)
    maker: str = Field("", max_length=200)
    grade: Literal["consumer", "tactical", "navigation", ""] = ""
    accel_accuracy_g: float = Field(0.01, gt=0.0, le=100.0,
                                    description="held-out accuracy spec [g]")
    gyro_accuracy_dps: float = Field(0.5, gt=0.0, le=1000.0,
                                     description="held-out accuracy spec [°/s]")
    gyro_noise_dps: float | None = Field(None, gt=0.0, le=1000.0,
                                         description="gyro noise spec [°/s]")
    limits: SpecLimits = Field(default_factory=SpecLimits,
                               description="per-parameter limits (none: not checked)")
    noise: ImuNoiseConfig | None = Field(
        None, exclude_if=lambda value: value is None,  # a plan without it dumps as before
        description="the unit's declared noise from its noise characterisation (none: the "
                    "grade's)")


class AcceptanceConfig(_Model):
    """The decision rule (ISO/IEC Guide 98-4 §8; ILAC-G8:09/2019, docs/p1.md "Acceptance").

    ``simple``: a value passes when it is within its limit (the probability of a false accept
    can reach 50 % at the limit). ``guarded``: it passes only when |value| + k·u is within the
    limit (guard band w = k·u, u the standard uncertainty, misfit-scaled when the fit is a
    misfit), so a pass is a pass at about 97.7 % (k = 2) confidence; a value whose band
    straddles the limit fails.
    """

    rule: Literal["simple", "guarded"] = "simple"
    guard_band_k: float = Field(2.0, gt=0.0, le=10.0,
                                description="guard band in standard uncertainties")


class EquipmentConfig(_Model):
    """What the plan requires of the equipment (docs/p1.md, preparation).

    The analysis also uses these as Type B uncertainties (uniform, u = a/√3) of the quantities
    they limit: table angle errors tilt the reference gravity (accelerometer misalignments),
    a non-perpendicular axis pair tilts the reference rates (gyro misalignments).
    """

    table_position_accuracy_arcsec: float = Field(10.0, ge=0.0, le=3600.0, description="[″]")
    table_orthogonality_arcsec: float = Field(5.0, ge=0.0, le=3600.0, description="[″]")
    acquisition_rate_min_hz: float = Field(100.0, ge=MIN_SAMPLE_RATE_HZ, le=MAX_SAMPLE_RATE_HZ,
                                           description="[Hz]")


class _Step(_Model):
    label: str = Field("", max_length=200)
    role: str = Field("", max_length=128,
                      description="what the step is for in its procedure, e.g. "
                                  "p1.accel-position (procedures/<name>/roles.py); stored with "
                                  "the executed step")
    tags: tuple[Annotated[str, Field(max_length=64)], ...] = Field((), max_length=32)


class SoakStep(_Step):
    """Set the chamber, then wait until chamber and IMU temperatures are stable."""

    kind: Literal["soak"]
    temperature_degc: float = Field(ge=MIN_TEMPERATURE_DEGC, le=MAX_TEMPERATURE_DEGC,
                                    description="[°C]")
    ramp_degc_per_min: float | None = Field(None, ge=MIN_RAMP_DEGC_PER_MIN,
                                            le=MAX_RAMP_DEGC_PER_MIN,
                                            description="[°C/min]")
    band_degc: float = Field(0.5, gt=0.0, le=50.0,
                             description="chamber air within ± of the setpoint [°C]")
    imu_band_degc: float = Field(0.2, gt=0.0, le=50.0,
                                 description="IMU temperature span when stable [°C]")
    stable_for_s: float = Field(600.0, gt=0.0, le=MAX_WAIT_S, description="[s]")
    timeout_s: float = Field(7200.0, gt=0.0, le=MAX_WAIT_S, description="[s]")

    @model_validator(mode="after")
    def _reachable(self) -> SoakStep:
        if self.stable_for_s > self.timeout_s:
            raise ValueError(f"stable_for_s ({self.stable_for_s:g} s) exceeds timeout_s "
                             f"({self.timeout_s:g} s): the soak could never end")
        return self


class WarmUpStep(_Step):
    """Power-on warm-up: at least `duration_s`, and until the IMU output has stopped drifting."""

    kind: Literal["warm-up"]
    duration_s: float = Field(gt=0.0, le=MAX_WAIT_S, description="[s]")
    window_s: float = Field(60.0, gt=0.0, le=MAX_SETTLE_S,
                            description="window whose means are compared [s]")
    max_gyro_drift_dps: float = Field(0.01, gt=0.0, le=100.0,
                                      description="change of consecutive means [°/s]")
    max_accel_drift_g: float = Field(0.001, gt=0.0, le=10.0,
                                     description="change of consecutive means [g]")
    timeout_s: float = Field(7200.0, gt=0.0, le=MAX_WAIT_S, description="[s]")

    @model_validator(mode="after")
    def _reachable(self) -> WarmUpStep:
        if self.duration_s > self.timeout_s:
            raise ValueError(f"duration_s ({self.duration_s:g} s) exceeds timeout_s "
                             f"({self.timeout_s:g} s): the warm-up could never end")
        return self


class PositionStep(_Step):
    """Move the table to angles (one per axis), settle, record."""

    kind: Literal["position"]
    angles_deg: tuple[_ANGLE, ...] = Field(min_length=1, max_length=2, description="[°]")
    settle_s: float = Field(30.0, ge=0.0, le=MAX_SETTLE_S, description="[s]")
    record_s: float = Field(10.0, gt=0.0, le=MAX_RECORD_S, description="[s]")


class RateStep(_Step):
    """Spin one table axis at a rate, settle, record whole revolutions (or a duration)."""

    kind: Literal["rate"]
    axis: int = Field(0, ge=0, le=1)
    rate_dps: float = Field(ge=-MAX_TABLE_RATE_DPS, le=MAX_TABLE_RATE_DPS,
                            description="within limits.max_rate_dps [°/s]")
    settle_s: float = Field(20.0, ge=0.0, le=MAX_SETTLE_S, description="[s]")
    revolutions: int | None = Field(None, ge=1, le=MAX_REVOLUTIONS)
    record_s: float | None = Field(None, gt=0.0, le=MAX_RECORD_S, description="[s]")

    @model_validator(mode="after")
    def _length(self) -> RateStep:
        if self.revolutions is not None and self.rate_dps == 0.0:
            raise ValueError("`revolutions` needs a non-zero `rate_dps`; use `record_s` at 0 °/s")
        if (self.revolutions is None) == (self.record_s is None):
            raise ValueError("give exactly one of `revolutions` and `record_s`")
        check_record_length(self.revolutions, self.record_s, self.rate_dps)
        return self


class CentrifugeStep(_Step):
    """Spin the centrifuge (or position its arm at rest), settle, record."""

    kind: Literal["centrifuge"]
    rate_dps: float = Field(0.0, ge=-MAX_CENTRIFUGE_RATE_DPS, le=MAX_CENTRIFUGE_RATE_DPS,
                            description="within limits.max_centrifuge_rate_dps [°/s]")
    arm_position_deg: _ANGLE | None = Field(None, description="[°]")
    settle_s: float = Field(10.0, ge=0.0, le=MAX_SETTLE_S, description="[s]")
    revolutions: int | None = Field(None, ge=1, le=MAX_REVOLUTIONS)
    record_s: float | None = Field(None, gt=0.0, le=MAX_RECORD_S, description="[s]")

    @model_validator(mode="after")
    def _length(self) -> CentrifugeStep:
        if self.revolutions is not None and self.rate_dps == 0.0:
            raise ValueError("`revolutions` needs a non-zero `rate_dps`; use `record_s` at rest")
        if (self.revolutions is None) == (self.record_s is None):
            raise ValueError("give exactly one of `revolutions` and `record_s`")
        if self.arm_position_deg is not None and self.rate_dps != 0.0:
            raise ValueError("`arm_position_deg` positions the arm at rest; `rate_dps` must be 0")
        check_record_length(self.revolutions, self.record_s, self.rate_dps)
        return self


class StaticStep(_Step):
    """Record where the table is, nothing moving (the long static record of P1 step 2)."""

    kind: Literal["static"]
    duration_s: float = Field(gt=0.0, le=MAX_RECORD_S, description="[s]")


class OperatorCheckStep(_Step):
    """An item the operator confirms (mounting, alignment, remount); who and when are recorded.

    ``item`` is the operator's instruction. A remount check also says, in ``remount``, which
    fixture axis the operator places pointing up (along the table's spin axis), and in
    ``remount_yaw_deg`` the fixture's turn about the vertical after placing it
    (:mod:`imucalib.plan.fixture_poses`); a twin station puts its fixture in that pose once the
    check is confirmed, a real station relies on the operator having done it.

    A unit swap names, in ``swap_units``, the two units the operator exchanges on the fixture
    (each takes the other's place and orientation; P3's reversal of the references), and
    ``centrifuge_load_kg`` the test load on the centrifuge arm after the check (it sets the
    dynamic unbalance). A twin station applies both once the check is confirmed, like a remount.
    """

    kind: Literal["operator-check"]
    item: str = Field(min_length=1, max_length=500)
    remount: FixtureAxis | None = Field(
        None, description="fixture axis placed pointing up (along the table's spin axis)")
    remount_yaw_deg: float = Field(0.0, ge=-360.0, le=360.0,
                                   description="fixture's turn about the vertical [°]")
    swap_units: tuple[str, str] | None = Field(
        None, description="the two units the operator exchanges on the fixture (each takes the "
                          "other's place and orientation)")
    centrifuge_load_kg: float | None = Field(
        None, ge=0.0, le=1000.0, description="the test load on the centrifuge arm after this "
                                             "check [kg]")

    @model_validator(mode="after")
    def _remount(self) -> OperatorCheckStep:
        if self.remount is None and self.remount_yaw_deg != 0.0:
            raise ValueError(f"`remount_yaw_deg` ({self.remount_yaw_deg:g}) needs `remount` (the "
                             "fixture axis placed pointing up)")
        if self.swap_units is not None:
            a, b = self.swap_units
            if not a.strip() or not b.strip():
                raise ValueError("`swap_units` names two units; got an empty name")
            if a == b:
                raise ValueError(f"`swap_units` exchanges two different units; got {a!r} twice")
        return self


PlanStep = Annotated[
    SoakStep | WarmUpStep | PositionStep | RateStep | CentrifugeStep | StaticStep
    | OperatorCheckStep,
    Field(discriminator="kind"),
]


class Plan(_Model):
    """A test plan."""

    name: str = Field(min_length=1, max_length=200)
    description: str = Field("", max_length=2000)
    procedure: str = Field("", max_length=64, description="analysis that applies: p1, allan, …")
    imu: ImuSpecConfig = Field(default_factory=ImuSpecConfig)
    acceptance: AcceptanceConfig = Field(default_factory=AcceptanceConfig)
    limits: PlanLimits = Field(default_factory=PlanLimits)
    guards: GuardConfig = Field(default_factory=GuardConfig)
    equipment: EquipmentConfig = Field(default_factory=EquipmentConfig)
    twin: TwinEquipment | None = Field(
        None, description="the twin station to run this plan on with --station sim")
    steps: tuple[PlanStep, ...] = Field(min_length=1, max_length=MAX_STEPS)

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
        if self.twin is not None:
            problems = operator_check_problems(
                self.steps, [imu.name for imu in self.twin.imus], self.twin.centrifuge.enabled)
            if problems:
                raise ValueError(f"{problems[0]} (the plan's twin)")
        total = plan_min_duration_s(self)
        if total > MAX_TOTAL_S:
            raise ValueError(f"the steps take at least {total:.6g} s ({total / 86400:.3g} days); "
                             f"a plan may last at most {MAX_TOTAL_S:.0f} s (14 days)")
        return self

    def step_label(self, index: int) -> str:
        """Return the label of step `index`, or ``"<kind> <index>"`` when it has none."""
        step = self.steps[index]
        return step.label or f"{step.kind} {index}"


def operator_check_problems(steps: Sequence[PlanStep], unit_names: Sequence[str],
                            has_centrifuge: bool) -> list[str]:
    """Return what a station with these units cannot do of the steps' swaps and load changes.

    Parameters
    ----------
    steps : sequence of PlanStep
        The steps (only operator checks are looked at).
    unit_names : sequence of str
        The station's units.
    has_centrifuge : bool
        Whether the station has a centrifuge.

    Returns
    -------
    list of str
        One sentence per problem: a ``swap_units`` naming a unit the station lacks, a
        ``centrifuge_load_kg`` without a centrifuge; empty when all is well.
    """
    problems = []
    for i, step in enumerate(steps):
        if not isinstance(step, OperatorCheckStep):
            continue
        where = f"steps.{i} (operator-check{' ' + repr(step.label) if step.label else ''})"
        if step.swap_units is not None:
            unknown = [n for n in step.swap_units if n not in unit_names]
            if unknown:
                problems.append(f"{where}: swap_units names unit(s) {unknown} the station does "
                                f"not have; its units are {list(unit_names)}")
        if step.centrifuge_load_kg is not None and not has_centrifuge:
            problems.append(f"{where}: centrifuge_load_kg {step.centrifuge_load_kg:g} kg needs a "
                            "centrifuge; the station has none")
    return problems


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


def plan_min_duration_s(plan: Plan) -> float:
    """Return the least time the whole plan takes: the sum of :func:`step_min_duration_s`. [s]"""
    return sum(step_min_duration_s(step) for step in plan.steps)
