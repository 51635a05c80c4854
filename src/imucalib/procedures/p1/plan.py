"""The default plan of procedure P1 (two-dimensional calibration on a dual-axis table).

:func:`generate_p1_plan` writes procedure P1 (docs/p1.md) as a
:class:`~imucalib.plan.schema.Plan`: an operator check of the mounting, a warm-up, then
``repetitions`` complete calibrations, each with

1. the six static positions (pitch, roll) = (0, 0) Z up, (0, 180) Z down, (90, 0) X up,
   (−90, 0) X down, (0, 90) Y up, (0, 270) Y down; settle ≥30 s, record ≥10 s
   (tag ``"six-position"``). The procedure lists (90°, 180°) for X down, but by its own
   reference formula a_X = g·sin θ that position reads +g on X (rolling about the vertical X
   axis does not turn X over): X down needs pitch −90°;
2. the level static record for the gyro bias, 60 min by default (tag ``"gyro-bias"``);
3. the rate points about pitch and roll, both signs and 0, e.g. −100, −50, 0, +50, +100 °/s;
   settle ≥20 s; whole revolutions (tag ``"rate"``); and, by default, about pitch with roll at
   90°, which turns the IMU about Z. With the procedure's own positions ((90°, 0°) puts X up),
   pitch turns the IMU about its Y axis and roll about X; its text pairs pitch with the X gyro,
   which contradicts its position table, and we follow the geometry (docs/p1.md, "The plan");
4. held-out positions and rates for the accuracy verification (tag ``"verification"``),

every step also tagged ``"rep<k>"``. The steps the fit uses carry ``"calibration"``.

Each measuring step also has a role (:mod:`.roles`), stored with the executed
step so that the analysis needs no plan: ``"p1.accel-position"`` (the six positions),
``"p1.gyro-bias"`` (the level static record), ``"p1.gyro-rate"`` (calibration rates),
``"p1.held-out-position"`` and ``"p1.held-out-rate"`` (verification). The operator check, the
warm-up and the moves to a start position have none.

The plan carries a ``[twin]`` table describing a simulated station for it (a high-grade dual-axis
table and one IMU of the chosen grade), so that ``imucalib run PLAN --station sim`` runs it.
Given a noise characterisation of the unit, its ``[imu.noise]`` table carries the unit's declared
noise (docs/test-design.md, "A noise characterisation in place of the grade's").
"""

from __future__ import annotations

from collections.abc import Sequence

from imucalib.errors import ConfigurationError
from imucalib.plan.equipment import ImuConfig, SiteConfig, TableConfig, TwinEquipment
from imucalib.plan.schema import (
    AcceptanceConfig,
    GuardConfig,
    ImuSpecConfig,
    OperatorCheckStep,
    Plan,
    PlanLimits,
    PlanStep,
    PositionStep,
    RateStep,
    SpecLimits,
    StaticStep,
    WarmUpStep,
)
from imucalib.procedures.common.grade import characterization_config
from imucalib.procedures.p1.roles import (
    P1_ACCEL_POSITION,
    P1_GYRO_BIAS,
    P1_GYRO_RATE,
    P1_HELD_OUT_POSITION,
    P1_HELD_OUT_RATE,
)

__all__ = [
    "P1_HELD_OUT_POSITIONS_DEG",
    "P1_SIX_POSITIONS_DEG",
    "default_specification",
    "generate_p1_plan",
]

#: The six positions of P1 step 1 (docs/p1.md), (pitch, roll) [°], and which axis points up.
P1_SIX_POSITIONS_DEG: tuple[tuple[tuple[float, float], str], ...] = (
    ((0.0, 0.0), "Z up"), ((0.0, 180.0), "Z down"), ((90.0, 0.0), "X up"),
    ((-90.0, 0.0), "X down"), ((0.0, 90.0), "Y up"), ((0.0, 270.0), "Y down"),
)
#: Positions not used by the fit, for the accuracy check (pitch, roll) [°].
P1_HELD_OUT_POSITIONS_DEG: tuple[tuple[float, float], ...] = (
    (45.0, 0.0), (0.0, 45.0), (30.0, 120.0), (60.0, 225.0),
)
_WARM_UP_S = {"consumer": 900.0, "tactical": 1800.0, "navigation": 3600.0}
#: Held-out accuracy limits per grade (accelerometer [g], gyro [°/s]), docs/p1.md "Acceptance".
GRADE_ACCURACY: dict[str, tuple[float, float]] = {
    "consumer": (0.01, 0.5), "tactical": (1e-3, 0.05), "navigation": (1e-4, 0.005)}
#: A grade's parameter limits are this many one-sigma spreads of the grade (datasheet maxima).
SPEC_SPREADS = 4.0
#: Its noise limits are this many times the grade's typical white noise.
SPEC_NOISE_FACTOR = 2.0


def default_specification(grade: str, *, serial: str = "", model: str = "",
                          maker: str = "") -> ImuSpecConfig:
    """Return the specification P1 checks a unit of `grade` against when none is given.

    Parameter limits are :data:`SPEC_SPREADS` times the grade's one-sigma spreads
    (:data:`imucalib.models.imu.GRADES`, docs/equations.md §13): the maxima a datasheet of that
    grade states; noise limits :data:`SPEC_NOISE_FACTOR` times its typical white noise;
    held-out accuracy limits :data:`GRADE_ACCURACY`. A term the grade does not have (the
    g-sensitivity of optical gyros) is not checked. A real unit's own datasheet belongs in the
    plan's ``[imu.limits]`` instead (docs/p1.md, "Acceptance").

    Raises
    ------
    ConfigurationError
        For an unknown grade.
    """
    from imucalib.models.imu import GRADES

    if grade not in GRADES:
        raise ConfigurationError(f"`grade` must be one of {sorted(GRADES)}; got {grade!r}")
    g = GRADES[grade]
    k, n = SPEC_SPREADS, SPEC_NOISE_FACTOR

    def limit(spread: float, factor: float = 1.0) -> float | None:
        return k * spread * factor if spread > 0 else None

    limits = SpecLimits(
        accel_bias_ug=limit(g.accel_bias_ug), accel_scale_ppm=limit(g.accel_scale_ppm),
        accel_misalignment_urad=limit(g.accel_misalignment_mrad, 1000.0),
        gyro_bias_dph=limit(g.gyro_bias_dph), gyro_scale_ppm=limit(g.gyro_scale_ppm),
        gyro_misalignment_urad=limit(g.gyro_misalignment_mrad, 1000.0),
        gyro_g_sensitivity_dph_per_g=limit(g.gyro_g_sensitivity_dph_per_g),
        gyro_arw_deg_rth=n * g.gyro_arw_deg_rth, accel_vrw_ug_rthz=n * g.accel_vrw_ug_rthz)
    accel_g, gyro_dps = GRADE_ACCURACY[grade]
    return ImuSpecConfig(serial=serial, model=model, maker=maker,
                         grade=grade,
                         accel_accuracy_g=accel_g, gyro_accuracy_dps=gyro_dps, limits=limits)


def _repetition_parts(tag: str, *, rates_dps: Sequence[float],
                      held_out_rates_dps: Sequence[float], revolutions: int,
                      held_out_revolutions: int, static_s: float, settle_s: float,
                      record_s: float, held_out_record_s: float, rate_settle_s: float,
                      z_rates: bool) -> list[list[PlanStep]]:
    """Return one repetition's four parts, in the procedure's order (module docstring).

    The six positions; the level static record (with the move to level before it); the rate
    points of each axis (each group after its start position); the held-out positions.
    """
    six: list[PlanStep] = [
        PositionStep(kind="position", angles_deg=(pitch, roll), settle_s=settle_s,
                     record_s=record_s, label=f"{tag} {up} (pitch {pitch:g}, roll {roll:g})",
                     role=P1_ACCEL_POSITION, tags=("calibration", "six-position", tag))
        for (pitch, roll), up in P1_SIX_POSITIONS_DEG]
    static: list[PlanStep] = [
        PositionStep(kind="position", angles_deg=(0.0, 0.0), settle_s=settle_s, record_s=1.0,
                     label=f"{tag} level for the static record", tags=(tag,)),
        StaticStep(kind="static", duration_s=static_s, label=f"{tag} level static (gyro bias)",
                   role=P1_GYRO_BIAS, tags=("calibration", "gyro-bias", tag))]
    rates: list[PlanStep] = []
    groups = [(0, 0.0, "pitch (Y)"), (1, 0.0, "roll (X)")]
    if z_rates:
        groups.append((0, 90.0, "pitch at roll 90° (Z)"))
    for axis, roll_deg, group in groups:
        rates.append(PositionStep(kind="position", angles_deg=(0.0, roll_deg), settle_s=5.0,
                                  record_s=1.0, label=f"{tag} start of {group} rates",
                                  tags=(tag,)))
        for rate, use in [*((r, "calibration") for r in rates_dps),
                          *((r, "verification") for r in held_out_rates_dps)]:
            turns = revolutions if use == "calibration" else held_out_revolutions
            length: dict[str, float | int] = ({"record_s": record_s} if rate == 0.0
                                              else {"revolutions": turns})
            rates.append(RateStep(kind="rate", axis=axis, rate_dps=rate, settle_s=rate_settle_s,
                                  label=f"{tag} {group} {rate:+g} °/s",
                                  role=(P1_GYRO_RATE if use == "calibration"
                                        else P1_HELD_OUT_RATE),
                                  tags=(use, "rate", tag), **length))
    held_out: list[PlanStep] = [
        PositionStep(kind="position", angles_deg=(pitch, roll), settle_s=settle_s,
                     record_s=held_out_record_s,
                     label=f"{tag} held-out (pitch {pitch:g}, roll {roll:g})",
                     role=P1_HELD_OUT_POSITION, tags=("verification", "position", tag))
        for pitch, roll in P1_HELD_OUT_POSITIONS_DEG]
    return [six, static, rates, held_out]


def generate_p1_plan(
    *,
    name: str = "p1-dual-axis",
    grade: str = "tactical",
    rates_dps: Sequence[float] = (-100.0, -50.0, 0.0, 50.0, 100.0),
    held_out_rates_dps: Sequence[float] = (-75.0, 25.0),
    revolutions: int = 3,
    held_out_revolutions: int | None = None,
    static_s: float = 3600.0,
    settle_s: float = 30.0,
    record_s: float = 10.0,
    held_out_record_s: float | None = None,
    rate_settle_s: float = 20.0,
    repetitions: int = 3,
    reverse_last: bool = False,
    z_rates: bool = True,
    warm_up_s: float | None = None,
    sample_rate_hz: float = 1000.0,
    latitude_deg: float = 45.0,
    heading_deg: float = 0.0,
    seed: int = 1,
    serial: str = "",
    model: str = "",
    maker: str = "",
    acceptance: str = "simple",
    noise_characterization: str = "",
) -> Plan:
    """Return the default P1 plan.

    Parameters
    ----------
    name : str
        Plan name (the recording's file name starts with it).
    grade : {"consumer", "tactical", "navigation"}
        The IMU's grade: the twin's IMU and the warm-up time (10–20 min consumer, 30–60 min
        navigation; docs/p1.md, preparation).
    rates_dps : sequence of float
        Rate points per axis (docs/p1.md, step 3: 5–7 points, both signs and 0). [°/s]
    held_out_rates_dps : sequence of float
        Rate points per axis kept out of the fit for verification. [°/s]
    revolutions : int
        Whole turns recorded at each non-zero calibration rate.
    held_out_revolutions : int, optional
        Whole turns at each non-zero held-out rate; `revolutions` when omitted. The held-out
        check (docs/p1.md, rule 7) compares the compensated rate with the accuracy limit, far
        above a window's noise, so an optimised plan keeps the default plan's verification
        (docs/test-design.md, "The optimiser (P1)") instead of lengthening it with the
        calibration windows.
    static_s : float
        Level static record for the gyro bias (docs/p1.md, step 2: ≥60 min). [s]
    settle_s, record_s : float
        Settling and recording time at each position (≥30 s, ≥10 s). [s]
    held_out_record_s : float, optional
        Record at each held-out position; `record_s` when omitted (as `held_out_revolutions`).
        [s]
    rate_settle_s : float
        Settling time at each rate (≥20 s). [s]
    repetitions : int
        Complete calibrations (docs/p1.md, rule 6: three, for the repeatability check).
    reverse_last : bool
        Run the last repetition's four parts in reverse order: held-out positions, rate
        points, level static, six positions. Every step is kept; the six positions then close
        the run, so the accelerometer's windows span the whole session, which lowers the
        biases' σ under flicker noise (docs/test-design.md, "The optimiser (P1)"). The
        procedure's order (False) by default.
    z_rates : bool
        Add rate points about the pitch axis with the roll axis at 90°, which turns the IMU
        about its Z axis. Procedure P1 is two-dimensional (rates about pitch and roll only);
        without them the Z gyro's scale factor and its Z-input misalignments are unobservable.
    warm_up_s : float, optional
        Warm-up duration; the grade's default when omitted. [s]
    sample_rate_hz : float
        The twin IMU's output data rate (≥100 Hz). [Hz]
    latitude_deg, heading_deg : float
        Site of the twin station. [°]
    seed : int
        Seed of the twin (the IMU's truth and noise).
    serial, model, maker : str
        The unit's identity, carried into the result.
    acceptance : {"simple", "guarded"}
        The decision rule (:class:`~imucalib.plan.schema.AcceptanceConfig`, guard band 2u).
    noise_characterization : str
        Path of a noise characterisation of the unit (the noise JSON ``imucalib allan``
        writes); its fitted N, B and K per axis, with the file's name and SHA-256, become the
        plan's ``[imu.noise]``
        (:func:`~imucalib.procedures.common.grade.characterization_config`), the noise the
        prediction and the analysis's declared flicker floor take instead of the grade's
        (docs/p1.md, "Noise model of the window means"). Empty: none, the grade's.

    The unit's specification is the grade's (:func:`default_specification`); edit the plan's
    ``[imu]`` and ``[imu.limits]`` for a unit's own datasheet.

    Raises
    ------
    ConfigurationError
        For fewer than 3 rate points or no zero rate, fewer than 1 repetition, a held-out record
        ≤ 0 s or fewer than 1 held-out revolution, or a rate plan that P1's minimums
        (docs/p1.md) reject.
    InvalidInputError
        A noise characterisation that cannot be read (one line naming the file).
    """
    if grade not in _WARM_UP_S:
        raise ConfigurationError(f"`grade` must be one of {sorted(_WARM_UP_S)}; got {grade!r}")
    if acceptance not in ("simple", "guarded"):
        raise ConfigurationError(f"`acceptance` must be 'simple' or 'guarded'; got "
                                 f"{acceptance!r}")
    if len(rates_dps) < 3 or 0.0 not in rates_dps or not any(r < 0 for r in rates_dps) \
            or not any(r > 0 for r in rates_dps):
        raise ConfigurationError(
            f"`rates_dps` needs at least 3 points with both signs and 0 (procedure P1, docs/p1.md "
            f"step 3, uses 5–7); got {list(rates_dps)}")
    if repetitions < 1:
        raise ConfigurationError(f"`repetitions` must be ≥ 1; got {repetitions}")
    held_out_turns = revolutions if held_out_revolutions is None else held_out_revolutions
    held_out_record = record_s if held_out_record_s is None else held_out_record_s
    if held_out_record_s is not None and not held_out_record_s > 0:
        raise ConfigurationError(f"`held_out_record_s` must be > 0 s; got {held_out_record_s:g}")
    if held_out_turns < 1:
        raise ConfigurationError(f"`held_out_revolutions` must be ≥ 1; got {held_out_turns}")
    steps: list[PlanStep] = [
        OperatorCheckStep(kind="operator-check", label="mounting",
                          item="IMU mounted: X parallel to the roll axis, Z up when level, "
                               "axis parallelism ≤5″; cables strain-relieved"),
        WarmUpStep(kind="warm-up", label="warm-up",
                   duration_s=_WARM_UP_S[grade] if warm_up_s is None else warm_up_s,
                   window_s=60.0),
    ]
    for rep in range(1, repetitions + 1):
        parts = _repetition_parts(
            f"rep{rep}", rates_dps=rates_dps, held_out_rates_dps=held_out_rates_dps,
            revolutions=revolutions, held_out_revolutions=held_out_turns, static_s=static_s,
            settle_s=settle_s, record_s=record_s, held_out_record_s=held_out_record,
            rate_settle_s=rate_settle_s, z_rates=z_rates)
        if reverse_last and rep == repetitions:
            parts = parts[::-1]
        for part in parts:
            steps += part
    imu = default_specification(grade, serial=serial, model=model, maker=maker)
    if noise_characterization:
        imu = imu.model_copy(update={"noise": characterization_config(noise_characterization)})
    max_rate = max(abs(r) for r in (*rates_dps, *held_out_rates_dps))
    twin = TwinEquipment(
        seed=seed,
        site=SiteConfig(latitude_deg=latitude_deg, heading_deg=heading_deg),
        table=TableConfig(kind="dual-axis", grade="high"),
        imus=(ImuConfig(name=serial or "IMU-0001", grade=grade, sample_rate_hz=sample_rate_hz),),
    )
    return Plan(
        name=name,
        description=f"P1 (docs/p1.md) on a dual-axis table: six positions, {static_s / 60:g} min "
                    f"static, {len(rates_dps)} rates per axis, held-out checks, "
                    f"{repetitions} repetition(s).",
        procedure="p1",
        imu=imu,
        acceptance=AcceptanceConfig(rule=acceptance),
        limits=PlanLimits(max_rate_dps=max(300.0, 1.2 * max_rate)),
        guards=GuardConfig(),
        twin=twin,
        steps=tuple(steps),
    )
