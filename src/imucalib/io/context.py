"""What a recording says about its calibration, read in one place: :class:`RecordingContext`.

A station run writes, besides the plan it ran (``plan_toml``, kept as provenance), the facts
an analysis, a report or the records need as metadata keys of their own (docs/recording-format.md):
the ``procedure``, the ``plan_name`` and ``plan_hash``, the equipment accuracies
(``equipment_json``), the IMU's specification (``imu_spec_json``) and the decision rule
(``acceptance``); an import from a CSV and its step file writes the same keys. A recording made
before the runner wrote them (format v2 of an earlier version) has them only inside its stored
plan: :meth:`RecordingContext.of` then reads that TOML as plain data. Nothing else parses the
stored plan for these facts.

Contents
--------
:class:`RecordingContext`
"""

from __future__ import annotations

import json
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

__all__ = ["RecordingContext"]

#: The equipment accuracies a calibration uses (plan table ``[equipment]``).
EQUIPMENT_KEYS = ("table_position_accuracy_arcsec", "table_orthogonality_arcsec")
#: The IMU specification a calibration checks against (plan table ``[imu]``).
IMU_SPEC_KEYS = ("accel_accuracy_g", "gyro_accuracy_dps", "gyro_noise_dps")


def _numbers(table: Any, keys: tuple[str, ...]) -> dict[str, float]:
    """Return the numeric entries of `table` among `keys` (booleans and text left out)."""
    if not isinstance(table, Mapping):
        return {}
    return {k: float(table[k]) for k in keys
            if isinstance(table.get(k), int | float) and not isinstance(table.get(k), bool)}


def _json_table(text: Any) -> dict[str, Any]:
    """Return a ``*_json`` metadata value as a dict ({} when absent or not an object)."""
    if not text:
        return {}
    try:
        value = json.loads(str(text))
    except json.JSONDecodeError:
        return {}
    return value if isinstance(value, dict) else {}


@dataclass(frozen=True)
class RecordingContext:
    """The calibration facts of a recording (module docstring).

    Attributes
    ----------
    procedure : str
        The procedure of its plan; ``""`` when it says none (a recording without a plan).
    plan_name, plan_hash : str
        The plan's name and hash; ``""`` when there is no plan.
    equipment : dict of str to float
        The equipment accuracies (:data:`EQUIPMENT_KEYS`) that were given.
    imu_spec : dict of str to float
        The IMU specification (:data:`IMU_SPEC_KEYS`) that was given.
    acceptance : str
        The decision rule (``"simple"``, ``"guarded"``); ``""`` when not given.
    """

    procedure: str = ""
    plan_name: str = ""
    plan_hash: str = ""
    equipment: dict[str, float] = field(default_factory=dict)
    imu_spec: dict[str, float] = field(default_factory=dict)
    acceptance: str = ""

    @classmethod
    def of(cls, metadata: Mapping[str, Any]) -> RecordingContext:
        """Read the context from a recording's metadata (its own keys; else its stored plan).

        A stored plan that is not valid TOML counts as no plan (the analysis that needs the
        plan itself says so).
        """
        plan: dict[str, Any] = {}
        text = metadata.get("plan_toml")
        if text:
            try:
                plan = tomllib.loads(str(text))
            except tomllib.TOMLDecodeError:
                plan = {}

        def text_of(key: str, fallback: Any) -> str:
            value = metadata.get(key)
            return str(value) if value else (str(fallback) if fallback else "")

        acceptance = plan.get("acceptance")
        rule = acceptance.get("rule") if isinstance(acceptance, Mapping) else None
        equipment = _numbers(_json_table(metadata.get("equipment_json")), EQUIPMENT_KEYS) or \
            _numbers(plan.get("equipment"), EQUIPMENT_KEYS)
        imu_spec = _numbers(_json_table(metadata.get("imu_spec_json")), IMU_SPEC_KEYS) or \
            _numbers(plan.get("imu"), IMU_SPEC_KEYS)
        return cls(procedure=text_of("procedure", plan.get("procedure")),
                   plan_name=text_of("plan_name", plan.get("name")),
                   plan_hash=text_of("plan_hash", None),
                   equipment=equipment, imu_spec=imu_spec,
                   acceptance=text_of("acceptance", rule))

    def metadata(self) -> dict[str, str]:
        """Return the metadata keys that carry this context (what a run or an import writes)."""
        out = {"procedure": self.procedure, "plan_name": self.plan_name,
               "plan_hash": self.plan_hash, "acceptance": self.acceptance}
        if self.equipment:
            out["equipment_json"] = json.dumps(self.equipment)
        if self.imu_spec:
            out["imu_spec_json"] = json.dumps(self.imu_spec)
        return {k: v for k, v in out.items() if v}
