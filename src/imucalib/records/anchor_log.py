"""The anchor log: the chain heads after every append, kept outside the database.

A deleted last row leaves no broken link behind it (Eq. (R.2) looks backwards only). Every
transaction that appends rows therefore also appends one line to ``anchors.jsonl`` in the key
folder (:func:`imucalib.records.signing.signing_folder`), after its commit:

(R.10) ``line = {"heads": {table: [seq, row_hash], …}, "key": fingerprint, "utc": time}`` with
       ``"sig" = Ed25519-Sign(k, "imucalib records anchor " ‖ C(line))``, ``C`` the canonical
       JSON of the line without ``"sig"`` (docs/records.md).

The file is only ever appended to (one ``write`` of a whole line, under an advisory lock), so
lines from two processes never interleave; their order does not matter, since each line is
checked on its own: every anchored row must still be in its table with the same hash.
``imucalib records backup`` copies the log into every backup folder.

Contents
--------
:class:`AnchorLine`, :func:`append_heads`, :func:`read_log`, :func:`line_message`
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from imucalib.errors import RecordsError
from imucalib.records.canonical import canonical_json
from imucalib.records.signing import StationKey

__all__ = ["AnchorLine", "append_heads", "line_message", "read_log"]

#: The most bytes of one line read back (a longer line is reported, not parsed).
MAX_LINE = 1 << 16


@dataclass(frozen=True)
class AnchorLine:
    """One line of the anchor log (its number counts from 1)."""

    number: int
    utc: str
    key: str
    heads: dict[str, tuple[int, str]] = field(default_factory=dict)
    sig: str = ""
    body: dict[str, Any] = field(default_factory=dict)


def line_message(body: Mapping[str, Any]) -> bytes:
    """Return what Eq. (R.10) signs for a line `body` (the line without ``"sig"``)."""
    return b"imucalib records anchor " + canonical_json(dict(body)).encode("utf-8")


def append_heads(path: Path, key: StationKey, heads: Mapping[str, tuple[int, str]]) -> None:
    """Append one signed line holding `heads` (table → (seq, row_hash)) to the log at `path`.

    Raises
    ------
    RecordsError
        The log cannot be written (the rows are committed; ``records verify`` will not find
        them anchored).
    """
    body = {"heads": {t: [int(s), str(h)] for t, (s, h) in sorted(heads.items())},
            "key": key.fingerprint,
            "utc": datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%S.%fZ")}
    line = canonical_json({**body, "sig": key.sign(line_message(body))}) + "\n"
    try:
        path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
        fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o600)
        try:
            try:
                import fcntl

                fcntl.flock(fd, fcntl.LOCK_EX)
            except ImportError:  # pragma: no cover - not POSIX
                pass
            os.write(fd, line.encode("utf-8"))
        finally:
            os.close(fd)
    except OSError as exc:
        raise RecordsError(f"cannot append to the anchor log {path}: {exc}") from exc


def _parse(number: int, text: str) -> AnchorLine | str:
    try:
        raw = json.loads(text)
        heads = {str(t): (int(v[0]), str(v[1])) for t, v in raw["heads"].items()}
        if not all(isinstance(v[0], int) and not isinstance(v[0], bool)
                   for v in raw["heads"].values()):
            raise TypeError("a seq that is not an integer")
        body = {k: v for k, v in raw.items() if k != "sig"}
        return AnchorLine(number, str(raw["utc"]), str(raw["key"]), heads, str(raw["sig"]),
                          body)
    except (ValueError, KeyError, TypeError, AttributeError, IndexError,
            RecursionError) as exc:
        return f"line {number} is not an anchor line ({type(exc).__name__}: {exc})"


def read_log(path: Path) -> tuple[list[AnchorLine], list[str]]:
    """Return the lines of the anchor log at `path`, and one text per malformed line.

    A missing file gives two empty lists.

    Raises
    ------
    RecordsError
        The log exists but cannot be read.
    """
    lines: list[AnchorLine] = []
    bad: list[str] = []
    try:
        with path.open("rb") as f:
            for number, raw in enumerate(f, start=1):
                if len(raw) > MAX_LINE:
                    bad.append(f"line {number} is longer than {MAX_LINE} bytes")
                    continue
                try:
                    text = raw.decode("utf-8").strip()
                except UnicodeDecodeError:
                    bad.append(f"line {number} is not UTF-8")
                    continue
                if not text:
                    continue
                parsed = _parse(number, text)
                (bad.append if isinstance(parsed, str) else lines.append)(parsed)  # type: ignore[arg-type]
    except FileNotFoundError:
        return [], []
    except OSError as exc:
        raise RecordsError(f"cannot read the anchor log {path}: {exc}") from exc
    return lines, bad
