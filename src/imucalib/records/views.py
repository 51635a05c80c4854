"""What the records queries return: frozen, plain values (no database session behind them).

Contents
--------
:class:`ParameterRow`, :class:`ReviewView`, :class:`HistoryEntry`, :class:`DriftPoint`,
:class:`DueUnit`, :class:`EquipmentView`, :class:`RunView`, :class:`Problem`, :class:`ChainHead`,
:class:`UserView`, :class:`UserEventView`, :class:`ReleaseStatus`
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import date, datetime
from typing import Any

__all__ = ["ChainHead", "DriftPoint", "DueUnit", "EquipmentView", "HistoryEntry", "KeyUse",
           "ParameterRow", "Problem", "ReleaseStatus", "ReviewView", "RunView", "UserEventView",
           "UserView", "VerifyReport"]


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

    @property
    def decision(self) -> str:
        """``"approve"`` or ``"reject"``."""
        return "approve" if self.approved else "reject"


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

    @property
    def opened_by(self) -> str:
        """``"run"`` (``imucalib run``) or ``"calibrate"`` (data no run recorded); "" if older."""
        return str(self.environment.get("opened_by", ""))

    @property
    def unplanned(self) -> bool:
        """True for a run ``calibrate`` opened for data no plan produced (a log, a CSV)."""
        return bool(self.environment.get("unplanned", False))


@dataclass(frozen=True)
class Problem:
    """A mismatch :meth:`~imucalib.records.api.Records.verify` found.

    Attributes
    ----------
    table : str
        The table (``"results"``) or ``"recordings"``.
    key : int
        The row's ``seq`` (or the run's id for a recording, the line of the anchor log).
    what : str
        What was expected and what was found.
    kind : str
        The kind of change: ``edited``, ``deleted``, ``chain broken``, ``re-hashed``,
        ``forged``, ``unsigned``, ``bad value``, ``dangling``, ``untrusted key``,
        ``anchor log``, ``recording`` (docs/records.md, "What verify checks").
    """

    table: str
    key: int
    what: str
    kind: str = ""

    def __str__(self) -> str:
        return f"{self.table} row {self.key}: {self.what}"


@dataclass(frozen=True)
class KeyUse:
    """A signing key of the records and what it signed (``records verify``).

    ``trusted``: the key file (or ``station.pub``) is this key, or a trusted key endorses it
    (docs/records.md, "Signing"); ``rows``: rows per table it signed.
    """

    key_id: int
    fingerprint: str
    trusted: bool
    rows: dict[str, int]
    registered_utc: datetime | None = None
    reason: str = ""


@dataclass(frozen=True)
class VerifyReport:
    """Everything ``records verify`` found: problems, notes, and which key signed what.

    ``problems`` empty means intact; ``notes`` are facts that are no problem (rows made
    before signing, rows after the last anchor, the trusted key used).
    """

    problems: tuple[Problem, ...]
    notes: tuple[str, ...] = ()
    keys: tuple[KeyUse, ...] = ()


@dataclass(frozen=True)
class ChainHead:
    """The last row of a table's chain: keep it elsewhere to detect a deleted last row."""

    table: str
    seq: int
    row_hash: str


@dataclass(frozen=True)
class UserEventView:
    """A change of a user's state (``disable`` or ``enable``): when, why, by whom."""

    event: str
    reason: str
    by: str
    utc: datetime


@dataclass(frozen=True)
class UserView:
    """A user of the records: name, initials, role, and whether active now.

    ``events`` are the user's state changes, oldest first; ``active`` is the state after the
    last of them (a new user is active).
    """

    user_id: int
    name: str
    initials: str
    role: str
    active: bool
    added_utc: datetime
    added_by: str
    events: tuple[UserEventView, ...] = ()


@dataclass(frozen=True)
class ReleaseStatus:
    """Whether a result is released, by whom, when, with what decision.

    Released: the latest review of its current version approves it and was made by an
    authorised reviewer (docs/records.md, "Users and roles", rule (U.4)).

    Attributes
    ----------
    result_id : int
        The result asked about.
    current_id : int
        Its current version (``result_id`` unless it was amended).
    released : bool
    decision : str or None
        ``"approve"``, ``"reject"``, or None (no review of the current version).
    reviewer, reviewer_initials, reviewer_role : str
        Of that latest review ("" when none, or the reviewer is not a registered user).
    reviewed_utc : datetime or None
    comment : str
    review_id : int or None
    authorised : bool
        The latest review's reviewer was, when reviewing, an active user with role reviewer or
        admin, other than the run's operator.
    reason : str
        One line: why released or why not.
    """

    result_id: int
    current_id: int
    released: bool
    decision: str | None
    reviewer: str
    reviewer_initials: str
    reviewer_role: str
    reviewed_utc: datetime | None
    comment: str
    review_id: int | None
    authorised: bool
    reason: str

    def text(self) -> str:
        """One line for a report or the terminal: ``"released: approved by …"`` or why not."""
        return f"{'released' if self.released else 'not released'}: {self.reason}"
