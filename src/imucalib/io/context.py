"""What a recording says about its calibration, read in one place: :class:`RecordingContext`.

A station run writes, besides the plan it ran (``plan_toml``, kept as provenance only), the
facts an analysis, a report or the records need as metadata keys of their own
(docs/recording-format.md, "Root attributes"): the ``procedure``, the ``plan_name`` and
``plan_hash``, the equipment accuracies (``equipment_json``), the IMU's specification
(``imu_spec_json``: the unit's identity, its held-out accuracies and gyro noise, its
per-parameter limits under ``"limits"`` and its declared noise under ``"noise"``, the plan's
``[imu]`` table) and the decision rule
(``acceptance`` and ``guard_band_k``); an import from a CSV and its step file writes the keys
its step file gives. A recording made before the runner wrote a fact as a key of its own has it
only inside its stored plan: :meth:`RecordingContext.of` then reads that TOML as plain data,
fact by fact. Nothing else parses the stored plan for these facts.

The facts are plain values (this package sits below :mod:`imucalib.plan`): a procedure builds
its configuration models from them (docs/recording-format.md, "Root attributes").

Contents
--------
:class:`RecordingContext`
    The facts, :meth:`~RecordingContext.of` a recording's metadata, :meth:`~RecordingContext.
    of_plan` a plan given as plain data, and the :meth:`~RecordingContext.metadata` keys that
    carry them.
:data:`EQUIPMENT_KEYS`, :data:`IMU_SPEC_KEYS`, :data:`IMU_UNIT_KEYS`, :data:`SPEC_LIMIT_KEYS`,
:data:`IMU_NOISE_KEYS`
    Which entries of the plan's tables it carries.
"""

from __future__ import annotations

import json
import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

__all__ = ["EQUIPMENT_KEYS", "IMU_NOISE_KEYS", "IMU_SPEC_KEYS", "IMU_UNIT_KEYS",
           "SPEC_LIMIT_KEYS", "RecordingContext"]

#: The equipment accuracies a calibration uses (plan table ``[equipment]``).
EQUIPMENT_KEYS = ("table_position_accuracy_arcsec", "table_orthogonality_arcsec")
#: The numbers of the IMU specification (plan table ``[imu]``): held-out accuracies, gyro noise.
IMU_SPEC_KEYS = ("accel_accuracy_g", "gyro_accuracy_dps", "gyro_noise_dps")
#: The identity of the unit under test (plan table ``[imu]``).
IMU_UNIT_KEYS = ("serial", "model", "maker", "grade")
#: The per-parameter specification limits (plan table ``[imu.limits]``; the fields of
#: :class:`imucalib.plan.schema.SpecLimits`, which tests/io/test_recording_context.py checks).
SPEC_LIMIT_KEYS = ("accel_bias_ug", "accel_scale_ppm", "accel_misalignment_urad",
                   "gyro_bias_dph", "gyro_scale_ppm", "gyro_misalignment_urad",
                   "gyro_g_sensitivity_dph_per_g", "gyro_arw_deg_rth", "accel_vrw_ug_rthz")
#: The unit's declared noise (plan table ``[imu.noise]``, a noise characterisation's terms; the
#: fields of :class:`imucalib.plan.schema.ImuNoiseConfig`): its text entries, its number, and
#: its per-axis triples (SI).
_NOISE_TEXTS = ("source", "source_sha256", "record")
_NOISE_NUMBERS = ("record_duration_s",)
_NOISE_TRIPLES = ("gyro_white_rps_rthz", "gyro_bias_instability_rps", "gyro_random_walk_rps_rts",
                  "accel_white_mps2_rthz", "accel_bias_instability_mps2",
                  "accel_random_walk_mps2_rts")
IMU_NOISE_KEYS = (*_NOISE_TEXTS, *_NOISE_NUMBERS, *_NOISE_TRIPLES)


def _text(value: Any) -> str:
    """Return `value` as text, ``""`` when it is absent or empty."""
    return str(value) if value else ""


def _number(value: Any) -> float | None:
    """Return `value` as a float when it is a finite number (not a bool), else None."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        try:  # an HDF5 attribute comes back as a NumPy scalar
            value = value.item() if hasattr(value, "item") else None
        except (TypeError, ValueError):
            return None
        if isinstance(value, bool) or not isinstance(value, int | float):
            return None
    return float(value) if math.isfinite(value) else None


def _numbers(table: Any, keys: tuple[str, ...]) -> dict[str, float]:
    """Return the numeric entries of `table` among `keys` (booleans and text left out)."""
    if not isinstance(table, Mapping):
        return {}
    return {k: v for k in keys if (v := _number(table.get(k))) is not None}


def _texts(table: Any, keys: tuple[str, ...]) -> dict[str, str]:
    """Return the non-empty text entries of `table` among `keys`."""
    if not isinstance(table, Mapping):
        return {}
    return {k: v for k in keys if isinstance(v := table.get(k), str) and v}


def _noise(table: Any) -> dict[str, Any]:
    """Return the ``[imu.noise]`` entries of `table` (:data:`IMU_NOISE_KEYS`) of their type.

    Texts, the number, and the triples of three finite numbers; {} without a source (no
    declared noise). The analysis validates the whole table (ImuNoiseConfig).
    """
    if not isinstance(table, Mapping):
        return {}
    out: dict[str, Any] = {**_texts(table, _NOISE_TEXTS), **_numbers(table, _NOISE_NUMBERS)}
    for key in _NOISE_TRIPLES:
        value = table.get(key)
        if isinstance(value, list | tuple) and len(value) == 3:
            numbers = [_number(v) for v in value]
            if all(n is not None for n in numbers):
                out[key] = numbers
    return out if out.get("source") else {}


def _json_table(value: Any) -> dict[str, Any]:
    """Return a ``*_json`` metadata value as a dict ({} when absent or not an object).

    :attr:`imucalib.io.reader.Recording.metadata` has decoded it already; a metadata mapping
    made by hand may hold the JSON text.
    """
    if isinstance(value, Mapping):
        return dict(value)
    if not value:
        return {}
    try:
        decoded = json.loads(str(value))
    except json.JSONDecodeError:
        return {}
    return decoded if isinstance(decoded, dict) else {}


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
        The numbers of the IMU specification (:data:`IMU_SPEC_KEYS`) that were given.
    imu_unit : dict of str to str
        The unit's identity in its specification (:data:`IMU_UNIT_KEYS`) that was given.
    spec_limits : dict of str to float
        The per-parameter specification limits (:data:`SPEC_LIMIT_KEYS`) that were given.
    imu_noise : dict of str to Any
        The unit's declared noise (:data:`IMU_NOISE_KEYS`), the plan's ``[imu.noise]``; {} when
        none was given.
    acceptance : str
        The decision rule (``"simple"``, ``"guarded"``); ``""`` when not given.
    guard_band_k : float or None
        k of a guarded rule (the guard band in standard uncertainties); None when not given.
    """

    procedure: str = ""
    plan_name: str = ""
    plan_hash: str = ""
    equipment: dict[str, float] = field(default_factory=dict)
    imu_spec: dict[str, float] = field(default_factory=dict)
    imu_unit: dict[str, str] = field(default_factory=dict)
    spec_limits: dict[str, float] = field(default_factory=dict)
    imu_noise: dict[str, Any] = field(default_factory=dict)
    acceptance: str = ""
    guard_band_k: float | None = None

    @property
    def has_plan(self) -> bool:
        """Whether the recording names the plan it was made from (its hash alone gives no fact)."""
        return bool(self.plan_name)

    @classmethod
    def of_plan(cls, plan: Mapping[str, Any], plan_hash: str = "") -> RecordingContext:
        """Read the context from a plan given as plain data.

        Parameters
        ----------
        plan : mapping
            A parsed plan TOML, or ``Plan.model_dump(mode="json")``: its ``procedure``,
            ``name`` and the tables ``[equipment]``, ``[imu]`` (with ``[imu.limits]``) and
            ``[acceptance]``. Entries of another type, and tables that are missing, give no
            fact; nothing is validated.
        plan_hash : str
            The plan's hash (a plan does not hold its own).
        """
        imu = plan.get("imu")
        acceptance = plan.get("acceptance")
        acceptance = acceptance if isinstance(acceptance, Mapping) else {}
        rule = acceptance.get("rule")
        return cls(procedure=_text(plan.get("procedure")), plan_name=_text(plan.get("name")),
                   plan_hash=plan_hash,
                   equipment=_numbers(plan.get("equipment"), EQUIPMENT_KEYS),
                   imu_spec=_numbers(imu, IMU_SPEC_KEYS), imu_unit=_texts(imu, IMU_UNIT_KEYS),
                   spec_limits=_numbers(imu.get("limits") if isinstance(imu, Mapping) else None,
                                        SPEC_LIMIT_KEYS),
                   imu_noise=_noise(imu.get("noise") if isinstance(imu, Mapping) else None),
                   acceptance=rule if isinstance(rule, str) else "",
                   guard_band_k=_number(acceptance.get("guard_band_k")))

    @classmethod
    def of(cls, metadata: Mapping[str, Any]) -> RecordingContext:
        """Read the context from a recording's metadata (its own keys; else its stored plan).

        Each fact (the procedure, the plan's name and hash, the equipment accuracies, the
        specification's numbers, the unit's identity, the limits, the rule, the guard band)
        comes from the recording's own key when that gives it, else from the stored plan
        (``plan_toml``, read as plain data): a recording written before the runner wrote a fact
        gives it as its plan states it. A stored plan that is not valid TOML counts as no plan.
        """
        planned = RecordingContext()
        text = metadata.get("plan_toml")
        if text:
            try:
                planned = cls.of_plan(tomllib.loads(str(text)))
            except tomllib.TOMLDecodeError:
                pass
        imu = _json_table(metadata.get("imu_spec_json"))
        own = cls(procedure=_text(metadata.get("procedure")),
                  plan_name=_text(metadata.get("plan_name")),
                  plan_hash=_text(metadata.get("plan_hash")),
                  equipment=_numbers(_json_table(metadata.get("equipment_json")),
                                     EQUIPMENT_KEYS),
                  imu_spec=_numbers(imu, IMU_SPEC_KEYS), imu_unit=_texts(imu, IMU_UNIT_KEYS),
                  spec_limits=_numbers(imu.get("limits"), SPEC_LIMIT_KEYS),
                  imu_noise=_noise(imu.get("noise")),
                  acceptance=_text(metadata.get("acceptance")),
                  guard_band_k=_number(metadata.get("guard_band_k")))
        return cls(procedure=own.procedure or planned.procedure,
                   plan_name=own.plan_name or planned.plan_name,
                   plan_hash=own.plan_hash or planned.plan_hash,
                   equipment=own.equipment or planned.equipment,
                   imu_spec=own.imu_spec or planned.imu_spec,
                   imu_unit=own.imu_unit or planned.imu_unit,
                   spec_limits=own.spec_limits or planned.spec_limits,
                   imu_noise=own.imu_noise or planned.imu_noise,
                   acceptance=own.acceptance or planned.acceptance,
                   guard_band_k=(own.guard_band_k if own.guard_band_k is not None
                                 else planned.guard_band_k))

    @property
    def imu_table(self) -> dict[str, Any]:
        """The IMU specification as the plan's ``[imu]`` table: identity, numbers, and tables."""
        table: dict[str, Any] = {**self.imu_unit, **self.imu_spec}
        if self.spec_limits:
            table["limits"] = dict(self.spec_limits)
        if self.imu_noise:
            table["noise"] = dict(self.imu_noise)
        return table

    def metadata(self) -> dict[str, str | float]:
        """Return the metadata keys that carry this context (what a run or an import writes)."""
        out: dict[str, str | float] = {
            "procedure": self.procedure, "plan_name": self.plan_name,
            "plan_hash": self.plan_hash, "acceptance": self.acceptance}
        if self.guard_band_k is not None:
            out["guard_band_k"] = self.guard_band_k
        if self.equipment:
            out["equipment_json"] = json.dumps(self.equipment)
        if imu := self.imu_table:
            out["imu_spec_json"] = json.dumps(imu)
        return {k: v for k, v in out.items() if v != ""}
