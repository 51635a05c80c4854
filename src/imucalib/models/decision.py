"""The one shape of a procedure's verdict: :class:`Decision`, its :class:`Check` and rows.

Every procedure's result carries one :class:`Decision` (the result contract,
docs/procedures.md, "The result contract"): passed, failed, or — for a test that has no
acceptance limits (a noise characterisation, the classical tests run without a specification)
— *no decision*, said explicitly (:func:`no_decision`), never a silent ``None``. The checks
that make a decision are built by :mod:`imucalib.analysis.verification` (residuals, accuracy,
repeatability, specification) under the decision rule it states (simple or guarded acceptance,
ISO/IEC Guide 98-4:2012 §8; ILAC-G8:09/2019).

Contents
--------
:class:`CheckRow`, :class:`Check`, :class:`Decision`, :func:`no_decision`,
:func:`decision_from_dict`
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from imucalib.errors import InvalidInputError

__all__ = ["Check", "CheckRow", "Decision", "decision_from_dict", "no_decision"]


@dataclass(frozen=True)
class CheckRow:
    """One compared quantity: its value, its limit, and whether it is within it."""

    name: str
    value: float
    limit: float
    unit: str
    passed: bool
    detail: str = ""

    def to_dict(self) -> dict[str, Any]:
        """Return the JSON-able form (a non-finite value or limit as None)."""
        return {"name": self.name, "value": _finite(self.value), "limit": _finite(self.limit),
                "unit": self.unit, "passed": bool(self.passed), "detail": self.detail}


@dataclass(frozen=True)
class Check:
    """A named check: its rows, its verdict (None when not assessed) and a summary line."""

    name: str
    passed: bool | None
    summary: str
    rows: tuple[CheckRow, ...] = ()

    @property
    def assessed(self) -> bool:
        """Whether the check could be made."""
        return self.passed is not None

    def to_dict(self) -> dict[str, Any]:
        """Return the JSON-able form."""
        return {"name": self.name, "passed": self.passed, "summary": self.summary,
                "rows": [r.to_dict() for r in self.rows]}


@dataclass(frozen=True)
class Decision:
    """The overall verdict of one result.

    Attributes
    ----------
    passed : bool or None
        True: every assessed check passed; False: one failed; None: *no decision* (the test
        has no acceptance limits; `rule` says why).
    rule : str
        The decision rule applied (its statement), or why no decision is made.
    failed, not_assessed : tuple of str
        The checks that failed, and those that could not be made.
    checks : tuple of Check
    notes : tuple of str
        What the decision must say besides its checks (a misfit and its scaled σ).
    """

    passed: bool | None
    rule: str
    failed: tuple[str, ...] = ()
    not_assessed: tuple[str, ...] = ()
    checks: tuple[Check, ...] = field(default_factory=tuple)
    notes: tuple[str, ...] = ()

    @property
    def verdict(self) -> str:
        """``"PASS"``, ``"FAIL"`` or ``"NO DECISION"``."""
        return {True: "PASS", False: "FAIL", None: "NO DECISION"}[self.passed]

    def summary(self) -> str:
        """Return the verdict in one line (its notes after it)."""
        text = f"{self.verdict} ({self.rule})"
        if self.failed:
            text += "; failed: " + ", ".join(self.failed)
        if self.not_assessed:
            text += "; not assessed: " + ", ".join(self.not_assessed)
        for note in self.notes:
            text += f"; {note}"
        return text

    def to_dict(self) -> dict[str, Any]:
        """Return the JSON-able form (:func:`decision_from_dict` reads it back)."""
        return {"passed": self.passed, "verdict": self.verdict, "rule": self.rule,
                "failed": list(self.failed), "not_assessed": list(self.not_assessed),
                "notes": list(self.notes), "checks": [c.to_dict() for c in self.checks],
                "summary": self.summary()}


def no_decision(reason: str, *, notes: tuple[str, ...] = ()) -> Decision:
    """Return the explicit *no decision* of a result without acceptance limits.

    Parameters
    ----------
    reason : str
        Why nothing is decided (``"a noise characterisation has no acceptance limits"``).
    notes : tuple of str
        What the reader must know besides (a misfit).
    """
    return Decision(passed=None, rule=reason, notes=tuple(notes))


def decision_from_dict(data: Mapping[str, Any], source: str = "<dict>") -> Decision:
    """Rebuild a :class:`Decision` from :meth:`Decision.to_dict`'s form.

    Raises
    ------
    InvalidInputError
        A field missing or of the wrong type (named, with `source`).
    """
    def strings(key: str) -> tuple[str, ...]:
        value = data.get(key, [])
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise InvalidInputError(f"{source}: decision.{key} must be a list of strings; got "
                                    f"{_shown(value)}")
        return tuple(value)

    passed = data.get("passed")
    if passed is not None and not isinstance(passed, bool):
        raise InvalidInputError(f"{source}: decision.passed must be true, false or null; got "
                                f"{_shown(passed)}")
    rule = data.get("rule")
    if not isinstance(rule, str):
        raise InvalidInputError(f"{source}: decision.rule must be a string; got {_shown(rule)}")
    raw_checks = data.get("checks", []) or []
    if not isinstance(raw_checks, list):
        raise InvalidInputError(f"{source}: decision.checks must be a list of checks; got "
                                f"{_shown(raw_checks)}")
    checks = []
    for i, c in enumerate(raw_checks):
        try:
            rows = tuple(CheckRow(str(r["name"]), _number(r["value"]), _number(r["limit"]),
                                  str(r["unit"]), bool(r["passed"]), str(r.get("detail", "")))
                         for r in c.get("rows", []))
            if c["passed"] is not None and not isinstance(c["passed"], bool):
                raise TypeError(f"`passed` is {_shown(c['passed'])}, not true, false or null")
            checks.append(Check(str(c["name"]), c["passed"], str(c["summary"]), rows))
        except (KeyError, TypeError, AttributeError, ValueError, OverflowError) as exc:
            raise InvalidInputError(f"{source}: decision.checks[{i}] is malformed ({exc})"
                                    ) from exc
    return Decision(passed=passed, rule=rule, failed=strings("failed"),
                    not_assessed=strings("not_assessed"), checks=tuple(checks),
                    notes=strings("notes"))


def _finite(value: float) -> float | None:
    v = float(value)
    return v if math.isfinite(v) else None


def _number(value: Any) -> float:
    """Return a check's number (None: NaN); refuse a string or a boolean (TypeError)."""
    if value is not None and (isinstance(value, bool | str) or not isinstance(value, int | float)):
        raise TypeError(f"expected a number; got {_shown(value)}")
    return math.nan if value is None else float(value)


def _shown(value: object, limit: int = 60) -> str:
    """`value` as written in a message, cut at `limit` characters."""
    text = repr(value)
    return text if len(text) <= limit else text[:limit] + "…"
