"""The tables of the calibration records database (SQLAlchemy 2 declarative models).

Contents
--------
:class:`Base`
    The declarative base; ``Base.metadata`` is what the migrations create.
:class:`Unit`, :class:`Station`, :class:`Equipment`, :class:`Run`, :class:`Result`,
:class:`Review`, :class:`User`, :class:`UserEvent`, :class:`SigningKey`, :class:`Credential`,
:class:`AuditEvent`
    The chained tables: each row carries ``seq`` (1, 2, … per table, equal to its ``id``),
    ``prev_hash`` and ``row_hash`` (docs/records.md, Eqs. (R.1)–(R.3)).
:class:`RunEquipment`, :class:`ResultParameter`
    Child rows hashed with their parent (a run's equipment, a result's parameters).
:data:`CHAINED`
    The chained models in the order :meth:`~imucalib.records.api.Records.verify` checks them.
:class:`WebSession`, :class:`StationLock`
    The web server's working state (docs/web.md): sessions and the station lock. They are not
    records: rows are updated and deleted (a logout, a lock released), nothing is hashed; what
    happened is in :class:`AuditEvent`.

Nothing here is ever updated or deleted by :class:`~imucalib.records.api.Records`: an amendment
is a new :class:`Result` whose ``replaces_id`` names the one it replaces, a new certificate a new
:class:`Equipment` row whose ``replaces_id`` names the old one, a disabled user a new
:class:`UserEvent` row. JSON documents (a unit's
specification, a run's environment, a result's verification and full result document) are
stored as canonical JSON text (:func:`imucalib.records.canonical.canonical_json`), so that the
text hashed is the text stored.
"""

# No ``from __future__ import annotations`` here: SQLAlchemy reads every ``Mapped[...]``
# annotation, and an evaluated one saves it parsing the text of each (a command that opens the
# records starts faster, bench/bench_cli_startup.py).
from datetime import date, datetime
from typing import Final

from sqlalchemy import (
    Boolean,
    Date,
    DateTime,
    Float,
    ForeignKey,
    Integer,
    MetaData,
    String,
    Text,
)
from sqlalchemy.orm import DeclarativeBase, Mapped, mapped_column

__all__ = [
    "CHAINED",
    "AuditEvent",
    "Base",
    "Credential",
    "Equipment",
    "Result",
    "ResultParameter",
    "Review",
    "Run",
    "RunEquipment",
    "SigningKey",
    "Station",
    "StationLock",
    "Unit",
    "User",
    "UserEvent",
    "WebSession",
]

#: Constraint names Alembic can find again (the migrations use the same convention).
NAMING: Final = {
    "ix": "ix_%(column_0_label)s",
    "uq": "uq_%(table_name)s_%(column_0_name)s",
    "ck": "ck_%(table_name)s_%(constraint_name)s",
    "fk": "fk_%(table_name)s_%(column_0_name)s_%(referred_table_name)s",
    "pk": "pk_%(table_name)s",
}
HASH_LEN: Final = 64


class Base(DeclarativeBase):
    """Declarative base of the records tables."""

    metadata = MetaData(naming_convention=NAMING)


class _Chained:
    """The chain columns every chained table has (docs/records.md, "The hash chain")."""

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=False)
    seq: Mapped[int] = mapped_column(Integer, unique=True)
    prev_hash: Mapped[str] = mapped_column(String(HASH_LEN))
    row_hash: Mapped[str] = mapped_column(String(HASH_LEN))
    created_utc: Mapped[datetime] = mapped_column(DateTime(timezone=True))
    #: 1: Eq. (R.1) over the row's columns (rows made before revision 0003, unsigned);
    #: 2: Eq. (R.1) with the table name, ``hash_version`` and ``key_id`` in C, signed (R.7).
    hash_version: Mapped[int] = mapped_column(Integer, default=2, server_default="1")
    key_id: Mapped[int | None] = mapped_column(Integer, nullable=True)
    signature: Mapped[str] = mapped_column(Text, default="", server_default="")


class Unit(_Chained, Base):
    """An IMU unit, known by its serial number."""

    __tablename__ = "units"
    serial: Mapped[str] = mapped_column(String(200), unique=True)
    model: Mapped[str] = mapped_column(String(200), default="")
    maker: Mapped[str] = mapped_column(String(200), default="")
    specification_json: Mapped[str] = mapped_column(Text, default="{}")
    recal_interval_days: Mapped[int | None] = mapped_column(Integer, nullable=True)


class Station(_Chained, Base):
    """A calibration station (a place where runs are made)."""

    __tablename__ = "stations"
    name: Mapped[str] = mapped_column(String(200), unique=True)
    location: Mapped[str] = mapped_column(String(400), default="")


class Equipment(_Chained, Base):
    """A piece of equipment of a station with its own calibration certificate."""

    __tablename__ = "equipment"
    station_id: Mapped[int | None] = mapped_column(ForeignKey("stations.id"), nullable=True)
    kind: Mapped[str] = mapped_column(String(100))
    model: Mapped[str] = mapped_column(String(200), default="")
    serial: Mapped[str] = mapped_column(String(200), default="")
    certificate: Mapped[str] = mapped_column(String(200), default="")
    calibrated_on: Mapped[date | None] = mapped_column(Date, nullable=True)
    due_on: Mapped[date | None] = mapped_column(Date, nullable=True)
    replaces_id: Mapped[int | None] = mapped_column(ForeignKey("equipment.id"), nullable=True,
                                                    unique=True)


class Run(_Chained, Base):
    """One execution of a plan on a station: the recording it left and its circumstances."""

    __tablename__ = "runs"
    plan_name: Mapped[str] = mapped_column(String(200), default="", index=True)
    plan_hash: Mapped[str] = mapped_column(String(HASH_LEN), default="", index=True)
    procedure: Mapped[str] = mapped_column(String(50), default="")
    recording_path: Mapped[str] = mapped_column(Text, default="")
    recording_sha256: Mapped[str] = mapped_column(String(HASH_LEN), default="")
    environment_json: Mapped[str] = mapped_column(Text, default="{}")
    operator: Mapped[str] = mapped_column(String(200), default="")
    software_version: Mapped[str] = mapped_column(String(50), default="")
    station_id: Mapped[int | None] = mapped_column(ForeignKey("stations.id"), nullable=True)
    started_utc: Mapped[datetime | None] = mapped_column(DateTime(timezone=True), nullable=True)
    ended_utc: Mapped[datetime | None] = mapped_column(DateTime(timezone=True), nullable=True)


class RunEquipment(Base):
    """The equipment a run used (hashed with the run)."""

    __tablename__ = "run_equipment"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    run_id: Mapped[int] = mapped_column(ForeignKey("runs.id"), index=True)
    equipment_id: Mapped[int] = mapped_column(ForeignKey("equipment.id"))


class Result(_Chained, Base):
    """The result of one unit in one run, version 1, or an amendment (version > 1)."""

    __tablename__ = "results"
    run_id: Mapped[int] = mapped_column(ForeignKey("runs.id"), index=True)
    unit_id: Mapped[int] = mapped_column(ForeignKey("units.id"), index=True)
    procedure: Mapped[str] = mapped_column(String(50), default="")
    model: Mapped[str] = mapped_column(String(50), default="")
    passed: Mapped[bool | None] = mapped_column(Boolean, nullable=True)
    verification_json: Mapped[str] = mapped_column(Text, default="{}")
    document_json: Mapped[str] = mapped_column(Text, default="{}")
    version: Mapped[int] = mapped_column(Integer, default=1)
    replaces_id: Mapped[int | None] = mapped_column(ForeignKey("results.id"), nullable=True,
                                                    unique=True)
    amendment_reason: Mapped[str] = mapped_column(Text, default="")


class ResultParameter(Base):
    """One parameter of a result with its standard uncertainty (hashed with the result)."""

    __tablename__ = "result_parameters"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    result_id: Mapped[int] = mapped_column(ForeignKey("results.id"), index=True)
    name: Mapped[str] = mapped_column(String(100))
    value: Mapped[float] = mapped_column(Float)
    std: Mapped[float] = mapped_column(Float)
    unit: Mapped[str] = mapped_column(String(50), default="")


class Review(_Chained, Base):
    """A review of a result: who, when, approved or not, and why."""

    __tablename__ = "reviews"
    result_id: Mapped[int] = mapped_column(ForeignKey("results.id"), index=True)
    reviewer: Mapped[str] = mapped_column(String(200))
    reviewed_utc: Mapped[datetime] = mapped_column(DateTime(timezone=True))
    approved: Mapped[bool] = mapped_column(Boolean)
    comment: Mapped[str] = mapped_column(Text, default="")


class User(_Chained, Base):
    """A person of the laboratory who acts on the records (docs/records.md, "Users and roles").

    ``role`` is one of ``operator``, ``engineer``, ``reviewer``, ``admin``; ``added_by`` the
    user who added this one ("" for the first). A user is active from this row on until a
    :class:`UserEvent` disables them (rows are never updated).
    """

    __tablename__ = "users"
    name: Mapped[str] = mapped_column(String(200), unique=True)
    initials: Mapped[str] = mapped_column(String(20), default="")
    role: Mapped[str] = mapped_column(String(20))
    added_by: Mapped[str] = mapped_column(String(200), default="")


class UserEvent(_Chained, Base):
    """A change of a user's state: ``disable`` or ``enable``, why, and by whom."""

    __tablename__ = "user_events"
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id"), index=True)
    event: Mapped[str] = mapped_column(String(20))
    reason: Mapped[str] = mapped_column(Text, default="")
    by_user: Mapped[str] = mapped_column(String(200), default="")


class SigningKey(_Chained, Base):
    """A station key whose signatures the records carry (docs/records.md, "Signing").

    ``public_key`` (Ed25519, 64 hex digits) and its ``fingerprint`` (R.9); ``previous_key_id``
    the key it replaces (None for the first); ``endorsement`` the previous key's signature of
    this public key (R.8), "" when the previous key was lost; ``heads_json`` the chain heads
    when the key was registered (``{table: seq}``): every later row must be signed. The row is
    signed by the key it registers.
    """

    __tablename__ = "signing_keys"
    public_key: Mapped[str] = mapped_column(String(HASH_LEN))
    fingerprint: Mapped[str] = mapped_column(String(16))
    previous_key_id: Mapped[int | None] = mapped_column(Integer, nullable=True)
    endorsement: Mapped[str] = mapped_column(Text, default="")
    reason: Mapped[str] = mapped_column(Text, default="")
    heads_json: Mapped[str] = mapped_column(Text, default="{}")


class Credential(_Chained, Base):
    """A user's password, set (docs/web.md, "Users and passwords").

    ``password_hash`` is an argon2id hash in its PHC string form (salt and parameters inside);
    ``by_user`` who set it (the user, or an admin). The newest row of a user is their password;
    a row is never updated, so a swapped hash breaks the chain and ``records verify`` says so.
    """

    __tablename__ = "user_credentials"
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id"), index=True)
    password_hash: Mapped[str] = mapped_column(Text)
    by_user: Mapped[str] = mapped_column(String(200), default="")


class AuditEvent(_Chained, Base):
    """Who did what at the station's web page, and when (docs/web.md, "The audit trail").

    ``actor`` the user's name (the name tried, for a failed login); ``action`` one of
    :data:`imucalib.records.access.AUDIT_ACTIONS`; ``station`` the station's name; ``run_ref``
    the run the action was about ("" for none); ``details_json`` canonical JSON.
    """

    __tablename__ = "audit_events"
    actor: Mapped[str] = mapped_column(String(200), default="")
    action: Mapped[str] = mapped_column(String(40), index=True)
    station: Mapped[str] = mapped_column(String(200), default="")
    run_ref: Mapped[str] = mapped_column(String(200), default="", index=True)
    details_json: Mapped[str] = mapped_column(Text, default="{}")


class WebSession(Base):
    """A login to the web page: its cookie token's SHA-256, whose, until when, its CSRF token.

    Working state, not a record (module docstring): a logout or an expiry deletes the row.
    """

    __tablename__ = "web_sessions"
    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    token_hash: Mapped[str] = mapped_column(String(HASH_LEN), unique=True)
    user_name: Mapped[str] = mapped_column(String(200), index=True)
    created_utc: Mapped[datetime] = mapped_column(DateTime(timezone=True))
    expires_utc: Mapped[datetime] = mapped_column(DateTime(timezone=True))
    csrf_token: Mapped[str] = mapped_column(String(HASH_LEN))


class StationLock(Base):
    """Who holds a station (one operator at a time), since when, and who asked for it.

    Working state, not a record (module docstring): taking, releasing and requesting the lock
    are audit rows.
    """

    __tablename__ = "station_locks"
    station: Mapped[str] = mapped_column(String(200), primary_key=True)
    holder: Mapped[str] = mapped_column(String(200), default="")
    since_utc: Mapped[datetime | None] = mapped_column(DateTime(timezone=True), nullable=True)
    requested_by: Mapped[str] = mapped_column(String(200), default="")
    requested_utc: Mapped[datetime | None] = mapped_column(DateTime(timezone=True),
                                                           nullable=True)


#: The chained tables, in the order verify checks them (and PostgreSQL takes their locks;
#: a new table is appended, so the lock keys of the others stay).
CHAINED: Final[tuple[type[_Chained], ...]] = (Unit, Station, Equipment, Run, Result, Review,
                                              User, UserEvent, SigningKey, Credential,
                                              AuditEvent)
