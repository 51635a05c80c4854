"""Users, roles, who is acting, and the review control (docs/records.md, "Users and roles").

Contents
--------
:data:`ROLES`, :data:`REVIEW_ROLES`, :data:`USER_ENV`
    The roles; those that may review; ``IMUCALIB_USER``.
:func:`resolve_user`
    Who is acting: ``--user NAME``, else ``$IMUCALIB_USER``, else the configured default (a
    parameter: the laboratory configuration file's default operator); when the database has
    users, none given is refused. Never the operating-system account.
:func:`add_user`, :func:`change_user`, :func:`users_of`, :func:`user_view`
    Session-level work behind :meth:`Records.add_user <imucalib.records.api.Records.add_user>`
    and the others.
:func:`check_operator`, :func:`check_review`, :func:`release_status`
    The controls at write time (a run's operator, a review), and what "released" means.

Rules
-----
(U.1) Bootstrap: a database without any user (a single-person setup) keeps the behaviour of
      before users existed: whoever is named acts, nothing is checked, the name is recorded as
      given. From the first user on, every controlled action names an active user.
(U.2) Adding, disabling or enabling a user: once users exist, the actor must be an active user,
      and, once an active admin exists, an admin. The last active admin, and the last active
      user, cannot be disabled.
(U.3) A review is made by an active user whose role is reviewer or admin, who is not the
      operator of the result's run (by name or initials, case and surrounding spaces ignored);
      only the current version of a result is reviewed; a rejection says why.
(U.4) A result is released when the latest review of its current version approves it and that
      review's reviewer was authorised under (U.3) *when the review was made* (the users and
      their state changes up to the review's ``created_utc``). A review made while the database
      had no users authorises nothing, so nothing is released without registered reviewers.
(U.5) Once users exist, a run's operator is an active user (any role but observer), recorded
      by name (:meth:`Records.record_run <imucalib.records.api.Records.record_run>` refuses
      another).
"""

from __future__ import annotations

import os
from datetime import UTC, datetime
from typing import TYPE_CHECKING, Final

from sqlalchemy import select
from sqlalchemy.orm import Session

from imucalib.errors import InvalidInputError, RecordsError
from imucalib.records import chain
from imucalib.records.schema import Result, Review, Run, User, UserEvent
from imucalib.records.views import ReleaseStatus, UserEventView, UserView

if TYPE_CHECKING:
    from imucalib.records.api import Records

__all__ = ["RECORD_ROLES", "REVIEW_ROLES", "ROLES", "USER_ENV", "add_user", "change_user",
           "check_operator", "check_review", "release_status", "resolve_user", "user_view",
           "users_of"]

#: The roles a user of the records can have.
RECORD_ROLES: Final = ("operator", "engineer", "reviewer", "admin")
#: Every role: the records' and ``observer``, who only watches the web pages (docs/web.md).
ROLES: Final = (*RECORD_ROLES, "observer")
#: The roles that may review (approve or reject) a result.
REVIEW_ROLES: Final = frozenset({"reviewer", "admin"})
#: The environment variable naming who is acting.
USER_ENV: Final = "IMUCALIB_USER"
#: A user's state changes.
EVENTS: Final = ("disable", "enable")


def _utc(value: datetime) -> datetime:
    return value.replace(tzinfo=UTC) if value.tzinfo is None else value.astimezone(UTC)


def _fold(text: str) -> str:
    return " ".join(text.split()).casefold()


def _names(users: list[UserView]) -> str:
    return ", ".join(f"{u.name} ({u.role})" for u in users) or "none"


# --- reading ---------------------------------------------------------------------------------
def _events(session: Session, user_id: int) -> list[UserEvent]:
    return list(session.scalars(select(UserEvent).where(UserEvent.user_id == user_id)
                                .order_by(UserEvent.seq)))


def user_view(session: Session, user: User) -> UserView:
    """Return `user` with its state changes and whether it is active now."""
    events = _events(session, user.id)
    return UserView(user.id, user.name, user.initials, user.role,
                    not events or events[-1].event != "disable", _utc(user.created_utc),
                    user.added_by,
                    tuple(UserEventView(e.event, e.reason, e.by_user, _utc(e.created_utc))
                          for e in events))


def users_of(session: Session) -> list[UserView]:
    """Return every user, in the order they were added."""
    return [user_view(session, u) for u in session.scalars(select(User).order_by(User.seq))]


def _find(session: Session, name: str) -> User | None:
    return session.scalars(select(User).where(User.name == name)).first()


def _active_at(session: Session, user: User, at: datetime | None) -> bool:
    """Whether `user` existed and was active at `at` (None: now)."""
    if at is not None and _utc(user.created_utc) > at:
        return False
    state = True
    for e in _events(session, user.id):
        if at is not None and _utc(e.created_utc) > at:
            break
        state = e.event != "disable"
    return state


def _has_users(session: Session, at: datetime | None = None) -> bool:
    first = session.scalars(select(User.created_utc).order_by(User.seq).limit(1)).first()
    return first is not None and (at is None or _utc(first) <= at)


# --- who is acting ---------------------------------------------------------------------------
def _match(users: list[UserView], name: str) -> UserView | None:
    for test in (lambda u: u.name == name, lambda u: _fold(u.name) == _fold(name)):
        found = [u for u in users if test(u)]
        if found:
            return found[0]
    by_initials = [u for u in users if u.initials and _fold(u.initials) == _fold(name)]
    return by_initials[0] if len(by_initials) == 1 else None


def resolve_user(records: Records, given: str | None = None, *, configured: str | None = None,
                 action: str = "act") -> str:
    """Return the name of the user who is acting (rule (U.1) in the module docstring).

    Parameters
    ----------
    records : Records
    given : str, optional
        ``--user NAME`` (a user's name, or their initials when no one else has them).
    configured : str, optional
        The default from the laboratory configuration file; used after ``$IMUCALIB_USER``.
    action : str
        What the user is about to do, for the message (``"review a result"``).

    Returns
    -------
    str
        The user's registered name; without users, the name as given ("" when none was).

    Raises
    ------
    RecordsError
        The database has users and none was named, or the one named is unknown or disabled.
    """
    sources = ((given, "--user"), (os.environ.get(USER_ENV), USER_ENV),
               (configured, "the configuration's default user"))
    name, source = next(((n.strip(), s) for n, s in sources if n and n.strip()), ("", ""))
    users = records.users()
    if not users:
        return name
    active = [u for u in users if u.active]
    if not name:
        raise RecordsError(f"who is acting? the records database {records.url} has users, so to "
                           f"{action} pass --user NAME or set {USER_ENV} (active users: "
                           f"{_names(active)})")
    found = _match(users, name)
    if found is None:
        raise RecordsError(f"{source} names {name!r}, who is not a user of {records.url} "
                           f"(active users: {_names(active)})")
    if not found.active:
        why = found.events[-1].reason if found.events else ""
        raise RecordsError(f"user {found.name!r} ({source}) is disabled ({why}); active users: "
                           f"{_names(active)}")
    return found.name


# --- writing ---------------------------------------------------------------------------------
def _actor(session: Session, by: str | None, action: str) -> str:
    """Return the acting user's name under (U.2); "" or `by` as given without users."""
    if not _has_users(session):
        return (by or "").strip()
    everyone = users_of(session)
    active = [u for u in everyone if u.active]
    admins = [u for u in active if u.role == "admin"]
    who = next((u for u in everyone if u.name == (by or "").strip()), None)
    if not by or not by.strip():
        raise RecordsError(f"to {action}, name who is acting (--user NAME or {USER_ENV}): the "
                           f"records have users ({_names(admins or active)})")
    if who is None or not who.active:
        raise RecordsError(f"to {action}, the acting user must be an active user; "
                           f"{by!r} is {'disabled' if who else 'not a user'} (active users: "
                           f"{_names(active)})")
    if admins and who.role != "admin":
        raise RecordsError(f"only an admin may {action}; {who.name} is {_article(who.role)} "
                           f"(admins: {_names(admins)})")
    return who.name


def _article(role: str) -> str:
    return f"an {role}" if role[:1] in "aeiou" else f"a {role}"


def add_user(session: Session, name: str, initials: str, role: str, by: str | None) -> int:
    """Append a user and return its id (rules (U.1), (U.2))."""
    name = " ".join(name.split())
    if not name:
        raise InvalidInputError("a user needs a name; got an empty one")
    if role not in ROLES:
        raise InvalidInputError(f"role must be one of {', '.join(RECORD_ROLES)}; got {role!r} "
                                "(or observer: read-only web pages)")
    initials = initials.strip()
    chain.lock(session, User)
    actor = _actor(session, by, "add a user")
    clash = next((u for u in session.scalars(select(User)) if _fold(u.name) == _fold(name)),
                 None)
    if clash is not None:
        raise RecordsError(f"a user named {clash.name!r} is already recorded (users are never "
                           "removed: disable or enable them)")
    return int(chain.append(session, User(name=name, initials=initials, role=role,
                                          added_by=actor)).id)


def change_user(session: Session, name: str, event: str, reason: str, by: str | None) -> int:
    """Append a ``disable`` or ``enable`` of user `name`; return the event's id (rule (U.2))."""
    if event not in EVENTS:
        raise InvalidInputError(f"event must be one of {', '.join(EVENTS)}; got {event!r}")
    if not reason.strip():
        raise InvalidInputError(f"to {event} a user, give a reason; got an empty one")
    chain.lock(session, User)
    chain.lock(session, UserEvent)
    user = _find(session, name)
    if user is None:
        known = _names(users_of(session))
        raise RecordsError(f"no user named {name!r} in the records; users: {known}")
    actor = _actor(session, by, f"{event} a user")
    view = user_view(session, user)
    if event == "disable":
        if not view.active:
            raise RecordsError(f"user {user.name!r} is already disabled")
        others = [u for u in users_of(session) if u.active and u.user_id != user.id]
        if not others:
            raise RecordsError(f"user {user.name!r} is the last active user; add another "
                               "before disabling them")
        if user.role == "admin" and not any(u.role == "admin" for u in others):
            raise RecordsError(f"user {user.name!r} is the last active admin; add or enable "
                               "another admin first")
    elif view.active:
        raise RecordsError(f"user {user.name!r} is already active")
    return int(chain.append(session, UserEvent(user_id=user.id, event=event,
                                               reason=reason.strip(), by_user=actor)).id)


# --- the controls ------------------------------------------------------------------------------
def check_operator(session: Session, operator: str) -> str:
    """Refuse a run operator that (U.5) forbids; return the name to record."""
    if not _has_users(session):
        return operator                                 # (U.1): recorded as given
    name = operator.strip()
    user = _find(session, name) if name else None
    if user is not None and _active_at(session, user, None) and user.role != "observer":
        return user.name
    if user is not None and user.role == "observer" and _active_at(session, user, None):
        raise RecordsError(f"a run's operator must not be an observer (observers only watch); "
                           f"{user.name} is an observer")
    active = _names([u for u in users_of(session) if u.active])
    what = ("no operator was named" if not name else
            f"the operator {name!r} is {'disabled' if user else 'not a user of the records'}")
    raise RecordsError(f"a run's operator must be an active user once the records have users; "
                       f"{what} (name one with --operator/--user NAME or {USER_ENV}; active "
                       f"users: {active})")


def _successor(session: Session, result_id: int) -> int | None:
    found = session.scalars(select(Result.id).where(Result.replaces_id == result_id)).first()
    return None if found is None else int(found)


def _operated(session: Session, result: Result, user: User) -> bool:
    run = session.get(Run, result.run_id)
    operator = _fold(run.operator) if run is not None else ""
    return bool(operator) and operator in {_fold(user.name), _fold(user.initials or "\0")}


def _unauthorised(session: Session, result: Result, reviewer: str,
                  at: datetime | None) -> str:
    """Why `reviewer` may not review `result` at `at` (None: now) under (U.3); "" if they may."""
    user = _find(session, reviewer)
    if user is None or (at is not None and _utc(user.created_utc) > at):
        return f"{reviewer} is not a registered user"
    if not _active_at(session, user, at):
        return f"{user.name} is disabled"
    if user.role not in REVIEW_ROLES:
        return f"{user.name} is {_article(user.role)}: only a reviewer or an admin may review"
    if _operated(session, result, user):
        return (f"{user.name} is the operator of run {result.run_id}: a result is reviewed by "
                "someone other than its operator")
    return ""


def check_review(session: Session, result_id: int, who: str, approved: bool,
                 comment: str) -> str:
    """Refuse a review that (U.3) forbids; return the reviewer's name as it is recorded."""
    result = session.get(Result, result_id)
    if result is None:
        raise RecordsError(f"no result with id {result_id} in the records")
    newer = _successor(session, result_id)
    if newer is not None:
        raise RecordsError(f"result {result_id} was amended by result {newer}; review the "
                           f"current version")
    if not approved and not comment.strip():
        raise InvalidInputError("a rejection needs a comment saying why (--comment …)")
    if not _has_users(session):
        return who                                      # (U.1): nothing to check against
    why = _unauthorised(session, result, who, None)
    if why:
        reviewers = [u for u in users_of(session) if u.active and u.role in REVIEW_ROLES]
        raise RecordsError(f"review of result {result_id} refused: {why} (reviewers: "
                           f"{_names(reviewers)})")
    return who


def release_status(session: Session, result_id: int) -> ReleaseStatus:
    """Return whether result `result_id` is released, by whom, when (rule (U.4))."""
    result = session.get(Result, result_id)
    if result is None:
        raise RecordsError(f"no result with id {result_id} in the records")
    current, newer = result_id, _successor(session, result_id)
    while newer is not None:
        current, newer = newer, _successor(session, newer)
    review = session.scalars(select(Review).where(Review.result_id == result_id)
                             .order_by(Review.seq.desc()).limit(1)).first()
    if review is None:
        reason = f"result {result_id} has no review"
        if current != result_id:
            reason = f"result {result_id} was amended (current version: result {current})"
        return ReleaseStatus(result_id, current, False, None, "", "", "", None, "", None,
                             False, reason)
    at = _utc(review.created_utc)
    user = _find(session, review.reviewer)
    registered = user is not None and _utc(user.created_utc) <= at
    why = ("no users were registered when it was reviewed (a review counts once reviewers "
           "are users: imucalib users add)" if not _has_users(session, at)
           else _unauthorised(session, result, review.reviewer, at))
    decision = "approve" if review.approved else "reject"
    when = at if review.reviewed_utc is None else _utc(review.reviewed_utc)
    who = review.reviewer
    if registered and user is not None:
        who = f"{user.name} ({', '.join(filter(None, (user.initials, user.role)))})"
    said = (f"{'approved' if review.approved else 'rejected'} by {who} on "
            f"{when:%Y-%m-%d %H:%M} UTC{': ' + review.comment if review.comment else ''}")
    if current != result_id:
        reason = f"result {result_id} was amended (current version: result {current}); {said}"
    elif why:
        reason = f"{said}; not authorised: {why}"
    else:
        reason = said
    return ReleaseStatus(
        result_id=result_id, current_id=current,
        released=current == result_id and review.approved and not why, decision=decision,
        reviewer=review.reviewer, reviewer_initials=user.initials if registered and user else "",
        reviewer_role=user.role if registered and user else "", reviewed_utc=when,
        comment=review.comment, review_id=int(review.id), authorised=not why, reason=reason)
