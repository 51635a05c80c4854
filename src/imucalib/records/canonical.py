"""The canonical form of a record and its chained hash (docs/records.md, "The hash chain").

Equations
---------
(R.1) ``row_hash(n) = SHA-256( prev_hash(n) ‖ C(row n) )`` as lowercase hex, where ``‖`` joins
      the ASCII hex text of ``prev_hash`` and the UTF-8 bytes of ``C``;
(R.2) ``prev_hash(1) = "0" × 64`` and ``prev_hash(n) = row_hash(n − 1)`` in ``seq`` order, per
      table;
(R.3) ``C(row)`` = :func:`canonical_json` of an object holding every column of the row but
      ``prev_hash`` and ``row_hash`` (``id`` and ``seq`` included), plus the children hashed
      with it: a run's ``"equipment"`` (the sorted equipment ids) and a result's
      ``"parameters"`` (``{"name", "std", "unit", "value"}`` objects sorted by name).

Canonical JSON: keys sorted, no whitespace (``","`` and ``":"``), non-ASCII characters as
themselves, floats as Python's ``repr`` (shortest round-trip form, ``1.0`` not ``1``), integers
as integers, booleans ``true``/``false``, missing values ``null``, datetimes as ISO 8601 UTC with
microseconds (``2026-11-27T10:00:00.000000Z``; a naive datetime read back from SQLite is UTC),
dates as ``YYYY-MM-DD``. Each value is first coerced to its column's type, so the form does not
depend on the backend a row was read from.

Contents
--------
:data:`GENESIS`, :func:`canonical_json`, :func:`chain_hash`, :func:`row_content`,
:func:`utc_text`
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping, Sequence
from datetime import UTC, date, datetime
from typing import Any, Final

from sqlalchemy import Boolean, Date, DateTime, Float, Integer

__all__ = ["GENESIS", "canonical_json", "chain_hash", "row_content", "utc_text"]

#: ``prev_hash`` of the first row of every table, Eq. (R.2).
GENESIS: Final = "0" * 64
#: Columns that are the chain itself, not content (Eq. (R.3)).
CHAIN_COLUMNS: Final = frozenset({"prev_hash", "row_hash"})


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


def _coerce(column_type: Any, value: Any) -> Any:
    if value is None:
        return None
    if isinstance(column_type, Boolean):
        return bool(value)
    if isinstance(column_type, Integer):
        return int(value)
    if isinstance(column_type, Float):
        return float(value)
    if isinstance(column_type, DateTime):
        return utc_text(value)
    if isinstance(column_type, Date):
        return value.isoformat()
    return value


def row_content(row: Any, **children: Any) -> dict[str, Any]:
    """Return the content of an ORM `row` for Eq. (R.3), each value coerced to its column type.

    Parameters
    ----------
    row : a mapped instance of a chained table
    **children
        Child rows hashed with it (``equipment=[…]``, ``parameters=[…]``).
    """
    content = {c.name: _coerce(c.type, getattr(row, c.key))
               for c in row.__table__.columns if c.name not in CHAIN_COLUMNS}
    content.update(children)
    return content
