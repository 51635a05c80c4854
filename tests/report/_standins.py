"""A minimal result of the contract (models/procedure_result.py) for the report's tests."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from imucalib.models.decision import Decision, no_decision
from imucalib.models.procedure_result import ResultDefaults
from imucalib.models.reported import ReportedParameter


@dataclass(frozen=True)
class StandIn(ResultDefaults):
    """A result with given rows (name, value, σ, unit), verdict and ``to_dict``."""

    procedure: str
    unit: str
    rows: tuple[tuple[str, float, float, str], ...] = ()
    verdict: bool | None = None
    data: dict[str, Any] = field(default_factory=dict)
    fit_quality: tuple = ()
    notes: tuple[str, ...] = ()

    @property
    def decision(self) -> Decision:
        if self.verdict is None:
            return no_decision("no limits")
        return Decision(passed=self.verdict, rule="a stand-in rule")

    def parameter_rows(self) -> list[ReportedParameter]:
        return [ReportedParameter(n, v, s, u, s) for n, v, s, u in self.rows]

    def to_dict(self) -> dict[str, Any]:
        return dict(self.data)


def stand_in(procedure: str, unit: str, rows: list | tuple = (), *, passed: bool | None = None,
             to_dict: Callable[[], dict] | None = None) -> StandIn:
    """Return a :class:`StandIn`."""
    return StandIn(procedure, unit, tuple(rows), passed, dict(to_dict() if to_dict else {}))
