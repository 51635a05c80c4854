"""Test plans: schema, validation, files, description.

Contents
--------
:mod:`imucalib.plan.schema`
    :class:`Plan` and its step kinds; P1's numbers as defaults.
:mod:`imucalib.plan.io`
    :func:`load_plan`, :func:`parse_plan`, :func:`plan_to_toml`, :func:`write_plan`,
    :func:`plan_hash`, :func:`plan_json_schema`, :func:`describe_plan`.
:mod:`imucalib.plan.budget`
    The size of a plan's (or a scenario's) recording before it runs,
    :func:`~imucalib.plan.budget.estimate_recording_bytes`, and the free-space check
    (imported on its own: it needs the Recording layouts).
"""

from __future__ import annotations

from imucalib.plan.io import (
    PlanRow,
    describe_plan,
    load_plan,
    parse_plan,
    plan_hash,
    plan_json_schema,
    plan_to_toml,
    write_plan,
)
from imucalib.plan.schema import (
    CentrifugeStep,
    EquipmentConfig,
    GuardConfig,
    ImuSpecConfig,
    OperatorCheckStep,
    Plan,
    PlanLimits,
    PlanStep,
    PositionStep,
    RateStep,
    SoakStep,
    StaticStep,
    WarmUpStep,
)

__all__ = [
    "CentrifugeStep",
    "EquipmentConfig",
    "GuardConfig",
    "ImuSpecConfig",
    "OperatorCheckStep",
    "Plan",
    "PlanLimits",
    "PlanRow",
    "PlanStep",
    "PositionStep",
    "RateStep",
    "SoakStep",
    "StaticStep",
    "WarmUpStep",
    "describe_plan",
    "load_plan",
    "parse_plan",
    "plan_hash",
    "plan_json_schema",
    "plan_to_toml",
    "write_plan",
]
