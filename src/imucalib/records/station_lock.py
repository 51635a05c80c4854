"""The station lock: one operator holds a station at a time, everyone sees who (docs/web.md).

Contents
--------
:class:`LockView`, :class:`StationLockedError`
    A station's lock as read; the error of taking a lock another user holds.
:func:`lock_view`, :func:`take_lock`, :func:`release_lock`, :func:`request_lock`

Rules
-----
(L.1) A free station is taken by whoever asks (the web layer decides who may ask); a held one
      only by its holder (again: nothing changes) — anyone else gets
      :class:`StationLockedError` naming the holder.
(L.2) The holder releases it; so may an admin (``force``), for a holder who left.
(L.3) Anyone may request a held lock: the request (who, when) is shown to the holder and
      everyone; taking or releasing the lock clears it.

The lock lives in the records database (``station_locks``), so that every server of a lab
sharing one database sees every station's holder.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import UTC, datetime

from sqlalchemy import select
from sqlalchemy.orm import Session

from imucalib.errors import RecordsError
from imucalib.records.schema import StationLock

__all__ = ["LockView", "StationLockedError", "lock_view", "release_lock", "request_lock",
           "take_lock"]


class StationLockedError(RecordsError):
    """The station is held by another user."""


@dataclass(frozen=True)
class LockView:
    """A station's lock: its holder ("" when free), since when, and any request for it."""

    station: str
    holder: str = ""
    since_utc: datetime | None = None
    requested_by: str = ""
    requested_utc: datetime | None = None


def _utc(value: datetime | None) -> datetime | None:
    if value is None:
        return None
    return value.replace(tzinfo=UTC) if value.tzinfo is None else value.astimezone(UTC)


def _row(session: Session, station: str, *, for_update: bool = False) -> StationLock | None:
    query = select(StationLock).where(StationLock.station == station)
    if for_update and session.get_bind().dialect.name == "postgresql":
        query = query.with_for_update()
    return session.scalars(query).first()


def _view(station: str, row: StationLock | None) -> LockView:
    if row is None:
        return LockView(station)
    return LockView(station, row.holder, _utc(row.since_utc), row.requested_by,
                    _utc(row.requested_utc))


def lock_view(session: Session, station: str) -> LockView:
    """Return `station`'s lock as it is now."""
    return _view(station, _row(session, station))


def take_lock(session: Session, station: str, who: str) -> LockView:
    """Give `station` to `who` (rule (L.1)); return the new state.

    Raises
    ------
    StationLockedError
        Another user holds it.
    """
    row = _row(session, station, for_update=True)
    if row is not None and row.holder and row.holder != who:
        raise StationLockedError(f"station {station!r} is held by {row.holder} since "
                                 f"{_utc(row.since_utc):%Y-%m-%d %H:%M} UTC; ask them to "
                                 "release it (request the lock)")
    now = datetime.now(UTC)
    if row is None:
        row = StationLock(station=station, holder=who, since_utc=now, requested_by="",
                          requested_utc=None)
        session.add(row)
    elif row.holder != who:
        row.holder, row.since_utc = who, now
        row.requested_by, row.requested_utc = "", None
    session.flush()
    return _view(station, row)


def release_lock(session: Session, station: str, who: str, *, force: bool = False) -> str:
    """Free `station` (rule (L.2)); return who held it.

    Raises
    ------
    StationLockedError
        Another user holds it and `force` is not set.
    RecordsError
        Nobody holds it.
    """
    row = _row(session, station, for_update=True)
    if row is None or not row.holder:
        raise RecordsError(f"station {station!r} is not held by anyone; nothing to release")
    if row.holder != who and not force:
        raise StationLockedError(f"station {station!r} is held by {row.holder}, not by {who}; "
                                 "only its holder (or an admin) releases it")
    held = row.holder
    row.holder, row.since_utc = "", None
    row.requested_by, row.requested_utc = "", None
    session.flush()
    return held


def request_lock(session: Session, station: str, who: str) -> LockView:
    """Record that `who` asks for `station` (rule (L.3)); return the state.

    Raises
    ------
    RecordsError
        The station is free (take it instead) or `who` holds it already.
    """
    row = _row(session, station, for_update=True)
    if row is None or not row.holder:
        raise RecordsError(f"station {station!r} is free: take the lock instead of asking")
    if row.holder == who:
        raise RecordsError(f"station {station!r} is already held by you ({who})")
    row.requested_by, row.requested_utc = who, datetime.now(UTC)
    session.flush()
    return _view(station, row)
