"""The default plan of the Allan procedure (IEEE 952 Annex C noise characterisation).

:func:`generate_allan_plan` writes: an operator check (the IMU static on an isolated base), a
warm-up, then for each temperature (or once at ambient) an optional chamber soak and a long
static record (kind ``"static"``, role ``"allan.static"``, tags ``"allan"`` and
``"T<temperature>"``). ``imucalib calibrate`` on its recording runs
:func:`~.analysis.analyze_allan_recording`:
OADEV with confidence intervals and the noise-term fit per axis, for each record.

The plan carries a ``[twin]`` table: one IMU on a fixed plate (in a chamber when temperatures
are given), so that ``imucalib run PLAN --station sim`` runs it.
"""

from __future__ import annotations

from collections.abc import Sequence

from imucalib.errors import ConfigurationError
from imucalib.plan.equipment import ChamberConfig, ImuConfig, SiteConfig, TwinEquipment
from imucalib.plan.schema import (
    ImuSpecConfig,
    OperatorCheckStep,
    Plan,
    PlanLimits,
    PlanStep,
    SoakStep,
    StaticStep,
    WarmUpStep,
)
from imucalib.procedures.allan.roles import ALLAN_STATIC

__all__ = ["generate_allan_plan"]

_WARM_UP_S = {"consumer": 900.0, "tactical": 1800.0, "navigation": 3600.0}


def generate_allan_plan(*, name: str = "allan", grade: str = "tactical",
                        record_s: float = 7200.0,
                        temperatures_degc: Sequence[float] | None = None,
                        soak_stable_s: float = 1800.0, warm_up_s: float | None = None,
                        sample_rate_hz: float = 1000.0, latitude_deg: float = 45.0,
                        seed: int = 1) -> Plan:
    """Return the default Allan-variance plan.

    Parameters
    ----------
    name : str
        Plan name.
    grade : {"consumer", "tactical", "navigation"}
        The IMU's grade: the twin's IMU and the default warm-up.
    record_s : float
        Length of each static record; the longest τ resolved is about a tenth of it. [s]
    temperatures_degc : sequence of float, optional
        Record once at each temperature, after a chamber soak; None: once, at ambient. [°C]
    soak_stable_s : float
        How long chamber and IMU temperatures must stay stable before a record. [s]
    warm_up_s : float, optional
        Warm-up duration; the grade's default (15/30/60 min) when omitted. [s]
    sample_rate_hz : float
        The twin IMU's output data rate. [Hz]
    latitude_deg : float
        Site of the twin station. [°]
    seed : int
        Seed of the twin.

    Raises
    ------
    ConfigurationError
        For an unknown grade, or a record shorter than 10 minutes (too short for any bias
        instability reading).
    """
    if grade not in _WARM_UP_S:
        raise ConfigurationError(f"`grade` must be one of {sorted(_WARM_UP_S)}; got {grade!r}")
    if record_s < 600.0:
        raise ConfigurationError(f"`record_s` must be at least 600 s for an Allan record (its "
                                 f"longest τ is about a tenth of it); got {record_s:g} s")
    steps: list[PlanStep] = [
        OperatorCheckStep(kind="operator-check", label="mounting",
                          item="IMU fixed on an isolated, level base; cables strain-relieved; "
                               "no vibration sources running"),
        WarmUpStep(kind="warm-up", label="warm-up",
                   duration_s=_WARM_UP_S[grade] if warm_up_s is None else warm_up_s),
    ]
    temps = list(temperatures_degc) if temperatures_degc is not None else [None]
    for temp in temps:
        tag = "ambient" if temp is None else f"T{temp:+g}"
        if temp is not None:
            steps.append(SoakStep(kind="soak", temperature_degc=float(temp),
                                  stable_for_s=soak_stable_s, timeout_s=4 * 3600.0,
                                  label=f"soak {temp:+g} °C", tags=(tag,)))
        steps.append(StaticStep(kind="static", duration_s=record_s,
                                label=f"static record ({tag})", role=ALLAN_STATIC,
                                tags=("allan", tag)))
    twin = TwinEquipment(
        seed=seed, site=SiteConfig(latitude_deg=latitude_deg),
        chamber=ChamberConfig(enabled=temperatures_degc is not None,
                              initial_temperature_degc=20.0),
        imus=(ImuConfig(name="IMU-0001", grade=grade,
                        sample_rate_hz=sample_rate_hz),),
    )
    return Plan(name=name,
                description=f"Allan variance (IEEE 952 Annex C): {len(temps)} static record(s) "
                            f"of {record_s / 3600:g} h",
                procedure="allan", imu=ImuSpecConfig(grade=grade),
                limits=PlanLimits(), twin=twin, steps=tuple(steps))
