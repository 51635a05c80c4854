"""What the records queries return: frozen, plain values (no database session behind them).

Contents
--------
:class:`ParameterRow`, :class:`ReviewView`, :class:`HistoryEntry`, :class:`DriftPoint`,
:class:`DueUnit`, :class:`EquipmentView`, :class:`RunView`, :class:`Problem`, :class:`ChainHead`
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import date, datetime
from typing import Any

__all__ = ["ChainHead", "DriftPoint", "DueUnit", "EquipmentView", "HistoryEntry",
           "ParameterRow", "Problem", "ReviewView", "RunView"]


@dataclass(frozen=True)
class ParameterRow:
    """One parameter of a result: its value and standard uncertainty, in `unit`."""

    name: str
    value: float
    std: float
    unit: str


@dataclass(frozen=True)
class ReviewView:
    """A review of a result."""

    review_id: int
    result_id: int
    reviewer: str
    reviewed_utc: datetime
    approved: bool
    comment: str


@dataclass(frozen=True)
class HistoryEntry:
    """One result of a unit, current or amended (``replaced_by`` names its successor)."""

    result_id: int
    run_id: int
    serial: str
    procedure: str
    model: str
    version: int
    calibrated_utc: datetime | None
    created_utc: datetime
    passed: bool | None
    replaces: int | None
    replaced_by: int | None
    amendment_reason: str
    parameters: tuple[ParameterRow, ...]
    reviews: tuple[ReviewView, ...]
    plan_name: str
    plan_hash: str

    @property
    def current(self) -> bool:
        """True when no amendment replaced this result."""
        return self.replaced_by is None

    def parameter(self, name: str) -> ParameterRow:
        """Return the parameter called `name` (KeyError if the result has none)."""
        for row in self.parameters:
            if row.name == name:
                return row
        raise KeyError(name)


@dataclass(frozen=True)
class DriftPoint:
    """One calibration's value of a parameter: when, value, standard uncertainty, which result."""

    calibrated_utc: datetime
    value: float
    std: float
    unit: str
    result_id: int


@dataclass(frozen=True)
class DueUnit:
    """A unit's last good calibration and its due date (`last_calibrated` None: never)."""

    serial: str
    model: str
    last_calibrated: date | None
    due_on: date | None
    interval_days: int
    result_id: int | None


@dataclass(frozen=True)
class EquipmentView:
    """A piece of equipment with its current certificate."""

    equipment_id: int
    station: str
    kind: str
    model: str
    serial: str
    certificate: str
    calibrated_on: date | None
    due_on: date | None
    replaces: int | None


@dataclass(frozen=True)
class RunView:
    """A run as recorded."""

    run_id: int
    plan_name: str
    plan_hash: str
    procedure: str
    recording_path: str
    recording_sha256: str
    environment: dict[str, Any]
    operator: str
    software_version: str
    station: str
    equipment_ids: tuple[int, ...]
    started_utc: datetime | None
    ended_utc: datetime | None
    result_ids: tuple[int, ...]


@dataclass(frozen=True)
class Problem:
    """A mismatch :meth:`~imucalib.records.api.Records.verify` found.

    Attributes
    ----------
    table : str
        The table (``"results"``) or ``"recordings"``.
    key : int
        The row's ``seq`` (or the run's id for a recording).
    what : str
        What was expected and what was found.
    """

    table: str
    key: int
    what: str

    def __str__(self) -> str:
        return f"{self.table}[{self.key}]: {self.what}"


@dataclass(frozen=True)
class ChainHead:
    """The last row of a table's chain: keep it elsewhere to detect a deleted last row."""

    table: str
    seq: int
    row_hash: str
