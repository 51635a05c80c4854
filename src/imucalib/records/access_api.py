"""The web page's methods of :class:`~imucalib.records.api.Records`: logins, audit, lock.

:class:`AccessRecords` is a base class of ``Records``: each method is one transaction of
``Records._run``; an action and its audit row are committed together (docs/web.md). The rules
are those of :mod:`imucalib.records.access` and :mod:`imucalib.records.station_lock`.
"""

from __future__ import annotations

from collections.abc import Callable
from datetime import datetime
from typing import TYPE_CHECKING, Any, TypeVar

from sqlalchemy.orm import Session

if TYPE_CHECKING:
    from imucalib.records.access import AuditView, LoginSession
    from imucalib.records.station_lock import LockView
    from imucalib.records.views import UserView

__all__ = ["AccessRecords", "Login"]

_T = TypeVar("_T")
#: A successful login: the user, the session's cookie token, its CSRF token, its expiry.
Login = tuple["UserView", str, str, datetime]


class AccessRecords:
    """Passwords, web sessions, the audit trail and the station lock of a records database."""

    if TYPE_CHECKING:
        def _run(self, work: Callable[[Session], _T], *, write: bool,
                 anchor_key: Any = None, checked: bool = True) -> _T: ...

    def set_password(self, name: str, password: str, *, by: str | None) -> int:
        """Set user `name`'s password (rule (A.1)); return the credential row's id.

        Audited as ``set_password`` (without the password, of course).
        """
        from imucalib.records import access

        def work(session: Session) -> int:
            row = access.set_password(session, name, password, by)
            access.audit(session, (by or name).strip(), "set_password",
                         details={"user": " ".join(name.split())})
            return row
        return self._run(work, write=True)

    def login(self, name: str, password: str, *, station: str = "",
              hours: float | None = None, source: str = "") -> Login | None:
        """Check a login; on success start a session. Either way an audit row is appended.

        Returns
        -------
        (UserView, token, csrf_token, expires_utc), or None when refused.

        Raises
        ------
        LoginThrottledError
            Too many recent failures of this name (rule (A.4)); nothing is appended.
        """
        from imucalib.records import access

        def work(session: Session) -> Login | None:
            access.check_throttle(session, name)
            user = access.authenticate(session, name, password)
            details = {"source": source} if source else {}
            if user is None:
                access.audit(session, name.strip()[:200], "login_failed", station=station,
                             details=details)
                return None
            token, csrf, expires = access.create_session(
                session, user.name, access.SESSION_HOURS if hours is None else hours)
            access.audit(session, user.name, "login", station=station, details=details)
            return user, token, csrf, expires
        return self._run(work, write=True)

    def web_session(self, token: str) -> LoginSession | None:
        """Return the live session of a cookie's token with its user, else None."""
        from imucalib.records import access

        return self._run(lambda s: access.session_of(s, token), write=False)

    def logout(self, token: str, *, station: str = "") -> str:
        """End the session of `token` (audited); return its user's name ("" if none)."""
        from imucalib.records import access

        def work(session: Session) -> str:
            name = access.end_session(session, token)
            if name:
                access.audit(session, name, "logout", station=station)
            return name
        return self._run(work, write=True)

    def audit(self, actor: str, action: str, *, station: str = "", run_ref: str = "",
              details: dict[str, Any] | None = None) -> int:
        """Append an audit row (chained, signed); return its sequence number."""
        from imucalib.records import access

        return self._run(lambda s: access.audit(s, actor, action, station=station,
                                                run_ref=run_ref, details=details), write=True)

    def audit_log(self, *, limit: int = 200, run_ref: str | None = None,
                  actor: str | None = None) -> list[AuditView]:
        """Return the newest audit rows, newest first."""
        from imucalib.records import access

        return self._run(lambda s: access.audit_rows(s, limit=limit, run_ref=run_ref,
                                                     actor=actor), write=False)

    def station_lock(self, station: str) -> LockView:
        """Return who holds `station`, and who asked for it."""
        from imucalib.records import station_lock

        return self._run(lambda s: station_lock.lock_view(s, station), write=False)

    def take_station(self, station: str, who: str) -> LockView:
        """Take `station`'s lock for `who` (audited ``lock``; StationLockedError if held)."""
        from imucalib.records import access, station_lock

        def work(session: Session) -> LockView:
            before = station_lock.lock_view(session, station)
            view = station_lock.take_lock(session, station, who)
            if before.holder != who:
                access.audit(session, who, "lock", station=station)
            return view
        return self._run(work, write=True)

    def release_station(self, station: str, who: str, *, force: bool = False) -> str:
        """Release `station`'s lock (audited ``unlock``); return who held it."""
        from imucalib.records import access, station_lock

        def work(session: Session) -> str:
            held = station_lock.release_lock(session, station, who, force=force)
            access.audit(session, who, "unlock", station=station,
                         details={"holder": held} if held != who else {})
            return held
        return self._run(work, write=True)

    def request_station(self, station: str, who: str) -> LockView:
        """Ask for `station`'s lock held by another user (audited ``lock_request``)."""
        from imucalib.records import access, station_lock

        def work(session: Session) -> LockView:
            view = station_lock.request_lock(session, station, who)
            access.audit(session, who, "lock_request", station=station,
                         details={"holder": view.holder})
            return view
        return self._run(work, write=True)
