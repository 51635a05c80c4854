"""Operator checks: who confirms a mounting, an alignment or a remount, and when.

Contents
--------
:class:`Operator` (protocol), :class:`OperatorAnswer`, :class:`AutoOperator` (confirms every
item under a given name: the twin, unattended test runs), :class:`ScriptedOperator` (answers from
a list: tests).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from datetime import UTC, datetime
from typing import Protocol, runtime_checkable

__all__ = ["AutoOperator", "Operator", "OperatorAnswer", "ScriptedOperator"]


@dataclass(frozen=True)
class OperatorAnswer:
    """An operator's answer to one check: confirmed or not, by whom, when (UTC), and a note."""

    confirmed: bool
    who: str
    when_utc: str = field(default_factory=lambda: datetime.now(UTC).strftime(
        "%Y-%m-%dT%H:%M:%SZ"))
    note: str = ""


@runtime_checkable
class Operator(Protocol):
    """Someone (or something) who confirms operator-check items."""

    def confirm(self, item: str) -> OperatorAnswer:
        """Ask the operator to confirm `item`."""
        ...


class AutoOperator:
    """Confirms every item under the name `who` (recorded as such)."""

    def __init__(self, who: str = "auto") -> None:
        self.who = who

    def confirm(self, item: str) -> OperatorAnswer:
        """Confirm `item`."""
        return OperatorAnswer(True, self.who, note="confirmed automatically")


class ScriptedOperator:
    """Answers items in order from a list of booleans (then confirms)."""

    def __init__(self, answers: Iterable[bool], who: str = "scripted") -> None:
        self._answers = list(answers)
        self.who = who
        self.asked: list[str] = []

    def confirm(self, item: str) -> OperatorAnswer:
        """Answer `item` with the next scripted answer."""
        self.asked.append(item)
        ok = self._answers.pop(0) if self._answers else True
        return OperatorAnswer(ok, self.who)
