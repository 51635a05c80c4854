"""The plan of procedure P3: K2 of an accelerometer on a centrifuge, the unbalance measured.

:func:`generate_p3_plan` writes P3 (docs/p3.md, "The plan") as a
:class:`~imucalib.plan.schema.Plan`:

1. an operator check of the mounting: reference accelerometers A and B at `reference_radius_m`
   (r_t/3 by default) on opposite sides of the spin axis, A on the test side, their input
   axes radial and pointing inward (they read +ω²r); the check's tags name the units
   (``ref-a=``, ``ref-b=``, ``test=``);
2. with ``tumble=True``, the 1 g tumble of every accelerometer: the operator turns the arm
   fixture so that the input axes point up, then down (remount checks ``+x`` and ``-x`` up),
   a record at rest in each, and back (``+z`` up) — K1 and K0 from ±1 g;
3. three configurations (tag ``config=<k>``), each: rest records at the four arm positions
   (0°, 90°, 180°, 270°: their mean cancels the gravity a tilted spin axis leaks into the
   radial input), the rates in ascending order, each over whole revolutions, and the four rest
   records again (a drift between them shows in the fit's χ²):

   - config 1: A on the test side, no test load;
   - an operator check swapping A and B (``swap_units``), config 2;
   - an operator check putting A and B back and mounting the test accelerometer with its load
     (``swap_units`` and ``centrifuge_load_kg``), config 3.

The rates: `n_rates` points (≥ 4) whose specific force at the test radius is equally spaced
up to `test_range_g` (20 g by default): ω_i = √(a_i/r_t), a_i = i·a_max/n. With
``both_directions=True`` each rate is also run negative (the Earth-rate Coriolis term changes
sign; the analysis models it either way).

Every step has a role (:mod:`.roles`: ``p3.mount``, ``p3.tumble``,
``p3.rest``, ``p3.rate``, ``p3.swap``, ``p3.load``).

The plan carries a ``[twin]`` table: a centrifuge of static radius r_t whose rotor centre
moves by `unbalance_um` at the top rate with the test load (half of it without: c and c′
differ), the arm fixture (``FixtureConfig(kind="arm")``) with units REF-A at +r_r, REF-B at
−r_r and TEST at +r_t, each a navigation-grade unit whose x accelerometer is the instrument
(its gyro range widened to the top rate: the twin's units are IMUs, a real station's are
single accelerometers).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from imucalib import units
from imucalib.errors import ConfigurationError
from imucalib.plan.equipment import (
    CentrifugeConfig,
    FixtureConfig,
    ImuConfig,
    SiteConfig,
    TwinEquipment,
)
from imucalib.plan.schema import (
    CentrifugeStep,
    GuardConfig,
    ImuSpecConfig,
    OperatorCheckStep,
    Plan,
    PlanLimits,
    PlanStep,
)
from imucalib.procedures.p3.roles import P3_LOAD, P3_MOUNT, P3_RATE, P3_REST, P3_SWAP, P3_TUMBLE

__all__ = ["ARM_POSITIONS_DEG", "UNIT_NAMES", "generate_p3_plan", "p3_rates_dps"]

#: The four arm positions at rest [°].
ARM_POSITIONS_DEG: tuple[float, ...] = (0.0, 90.0, 180.0, 270.0)
#: The units of the generated plan: reference A, reference B, the test accelerometer.
UNIT_NAMES: dict[str, str] = {"ref-a": "REF-A", "ref-b": "REF-B", "test": "TEST"}
#: Fewest rate points: the ω² and ω⁴ coefficients and two degrees of freedom (docs/p3.md).
MIN_RATES = 4


def p3_rates_dps(static_radius_m: float, test_range_g: float, n_rates: int) -> list[float]:
    """Return the rates [°/s] whose specific force at r_t is i·a_max/n, i = 1 … n.

    Raises
    ------
    ConfigurationError
        Fewer than :data:`MIN_RATES` rates, a radius or range not positive.
    """
    if n_rates < MIN_RATES:
        raise ConfigurationError(f"P3 needs at least {MIN_RATES} rate points (the ω² and ω⁴ "
                                 f"coefficients and two degrees of freedom); got {n_rates}")
    if not (static_radius_m > 0 and test_range_g > 0):
        raise ConfigurationError(f"`static_radius_m` and `test_range_g` must be positive; got "
                                 f"{static_radius_m!r}, {test_range_g!r}")
    top = test_range_g * units.G0_MPS2
    return [math.sqrt(top * i / n_rates / static_radius_m) / units.DEG
            for i in range(1, n_rates + 1)]


def _twin(static_radius_m: float, reference_radius_m: float, top_rate_dps: float,
          unbalance_um: float, test_load_kg: float, grade: str, sample_rate_hz: float,
          seed: int) -> TwinEquipment:
    w2 = (top_rate_dps * units.DEG) ** 2
    c_loaded = unbalance_um * 1e-6 / w2
    per_kg = 0.5 * c_loaded / test_load_kg if test_load_kg > 0 else 0.0
    names = UNIT_NAMES
    return TwinEquipment(
        seed=seed,
        site=SiteConfig(latitude_deg=45.0),
        centrifuge=CentrifugeConfig(
            enabled=True, static_radius_m=static_radius_m,
            unbalance_c0_m_per_rps_sq=c_loaded - per_kg * test_load_kg,
            unbalance_c_m_per_rps_sq_per_kg=per_kg, load_kg=0.0,
            max_rate_dps=min(1.25 * top_rate_dps, 10_000.0),
            imbalance_alarm_um=max(200.0, 4.0 * unbalance_um)),
        fixture=FixtureConfig(kind="arm", arm_radii_m=(reference_radius_m, -reference_radius_m,
                                                       static_radius_m)),
        imus=tuple(ImuConfig(name=names[role], grade=grade, sample_rate_hz=sample_rate_hz,
                             gyro_range_dps=max(1.5 * top_rate_dps, 2000.0))
                   for role in ("ref-a", "ref-b", "test")),
    )


def generate_p3_plan(
    *,
    static_radius_m: float = 1.0,
    reference_radius_m: float | None = None,
    test_range_g: float = 20.0,
    n_rates: int = 5,
    rates_dps: Sequence[float] | None = None,
    both_directions: bool = False,
    rate_record_s: float = 60.0,
    rest_record_s: float = 30.0,
    settle_s: float = 20.0,
    arm_positions_deg: Sequence[float] = ARM_POSITIONS_DEG,
    test_load_kg: float = 2.0,
    tumble: bool = True,
    tumble_record_s: float = 30.0,
    unbalance_um: float = 10.0,
    grade: str = "navigation",
    sample_rate_hz: float = 100.0,
    seed: int = 0,
    twin: TwinEquipment | None = None,
    name: str = "p3-centrifuge-k2",
) -> Plan:
    """Return procedure P3's plan (module docstring).

    Parameters
    ----------
    static_radius_m : float
        Static radius r_t of the test position. [m]
    reference_radius_m : float, optional
        Radius of the references (default r_t/3, the method's). [m]
    test_range_g : float
        Specific force at r_t at the top rate. [g]
    n_rates : int
        Rate points (≥ 4), equally spaced in specific force.
    rates_dps : sequence of float, optional
        Explicit rates instead (positive, ≥ 4 distinct). [°/s]
    both_directions : bool
        Run every rate at +ω and −ω.
    rate_record_s, rest_record_s, tumble_record_s : float
        Record lengths: at least this long at each rate (whole revolutions), at each arm
        position, in each tumble pose. [s]
    settle_s : float
        Settling before each record (a rate step's ramp included). [s]
    arm_positions_deg : sequence of float
        The arm positions at rest (four, 90° apart by default). [°]
    test_load_kg : float
        The test load mounted for configuration 3 (the twin's c′ grows with it). [kg]
    tumble : bool
        Record the 1 g tumble (K1, K0 of each accelerometer); without it the analysis needs
        them as inputs.
    unbalance_um : float
        The twin's rotor-centre shift at the top rate with the test load. [µm]
    grade, sample_rate_hz, seed :
        The twin's units.
    twin : TwinEquipment, optional
        Another twin station (its unit names must be REF-A, REF-B and TEST, or the analysis
        is told the names).
    name : str
        The plan's name.

    Raises
    ------
    ConfigurationError
        Options out of range (fewer than 4 rates, a rate beyond 10 000 °/s, radii not
        positive, fewer than 2 arm positions).
    """
    if not static_radius_m > 0:
        raise ConfigurationError(f"`static_radius_m` must be positive; got {static_radius_m!r}")
    r_ref = static_radius_m / 3.0 if reference_radius_m is None else float(reference_radius_m)
    if not 0 < r_ref < static_radius_m:
        raise ConfigurationError(f"`reference_radius_m` must lie between 0 and the test radius "
                                 f"{static_radius_m:g} m; got {r_ref!r}")
    if rates_dps is None:
        rates = p3_rates_dps(static_radius_m, test_range_g, n_rates)
    else:
        rates = sorted({abs(float(r)) for r in rates_dps})
        if len(rates) < MIN_RATES or rates[0] <= 0:
            raise ConfigurationError(f"`rates_dps` must hold at least {MIN_RATES} distinct "
                                     f"positive rates; got {list(rates_dps)}")
    top = max(rates)
    if top > 10_000.0:
        raise ConfigurationError(f"the top rate {top:.6g} °/s exceeds a centrifuge's 10 000 °/s "
                                 "(a smaller test range or a larger radius)")
    arm = [float(a) for a in arm_positions_deg]
    spread = abs(sum(complex(math.cos(math.radians(a)), math.sin(math.radians(a)))
                     for a in arm) / max(len(arm), 1))
    if len(arm) < 2 or len(set(arm)) != len(arm) or spread > 0.01:
        raise ConfigurationError(f"`arm_positions_deg` must hold distinct positions spread "
                                 f"evenly around the circle (their mean cancels a tilted spin "
                                 f"axis' gravity leak: |mean e^(iφ)| ≤ 0.01); got {arm}")
    if min(rate_record_s, rest_record_s, tumble_record_s) <= 0 or settle_s < 0:
        raise ConfigurationError("record lengths must be positive and `settle_s` ≥ 0")
    if not 0 <= test_load_kg <= 1000:
        raise ConfigurationError(f"`test_load_kg` must be 0 … 1000; got {test_load_kg!r}")
    equipment = twin if twin is not None else _twin(
        static_radius_m, r_ref, top, unbalance_um, test_load_kg, grade, sample_rate_hz, seed)
    a, b, t = UNIT_NAMES["ref-a"], UNIT_NAMES["ref-b"], UNIT_NAMES["test"]
    steps: list[PlanStep] = [OperatorCheckStep(
        kind="operator-check", role=P3_MOUNT,
        tags=(f"ref-a={a}", f"ref-b={b}", f"test={t}"),
        item=(f"reference {a} at +{r_ref:g} m (the test side) and {b} at −{r_ref:g} m, input "
              "axes radial and pointing towards the spin axis; counterweights set; no test "
              "load"),
        label="mount the references")]
    if tumble:
        for pose, what in (("+x", "up"), ("-x", "down")):
            steps.append(OperatorCheckStep(
                kind="operator-check", role=P3_MOUNT, remount=pose,
                item=f"turn the arm fixture so that the fixture's {pose} axis points up "
                     "(the input axes vertical)", label=f"tumble: fixture {pose} up"))
            steps.append(CentrifugeStep(
                kind="centrifuge", rate_dps=0.0, arm_position_deg=0.0, settle_s=5.0,
                record_s=tumble_record_s, role=P3_TUMBLE, tags=(f"pose={pose}",),
                label=f"tumble {pose} up ({what})"))
        steps.append(OperatorCheckStep(
            kind="operator-check", role=P3_MOUNT, remount="+z",
            item="turn the arm fixture back: input axes radial, pointing towards the spin axis",
            label="tumble done: fixture +z up"))

    def configuration(k: int) -> list[PlanStep]:
        tag = f"config={k}"

        def rest(phase: str) -> list[PlanStep]:
            return [CentrifugeStep(kind="centrifuge", rate_dps=0.0, arm_position_deg=pos,
                                   settle_s=5.0, record_s=rest_record_s, role=P3_REST,
                                   tags=(tag, f"arm={pos:g}", f"phase={phase}"),
                                   label=f"config {k}: rest at {pos:g}° ({phase})")
                    for pos in arm]

        out = rest("before")
        for rate in rates:
            for sign in ((1.0, -1.0) if both_directions else (1.0,)):
                revs = max(1, math.ceil(rate_record_s * rate / 360.0))
                out.append(CentrifugeStep(kind="centrifuge", rate_dps=sign * rate,
                                          settle_s=settle_s, revolutions=revs, role=P3_RATE,
                                          tags=(tag,),
                                          label=f"config {k}: {sign * rate:+.6g} °/s"))
        return out + rest("after")

    steps += configuration(1)
    steps.append(OperatorCheckStep(
        kind="operator-check", role=P3_SWAP, swap_units=(a, b), tags=("config=2",),
        item=f"exchange the references: {a} to −{r_ref:g} m, {b} to +{r_ref:g} m (input axes "
             "inward)", label="swap A and B"))
    steps += configuration(2)
    steps.append(OperatorCheckStep(
        kind="operator-check", role=P3_LOAD, swap_units=(a, b),
        centrifuge_load_kg=test_load_kg, tags=("config=3",),
        item=f"put {a} back at +{r_ref:g} m and {b} at −{r_ref:g} m; mount the test "
             f"accelerometer {t} at +{static_radius_m:g} m (input axis inward) with its load "
             f"({test_load_kg:g} kg in all); counterweights as for the test",
        label="mount the test load"))
    steps += configuration(3)
    return Plan(
        name=name,
        description=("P3 (docs/p3.md): K2 of an accelerometer on a precision centrifuge, the "
                     "dynamic unbalance measured by two reference accelerometers in a "
                     "round-robin (swapped, then with the test load)."),
        procedure="p3",
        imu=ImuSpecConfig(grade=grade),
        # the twin centrifuge accelerates at up to 90 °/s²
        limits=PlanLimits(max_centrifuge_rate_dps=min(1.1 * top, 10_000.0), max_accel_dps2=90.0),
        guards=GuardConfig(rate_tolerance_dps=max(0.5, 1e-3 * top)),
        twin=equipment,
        steps=tuple(steps),
    )
