"""The canonical form of a record and its chained hash (docs/records.md, "The hash chain").

Equations
---------
(R.1) ``row_hash(n) = SHA-256( prev_hash(n) ‖ C(row n) )`` as lowercase hex, where ``‖`` joins
      the ASCII hex text of ``prev_hash`` and the UTF-8 bytes of ``C``;
(R.2) ``prev_hash(1) = "0" × 64`` and ``prev_hash(n) = row_hash(n − 1)`` in ``seq`` order, per
      table;
(R.3) ``C(row)`` = :func:`canonical_json` of an object holding every column of the row but
      ``prev_hash``, ``row_hash`` and ``signature`` (``id`` and ``seq`` included), plus the
      children hashed with it: a run's ``"equipment"`` (the sorted equipment ids) and a
      result's ``"parameters"`` (``{"name", "std", "unit", "value"}`` objects sorted by name).
      Hash version 1 (rows made before revision 0003) leaves ``hash_version`` and ``key_id``
      out too; hash version 2 (every row since) also holds ``"_table"``, the table's name, so
      that the hash binds the row's table, id and sequence number.

Canonical JSON: keys sorted, no whitespace (``","`` and ``":"``), non-ASCII characters as
themselves, floats as Python's ``repr`` (shortest round-trip form, ``1.0`` not ``1``), integers
as integers, booleans ``true``/``false``, missing values ``null``, datetimes as ISO 8601 UTC with
microseconds (``2026-11-27T10:00:00.000000Z``; a naive datetime read back from SQLite is UTC),
dates as ``YYYY-MM-DD``. Each value is first coerced to its column's type, so the form does not
depend on the backend a row was read from.

Contents
--------
:data:`GENESIS`, :func:`canonical_json`, :func:`chain_hash`, :func:`row_content`,
:func:`content_of`, :func:`utc_text`, :class:`StoredValueError`
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping, Sequence
from datetime import UTC, date, datetime
from typing import Any, Final

from sqlalchemy import Boolean, Date, DateTime, Float, Integer

__all__ = ["GENESIS", "HASH_VERSIONS", "StoredValueError", "canonical_json", "chain_hash",
           "content_of", "row_content", "utc_text"]

#: ``prev_hash`` of the first row of every table, Eq. (R.2).
GENESIS: Final = "0" * 64
#: Columns that are the chain itself, not content (Eq. (R.3)).
CHAIN_COLUMNS: Final = frozenset({"prev_hash", "row_hash", "signature"})
#: Columns hash version 1 leaves out (they did not exist before revision 0003).
V2_COLUMNS: Final = frozenset({"hash_version", "key_id"})
#: The hash versions this software knows (Eq. (R.3)).
HASH_VERSIONS: Final = (1, 2)
#: The largest integer a stored value may be (a 64-bit signed column).
MAX_INT: Final = 2**63 - 1


class StoredValueError(ValueError):
    """A stored value that is not of its column's type (``std is not a number``)."""

    def __init__(self, column: str, value: Any, expected: str) -> None:
        shown = repr(value)
        shown = shown if len(shown) <= 60 else shown[:57] + "…"
        super().__init__(f"{column} is {expected} ({shown})")
        self.column = column


def utc_text(value: datetime) -> str:
    """Return a datetime as ISO 8601 UTC with microseconds; a naive one is taken as UTC."""
    aware = value.replace(tzinfo=UTC) if value.tzinfo is None else value.astimezone(UTC)
    return aware.strftime("%Y-%m-%dT%H:%M:%S.%fZ")


def _plain(value: Any) -> Any:
    if isinstance(value, datetime):
        return utc_text(value)
    if isinstance(value, date):
        return value.isoformat()
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, Sequence) and not isinstance(value, str | bytes):
        return [_plain(v) for v in value]
    if hasattr(value, "item") and callable(value.item):  # numpy scalars
        return _plain(value.item())
    return value


def canonical_json(value: Any) -> str:
    """Return the canonical JSON text of `value` (module docstring).

    Examples
    --------
    >>> canonical_json({"b": 1.0, "a": [True, None, 0.1]})
    '{"a":[true,null,0.1],"b":1.0}'
    """
    return json.dumps(_plain(value), sort_keys=True, separators=(",", ":"), ensure_ascii=False)


def chain_hash(prev_hash: str, content: Mapping[str, Any]) -> str:
    """Return Eq. (R.1): SHA-256 of `prev_hash` followed by the canonical JSON of `content`.

    Examples
    --------
    >>> chain_hash(GENESIS, {"id": 1})[:12]
    'c6b7d0af3e21'
    """
    text = prev_hash + canonical_json(content)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def _python(value: Any) -> Any:
    """Return a numpy scalar as its Python value, anything else as it is."""
    if not isinstance(value, str | bytes) and hasattr(value, "item") and callable(value.item):
        return value.item()
    return value


def coerce(name: str, column_type: Any, value: Any, nullable: bool = True) -> Any:
    """Return `value` read as its column's type (Eq. (R.3)), strictly.

    A value as the database driver hands it back: SQLite gives text for a datetime and 0/1
    for a boolean. Anything else — text in a number column, a timestamp with junk after it,
    a float in an integer column, NULL where the schema forbids it — is refused.

    Raises
    ------
    StoredValueError
        Naming the column and what it holds.
    """
    if value is None:
        if not nullable:
            raise StoredValueError(name, value, "NULL, not allowed")
        return None
    if isinstance(column_type, Boolean):
        if isinstance(value, bool) or (isinstance(value, int) and value in (0, 1)):
            return bool(value)
        raise StoredValueError(name, value, "not a boolean")
    if isinstance(column_type, Integer):
        if isinstance(value, int) and not isinstance(value, bool) and abs(value) <= MAX_INT:
            return int(value)
        raise StoredValueError(name, value, "not an integer")
    if isinstance(column_type, Float):
        if isinstance(value, int | float) and not isinstance(value, bool):
            return float(value)
        raise StoredValueError(name, value, "not a number")
    if isinstance(column_type, DateTime):
        if isinstance(value, str):
            try:
                value = datetime.fromisoformat(value)
            except ValueError:
                raise StoredValueError(name, value, "not a timestamp") from None
        if not isinstance(value, datetime):
            raise StoredValueError(name, value, "not a timestamp")
        return utc_text(value)
    if isinstance(column_type, Date):
        if isinstance(value, str):
            try:
                value = date.fromisoformat(value)
            except ValueError:
                raise StoredValueError(name, value, "not a date") from None
        if not isinstance(value, date) or isinstance(value, datetime):
            raise StoredValueError(name, value, "not a date")
        return value.isoformat()
    if not isinstance(value, str):
        raise StoredValueError(name, value, "not text")
    return value


def content_of(table: Any, values: Mapping[str, Any], **children: Any) -> dict[str, Any]:
    """Return the content C of a row of `table` (Eq. (R.3)) from its stored `values`.

    Parameters
    ----------
    table : sqlalchemy.Table
        The chained table.
    values : mapping
        Column name → value as stored (``hash_version`` decides the form).
    **children
        Child rows hashed with it (``equipment=[…]``, ``parameters=[…]``).

    Raises
    ------
    StoredValueError
        A value that is not of its column's type.
    """
    version = values.get("hash_version") or 1
    skip = CHAIN_COLUMNS | (V2_COLUMNS if version == 1 else frozenset())
    content = {c.name: coerce(c.name, c.type, values.get(c.name), bool(c.nullable)
                              or c.name in V2_COLUMNS)
               for c in table.columns if c.name not in skip}
    if version != 1:
        content["_table"] = table.name
    content.update(children)
    return content


def row_content(row: Any, **children: Any) -> dict[str, Any]:
    """Return the content of an ORM `row` for Eq. (R.3), each value coerced to its column type.

    Parameters
    ----------
    row : a mapped instance of a chained table
    **children
        Child rows hashed with it (``equipment=[…]``, ``parameters=[…]``).
    """
    table = row.__table__
    values = {c.name: _python(getattr(row, c.key)) for c in table.columns}
    return content_of(table, values, **children)
