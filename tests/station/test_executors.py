"""Every step kind of the plan vocabulary has its executor (station/executors/)."""

from __future__ import annotations

import typing

from imucalib.plan.schema import PlanStep
from imucalib.station.executors import EXECUTORS


def _step_kinds() -> set[str]:
    union = typing.get_args(PlanStep)[0]
    return {typing.get_args(cls.model_fields["kind"].annotation)[0]
            for cls in typing.get_args(union)}


def test_every_step_kind_has_an_executor_and_no_other_kind_does():
    kinds = _step_kinds()
    assert "operator-check" in kinds and "position" in kinds
    assert set(EXECUTORS) == kinds
