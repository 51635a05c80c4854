"""The station's signing key, kept outside the records database (docs/records.md, "Signing").

Equations
---------
(R.7) ``σ(row) = Ed25519-Sign(k, "imucalib records row " ‖ row_hash)``: the signature of a
      row covers its hash (R.1), which binds its table, id, sequence number and content;
(R.8) ``ε(new) = Ed25519-Sign(k_old, "imucalib records key " ‖ public_key_new)``: the
      endorsement of a new key by the key it replaces (``records rekey``);
(R.9) ``fingerprint(key) = SHA-256(public key bytes)[:16 hex]``.

Ed25519 is the signature scheme of RFC 8032 (Josefsson & Liusvaara, 2017), through the
``cryptography`` package. Signatures and public keys are stored as lowercase hex.

The key folder (:func:`signing_folder`): ``$IMUCALIB_RECORDS_SIGNING`` when set; else, for an
SQLite file ``…/records.db``, the folder ``…/records.db.signing`` beside it; else (PostgreSQL,
an in-memory SQLite) ``<user config dir>/records-signing/<host>-<port>-<database>``
(platformdirs). It holds ``station.key`` (the private key, PKCS#8 PEM, owner-only: mode 0600),
``station.pub`` (its public key in hex, for an auditor) and ``anchors.jsonl`` (the anchor log,
:mod:`imucalib.records.anchor_log`).

Contents
--------
:class:`StationKey`, :func:`signing_folder`, :func:`load_key`, :func:`create_key`,
:func:`read_public`, :func:`verify_signature`, :func:`fingerprint`, :func:`row_message`,
:func:`endorsement_message`
"""

from __future__ import annotations

import hashlib
import os
import re
import stat
import sys
import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import Final

from imucalib.errors import RecordsError

__all__ = ["KEY_FILE", "LOG_FILE", "PUB_FILE", "SIGNING_ENV", "StationKey", "create_key",
           "endorsement_message", "fingerprint", "load_key", "read_public", "row_message",
           "signing_folder", "verify_signature", "write_public"]

#: Environment variable naming the key folder of the database in use.
SIGNING_ENV: Final = "IMUCALIB_RECORDS_SIGNING"
KEY_FILE: Final = "station.key"
PUB_FILE: Final = "station.pub"
LOG_FILE: Final = "anchors.jsonl"
_HEX64 = re.compile(r"[0-9a-f]{64}")
_HEX128 = re.compile(r"[0-9a-f]{128}")


def signing_folder(url: str) -> Path:
    """Return the key folder of the database at `url` (module docstring)."""
    env = os.environ.get(SIGNING_ENV)
    if env:
        return Path(env).expanduser()
    from sqlalchemy.engine import make_url

    parsed = make_url(url)
    database = parsed.database or ""
    if parsed.get_backend_name() == "sqlite" and database and database != ":memory:" \
            and not database.startswith("file:"):
        path = Path(database).expanduser().resolve()
        return path.with_name(path.name + ".signing")
    import platformdirs

    name = "-".join(str(p) for p in (parsed.host or "local", parsed.port or "",
                                     database or "memory") if p != "")
    name = re.sub(r"[^A-Za-z0-9._-]", "_", name)
    return Path(platformdirs.user_config_dir("imucalib")) / "records-signing" / name


def fingerprint(public_hex: str) -> str:
    """Return Eq. (R.9): the first 16 hex digits of SHA-256 of the public key's bytes."""
    try:
        raw = bytes.fromhex(public_hex)
    except ValueError:
        raw = public_hex.encode("utf-8", "replace")
    return hashlib.sha256(raw).hexdigest()[:16]


def row_message(row_hash: str) -> bytes:
    """Return what Eq. (R.7) signs for a row whose hash is `row_hash`."""
    return b"imucalib records row " + row_hash.encode("ascii", "replace")


def endorsement_message(public_hex: str) -> bytes:
    """Return what Eq. (R.8) signs: the new key's public key."""
    return b"imucalib records key " + public_hex.encode("ascii", "replace")


def verify_signature(public_hex: str, signature_hex: str, message: bytes) -> bool:
    """Return whether `signature_hex` is a valid Ed25519 signature of `message` by the key.

    Malformed keys or signatures (not hex, wrong length) are simply not valid.
    """
    from cryptography.exceptions import InvalidSignature
    from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PublicKey

    if not (isinstance(public_hex, str) and isinstance(signature_hex, str)
            and _HEX64.fullmatch(public_hex) and _HEX128.fullmatch(signature_hex)):
        return False
    try:
        Ed25519PublicKey.from_public_bytes(bytes.fromhex(public_hex)).verify(
            bytes.fromhex(signature_hex), message)
    except (InvalidSignature, ValueError):
        return False
    return True


@dataclass(frozen=True)
class StationKey:
    """The station's private key as loaded from its key file.

    Attributes
    ----------
    path : Path
        The key file.
    private : Ed25519PrivateKey
    public_hex : str
        The 32-byte public key as 64 hex digits.
    """

    path: Path
    private: object
    public_hex: str

    @property
    def fingerprint(self) -> str:
        """Eq. (R.9)."""
        return fingerprint(self.public_hex)

    def sign(self, message: bytes) -> str:
        """Return the Ed25519 signature of `message` as 128 hex digits."""
        return str(self.private.sign(message).hex())  # type: ignore[attr-defined]


def _public_hex(private: object) -> str:
    from cryptography.hazmat.primitives.serialization import Encoding, PublicFormat

    return str(private.public_key().public_bytes(  # type: ignore[attr-defined]
        Encoding.Raw, PublicFormat.Raw).hex())


def _check_mode(path: Path) -> None:
    if sys.platform == "win32":  # pragma: no cover - POSIX modes only
        return
    mode = stat.S_IMODE(path.stat().st_mode)
    if mode & 0o077:
        raise RecordsError(f"the station key {path} is readable by others (mode {mode:04o}): "
                           f"expected owner-only permissions; run `chmod 600 {path}`")


def load_key(path: Path) -> StationKey | None:
    """Return the key in the file `path`, or None when there is no such file.

    Raises
    ------
    RecordsError
        A key file readable by group or others, unreadable, or not an Ed25519 private key.
    """
    from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PrivateKey
    from cryptography.hazmat.primitives.serialization import load_pem_private_key

    if not path.exists():
        return None
    _check_mode(path)
    try:
        private = load_pem_private_key(path.read_bytes(), password=None)
    except (OSError, ValueError, TypeError) as exc:
        raise RecordsError(f"the station key {path} cannot be read: expected an Ed25519 "
                           f"private key (PKCS#8 PEM), got {exc}") from exc
    if not isinstance(private, Ed25519PrivateKey):
        raise RecordsError(f"the station key {path} is a {type(private).__name__}: expected "
                           "an Ed25519 private key")
    return StationKey(path, private, _public_hex(private))


def create_key(path: Path, *, publish: bool = True) -> StationKey:
    """Create a new key file at `path` (mode 0600) and its ``station.pub``; return the key.

    Safe against a concurrent creator: the file appears whole (written aside, then linked);
    when another process made it first, its key is returned.
    """
    from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PrivateKey
    from cryptography.hazmat.primitives.serialization import (
        Encoding,
        NoEncryption,
        PrivateFormat,
    )

    private = Ed25519PrivateKey.generate()
    pem = private.private_bytes(Encoding.PEM, PrivateFormat.PKCS8, NoEncryption())
    try:
        path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
        tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex}")
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        try:
            os.write(fd, pem)
            os.fsync(fd)
        finally:
            os.close(fd)
        try:
            os.link(tmp, path)
        except FileExistsError:
            pass                          # another process made it: use theirs
        finally:
            tmp.unlink(missing_ok=True)
    except OSError as exc:
        raise RecordsError(f"cannot create the station key {path}: {exc}") from exc
    key = load_key(path)
    if key is None:  # pragma: no cover - removed between the link and the read
        raise RecordsError(f"the station key {path} vanished while it was created")
    if publish:
        write_public(key)
    return key


def write_public(key: StationKey) -> None:
    """Write ``station.pub`` beside the key file (its public key, for an auditor)."""
    pub = key.path.with_name(PUB_FILE)
    try:
        if read_public(pub) != key.public_hex:
            tmp = pub.with_name(f".{pub.name}.{uuid.uuid4().hex}")
            tmp.write_text(key.public_hex + "\n", encoding="ascii")
            tmp.replace(pub)
    except OSError as exc:
        raise RecordsError(f"cannot write {pub}: {exc}") from exc


def read_public(path: Path) -> str | None:
    """Return the public key (hex) in ``station.pub`` at `path`, or None (missing, malformed)."""
    try:
        text = path.read_text(encoding="ascii").strip()
    except (OSError, UnicodeDecodeError):
        return None
    return text if _HEX64.fullmatch(text) else None
