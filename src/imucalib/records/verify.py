"""Re-hash the records and their recording files; name every mismatch (docs/records.md, "Verify").

Contents
--------
:func:`verify_session`

For each chained table, in ``seq`` order, with ``prev`` the stored ``row_hash`` of the row
before (``GENESIS`` before the first):

- a ``seq`` that skips numbers: each missing ``seq`` is named (a deleted row);
- an ``id`` that differs from ``seq``;
- a ``prev_hash`` other than ``prev``: the chain is broken there (a row before it was deleted
  or re-hashed);
- a ``row_hash`` other than Eq. (R.1) recomputed from the row's own ``prev_hash`` and content
  (children included): the row, or one of its parameters or equipment links, was edited;
- an anchor (an earlier :class:`~imucalib.records.views.ChainHead`) whose ``seq`` is gone or
  whose hash differs (a deleted or replaced last row).

For each run with a recording: the file is missing, or its SHA-256 differs from the one
recorded.
"""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path
from typing import Any

from sqlalchemy import select
from sqlalchemy.orm import Session

from imucalib.io.hashing import file_sha256
from imucalib.records.canonical import GENESIS, chain_hash, row_content
from imucalib.records.chain import parameter_content
from imucalib.records.schema import CHAINED, Result, ResultParameter, Run, RunEquipment
from imucalib.records.views import ChainHead, Problem

__all__ = ["verify_session"]


def _children(session: Session) -> dict[type[Any], dict[int, dict[str, Any]]]:
    params: dict[int, list[ResultParameter]] = defaultdict(list)
    for p in session.scalars(select(ResultParameter)):
        params[p.result_id].append(p)
    links: dict[int, list[int]] = defaultdict(list)
    for link in session.scalars(select(RunEquipment)):
        links[link.run_id].append(int(link.equipment_id))
    return {
        Result: defaultdict(lambda: {"parameters": []},
                            {k: {"parameters": parameter_content(v)} for k, v in params.items()}),
        Run: defaultdict(lambda: {"equipment": []},
                         {k: {"equipment": sorted(v)} for k, v in links.items()}),
    }


def _check_chain(session: Session, model: type[Any], children: dict[int, dict[str, Any]] | None,
                 anchors: list[ChainHead]) -> list[Problem]:
    table = model.__tablename__
    problems = []
    prev, expected_seq = GENESIS, 1
    stored: dict[int, str] = {}
    for row in session.scalars(select(model).order_by(model.seq)):
        seq = int(row.seq)
        stored[seq] = row.row_hash
        for missing in range(expected_seq, seq):
            problems.append(Problem(table, missing, f"row seq {missing} is missing (deleted); "
                                                    f"the chain jumps from {expected_seq - 1} "
                                                    f"to {seq}"))
        if row.id != seq:
            problems.append(Problem(table, seq, f"id {row.id} differs from seq {seq}"))
        if row.prev_hash != prev:
            problems.append(Problem(table, seq, f"prev_hash {row.prev_hash[:16]}… does not "
                                                f"match the previous row's row_hash "
                                                f"{prev[:16]}… (chain broken)"))
        content = row_content(row, **(children[row.id] if children is not None else {}))
        again = chain_hash(row.prev_hash, content)
        if again != row.row_hash:
            problems.append(Problem(table, seq, f"content re-hashes to {again[:16]}…, not the "
                                                f"stored row_hash {row.row_hash[:16]}… "
                                                "(edited)"))
        prev, expected_seq = row.row_hash, seq + 1
    for anchor in anchors:
        if anchor.table != table or anchor.seq == 0:
            continue
        if anchor.seq not in stored:
            problems.append(Problem(table, anchor.seq, f"anchored row seq {anchor.seq} is "
                                                       "missing (deleted)"))
        elif stored[anchor.seq] != anchor.row_hash:
            problems.append(Problem(table, anchor.seq, f"row_hash {stored[anchor.seq][:16]}… "
                                                       f"differs from the anchor "
                                                       f"{anchor.row_hash[:16]}…"))
    return problems


def _check_recordings(session: Session) -> list[Problem]:
    problems = []
    for run in session.scalars(select(Run).where(Run.recording_path != "").order_by(Run.seq)):
        path = Path(run.recording_path)
        if not path.is_file():
            problems.append(Problem("recordings", run.id, f"recording {path} of run {run.id} "
                                                          "is missing"))
            continue
        try:
            sha = file_sha256(path)
        except OSError as exc:
            problems.append(Problem("recordings", run.id, f"recording {path} of run {run.id} "
                                                          f"cannot be read: {exc}"))
            continue
        if sha != run.recording_sha256:
            problems.append(Problem("recordings", run.id, f"recording {path} of run {run.id} "
                                                          f"has sha256 {sha}, recorded "
                                                          f"{run.recording_sha256} (changed)"))
    return problems


def verify_session(session: Session, *, recordings: bool = True,
                   anchors: list[ChainHead] | None = None) -> list[Problem]:
    """Return every mismatch in the database `session` reads (module docstring)."""
    children = _children(session)
    problems: list[Problem] = []
    for model in CHAINED:
        problems += _check_chain(session, model, children.get(model), anchors or [])
    if recordings:
        problems += _check_recordings(session)
    return problems
