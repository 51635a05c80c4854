"""Passwords, web sessions and the audit trail of the station's web page (docs/web.md).

Contents
--------
:data:`AUDIT_ACTIONS`, :data:`MIN_PASSWORD_LENGTH`, :data:`SESSION_HOURS`
    What the audit trail records; the shortest password; how long a login lasts.
:func:`hash_password`, :func:`password_matches`
    argon2id hashes (RFC 9106) in their PHC string form.
:func:`set_password`, :func:`authenticate`
    A user's password (a new chained ``user_credentials`` row); who a name and password are.
:func:`create_session`, :func:`session_of`, :func:`end_session`
    Web sessions: the cookie's token is random (256 bits) and only its SHA-256 is stored.
:func:`audit`, :func:`audit_rows`
    Append an audit row (chained, signed) and read them back.

Rules
-----
(A.1) A password is set by its user or, once an active admin exists, by an admin; it has at least
      :data:`MIN_PASSWORD_LENGTH` characters. A user without a password cannot log in.
(A.2) A login succeeds for an active user whose newest password matches; a disabled user's
      sessions stop working at their next request.
(A.3) A session lasts :data:`SESSION_HOURS` from login (no sliding renewal); an expired one is
      deleted when met.
(A.4) After :data:`MAX_FAILED_LOGINS` failed logins of a name within
      :data:`FAILED_LOGIN_WINDOW_MIN` minutes (and since the user's newest password), that
      name's logins are refused (:class:`LoginThrottledError`) until the window has passed or a
      new password is set; the failures are audit rows.
"""

from __future__ import annotations

import hashlib
import secrets
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from typing import Any, Final

from sqlalchemy import delete, select
from sqlalchemy.orm import Session

from imucalib.errors import InvalidInputError, RecordsError
from imucalib.records import chain
from imucalib.records.canonical import canonical_json
from imucalib.records.schema import AuditEvent, Credential, User, WebSession
from imucalib.records.views import UserView

__all__ = ["AUDIT_ACTIONS", "FAILED_LOGIN_WINDOW_MIN", "MAX_FAILED_LOGINS",
           "MIN_PASSWORD_LENGTH", "SESSION_HOURS", "AuditView", "LoginSession",
           "LoginThrottledError", "audit", "audit_rows", "authenticate", "check_throttle",
           "create_session", "end_session", "hash_password", "password_matches", "session_of",
           "set_password", "token_hash"]

#: The actions an audit row names.
AUDIT_ACTIONS: Final = ("login", "logout", "login_failed", "start", "prompt_answer", "abort",
                        "resume", "lock", "unlock", "lock_request", "review", "approve",
                        "reject", "set_password", "calibrate", "override_due")
#: The shortest password accepted. [characters]
MIN_PASSWORD_LENGTH: Final = 8
#: How long a web session lasts after login. [h]
SESSION_HOURS: Final = 8.0
#: Failed logins of one name that stop its logins for a while (rule (A.4)).
MAX_FAILED_LOGINS: Final = 10
#: The window over which failed logins are counted. [min]
FAILED_LOGIN_WINDOW_MIN: Final = 15
#: argon2id's cost (argon2-cffi's defaults, RFC 9106's second recommendation: 3 passes over
#: 64 MiB); tests lower it.
ARGON2_PARAMS: dict[str, int] = {"time_cost": 3, "memory_cost": 65536, "parallelism": 4}
#: A hash :func:`authenticate` checks for an unknown name, so that the answer takes as long.
_DUMMY: list[str] = []


class LoginThrottledError(RecordsError):
    """Too many failed logins of one name lately (rule (A.4))."""


@dataclass(frozen=True)
class AuditView:
    """One audit row: its sequence number, when, who, what, at which station, on which run."""

    seq: int
    utc: datetime
    actor: str
    action: str
    station: str
    run_ref: str
    details: dict[str, Any]


@dataclass(frozen=True)
class LoginSession:
    """A valid web session: its user (as now), its CSRF token and when it expires."""

    user: UserView
    csrf_token: str
    expires_utc: datetime


def _utc(value: datetime) -> datetime:
    return value.replace(tzinfo=UTC) if value.tzinfo is None else value.astimezone(UTC)


def hash_password(password: str) -> str:
    """Return the argon2id hash of `password` (PHC string: parameters and salt inside)."""
    from argon2 import PasswordHasher

    p = ARGON2_PARAMS
    return PasswordHasher(time_cost=p["time_cost"], memory_cost=p["memory_cost"],
                          parallelism=p["parallelism"]).hash(password)


def password_matches(stored: str, password: str) -> bool:
    """Return whether `password` matches the argon2 hash `stored` (False for a damaged hash)."""
    from argon2 import PasswordHasher
    from argon2.exceptions import Argon2Error, InvalidHashError

    try:
        return bool(PasswordHasher().verify(stored, password))
    except (Argon2Error, InvalidHashError, ValueError):
        return False


def token_hash(token: str) -> str:
    """Return the SHA-256 (hex) under which a session token is stored."""
    return hashlib.sha256(token.encode()).hexdigest()


def _user(session: Session, name: str) -> User | None:
    return session.scalars(select(User).where(User.name == " ".join(name.split()))).first()


def set_password(session: Session, name: str, password: str, by: str | None) -> int:
    """Append a new password of user `name` (rule (A.1)); return the row's id.

    Raises
    ------
    RecordsError
        No such user, or an actor who may not set it.
    InvalidInputError
        A password shorter than :data:`MIN_PASSWORD_LENGTH`.
    """
    from imucalib.records import users

    if len(password) < MIN_PASSWORD_LENGTH:
        raise InvalidInputError(f"a password needs at least {MIN_PASSWORD_LENGTH} characters; "
                                f"got {len(password)}")
    chain.lock(session, Credential)
    user = _user(session, name)
    if user is None:
        known = ", ".join(u.name for u in users.users_of(session)) or "none"
        raise RecordsError(f"no user named {name!r} in the records; users: {known}")
    view = users.user_view(session, user)
    actor = (by or "").strip()
    if not (actor == user.name and view.active):
        actor = users._actor(session, by, "set another user's password")
    return int(chain.append(session, Credential(user_id=user.id,
                                                password_hash=hash_password(password),
                                                by_user=actor)).id)


def authenticate(session: Session, name: str, password: str) -> UserView | None:
    """Return the active user `name` if `password` is their newest one (rule (A.2)), else None."""
    from imucalib.records import users

    user = _user(session, name) if name.strip() else None
    stored = None
    if user is not None:
        stored = session.scalars(select(Credential.password_hash)
                                 .where(Credential.user_id == user.id)
                                 .order_by(Credential.seq.desc()).limit(1)).first()
    if user is None or stored is None:
        if not _DUMMY or f"m={ARGON2_PARAMS['memory_cost']}," not in _DUMMY[0]:
            _DUMMY[:] = [hash_password(secrets.token_hex(8))]
        password_matches(_DUMMY[0], password)           # as long as a real check
        return None
    if not password_matches(stored, password):
        return None
    view = users.user_view(session, user)
    return view if view.active else None


def check_throttle(session: Session, name: str) -> None:
    """Refuse a login of `name` after too many recent failures (rule (A.4)).

    Raises
    ------
    LoginThrottledError
        :data:`MAX_FAILED_LOGINS` failures within the window.
    """
    from sqlalchemy import func

    since = datetime.now(UTC) - timedelta(minutes=FAILED_LOGIN_WINDOW_MIN)
    user = _user(session, name) if name.strip() else None
    if user is not None:
        newest = session.scalar(select(func.max(Credential.created_utc))
                                .where(Credential.user_id == user.id))
        if newest is not None and _utc(newest) > since:
            since = _utc(newest)
    failed = session.scalar(select(func.count()).select_from(AuditEvent).where(
        AuditEvent.action == "login_failed", AuditEvent.actor == name.strip()[:200],
        AuditEvent.created_utc >= since))
    if int(failed or 0) >= MAX_FAILED_LOGINS:
        raise LoginThrottledError(f"{failed} failed logins of {name.strip()!r} in the last "
                                  f"{FAILED_LOGIN_WINDOW_MIN} min: expected a login after the "
                                  "window has passed, or after an admin sets a new password")


def create_session(session: Session, user_name: str,
                   hours: float = SESSION_HOURS) -> tuple[str, str, datetime]:
    """Start a session of `user_name`; return its token, CSRF token and expiry (rule (A.3))."""
    now = datetime.now(UTC)
    session.execute(delete(WebSession).where(WebSession.expires_utc <= now))
    token, csrf = secrets.token_urlsafe(32), secrets.token_urlsafe(32)
    expires = now + timedelta(hours=hours)
    session.add(WebSession(token_hash=token_hash(token), user_name=user_name, created_utc=now,
                           expires_utc=expires, csrf_token=csrf))
    session.flush()
    return token, csrf, expires


def session_of(session: Session, token: str) -> LoginSession | None:
    """Return the live session of cookie `token` with its active user, else None (A.2), (A.3)."""
    from imucalib.records import users

    if not token:
        return None
    row = session.scalars(select(WebSession)
                          .where(WebSession.token_hash == token_hash(token))).first()
    if row is None or _utc(row.expires_utc) <= datetime.now(UTC):
        return None
    user = _user(session, row.user_name)
    if user is None:
        return None
    view = users.user_view(session, user)
    if not view.active:
        return None
    return LoginSession(view, row.csrf_token, _utc(row.expires_utc))


def end_session(session: Session, token: str) -> str:
    """Delete the session of cookie `token`; return its user's name ("" if there was none)."""
    row = session.scalars(select(WebSession)
                          .where(WebSession.token_hash == token_hash(token))).first()
    if row is None:
        return ""
    name = row.user_name
    session.delete(row)
    session.flush()
    return name


def audit(session: Session, actor: str, action: str, *, station: str = "", run_ref: str = "",
          details: dict[str, Any] | None = None) -> int:
    """Append an audit row (chained and signed) and return its sequence number.

    Raises
    ------
    InvalidInputError
        An action not in :data:`AUDIT_ACTIONS`, or details that are not JSON-able.
    """
    if action not in AUDIT_ACTIONS:
        raise InvalidInputError(f"audit action must be one of {', '.join(AUDIT_ACTIONS)}; got "
                                f"{action!r}")
    try:
        text = canonical_json(dict(details or {}))
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"audit details must be JSON-able; got {details!r}") from exc
    return int(chain.append(session, AuditEvent(actor=actor[:200], action=action,
                                                station=station[:200], run_ref=run_ref[:200],
                                                details_json=text)).seq)


def audit_rows(session: Session, *, limit: int = 200, run_ref: str | None = None,
               actor: str | None = None) -> list[AuditView]:
    """Return the newest `limit` audit rows (optionally of one run or actor), newest first."""
    import json

    query = select(AuditEvent).order_by(AuditEvent.seq.desc()).limit(limit)
    if run_ref is not None:
        query = query.where(AuditEvent.run_ref == run_ref)
    if actor is not None:
        query = query.where(AuditEvent.actor == actor)
    out = []
    for row in session.scalars(query):
        try:
            details = json.loads(row.details_json or "{}")
        except ValueError:
            details = {"unreadable": row.details_json}
        out.append(AuditView(int(row.seq), _utc(row.created_utc), row.actor, row.action,
                             row.station, row.run_ref, details if isinstance(details, dict)
                             else {"value": details}))
    return out
