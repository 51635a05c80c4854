"""Re-hash the records, check their signatures; name every mismatch (docs/records.md).

See "What verify checks" there.

Contents
--------
:func:`verify_report`, :func:`verify_session`

The rows are read as the database driver stores them (no type conversion that could fail) and
each value is read as its column's type (:func:`imucalib.records.canonical.coerce`): a value
that is not (text in a number column, a timestamp with junk after it, a NULL the schema
forbids) is a finding naming the row and the column, never an error. For each chained table,
in ``seq`` order, with ``prev`` the stored ``row_hash`` of the row before (``GENESIS`` before
the first):

- a ``seq`` that is not an integer in 1 … 2⁶³ − 1, or one that skips numbers: each missing
  ``seq`` is named (a deleted row; a long gap as one range);
- an ``id`` that differs from ``seq``;
- a ``prev_hash`` other than ``prev``: the chain is broken there;
- a ``row_hash`` other than Eq. (R.1) recomputed from the row's own ``prev_hash`` and content
  (children included, hash version 1 or 2 as the row says);
- hash version 2: the signature, Eq. (R.7), by the key named in ``key_id``, which must be a
  registered key (``signing_keys``) that is trusted: the key of the key file (or of
  ``station.pub``), or a key a trusted key endorses (R.8) or vouches for (a trusted key's row
  names it as ``previous_key_id``);
- hash version 1 (unsigned): a note when the row was made before the first key was registered
  (its ``heads_json``), a finding when after (a row re-hashed without the key, or downgraded);
- a dangling reference (a result whose run is not there, a review of a missing result …);
- every line of the anchor log (R.10): its signature by a trusted key, and each head it names
  still in its table with the same hash (a deleted or replaced last row); likewise each
  anchor given (an earlier :class:`~imucalib.records.views.ChainHead`).

For each run with a recording: the file is missing, or its SHA-256 differs from the one
recorded.
"""

from __future__ import annotations

import json
from collections import defaultdict
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final

from sqlalchemy import Table, text
from sqlalchemy.orm import Session

from imucalib.io.hashing import file_sha256
from imucalib.records.anchor_log import AnchorLine, line_message, read_log
from imucalib.records.canonical import (
    GENESIS,
    HASH_VERSIONS,
    MAX_INT,
    StoredValueError,
    chain_hash,
    coerce,
    content_of,
)
from imucalib.records.schema import CHAINED, ResultParameter, SigningKey
from imucalib.records.signing import (
    endorsement_message,
    fingerprint,
    row_message,
    verify_signature,
)
from imucalib.records.views import ChainHead, KeyUse, Problem, VerifyReport

__all__ = ["REFERENCES", "verify_report", "verify_session"]

#: The most missing rows named one by one; a longer gap is one finding.
MAX_NAMED_GAP: Final = 10
#: Foreign keys verify follows: (table, column) → table referred to.
REFERENCES: Final = {
    ("equipment", "station_id"): "stations", ("equipment", "replaces_id"): "equipment",
    ("runs", "station_id"): "stations", ("results", "run_id"): "runs",
    ("results", "unit_id"): "units", ("results", "replaces_id"): "results",
    ("reviews", "result_id"): "results", ("user_events", "user_id"): "users",
    ("signing_keys", "previous_key_id"): "signing_keys",
    ("user_credentials", "user_id"): "users",
}


@dataclass
class _Table:
    """What verify learned of one chained table."""

    name: str
    rows: dict[int, dict[str, Any]] = field(default_factory=dict)   # seq → stored values
    hashes: dict[int, str] = field(default_factory=dict)            # seq → stored row_hash


def _raw(session: Session, name: str) -> list[dict[str, Any]]:
    """Every row of table `name` as the driver hands it back (no type processing)."""
    return [dict(r) for r in session.execute(text(f'SELECT * FROM "{name}"')).mappings()]


def _int(value: Any) -> int | None:
    if isinstance(value, int) and not isinstance(value, bool) and 1 <= value <= MAX_INT:
        return int(value)
    return None


def _children(session: Session) -> tuple[dict[str, dict[int, dict[str, Any]]], list[Problem]]:
    """Return the child content of runs and results (R.3), naming a child with a bad value."""
    problems: list[Problem] = []
    params: dict[int, list[dict[str, Any]]] = defaultdict(list)
    table = ResultParameter.__table__
    for raw in _raw(session, "result_parameters"):
        owner = raw.get("result_id")
        try:
            p = {c: coerce(c, table.c[c].type, raw.get(c), False)
                 for c in ("name", "value", "std", "unit", "result_id")}
        except StoredValueError as exc:
            problems.append(Problem("results", _int(owner) or 0,
                                    f"parameter {raw.get('name')!r} (result_parameters row "
                                    f"{raw.get('id')!r}): {exc}", "bad value"))
            continue
        params[p["result_id"]].append({k: p[k] for k in ("name", "std", "unit", "value")})
    links: dict[int, list[int]] = defaultdict(list)
    for raw in _raw(session, "run_equipment"):
        run_id, eq = raw.get("run_id"), raw.get("equipment_id")
        if _int(run_id) is None or _int(eq) is None:
            problems.append(Problem("run_equipment", _int(raw.get("id")) or 0,
                                    f"run_id {run_id!r} or equipment_id {eq!r} is not an "
                                    "integer id", "bad value"))
            continue
        links[int(run_id)].append(int(eq))  # type: ignore[arg-type]
    return {
        "results": {k: {"parameters": sorted(v, key=lambda d: str(d["name"]))}
                    for k, v in params.items()},
        "runs": {k: {"equipment": sorted(v)} for k, v in links.items()},
    }, problems


def _empty_children(name: str) -> dict[str, Any]:
    return {"results": {"parameters": []}, "runs": {"equipment": []}}.get(name, {})


@dataclass
class _Keys:
    """The registered signing keys and which of them are trusted."""

    public: dict[int, str] = field(default_factory=dict)          # key id → public key hex
    rows: dict[int, dict[str, Any]] = field(default_factory=dict)
    trusted: set[int] = field(default_factory=set)
    first_heads: dict[str, int] | None = None                     # heads when signing began


def _trust(keys: _Keys, roots: set[str], self_signed: set[int]) -> None:
    """Mark the keys a root trusts, following endorsements (R.8) and ``previous_key_id``."""
    keys.trusted = {k for k, pub in keys.public.items() if pub in roots and k in self_signed}
    changed = True
    while changed:
        changed = False
        for k, row in keys.rows.items():
            prev = _int(row.get("previous_key_id"))
            if prev is None or prev not in keys.public:
                continue
            if k in keys.trusted and prev not in keys.trusted:       # vouched by the newer
                keys.trusted.add(prev)
                changed = True
            elif prev in keys.trusted and k not in keys.trusted and k in self_signed \
                    and verify_signature(keys.public[prev], str(row.get("endorsement") or ""),
                                         endorsement_message(keys.public[k])):
                keys.trusted.add(k)
                changed = True


def _check_table(session: Session, model: type[Any], children: Mapping[int, dict[str, Any]],
                 keys: _Keys, uses: dict[int, dict[str, int]], notes: list[str],
                 bad_rows: set[tuple[str, int]]) -> tuple[_Table, list[Problem]]:
    table: Table = model.__table__
    name = table.name
    out = _Table(name)
    problems: list[Problem] = []
    ordered: list[tuple[int, dict[str, Any]]] = []
    for raw in _raw(session, name):
        seq = _int(raw.get("seq"))
        if seq is None:
            key = _int(raw.get("id")) or 0
            problems.append(Problem(name, key, f"seq {raw.get('seq')!r} is not a sequence "
                                               "number (an integer from 1)", "bad value"))
            bad_rows.add((name, key))
            continue
        ordered.append((seq, raw))
    ordered.sort(key=lambda item: item[0])
    prev, expected = GENESIS, 1
    unsigned_before = 0
    first = (keys.first_heads or {}).get(name)
    for seq, raw in ordered:
        out.rows[seq] = raw
        stored = raw.get("row_hash")
        out.hashes[seq] = stored if isinstance(stored, str) else ""
        gap = seq - expected
        if 0 < gap <= MAX_NAMED_GAP:
            for missing in range(expected, seq):
                problems.append(Problem(name, missing, f"row seq {missing} is missing "
                                                       f"(deleted); the chain jumps from "
                                                       f"{expected - 1} to {seq}", "deleted"))
        elif gap > MAX_NAMED_GAP:
            problems.append(Problem(name, expected, f"rows seq {expected} … {seq - 1} ({gap} "
                                                    f"rows) are missing (deleted, or a seq "
                                                    f"was changed to {seq})", "deleted"))
        expected = seq + 1
        if raw.get("id") != seq:
            problems.append(Problem(name, seq, f"id {raw.get('id')!r} differs from seq {seq}",
                                    "edited"))
        prev_hash = raw.get("prev_hash")
        if prev_hash != prev:
            problems.append(Problem(name, seq, f"prev_hash {str(prev_hash)[:16]}… does not "
                                               f"match the previous row's row_hash "
                                               f"{prev[:16]}… (chain broken)", "chain broken"))
        prev = out.hashes[seq]
        version = raw.get("hash_version", 1)
        if version not in HASH_VERSIONS or isinstance(version, bool):
            problems.append(Problem(name, seq, f"hash_version {version!r} is not one this "
                                               f"software knows ({HASH_VERSIONS})", "bad value"))
            bad_rows.add((name, seq))
            continue
        try:
            own = children.get(_int(raw.get("id")) or -1, _empty_children(name))
            content = content_of(table, raw, **own)
            again = chain_hash(str(prev_hash), content)
        except StoredValueError as exc:
            problems.append(Problem(name, seq, str(exc), "bad value"))
            bad_rows.add((name, seq))
            continue
        if again != stored:
            problems.append(Problem(name, seq, f"content re-hashes to {again[:16]}…, not the "
                                               f"stored row_hash {str(stored)[:16]}… (edited)",
                                    "edited"))
        if version == 1:
            if keys.first_heads is not None and (first is None or seq > first):
                problems.append(Problem(name, seq, "unsigned (hash version 1) but made after "
                                                   "signing began: re-hashed or written "
                                                   "without the station key", "unsigned"))
            else:
                unsigned_before += 1
            continue
        _check_signature(name, seq, raw, keys, uses, problems)
    if unsigned_before:
        notes.append(f"{name}: {unsigned_before} row(s) unsigned, made before signing "
                     "(hash version 1; their hash chain is checked)")
    return out, problems


def _check_signature(name: str, seq: int, raw: Mapping[str, Any], keys: _Keys,
                     uses: dict[int, dict[str, int]], problems: list[Problem]) -> None:
    key_id = _int(raw.get("key_id"))
    if key_id is None or key_id not in keys.public:
        problems.append(Problem(name, seq, f"signed by key {raw.get('key_id')!r}, which is not "
                                           "a registered key (forged or its key deleted)",
                                "forged"))
        return
    if not verify_signature(keys.public[key_id], str(raw.get("signature") or ""),
                            row_message(str(raw.get("row_hash")))):
        problems.append(Problem(name, seq, f"signature does not verify with key {key_id} "
                                           f"({fingerprint(keys.public[key_id])}): the row "
                                           "was re-hashed or forged without the station key",
                                "forged"))
        return
    uses.setdefault(key_id, {})
    uses[key_id][name] = uses[key_id].get(name, 0) + 1
    if key_id not in keys.trusted:
        problems.append(Problem(name, seq, f"signed by key {key_id} "
                                           f"({fingerprint(keys.public[key_id])}), which is "
                                           "not trusted (a key someone registered without "
                                           "the station key)", "untrusted key"))


def _load_keys(session: Session, roots: set[str]) -> tuple[_Keys, list[Problem]]:
    """Read ``signing_keys`` (values checked loosely here; the chain check names bad rows)."""
    keys = _Keys()
    self_signed: set[int] = set()
    for raw in _raw(session, "signing_keys"):
        seq = _int(raw.get("seq"))
        pub = raw.get("public_key")
        if seq is None or not isinstance(pub, str):
            continue
        keys.public[seq] = pub
        keys.rows[seq] = raw
        if _int(raw.get("key_id")) == seq and verify_signature(
                pub, str(raw.get("signature") or ""), row_message(str(raw.get("row_hash")))):
            self_signed.add(seq)
    if keys.rows:
        first = keys.rows[min(keys.rows)]
        try:
            heads = json.loads(str(first.get("heads_json") or "{}"))
            keys.first_heads = {str(k): int(v) for k, v in dict(heads).items()}
        except (ValueError, TypeError, AttributeError, RecursionError):
            keys.first_heads = {}
    problems: list[Problem] = []
    if roots:
        _trust(keys, roots, self_signed)
    else:
        keys.trusted = set(self_signed)
    for k, row in sorted(keys.rows.items()):
        if k not in self_signed:
            problems.append(Problem("signing_keys", k, f"key {k} is not signed by itself "
                                                       "(its row or its public key was "
                                                       "changed)", "forged"))
        elif k not in keys.trusted:
            problems.append(Problem("signing_keys", k, f"key {k} ({fingerprint(keys.public[k])}) "
                                                       "is not trusted: neither the key file "
                                                       "nor a trusted key endorses it",
                                    "untrusted key"))
        if row.get("fingerprint") != fingerprint(keys.public[k]):
            problems.append(Problem("signing_keys", k, f"fingerprint {row.get('fingerprint')!r}"
                                                       " is not that of its public key",
                                    "edited"))
    return keys, problems


def _check_references(tables: dict[str, _Table], bad_rows: set[tuple[str, int]]
                      ) -> list[Problem]:
    problems = []
    for (name, column), target in REFERENCES.items():
        there = tables.get(name)
        if there is None or target not in tables:
            continue
        for seq, raw in there.rows.items():
            value = raw.get(column)
            if value is None or (name, seq) in bad_rows:
                continue
            ref = _int(value)
            if ref is None or ref not in tables[target].rows:
                problems.append(Problem(name, seq, f"{column} {value!r} names a row of "
                                                   f"{target} that is not there (dangling)",
                                        "dangling"))
    return problems


def _check_anchor_log(path: Path, log: tuple[list[AnchorLine], list[str]],
                      tables: dict[str, _Table], keys: _Keys, roots: set[str],
                      notes: list[str]) -> tuple[list[Problem], dict[str, int]]:
    lines, bad = log
    problems = [Problem("anchor log", 0, f"{path}: {b}", "anchor log") for b in bad]
    trusted = {fingerprint(pub): pub for k, pub in keys.public.items() if k in keys.trusted}
    trusted.update({fingerprint(pub): pub for pub in roots})   # also with its key row gone
    anchored: dict[str, int] = {}
    for line in lines:
        pub = trusted.get(line.key)
        if pub is None or not verify_signature(pub, line.sig, line_message(line.body)):
            problems.append(Problem("anchor log", line.number,
                                    f"{path.name} line {line.number}: its signature does not "
                                    f"verify with a trusted key (key {line.key}): edited or "
                                    "forged", "anchor log"))
            continue
        for table, (seq, row_hash) in line.heads.items():
            anchored[table] = max(anchored.get(table, 0), seq)
            problems += _anchor_problems(tables, table, seq, row_hash,
                                         f"the anchor log (line {line.number})")
    for name, t in tables.items():
        if t.rows and max(t.rows) > anchored.get(name, 0) and keys.rows:
            notes.append(f"{name}: rows after seq {anchored.get(name, 0)} are not in the "
                         "anchor log (made before signing, or a write whose log line failed)")
    return problems, anchored


def _anchor_problems(tables: dict[str, _Table], table: str, seq: int, row_hash: str,
                     where: str) -> list[Problem]:
    t = tables.get(table)
    if t is None or seq == 0:
        return []
    if seq not in t.rows:
        return [Problem(table, seq, f"row seq {seq} is named by {where} but missing "
                                    "(deleted)", "deleted")]
    if t.hashes[seq] != row_hash:
        return [Problem(table, seq, f"row_hash {t.hashes[seq][:16]}… differs from "
                                    f"{where}, {row_hash[:16]}… (replaced or re-hashed)",
                        "re-hashed")]
    return []


def _check_recordings(session: Session, runs: _Table) -> list[Problem]:
    problems = []
    for seq, raw in sorted(runs.rows.items()):
        where, want = raw.get("recording_path"), raw.get("recording_sha256")
        if not isinstance(where, str) or not where:
            continue
        path = Path(where)
        try:
            there = path.is_file()
        except (OSError, ValueError):
            there = False
        if not there:
            problems.append(Problem("recordings", seq, f"recording {path} of run {seq} "
                                                       "is missing", "recording"))
            continue
        try:
            sha = file_sha256(path)
        except OSError as exc:
            problems.append(Problem("recordings", seq, f"recording {path} of run {seq} "
                                                       f"cannot be read: {exc}", "recording"))
            continue
        if sha != want:
            problems.append(Problem("recordings", seq, f"recording {path} of run {seq} "
                                                       f"has sha256 {sha}, recorded "
                                                       f"{want} (changed)", "recording"))
    return problems


def verify_report(session: Session, *, recordings: bool = True,
                  anchors: Iterable[ChainHead] = (), anchor_log: Path | None = None,
                  trusted_keys: Iterable[str] = (),
                  log: tuple[list[AnchorLine], list[str]] | None = None,
                  log_present: bool | None = None) -> VerifyReport:
    """Return everything wrong in the database `session` reads (module docstring).

    Parameters
    ----------
    recordings : bool
        Also re-hash each run's recording file.
    anchors : iterable of ChainHead
        Heads kept elsewhere (a backup's ``heads.json``).
    anchor_log : Path, optional
        The anchor log (R.10); None: not checked.
    log : (lines, malformed), optional
        The anchor log as :func:`~imucalib.records.anchor_log.read_log` read it *before*
        `session` began (a line written after the snapshot would name rows it cannot see);
        default: read now.
    log_present : bool, optional
        Whether the log file was there when `log` was read (default: whether it is now).
    trusted_keys : iterable of str
        Public keys (hex) trusted as roots (the key file's, ``station.pub``'s); none: every
        self-signed registered key is taken as it is (a note says so).
    """
    roots = {k for k in trusted_keys if k}
    keys, problems = _load_keys(session, roots)
    notes: list[str] = []
    if keys.rows and not roots:
        notes.append("no trusted key given (no key file, no station.pub): the signatures were "
                     "checked against the keys the database registers, which someone with "
                     "write access could have replaced")
    elif roots and keys.rows and not (roots & set(keys.public.values())):
        problems.append(Problem("signing_keys", 0, "the station's key (key file or "
                                                   "station.pub) is not registered in these "
                                                   "records", "untrusted key"))
    children, child_problems = _children(session)
    uses: dict[int, dict[str, int]] = {}
    tables: dict[str, _Table] = {}
    bad_rows: set[tuple[str, int]] = set()
    per_table: list[Problem] = []
    for model in CHAINED:
        name = model.__tablename__  # type: ignore[attr-defined]
        tables[name], found = _check_table(session, model, children.get(name, {}), keys,
                                           uses, notes, bad_rows)
        per_table += found
    problems = per_table + problems + child_problems + _check_references(tables, bad_rows)
    if anchor_log is not None:
        if log_present is None:
            log_present = anchor_log.exists()
        if log is None:
            log = read_log(anchor_log) if log_present else ([], [])
        if log_present:
            seen = {(p.table, p.key, p.kind) for p in problems}
            problems += [p for p in _check_anchor_log(anchor_log, log, tables, keys, roots,
                                                         notes)[0]
                         if (p.table, p.key, p.kind) not in seen]
        elif keys.rows and any(t.rows for t in tables.values()):
            problems.append(Problem("anchor log", 0, f"the anchor log {anchor_log} is missing "
                                                     "although the records are signed: a "
                                                     "deleted last row cannot be told",
                                    "anchor log"))
    seen = {(p.table, p.key, p.kind) for p in problems}
    for head in anchors:
        for p in _anchor_problems(tables, head.table, head.seq, head.row_hash, "an anchor"):
            if (p.table, p.key, p.kind) not in seen:
                problems.append(p)
    if recordings:
        problems += _check_recordings(session, tables["runs"])
    key_uses = tuple(KeyUse(k, fingerprint(pub), k in keys.trusted, uses.get(k, {}),
                            _created(keys.rows[k]), str(keys.rows[k].get("reason") or ""))
                     for k, pub in sorted(keys.public.items()))
    return VerifyReport(tuple(problems), tuple(notes), key_uses)


def _created(raw: Mapping[str, Any]) -> Any:
    try:
        from datetime import datetime

        text_value = coerce("created_utc", SigningKey.__table__.c.created_utc.type,
                            raw.get("created_utc"))
        return datetime.fromisoformat(str(text_value).replace("Z", "+00:00"))
    except (StoredValueError, ValueError):
        return None


def verify_session(session: Session, *, recordings: bool = True,
                   anchors: list[ChainHead] | None = None) -> list[Problem]:
    """Return every problem :func:`verify_report` finds (no anchor log, no trusted key)."""
    return list(verify_report(session, recordings=recordings, anchors=anchors or ()).problems)



def _allowed(column: Any) -> str:
    """Return an SQLite condition true when `column` holds a value of its type."""
    from sqlalchemy import Boolean, Date, DateTime, Float, Integer

    name = f'"{column.name}"'
    kind = column.type
    if isinstance(kind, Boolean):
        ok = f"(typeof({name}) = 'integer' AND {name} IN (0, 1))"
    elif isinstance(kind, Integer):
        ok = f"typeof({name}) = 'integer'"
    elif isinstance(kind, Float):
        ok = f"typeof({name}) IN ('real', 'integer')"
    elif isinstance(kind, DateTime | Date):
        ok = f"typeof({name}) = 'text'"
    else:
        ok = f"typeof({name}) = 'text'"
    return f"({ok} OR {name} IS NULL)" if column.nullable else ok


def _type_words(kind: Any) -> str:
    from sqlalchemy import Boolean, Date, DateTime, Float, Integer

    for cls, words in ((Boolean, "a boolean"), (Integer, "an integer"), (Float, "a number"),
                       (DateTime, "a timestamp"), (Date, "a date")):
        if isinstance(kind, cls):
            return words
    return "text"


def first_bad_value(session: Session) -> str:
    """Return the first stored value not of its column's type (SQLite; "" when none).

    One query per table, so that every records command can refuse a database holding text in
    a number column before it misreads it (``records verify`` names them all). PostgreSQL
    enforces the column types itself.
    """
    from imucalib.records.schema import Base

    if session.get_bind().dialect.name != "sqlite":
        return ""
    for table in Base.metadata.sorted_tables:
        condition = " AND ".join(_allowed(c) for c in table.columns)
        found = session.execute(text(f'SELECT * FROM "{table.name}" WHERE NOT ({condition}) '
                                     "LIMIT 1")).mappings().first()
        if found is None:
            continue
        for column in table.columns:
            value = found.get(column.name)
            single = session.execute(text(f"SELECT {_allowed(column)} FROM \"{table.name}\" "
                                          "WHERE rowid = (SELECT rowid FROM "
                                          f"\"{table.name}\" WHERE NOT ({condition}) LIMIT 1)")
                                     ).scalar()
            if not single:
                row = found.get("seq", found.get("id"))
                return (f"{table.name} row {row!r}: {column.name} holds {value!r}, not "
                        f"{_type_words(column.type)}")
        return f"{table.name}: a value not of its column's type"
    return ""
