"""Read, write, hash and describe plan files.

Contents
--------
:func:`load_plan`, :func:`parse_plan`
    A TOML plan file (or text) → validated :class:`~imucalib.plan.schema.Plan`.
:func:`plan_to_toml`, :func:`write_plan`
    A plan → TOML text (round-trips through :func:`parse_plan`) / a file.
:func:`plan_hash`
    SHA-256 of a plan's canonical TOML, recorded with every run and result.
:func:`plan_json_schema`
    The JSON Schema of plan files, for editors.
:func:`describe_plan`, :class:`PlanRow`
    The expanded step list with the least duration of each step and in total.
"""

from __future__ import annotations

import hashlib
import json
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import tomli_w
from pydantic import ValidationError

from imucalib.errors import ConfigurationError
from imucalib.plan.bounds import format_validation_error
from imucalib.plan.schema import (
    CentrifugeStep,
    OperatorCheckStep,
    Plan,
    PlanStep,
    PositionStep,
    RateStep,
    SoakStep,
    StaticStep,
    WarmUpStep,
    step_min_duration_s,
)

__all__ = [
    "PlanRow",
    "describe_plan",
    "load_plan",
    "parse_plan",
    "plan_hash",
    "plan_json_schema",
    "plan_to_toml",
    "write_plan",
]


def parse_plan(text: str, source: str = "<text>") -> Plan:
    """Validate plan TOML text.

    Raises
    ------
    ConfigurationError
        If the text is not TOML or does not match the schema; one line per problem, naming the
        field path (``steps.3.rate.rate_dps: …``), what was expected and what was found.
    """
    try:
        data: dict[str, Any] = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigurationError(f"plan {source} is not valid TOML: {exc}") from exc
    try:
        return Plan.model_validate(data)
    except ValidationError as exc:
        raise ConfigurationError(format_validation_error(exc, source, "plan")) from exc


def load_plan(path: str | Path) -> Plan:
    """Read and validate a plan file (see :func:`parse_plan`)."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ConfigurationError(f"plan file {p} does not exist") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigurationError(f"cannot read plan file {p}: {exc}") from exc
    return parse_plan(text, str(p))


def _drop_none(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _drop_none(v) for k, v in value.items() if v is not None}
    if isinstance(value, list | tuple):
        return [_drop_none(v) for v in value]
    return value


def plan_to_toml(plan: Plan) -> str:
    """Return the plan as TOML text (``None`` fields omitted; defaults written out)."""
    return tomli_w.dumps(_drop_none(plan.model_dump(mode="json")))


def write_plan(plan: Plan, path: str | Path) -> Path:
    """Write `plan` to `path` as TOML and return the path."""
    p = Path(path)
    p.write_text(plan_to_toml(plan), encoding="utf-8")
    return p


def plan_hash(plan: Plan) -> str:
    """Return the SHA-256 (hex) of the plan's canonical TOML."""
    return hashlib.sha256(plan_to_toml(plan).encode("utf-8")).hexdigest()


def plan_json_schema() -> dict[str, Any]:
    """Return the JSON Schema (draft 2020-12) of plan files."""
    schema = Plan.model_json_schema()
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["title"] = "imucalib test plan"
    return json.loads(json.dumps(schema))


@dataclass(frozen=True)
class PlanRow:
    """One step of the expanded plan: what it does and the least time it takes."""

    index: int
    kind: str
    label: str
    what: str
    min_duration_s: float
    tags: tuple[str, ...]


def _what(step: PlanStep) -> str:
    if isinstance(step, SoakStep):
        ramp = "" if step.ramp_degc_per_min is None else f" at {step.ramp_degc_per_min:g} °C/min"
        return (f"chamber to {step.temperature_degc:g} °C{ramp}; stable ±{step.band_degc:g} °C "
                f"(IMU within {step.imu_band_degc:g} °C) for {step.stable_for_s:g} s")
    if isinstance(step, WarmUpStep):
        return f"warm up ≥{step.duration_s:g} s until the output stops drifting"
    if isinstance(step, PositionStep):
        angles = ", ".join(f"{a:g}°" for a in step.angles_deg)
        return f"table to ({angles}); settle {step.settle_s:g} s; record {step.record_s:g} s"
    if isinstance(step, RateStep):
        length = (f"{step.revolutions} rev" if step.revolutions is not None
                  else f"{step.record_s:g} s")
        return f"axis {step.axis} at {step.rate_dps:+g} °/s; settle {step.settle_s:g} s; {length}"
    if isinstance(step, CentrifugeStep):
        length = (f"{step.revolutions} rev" if step.revolutions is not None
                  else f"{step.record_s:g} s")
        if step.arm_position_deg is not None:
            return f"arm at rest to {step.arm_position_deg:g}°; record {length}"
        return f"centrifuge at {step.rate_dps:+g} °/s; settle {step.settle_s:g} s; {length}"
    if isinstance(step, StaticStep):
        return f"static record {step.duration_s:g} s"
    assert isinstance(step, OperatorCheckStep)
    extras = []
    if step.remount is not None:
        yaw = f", yaw {step.remount_yaw_deg:g}°" if step.remount_yaw_deg else ""
        extras.append(f"remount: {step.remount} up{yaw}")
    if step.swap_units is not None:
        extras.append(f"swap: {step.swap_units[0]} ↔ {step.swap_units[1]}")
    if step.centrifuge_load_kg is not None:
        extras.append(f"centrifuge load {step.centrifuge_load_kg:g} kg")
    return f"operator confirms: {step.item}" + (f" ({'; '.join(extras)})" if extras else "")


def describe_plan(plan: Plan) -> list[PlanRow]:
    """Return the expanded step list (the least duration excludes moves and stability waits)."""
    return [PlanRow(i, s.kind, plan.step_label(i), _what(s), step_min_duration_s(s), s.tags)
            for i, s in enumerate(plan.steps)]
