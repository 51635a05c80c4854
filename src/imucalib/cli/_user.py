"""Who is acting at the command line: a registered user, never the OS account silently.

The name comes from ``--user``/``--operator``, else ``$IMUCALIB_USER``, else the laboratory
configuration's ``[operator] default`` (docs/configuration.md); once the records database has
users, it must be an active one (:func:`imucalib.records.users.resolve_user`, rule (U.1) in
docs/records.md). A database without users (a single-person set-up) takes the name as given;
when none is given at all, the OS account is used and the terminal says so.
"""

from __future__ import annotations

import getpass

__all__ = ["acting_user"]


def acting_user(given: str | None, *, db: str | None, record: bool, action: str
                ) -> tuple[str, str]:
    """Return the name to record as the one who acts (module docstring).

    Parameters
    ----------
    given : str or None
        ``--user``/``--operator``.
    db : str or None
        ``--db``.
    record : bool
        Whether the records are used at all (``--no-record``: the name is not checked).
    action : str
        What the user does, for the messages (``"run a plan"``).

    Returns
    -------
    name : str
    note : str
        One line to print once the action has succeeded when the OS account was taken (else
        empty): the terminal says whose name was recorded.

    Raises
    ------
    RecordsError
        The database has users and none (or an unknown or disabled one) was named.
    """
    from imucalib.config import load_config
    from imucalib.records.users import USER_ENV

    configured = load_config().operator.default or None
    name = ""
    if record:
        from imucalib.records import open_records
        from imucalib.records.users import resolve_user

        with open_records(db) as records:
            name = resolve_user(records, given, configured=configured, action=action)
    else:
        import os

        name = next((n.strip() for n in (given, os.environ.get(USER_ENV), configured)
                     if n and n.strip()), "")
    if not name:
        name = getpass.getuser()
        done = "recorded" if record else "named in the result"
        return name, (f"note: {done} as {name!r} (the OS account): name who acts with "
                      f"--user, ${USER_ENV} or the configuration's [operator] default")
    return name, ""
