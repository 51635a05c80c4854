"""Backups of the records database and their restore, verified by checksums.

A backup is a folder (docs/records.md, "Backups") holding

- ``tables/<table>.jsonl``: every row of every table, one JSON object a line, the tables in
  dependency order (parents before children), read in **one** snapshot: a ``REPEATABLE READ``
  read-only transaction on PostgreSQL, one read transaction on SQLite, so that a backup taken
  while the station writes still satisfies every foreign key;
- ``database.sqlite3`` (SQLite only): a byte copy made with SQLite's online backup API from the
  same connection, inside the same read transaction (the same snapshot as the dumps);
- ``recordings/<name>``: byte copies of the recording files given;
- ``signing/anchors.jsonl`` and ``signing/station.pub``: the anchor log and the public key
  of the records' key folder (given as `extra_files`; never the private key);
- ``manifest.json``: each file's SHA-256 digest and size, the kind of database, its Alembic
  revision, the rows per table, the time, the software version, and the public keys the
  records register (``signing_keys``: id, fingerprint, public key; docs/records.md,
  "Signing").

A file is intact when

    SHA-256(bytes of the file) = digest in the manifest  and  size = size in the manifest   (K.1)

(SHA-256 of FIPS 180-4). :func:`backup` writes the same backup into several folders and checks
(K.1) for every file it copied by reading it back; :func:`verify_backup` checks (K.1) later and
names every missing or changed file; :func:`restore` refuses a backup that fails (K.1), creates
the schema in an empty database, loads the dumps in dependency order and the recordings.

Values are written JSON-typed: strings, integers, booleans, null and finite floats as themselves
(a float as its shortest repr, which reads back to the same double); everything else as a
one-key object naming its type, ``{"$datetime": ISO 8601}``, ``{"$date": …}``, ``{"$time": …}``,
``{"$bytes": base64}``, ``{"$decimal": str}``, ``{"$float": "nan" | "inf" | "-inf"}``,
``{"$uuid": …}``, ``{"$timedelta_s": seconds}``, ``{"$json": value}`` (a JSON column's list or
object), so that a dump reads back to the same Python values whatever the database it is loaded
into.

The module works on any schema: the tables come from a ``MetaData`` when one is given, else
from reflecting the database; Alembic's ``alembic_version`` table is not dumped (its revision is
in the manifest, and :func:`restore` refuses to load into a schema of another revision).

Contents
--------
:func:`backup`, :func:`verify_backup`, :func:`restore`, :class:`Manifest`, :class:`TableDump`,
:class:`FileDigest`, :class:`RestoreSummary`, :class:`BackupCorruptError`.
"""

from __future__ import annotations

import base64
import datetime as dt
import decimal
import hashlib
import json
import math
import os
import sqlite3
import uuid
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final

import sqlalchemy as sa
from sqlalchemy.engine import Connection, Engine

from imucalib.errors import CalibrationError, InvalidInputError

__all__ = [
    "BackupCorruptError",
    "FileDigest",
    "Manifest",
    "RestoreSummary",
    "TableDump",
    "backup",
    "restore",
    "verify_backup",
]

#: Name of the manifest in a backup folder.
MANIFEST: Final = "manifest.json"
#: Format name and version written into every manifest.
FORMAT: Final = "imucalib-records-backup"
FORMAT_VERSION: Final = 1
#: Alembic's bookkeeping table: not dumped, its revision goes into the manifest.
ALEMBIC_TABLE: Final = "alembic_version"
#: The SQLite byte copy's name in a backup folder.
SQLITE_COPY: Final = "database.sqlite3"

_CHUNK_BYTES: Final = 1 << 20
_INSERT_BATCH_ROWS: Final = 1000


class BackupCorruptError(CalibrationError):
    """A backup whose files do not match its manifest (missing, changed, or no manifest).

    Parameters
    ----------
    dest : Path
        The backup folder.
    problems : sequence of str
        One line per file, ``"<file>: missing"`` or ``"<file>: changed (…)"``.
    """

    def __init__(self, dest: Path, problems: Sequence[str]) -> None:
        self.dest = Path(dest)
        self.problems = tuple(problems)
        super().__init__(f"backup {self.dest} fails its checksums: " + "; ".join(self.problems))


@dataclass(frozen=True)
class FileDigest:
    """The SHA-256 digest (hex) and size of one file of a backup, (K.1)."""

    sha256: str
    size_bytes: int


@dataclass(frozen=True)
class TableDump:
    """One table of a backup: its name, its dump file (relative to the folder) and its rows."""

    name: str
    file: str
    rows: int


@dataclass(frozen=True)
class Manifest:
    """What one backup folder holds (its ``manifest.json``).

    Attributes
    ----------
    dest : Path
        The folder.
    created_utc : str
        When the snapshot was taken (ISO 8601, UTC).
    software_version : str
        The imucalib version that wrote it.
    database_kind : str
        The SQLAlchemy backend of the source (``"sqlite"``, ``"postgresql"``).
    schema_revision : str or None
        The source's Alembic revision, None when it has no ``alembic_version`` table.
    tables : tuple of TableDump
        In dependency order (parents first).
    files : dict
        Relative path → :class:`FileDigest` of every file but the manifest.
    recordings : tuple of str
        The recordings' relative paths (``recordings/<name>``).
    signing_keys : tuple of dict
        The public keys registered in the records (``id``, ``fingerprint``, ``public_key``).
    """

    dest: Path
    created_utc: str
    software_version: str
    database_kind: str
    schema_revision: str | None
    tables: tuple[TableDump, ...]
    files: dict[str, FileDigest] = field(default_factory=dict)
    recordings: tuple[str, ...] = ()
    signing_keys: tuple[dict[str, Any], ...] = ()

    def to_json(self) -> dict[str, Any]:
        """Return the manifest as written to ``manifest.json`` (without ``dest``)."""
        return {
            "format": FORMAT,
            "format_version": FORMAT_VERSION,
            "created_utc": self.created_utc,
            "software_version": self.software_version,
            "database_kind": self.database_kind,
            "schema_revision": self.schema_revision,
            "tables": [{"name": t.name, "file": t.file, "rows": t.rows} for t in self.tables],
            "files": {k: {"sha256": v.sha256, "size_bytes": v.size_bytes}
                      for k, v in sorted(self.files.items())},
            "recordings": list(self.recordings),
            "signing_keys": [dict(k) for k in self.signing_keys],
        }

    @classmethod
    def read(cls, dest: str | Path) -> Manifest:
        """Read ``dest/manifest.json``.

        Raises
        ------
        BackupCorruptError
            When the manifest is missing, unreadable or not a backup manifest.
        """
        dest = Path(dest)
        try:
            raw = json.loads((dest / MANIFEST).read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise BackupCorruptError(dest, [f"{MANIFEST}: missing"]) from None
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise BackupCorruptError(dest, [f"{MANIFEST}: unreadable ({exc})"]) from None
        try:
            if raw["format"] != FORMAT or int(raw["format_version"]) > FORMAT_VERSION:
                raise BackupCorruptError(dest, [
                    f"{MANIFEST}: not a {FORMAT} manifest of version ≤ {FORMAT_VERSION}"])
            return cls(
                dest=dest, created_utc=str(raw["created_utc"]),
                software_version=str(raw["software_version"]),
                database_kind=str(raw["database_kind"]),
                schema_revision=raw["schema_revision"],
                tables=tuple(TableDump(str(t["name"]), str(t["file"]), int(t["rows"]))
                             for t in raw["tables"]),
                files={str(k): FileDigest(str(v["sha256"]), int(v["size_bytes"]))
                       for k, v in raw["files"].items()},
                recordings=tuple(str(r) for r in raw["recordings"]),
                signing_keys=tuple(dict(k) for k in raw.get("signing_keys", [])))
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            raise BackupCorruptError(dest, [f"{MANIFEST}: malformed ({exc!r})"]) from None


@dataclass(frozen=True)
class RestoreSummary:
    """What :func:`restore` loaded: rows per table (dependency order) and recordings written."""

    rows: dict[str, int]
    files: tuple[Path, ...]
    schema_revision: str | None


# ---------------------------------------------------------------------------------------------
# Values <-> JSON


def _encode(value: Any) -> Any:
    """Write a column value as a JSON value (module docstring, "JSON-typed")."""
    if value is None or isinstance(value, bool | int | str):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else {"$float": repr(value)}
    if isinstance(value, dt.datetime):
        return {"$datetime": value.isoformat()}
    if isinstance(value, dt.date):
        return {"$date": value.isoformat()}
    if isinstance(value, dt.time):
        return {"$time": value.isoformat()}
    if isinstance(value, dt.timedelta):
        return {"$timedelta_s": value.total_seconds()}
    if isinstance(value, bytes | bytearray | memoryview):
        return {"$bytes": base64.b64encode(bytes(value)).decode("ascii")}
    if isinstance(value, decimal.Decimal):
        return {"$decimal": str(value)}
    if isinstance(value, uuid.UUID):
        return {"$uuid": str(value)}
    if isinstance(value, dict | list | tuple):
        return {"$json": value}
    raise InvalidInputError(f"cannot write a value of type {type(value).__name__} to a backup")


_DECODERS: Final[dict[str, Callable[[Any], Any]]] = {
    "$float": float,
    "$datetime": dt.datetime.fromisoformat,
    "$date": dt.date.fromisoformat,
    "$time": dt.time.fromisoformat,
    "$timedelta_s": lambda s: dt.timedelta(seconds=s),
    "$bytes": lambda s: base64.b64decode(s.encode("ascii"), validate=True),
    "$decimal": decimal.Decimal,
    "$uuid": uuid.UUID,
    "$json": lambda v: v,
}


def _decode(value: Any) -> Any:
    """Read a JSON value back into a column value (the inverse of :func:`_encode`)."""
    if isinstance(value, dict):
        ((tag, inner),) = value.items()
        return _DECODERS[tag](inner)
    return value


# ---------------------------------------------------------------------------------------------
# Files


def _digest(path: Path) -> FileDigest:
    """(K.1)'s left side: SHA-256 and size of `path`, read in chunks."""
    h = hashlib.sha256()
    size = 0
    with path.open("rb") as f:
        while chunk := f.read(_CHUNK_BYTES):
            h.update(chunk)
            size += len(chunk)
    return FileDigest(h.hexdigest(), size)


def _copy_hashed(src: Path, dst: Path) -> FileDigest:
    """Copy `src` to `dst` (fsynced) and return the digest of the bytes read from `src`."""
    h = hashlib.sha256()
    size = 0
    dst.parent.mkdir(parents=True, exist_ok=True)
    with src.open("rb") as fi, dst.open("wb") as fo:
        while chunk := fi.read(_CHUNK_BYTES):
            h.update(chunk)
            size += len(chunk)
            fo.write(chunk)
        fo.flush()
        os.fsync(fo.fileno())
    return FileDigest(h.hexdigest(), size)


def _check_files(dest: Path, files: dict[str, FileDigest]) -> list[str]:
    """Every file of `files` under `dest` that is missing or fails (K.1), one line each."""
    problems = []
    for rel, want in sorted(files.items()):
        path = dest / rel
        if not path.is_file():
            problems.append(f"{rel}: missing")
            continue
        got = _digest(path)
        if got != want:
            problems.append(f"{rel}: changed (sha256 {got.sha256[:12]}…, {got.size_bytes} bytes; "
                            f"the manifest says {want.sha256[:12]}…, {want.size_bytes} bytes)")
    return problems


def _safe_rel(dest: Path, rel: str) -> Path:
    """`dest/rel`, refusing a manifest path that leaves the folder."""
    path = (dest / rel).resolve()
    if not path.is_relative_to(dest.resolve()):
        raise BackupCorruptError(dest, [f"{rel}: outside the backup folder"])
    return path


# ---------------------------------------------------------------------------------------------
# Database


def _engine(url: str | sa.URL) -> Engine:
    """Open an engine of `url`; on SQLite with real transactions (BEGIN at the first statement).

    The pysqlite driver opens no transaction for a SELECT, so two SELECTs could see two states
    of the database; the recipe of the SQLAlchemy documentation (pysqlite, "Serializable
    isolation") makes one ``BEGIN`` cover every statement of a transaction. Foreign keys are
    enforced on SQLite connections of this module (a restore that breaks one fails).
    """
    engine = sa.create_engine(url)
    if engine.dialect.name == "sqlite":

        @sa.event.listens_for(engine, "connect")
        def _connect(dbapi_connection: Any, _record: Any) -> None:
            dbapi_connection.isolation_level = None
            dbapi_connection.execute("PRAGMA foreign_keys = ON")

        @sa.event.listens_for(engine, "begin")
        def _begin(conn: Connection) -> None:
            conn.exec_driver_sql("BEGIN")

    return engine


def _tables(conn: Connection, metadata: sa.MetaData | None) -> list[sa.Table]:
    """List the tables to dump, parents first; reflected from `conn` when `metadata` is None."""
    if metadata is None:
        metadata = sa.MetaData()
        metadata.reflect(bind=conn)
    return [t for t in metadata.sorted_tables if t.name != ALEMBIC_TABLE]


def _revision(conn: Connection) -> str | None:
    """Read the Alembic revision of the database on `conn` (None without ``alembic_version``)."""
    if not sa.inspect(conn).has_table(ALEMBIC_TABLE):
        return None
    rows = conn.execute(sa.text(f"SELECT version_num FROM {ALEMBIC_TABLE}")).scalars().all()
    return ",".join(sorted(str(r) for r in rows)) or None


def _dump_table(conn: Connection, table: sa.Table, path: Path) -> tuple[int, FileDigest]:
    """Write every row of `table` (primary-key order) to `path` as JSON lines."""
    order = list(table.primary_key.columns) or list(table.columns)
    names = [c.name for c in table.columns]
    h = hashlib.sha256()
    size = rows = 0
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("wb") as f:
        # Streamed (a server-side cursor on PostgreSQL): a large table is never all in memory.
        result = conn.execute(sa.select(*table.columns).order_by(*order)
                              .execution_options(yield_per=_INSERT_BATCH_ROWS))
        for row in result:
            line = json.dumps({n: _encode(v) for n, v in zip(names, row, strict=True)},
                              ensure_ascii=False, allow_nan=False, separators=(",", ":"))
            data = (line + "\n").encode("utf-8")
            h.update(data)
            size += len(data)
            rows += 1
            f.write(data)
        f.flush()
        os.fsync(f.fileno())
    return rows, FileDigest(h.hexdigest(), size)


def _sqlite_copy(conn: Connection, path: Path) -> FileDigest:
    """Byte copy of the SQLite database on `conn`, in `conn`'s read transaction (one step)."""
    raw = conn.connection.dbapi_connection
    if not isinstance(raw, sqlite3.Connection):
        raise InvalidInputError(f"an SQLite byte copy needs the sqlite3 driver, not {type(raw)}")
    target = sqlite3.connect(path)
    try:
        raw.backup(target)
    finally:
        target.close()
    return _digest(path)


def _prepare_dests(dests: Iterable[str | Path]) -> list[Path]:
    out: list[Path] = []
    for d in dests:
        p = Path(d)
        if p.exists() and (not p.is_dir() or any(p.iterdir())):
            raise InvalidInputError(f"backup destination {p} exists and is not an empty folder")
        if any(p.resolve() == q.resolve() for q in out):
            raise InvalidInputError(f"backup destination {p} is given twice")
        out.append(p)
    if not out:
        raise InvalidInputError("backup needs at least one destination folder")
    for p in out:
        p.mkdir(parents=True, exist_ok=True)
    return out


def _recording_names(recordings: Sequence[str | Path]) -> list[tuple[Path, str]]:
    out: list[tuple[Path, str]] = []
    seen: set[str] = set()
    for r in recordings:
        p = Path(r)
        if not p.is_file():
            raise InvalidInputError(f"recording {p} is not a file")
        if p.name in seen:
            raise InvalidInputError(f"two recordings are named {p.name!r}; a backup keeps one "
                                    "folder of recordings")
        seen.add(p.name)
        out.append((p, f"recordings/{p.name}"))
    return out


def _keys_of(dump: Path) -> tuple[dict[str, Any], ...]:
    """Return the public keys in a dump of ``signing_keys`` (id, fingerprint, public key)."""
    if not dump.is_file():
        return ()
    out = []
    for row in _rows(dump):
        out.append({"id": row.get("id"), "fingerprint": row.get("fingerprint"),
                    "public_key": row.get("public_key")})
    return tuple(out)


def backup(url: str | sa.URL, dests: Sequence[str | Path], *,
           recordings: Sequence[str | Path] = (),
           metadata: sa.MetaData | None = None,
           extra_files: Mapping[str, str | Path] | None = None) -> list[Manifest]:
    """Back the records database and its recordings up into each folder of `dests`.

    Parameters
    ----------
    url : str or sqlalchemy.URL
        The database.
    dests : sequence of path
        The backup folders (missing or empty), e.g. a local disk and a network share; each
        receives a complete backup with its own ``manifest.json``.
    recordings : sequence of path
        Recording files to copy into ``recordings/`` (names must differ).
    metadata : sqlalchemy.MetaData, optional
        The tables to dump; the database is reflected when omitted (every table but
        ``alembic_version``).
    extra_files : mapping, optional
        Relative path in the backup → a file to copy there (the anchor log, ``station.pub``);
        a file that is not there is left out.

    Returns
    -------
    list of Manifest
        One per folder, in the order of `dests`.

    Raises
    ------
    InvalidInputError
        A destination that is not empty, a recording that is not a file, no destination.
    BackupCorruptError
        A copied file that reads back different from what was written, (K.1); names it.
    """
    from imucalib import __version__

    folders = _prepare_dests(dests)
    recs = _recording_names(recordings)
    first = folders[0]
    files: dict[str, FileDigest] = {}
    tables: list[TableDump] = []
    for rel, src in sorted((extra_files or {}).items()):   # before the snapshot: the anchor
        if Path(src).is_file():                              # log names no row it lacks
            files[rel] = _copy_hashed(Path(src), _safe_rel(first, rel))
    engine = _engine(url)
    kind = engine.dialect.name
    try:
        with engine.connect() as conn:
            if kind == "postgresql":
                conn = conn.execution_options(isolation_level="REPEATABLE READ",
                                              postgresql_readonly=True)
            with conn.begin():
                created = dt.datetime.now(dt.UTC).isoformat(timespec="seconds")
                revision = _revision(conn)
                for table in _tables(conn, metadata):
                    rel = f"tables/{table.name}.jsonl"
                    rows, files[rel] = _dump_table(conn, table, first / rel)
                    tables.append(TableDump(table.name, rel, rows))
                if kind == "sqlite":
                    files[SQLITE_COPY] = _sqlite_copy(conn, first / SQLITE_COPY)
    finally:
        engine.dispose()

    for src, rel in recs:
        files[rel] = _copy_hashed(src, first / rel)
    keys = _keys_of(first / "tables" / "signing_keys.jsonl")
    for folder in folders[1:]:
        for rel in files:
            # From the first folder; checked below against the digests of what was written.
            _copy_hashed(first / rel, folder / rel)

    manifests = []
    for folder in folders:
        m = Manifest(dest=folder, created_utc=created, software_version=__version__,
                     database_kind=kind, schema_revision=revision, tables=tuple(tables),
                     files=dict(files), recordings=tuple(rel for _, rel in recs),
                     signing_keys=keys)
        tmp = folder / (MANIFEST + ".partial")
        tmp.write_text(json.dumps(m.to_json(), indent=2) + "\n", encoding="utf-8")
        tmp.replace(folder / MANIFEST)
        manifests.append(m)
    for m in manifests:
        problems = verify_backup(m.dest)
        if problems:
            raise BackupCorruptError(m.dest, problems)
    return manifests


def verify_backup(dest: str | Path) -> list[str]:
    """Check every file of a backup against its manifest, (K.1).

    Parameters
    ----------
    dest : path
        The backup folder.

    Returns
    -------
    list of str
        One line per missing or changed file (``"<file>: missing"``,
        ``"<file>: changed (…)"``), or per manifest problem; empty when the backup is intact.
    """
    dest = Path(dest)
    try:
        manifest = Manifest.read(dest)
    except BackupCorruptError as exc:
        return list(exc.problems)
    for rel in manifest.files:
        try:
            _safe_rel(dest, rel)
        except BackupCorruptError as exc:
            return list(exc.problems)
    listed = set(manifest.files)
    unlisted = [f"{t.file}: not in the manifest's files" for t in manifest.tables
                if t.file not in listed]
    unlisted += [f"{r}: not in the manifest's files" for r in manifest.recordings
                 if r not in listed]
    return unlisted + _check_files(dest, manifest.files)


def _rows(path: Path) -> Iterator[dict[str, Any]]:
    with path.open("r", encoding="utf-8") as f:
        for line in f:
            if line.strip():
                yield {k: _decode(v) for k, v in json.loads(line).items()}


def _batches(rows: Iterable[dict[str, Any]], n: int) -> Iterator[list[dict[str, Any]]]:
    batch: list[dict[str, Any]] = []
    for row in rows:
        batch.append(row)
        if len(batch) >= n:
            yield batch
            batch = []
    if batch:
        yield batch


def _reset_sequences(conn: Connection, table: sa.Table) -> None:
    """PostgreSQL: move each serial/identity sequence of `table`'s key past the loaded rows."""
    for col in table.primary_key.columns:
        seq = conn.execute(sa.text("SELECT pg_get_serial_sequence(:t, :c)"),
                           {"t": table.name, "c": col.name}).scalar()
        if seq is None:
            continue
        top = conn.execute(sa.select(sa.func.max(col))).scalar()
        if top is not None:
            conn.execute(sa.text("SELECT setval(:s, :v)"), {"s": seq, "v": int(top)})


def restore(dest: str | Path, url: str | sa.URL, *,
            metadata: sa.MetaData | None = None,
            create_schema: Callable[[Engine], None] | None = None,
            recordings_dir: str | Path | None = None) -> RestoreSummary:
    """Restore a backup into an empty database (and its recordings into a folder).

    Parameters
    ----------
    dest : path
        The backup folder; verified first, (K.1).
    url : str or sqlalchemy.URL
        The database to load, which must hold no table yet.
    metadata : sqlalchemy.MetaData, optional
        The schema, created with ``metadata.create_all``.
    create_schema : callable, optional
        Instead of `metadata`: creates the schema on the engine it is given (an Alembic
        ``upgrade head``, say). Exactly one of `metadata` and `create_schema` is required.
    recordings_dir : path, optional
        Where the recordings go (created when missing; an existing file of the same name and
        other content is refused); not restored when omitted.

    Returns
    -------
    RestoreSummary
        Rows loaded per table (dependency order), the recordings written, the revision.

    Raises
    ------
    BackupCorruptError
        A backup failing (K.1): names every missing or changed file; nothing is loaded.
    InvalidInputError
        A database that is not empty, a schema without a table of the backup, a schema of
        another Alembic revision, a recording in the way; both or neither of `metadata` and
        `create_schema`.
    """
    dest = Path(dest)
    if (metadata is None) == (create_schema is None):
        raise InvalidInputError("restore needs exactly one of metadata= and create_schema=")
    problems = verify_backup(dest)
    if problems:
        raise BackupCorruptError(dest, problems)
    manifest = Manifest.read(dest)

    written: list[Path] = []
    if recordings_dir is not None:
        out = Path(recordings_dir)
        for rel in manifest.recordings:
            in_the_way = out / Path(rel).name
            if in_the_way.exists() and _digest(in_the_way) != manifest.files[rel]:
                raise InvalidInputError(f"{in_the_way} exists with other content; "
                                        "not overwritten")

    engine = _engine(url)
    try:
        present = sa.inspect(engine).get_table_names()
        if present:
            raise InvalidInputError(f"restore needs an empty database; {url!s} holds "
                                    f"{len(present)} tables ({', '.join(sorted(present)[:5])}…)")
        if create_schema is not None:
            create_schema(engine)
        else:
            assert metadata is not None
            metadata.create_all(engine)
        if metadata is not None:
            target = metadata
        else:
            target = sa.MetaData()
            target.reflect(bind=engine)
        counts: dict[str, int] = {}
        with engine.begin() as conn:
            revision = _revision(conn)
            if manifest.schema_revision and revision and revision != manifest.schema_revision:
                raise InvalidInputError(
                    f"the backup is of schema revision {manifest.schema_revision}, the new "
                    f"schema is at {revision}: create the schema at the backup's revision")
            for dump in manifest.tables:
                if dump.name not in target.tables:
                    raise InvalidInputError(f"the new schema has no table {dump.name!r}")
                table = target.tables[dump.name]
                n = 0
                for batch in _batches(_rows(_safe_rel(dest, dump.file)), _INSERT_BATCH_ROWS):
                    conn.execute(table.insert(), batch)
                    n += len(batch)
                if n != dump.rows:
                    raise BackupCorruptError(dest, [
                        f"{dump.file}: {n} rows, the manifest says {dump.rows}"])
                if engine.dialect.name == "postgresql":
                    _reset_sequences(conn, table)
                counts[dump.name] = n
    finally:
        engine.dispose()

    if recordings_dir is not None:
        out = Path(recordings_dir)
        for rel in manifest.recordings:
            target_path = out / Path(rel).name
            if not target_path.exists():
                _copy_hashed(_safe_rel(dest, rel), target_path)
            if _digest(target_path) != manifest.files[rel]:
                raise BackupCorruptError(dest, [f"{rel}: restored copy {target_path} differs"])
            written.append(target_path)
    return RestoreSummary(rows=counts, files=tuple(written),
                          schema_revision=manifest.schema_revision)
