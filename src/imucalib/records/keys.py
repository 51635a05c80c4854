"""Registering the station key in the records, and replacing it (docs/records.md, "Signing").

Contents
--------
:func:`ensure_signer`
    The key every write signs with: the key file's, which must be the newest registered key;
    the first write to a database without keys creates the key file (if there is none) and
    registers it.
:func:`register_new_key`
    ``records rekey``: a new key registered after the current one, endorsed by it (R.8), or
    without endorsement when the current key was lost.
"""

from __future__ import annotations

import os
from pathlib import Path

from sqlalchemy import func, select
from sqlalchemy.orm import Session

from imucalib.errors import RecordsError
from imucalib.records import chain
from imucalib.records.canonical import canonical_json
from imucalib.records.schema import CHAINED, SigningKey
from imucalib.records.signing import (
    KEY_FILE,
    LOG_FILE,
    StationKey,
    create_key,
    endorsement_message,
    load_key,
)

__all__ = ["ensure_signer", "register_new_key"]


def _heads(session: Session) -> dict[str, int]:
    out = {}
    for model in CHAINED:
        if model is SigningKey:
            continue
        top = session.scalar(select(func.max(model.seq)))
        out[model.__tablename__] = int(top or 0)  # type: ignore[attr-defined]
    return out


def _touch(path: Path) -> None:
    try:
        os.close(os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o600))
    except OSError as exc:
        raise RecordsError(f"cannot create the anchor log {path}: {exc}") from exc


def _newest(session: Session) -> SigningKey | None:
    return session.scalars(select(SigningKey).order_by(SigningKey.seq.desc()).limit(1)).first()


def _register(session: Session, key: StationKey, previous: SigningKey | None,
              endorsement: str, reason: str) -> SigningKey:
    row = SigningKey(public_key=key.public_hex, fingerprint=key.fingerprint,
                     previous_key_id=None if previous is None else previous.id,
                     endorsement=endorsement, reason=reason,
                     heads_json=canonical_json(_heads(session)))
    return chain.append(session, row, self_signed=key)


def ensure_signer(session: Session, folder: Path,
                  cached: StationKey | None = None) -> tuple[StationKey, int]:
    """Return the station key and its id in the records, registering it when they have none.

    Raises
    ------
    RecordsError
        A key file readable by others; no key file although the records are signed (restore
        it, or ``records rekey --lost-key``); a key file that is not the newest registered key.
    """
    chain.lock(session, SigningKey)
    newest = _newest(session)
    path = folder / KEY_FILE
    key = cached if cached is not None and cached.path == path else load_key(path)
    if key is None:
        if newest is not None:
            raise RecordsError(
                f"the records are signed by key {newest.id} ({newest.fingerprint}) but its key "
                f"file {path} is missing: copy it back there (or set IMUCALIB_RECORDS_SIGNING "
                "to its folder), or register a new key with `imucalib records rekey "
                "--lost-key --reason …` (docs/records.md, \"A lost key\")")
        key = create_key(path)
    if newest is None:
        _touch(folder / LOG_FILE)   # there before the first signed row is committed
        return key, _register(session, key, None, "", "first key").id
    if newest.public_key != key.public_hex:
        old = session.scalars(select(SigningKey.id).where(
            SigningKey.public_key == key.public_hex)).first()
        was = (f"key {old}, which key {newest.id} replaced" if old is not None
               else "not registered in these records")
        raise RecordsError(f"the key file {path} ({key.fingerprint}) is {was}; these records "
                           f"are signed by key {newest.id} ({newest.fingerprint}): use its key "
                           "file, or `imucalib records rekey` (docs/records.md, \"Signing\")")
    return key, newest.id


def register_new_key(session: Session, old: StationKey | None, new: StationKey,
                     reason: str) -> int:
    """Register `new` after the newest key, endorsed by `old` (None: the old key was lost).

    Raises
    ------
    RecordsError
        `old` given but not the newest registered key.
    """
    chain.lock(session, SigningKey)
    newest = _newest(session)
    endorsement = ""
    if old is not None:
        if newest is not None and newest.public_key != old.public_hex:
            raise RecordsError(f"the key file {old.path} ({old.fingerprint}) is not the newest "
                               f"key of these records, key {newest.id} ({newest.fingerprint})")
        endorsement = old.sign(endorsement_message(new.public_hex))
    row = _register(session, new, newest, endorsement, reason)
    return int(row.id)
