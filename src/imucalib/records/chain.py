"""Appending to a table's hash chain, one writer at a time (docs/records.md, Eqs. (R.1)–(R.3)).

Contents
--------
:func:`append`
    Lock the table's chain, read its head, give the row the next ``seq`` (and ``id``), its
    ``prev_hash`` and its ``row_hash``, and add it.
:func:`children_of`
    The child content a row is hashed with (a run's equipment, a result's parameters).
:func:`expected_hash`
    Eq. (R.1) recomputed for a stored row (what verify compares).

Signing: every appended row gets ``hash_version`` 2, the id of the key that signs it and its
signature, Eq. (R.7), by the station key the session carries in ``session.info["signer"]``
(``(StationKey, key_id)``, set by :class:`~imucalib.records.api.Records`); a
``signing_keys`` row is signed by the key it registers. ``session.info["appended"]`` collects
the new head of each table appended to, for the anchor log (Eq. (R.10)).

Serialising: on SQLite the caller's transaction began with ``BEGIN IMMEDIATE`` (one writer for
the whole database); on PostgreSQL :func:`append` takes ``pg_advisory_xact_lock(key)`` with one
key per table, held to the end of the transaction. Callers append to tables in the order of
:data:`~imucalib.records.schema.CHAINED`, so two transactions never wait on each other in a
circle.
"""

from __future__ import annotations

from datetime import UTC, datetime
from typing import Any, Final

from sqlalchemy import func, select
from sqlalchemy.orm import Session

from imucalib.errors import RecordsError
from imucalib.records.canonical import GENESIS, chain_hash, row_content
from imucalib.records.schema import CHAINED, Result, ResultParameter, Run, RunEquipment
from imucalib.records.signing import StationKey, row_message

__all__ = ["LOCK_KEYS", "append", "children_of", "expected_hash", "lock"]

#: The advisory-lock key of each chained table on PostgreSQL.
LOCK_KEYS: Final = {model.__tablename__: 7252100 + i  # type: ignore[attr-defined]
                    for i, model in enumerate(CHAINED)}


def lock(session: Session, model: type[Any]) -> None:
    """Hold `model`'s chain until the transaction ends (PostgreSQL; SQLite holds the database)."""
    if session.get_bind().dialect.name == "postgresql":
        session.execute(select(func.pg_advisory_xact_lock(LOCK_KEYS[model.__tablename__])))


def parameter_content(rows: list[ResultParameter]) -> list[dict[str, Any]]:
    """Return a result's parameters as hashed (Eq. (R.3)): sorted by name."""
    return sorted(({"name": r.name, "std": float(r.std), "unit": r.unit,
                    "value": float(r.value)} for r in rows), key=lambda d: d["name"])


def children_of(session: Session, row: Any) -> dict[str, Any]:
    """Return the child content stored for `row` (Eq. (R.3))."""
    if isinstance(row, Run):
        ids = session.scalars(select(RunEquipment.equipment_id)
                              .where(RunEquipment.run_id == row.id)).all()
        return {"equipment": sorted(int(i) for i in ids)}
    if isinstance(row, Result):
        params = session.scalars(select(ResultParameter)
                                 .where(ResultParameter.result_id == row.id)).all()
        return {"parameters": parameter_content(list(params))}
    return {}


def expected_hash(session: Session, row: Any, prev_hash: str) -> str:
    """Return Eq. (R.1) for a stored `row` after `prev_hash`."""
    return chain_hash(prev_hash, row_content(row, **children_of(session, row)))


def _fill_defaults(row: Any) -> None:
    for column in row.__table__.columns:
        if getattr(row, column.key) is None and column.default is not None \
                and column.default.is_scalar:
            setattr(row, column.key, column.default.arg)


def append(session: Session, row: Any, *, self_signed: StationKey | None = None,
           **children: Any) -> Any:
    """Append `row` to its table's chain, signed, and return it (its ``id`` equals its ``seq``).

    Parameters
    ----------
    session : Session
        In a write transaction (module docstring), with ``info["signer"]``.
    row : a new instance of a chained model
    self_signed : StationKey, optional
        For a ``signing_keys`` row: the key it registers, which signs it.
    **children
        The child content it is hashed with, as :func:`children_of` will read it back
        (``equipment=[ids]``, ``parameters=[…]``); the caller adds the child rows.

    Raises
    ------
    RecordsError
        No station key to sign with.
    """
    model = type(row)
    lock(session, model)
    head = session.execute(select(model.seq, model.row_hash)
                           .order_by(model.seq.desc()).limit(1)).first()
    seq = 1 if head is None else int(head[0]) + 1
    prev = GENESIS if head is None else str(head[1])
    row.id = row.seq = seq
    row.prev_hash = prev
    if row.created_utc is None:
        row.created_utc = datetime.now(UTC)
    signer = session.info.get("signer")
    if self_signed is not None:
        key, key_id = self_signed, seq
    elif signer is not None:
        key, key_id = signer
    else:
        raise RecordsError("no station key to sign the new row with (docs/records.md, "
                           "\"Signing\")")
    row.hash_version, row.key_id = 2, key_id
    _fill_defaults(row)
    row.row_hash = chain_hash(prev, row_content(row, **children))
    row.signature = key.sign(row_message(row.row_hash))
    session.add(row)
    session.flush()
    session.info.setdefault("appended", {})[model.__tablename__] = (seq, row.row_hash)
    return row
