"""The calibration records database: units, stations, equipment, runs, results, reviews, users.

Every row is chained by hash to the one before it in its table, nothing is updated or deleted
(an amendment is a new version), and :meth:`Records.verify` names every edited or deleted row and
every changed or missing recording (docs/records.md).

Contents
--------
:func:`open_records`, :class:`Records` (:mod:`imucalib.records.api`)
    Open a database (SQLite by default, PostgreSQL by URL) and append to or query it.
:mod:`imucalib.records.schema`
    The SQLAlchemy models; :mod:`imucalib.records.migrations` the Alembic revisions.
:mod:`imucalib.records.canonical`, :mod:`imucalib.records.chain`, :mod:`imucalib.records.verify`
    The hash chain: canonical form, append, verification.
:mod:`imucalib.records.signing`, :mod:`imucalib.records.keys`, :mod:`imucalib.records.anchor_log`
    The station key (Ed25519) that signs every row, its registration and rotation, and the
    anchor log of chain heads kept beside it.
:mod:`imucalib.records.users`
    Users and roles, who is acting (:func:`resolve_user`), the review control and release.
:mod:`imucalib.records.views`
    What the queries return.
:mod:`imucalib.records.engine`
    The URL rules, the SQLite connection settings, the schema upgrade.
:mod:`imucalib.records.backup`
    Consistent backups to several places with a checksum manifest, their verification, restore.

Importing this package imports no SQLAlchemy; each name loads its module when first used.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from imucalib._lazy import lazy_getattr

if TYPE_CHECKING:
    from imucalib.records.api import DEFAULT_INTERVAL_DAYS, Records, open_records
    from imucalib.records.engine import ENV_VAR, default_url, resolve_url
    from imucalib.records.users import ROLES, USER_ENV, resolve_user
    from imucalib.records.views import (
        ChainHead,
        DriftPoint,
        DueUnit,
        EquipmentView,
        HistoryEntry,
        KeyUse,
        ParameterRow,
        Problem,
        ReleaseStatus,
        ReviewView,
        RunView,
        UserEventView,
        UserView,
        VerifyReport,
    )

__all__ = ["DEFAULT_INTERVAL_DAYS", "ENV_VAR", "ROLES", "USER_ENV", "ChainHead", "DriftPoint",
           "DueUnit", "EquipmentView", "HistoryEntry", "KeyUse", "ParameterRow", "Problem",
           "Records", "ReleaseStatus", "ReviewView", "RunView", "UserEventView", "UserView",
           "VerifyReport", "default_url", "open_records", "resolve_url", "resolve_user"]

_API, _ENGINE, _VIEWS = "imucalib.records.api", "imucalib.records.engine", "imucalib.records.views"
_USERS = "imucalib.records.users"
__getattr__ = lazy_getattr(__name__, {
    "DEFAULT_INTERVAL_DAYS": _API, "Records": _API, "open_records": _API,
    "ENV_VAR": _ENGINE, "default_url": _ENGINE, "resolve_url": _ENGINE,
    **dict.fromkeys(("ChainHead", "DriftPoint", "DueUnit", "EquipmentView", "HistoryEntry",
                     "KeyUse", "ParameterRow", "Problem", "ReleaseStatus", "ReviewView",
                     "RunView", "UserEventView", "UserView", "VerifyReport"), _VIEWS),
    "ROLES": _USERS, "USER_ENV": _USERS, "resolve_user": _USERS,
})
