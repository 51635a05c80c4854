"""P2's plan options (:func:`~imucalib.procedures.p2.plan.generate_p2_plan`).

Each field is one keyword of the generator with its help, unit, range and help section
(:func:`~imucalib.procedures.common.options.option`); ``imucalib plan new p2`` builds its
flags from them (docs/plugins.md).

:class:`P2AnalysisOptions` holds, the same way, the keys
:func:`~imucalib.procedures.p2.batch.analyze_p2` takes as ``options``; ``imucalib calibrate`` reads
them with ``--set NAME=VALUE``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from imucalib.plan.bounds import (
    MAX_IMUS,
    MAX_RAMP_DEGC_PER_MIN,
    MAX_RECORD_S,
    MAX_REVOLUTIONS,
    MAX_TABLE_RATE_DPS,
    MAX_TEMPERATURE_DEGC,
    MAX_WAIT_S,
    MIN_RAMP_DEGC_PER_MIN,
    MIN_TEMPERATURE_DEGC,
)
from imucalib.plan.schema import TwinEquipment
from imucalib.procedures.common.option_fields import (
    Grade,
    grade_field,
    plan_name_field,
    sample_rate_field,
    seed_field,
    settle_field,
    twin_field,
)
from imucalib.procedures.common.options import option
from imucalib.procedures.p2.plan import DEFAULT_HELD_OUT_DEGC, DEFAULT_TEMPERATURES_DEGC

__all__ = ["P2AnalysisOptions", "P2PlanOptions"]


@dataclass(frozen=True)
class P2PlanOptions:
    """Keywords of :func:`~imucalib.procedures.p2.plan.generate_p2_plan`."""

    temperatures_degc: tuple[float, ...] = option(
        DEFAULT_TEMPERATURES_DEGC, help="Calibration temperature points (at least two).",
        unit="°C", min=MIN_TEMPERATURE_DEGC, max=MAX_TEMPERATURE_DEGC, flag="temperatures")
    held_out_degc: tuple[float, ...] = option(
        DEFAULT_HELD_OUT_DEGC, help="Temperature points held out of the models, to check "
                                    "their predictions.", unit="°C",
        min=MIN_TEMPERATURE_DEGC, max=MAX_TEMPERATURE_DEGC, flag="held-out")
    hysteresis: bool = option(False, help="Visit the points heating then cooling (the models "
                                          "get a hysteresis term).")
    rate_dps: float = option(60.0, help="The turns' rate |ω| (each turn at +ω and −ω).",
                             unit="°/s", min=0.0, max=MAX_TABLE_RATE_DPS)
    revolutions: int = option(2, help="Whole revolutions recorded per turn.", min=1,
                              max=MAX_REVOLUTIONS)
    pose_order: Literal["temperature-major", "pose-major"] = option(
        "temperature-major", help="Six remounts at every temperature (temperature-major) or "
                                  "six temperature sweeps (pose-major).")
    ramp_degc_per_min: float = option(2.0, help="The chamber's ramp to each point.",
                                      unit="°C/min", min=MIN_RAMP_DEGC_PER_MIN,
                                      max=MAX_RAMP_DEGC_PER_MIN)
    band_degc: float = option(0.5, help="The chamber air's band around the setpoint for a "
                                        "soak to end.", unit="°C", min=0.0, max=50.0)
    imu_band_degc: float = option(0.2, help="The band every IMU's internal temperature must "
                                            "stay within for a soak to end.", unit="°C",
                                  min=0.0, max=50.0)
    start_degc: float = option(25.0, help="The chamber's temperature before the run (the "
                                          "first point's leg).", unit="°C",
                               min=MIN_TEMPERATURE_DEGC, max=MAX_TEMPERATURE_DEGC)
    static_s: float = option(10.0, help="Record length of each static window.", unit="s",
                             min=0.0, max=MAX_RECORD_S, group="timing")
    settle_s: float = settle_field(10.0)
    stable_for_s: float = option(900.0, help="How long the temperatures must stay stable to "
                                             "end a soak.", unit="s", min=0.0, max=MAX_WAIT_S,
                                 group="timing")
    resoak_s: float = option(120.0, help="The re-soak after each remount (the chamber was "
                                         "opened); 0: none.", unit="s", min=0.0, max=MAX_WAIT_S,
                             group="timing")
    soak_timeout_s: float = option(14400.0, help="Time-out of each soak.", unit="s", min=0.0,
                                   max=MAX_WAIT_S, group="timing")
    n_imus: int = option(8, help="Units on the cube (the twin's).", min=1, max=MAX_IMUS,
                         group="twin")
    grade: Grade = grade_field(
        "consumer",
        help="The units' grade (the twin's IMUs and the held-out accuracy limits).")
    sample_rate_hz: float = sample_rate_field(100.0)
    seed: int = seed_field(0)
    half_edge_m: float = option(0.06, help="Half edge of the twin's cube.", unit="m", min=0.0,
                                max=1.0, group="twin")
    twin: TwinEquipment | None = twin_field(
        help="Another twin station (its IMUs replace n_imus).")
    name: str = plan_name_field("p2-array-temperature")


@dataclass(frozen=True)
class P2AnalysisOptions:
    """The keys :func:`~.batch.analyze_p2` takes as ``options``.

    They are the procedure's ``analysis_options``; ``imucalib calibrate`` reads them with
    ``--set NAME=VALUE`` and shows them in ``calibrate NAME --help``.
    """

    lever_arm: Literal["estimate", "cancel", "ignore"] = option(
        "estimate", help="How the centripetal (lever-arm) term is treated.")
    max_order: int = option(3, help="The highest polynomial order of a temperature model.",
                            min=0, max=5)
    criterion: Literal["aicc", "cv"] = option(
        "aicc", help="How the order of a temperature model is chosen: AICc or cross-validation.")
    rate_term: bool = option(False, help="Add a dT/dt term to every temperature model.")
    hysteresis: Literal["auto", "on", "off"] = option(
        "auto", help="A heating/cooling term (auto: when each leg holds two calibration points "
                     "or more).")
    reference_temperature_degc: float = option(
        25.0, help="The temperature T0 of the models and of the result's values.", unit="°C")
    workers: int = option(1, help="Local processes the units are calibrated in (1: this one).",
                          min=1)
    scheduler: str | None = option(
        None, help="A Dask scheduler address (tcp://host:8786; from Python also a Client) to "
                   "run the units on instead of local processes (default: none).")
