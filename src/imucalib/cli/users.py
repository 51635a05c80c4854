"""``imucalib users …``: the people who act on the records and their roles (docs/records.md).

``add``, ``list``, ``disable``, ``enable``, ``set-password`` (the web page's login,
docs/web.md); every command takes ``--db URL``. Who is acting
(``--user NAME``, else ``$IMUCALIB_USER``) is resolved by
:func:`imucalib.records.users.resolve_user`: once the database has users, adding, disabling or
enabling one needs an active user (an admin, once there is one), and none named is refused.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated

import typer
from rich.table import Table

from imucalib.cli._app import app, console, fail, typer_app
from imucalib.cli.records import Db, Json, _jsonable, _open
from imucalib.errors import CalibrationError

if TYPE_CHECKING:
    from imucalib.records.api import Records

__all__ = ["users_app"]

users_app = typer_app(help="The users of the records database and their roles (operator, "
                           "engineer, reviewer, admin; docs/records.md).",
                      no_args_is_help=True)
app.add_typer(users_app, name="users")

Acting = Annotated[str | None, typer.Option(
    "--user", help="Who is acting (a user's name or initials; default $IMUCALIB_USER). Needed "
                   "once the database has users.")]
Reason = Annotated[str, typer.Option("--reason", help="Why (recorded).")]


def _actor(records: Records, user: str | None, action: str) -> str | None:
    from imucalib.records.users import resolve_user

    return resolve_user(records, user, action=action) or None


@users_app.command()
def add(name: Annotated[str, typer.Argument(help="The user's name, as it will be recorded.")],
        role: Annotated[str, typer.Option(
            help="operator, engineer, reviewer or admin (reviewers and admins may review).")],
        initials: Annotated[str, typer.Option(help="The user's initials.")] = "",
        user: Acting = None, db: Db = None) -> None:
    """Add a user with a role.

    The first user is added by anyone; after that --user (or $IMUCALIB_USER) names who adds
    them: an active user, and an admin once there is one.
    """
    try:
        with _open(db) as records:
            uid = records.add_user(name, initials, role,
                                   by=_actor(records, user, "add a user"))
            where = records.url
    except CalibrationError as exc:
        raise fail(exc) from exc
    console.print(f"user {uid}: {name} ({initials or 'no initials'}), {role}, in {where}",
                  highlight=False, soft_wrap=True)


@users_app.command("list")
def list_users(db: Db = None, as_json: Json = False) -> None:
    """List the users, their roles, and whether each is active."""
    try:
        with _open(db) as records:
            rows = records.users()
    except CalibrationError as exc:
        raise fail(exc) from exc
    if as_json:
        import json

        console.print_json(json.dumps(_jsonable(rows)))
        return
    table = Table("name", "initials", "role", "active", "added", "added_by", "last change",
                  title="users")
    for u in rows:
        last = u.events[-1] if u.events else None
        table.add_row(u.name, u.initials, u.role, "yes" if u.active else "no",
                      f"{u.added_utc:%Y-%m-%d}", u.added_by,
                      "" if last is None else
                      f"{last.event}d {last.utc:%Y-%m-%d} by {last.by or '?'}: {last.reason}")
    console.print(table)


@users_app.command()
def disable(name: Annotated[str, typer.Argument(help="The user's name.")], reason: Reason,
            user: Acting = None, db: Db = None) -> None:
    """Disable a user: they can no longer act; what they did stays (a new chained row)."""
    try:
        with _open(db) as records:
            eid = records.disable_user(name, reason,
                                       by=_actor(records, user, "disable a user"))
    except CalibrationError as exc:
        raise fail(exc) from exc
    console.print(f"user {name} disabled (event {eid}): {reason}", highlight=False,
                  soft_wrap=True)


@users_app.command()
def enable(name: Annotated[str, typer.Argument(help="The user's name.")], reason: Reason,
           user: Acting = None, db: Db = None) -> None:
    """Enable a disabled user again (a new chained row)."""
    try:
        with _open(db) as records:
            eid = records.enable_user(name, reason, by=_actor(records, user, "enable a user"))
    except CalibrationError as exc:
        raise fail(exc) from exc
    console.print(f"user {name} enabled (event {eid}): {reason}", highlight=False,
                  soft_wrap=True)


@users_app.command("set-password")
def set_password(
        name: Annotated[str, typer.Argument(help="The user whose password is set.")],
        password_stdin: Annotated[bool, typer.Option(
            "--password-stdin", help="Read the password from the first line of standard input "
                                     "(for scripts) instead of asking twice.")] = False,
        user: Acting = None, db: Db = None) -> None:
    """Set a user's password for the station's web page (docs/web.md).

    A user sets their own (--user NAME, or $IMUCALIB_USER, naming them); an admin sets anyone's.
    The password is asked for twice without echo, or read from standard input; it is stored as
    an argon2id hash in a new chained row.
    """
    import os
    import sys

    from imucalib.errors import InvalidInputError
    from imucalib.records.users import USER_ENV

    try:
        if password_stdin:
            password = sys.stdin.readline().rstrip("\r\n")
        else:
            password = typer.prompt(f"new password for {name}", hide_input=True,
                                    confirmation_prompt=True)
        if not password:
            raise InvalidInputError("a password is needed; got an empty one")
        with _open(db) as records:
            actor = user or os.environ.get(USER_ENV) or name
            rid = records.set_password(name, password, by=actor)
    except CalibrationError as exc:
        raise fail(exc) from exc
    except typer.Abort as exc:
        raise fail(InvalidInputError("no password was given (the prompt was closed)")) from exc
    console.print(f"password of {name} set (row {rid}), by {actor}", highlight=False,
                  soft_wrap=True)
