"""Read the steps of a version 1 Recording as version 2 steps (private).

Version 1 ``/steps`` had no ``role``, ``tags`` or ``units`` fields. The reader recovers them:

- ``tags``: from the step's ``commanded`` JSON, where a station run stored the plan step's
  fields (``tags`` among them); else from the plan stored in the metadata (``plan_toml``), the
  step ``commanded["plan_step"]``; else none;
- ``role``: :func:`imucalib.io.step_roles.role_from_tags` of the step's kind, those tags and the
  plan's ``procedure``, which is how the P1 and Allan generators now set roles;
- ``units``: none (``()``: the step concerns every IMU of the file, as every v1 step did).
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from imucalib.io.step_roles import role_from_tags

__all__ = ["V1Plan", "v1_plan", "v1_role_and_tags"]


@dataclass(frozen=True)
class V1Plan:
    """What the mapping needs of a stored plan: its procedure and each step's tags."""

    procedure: str = ""
    step_tags: tuple[tuple[str, ...] | None, ...] = ()


def _tags(value: Any) -> tuple[str, ...] | None:
    if isinstance(value, list | tuple) and all(isinstance(t, str) for t in value):
        return tuple(value)
    return None


def v1_plan(metadata: Mapping[str, Any]) -> V1Plan:
    """Read the procedure and step tags of the plan in `metadata` (empty when absent or bad).

    The plan is read as TOML only, not validated: a v1 file's steps get whatever tags its plan
    gave them, even from a plan that a later schema would refuse.
    """
    text = metadata.get("plan_toml")
    if not isinstance(text, str) or not text:
        return V1Plan()
    try:
        data = tomllib.loads(text)
    except (tomllib.TOMLDecodeError, ValueError):
        return V1Plan()
    procedure = data.get("procedure", "")
    steps = data.get("steps", [])
    if not isinstance(steps, list):
        steps = []
    return V1Plan(procedure=procedure if isinstance(procedure, str) else "",
                  step_tags=tuple(_tags(s.get("tags", [])) if isinstance(s, dict) else None
                                  for s in steps))


def v1_role_and_tags(kind: str, commanded: Any, plan: V1Plan) -> tuple[str, tuple[str, ...]]:
    """Return the (role, tags) of a version 1 step (module docstring)."""
    tags: tuple[str, ...] | None = None
    if isinstance(commanded, dict):
        if "tags" in commanded:
            tags = _tags(commanded["tags"])
        index = commanded.get("plan_step")
        if (tags is None and isinstance(index, int) and not isinstance(index, bool)
                and 0 <= index < len(plan.step_tags)):
            tags = plan.step_tags[index]
    found: Sequence[str] = tags or ()
    return role_from_tags(kind, found, plan.procedure), tuple(found)
