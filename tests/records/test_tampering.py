"""The tampering suite: every change to the records is caught by ``records verify``, naming the
row and the kind of change, with the station key and the anchor log present (docs/records.md,
"What verify checks").

Each case says which protection catches it (``NEEDS``):

- ``hash``: the hash chain alone, Eqs. (R.1)–(R.3) (an edit that is not re-hashed, a deleted
  middle row, a bad value);
- ``signature``: the station key's signature, Eq. (R.7) (a re-hashed chain, a forged row with
  a correct hash, a row signed by a key someone else registered, a downgraded row);
- ``anchor log``: the anchor log, Eq. (R.10) (deleted last rows: nothing after them breaks);
- ``recording``: the recording's SHA-256.

The cases run on one SQLite database built once and copied for each case (the attacks are plain
SQL, the same on PostgreSQL; tests/records/test_verify.py runs on both backends).
"""

from __future__ import annotations

import shutil
from collections.abc import Callable
from dataclasses import dataclass
from datetime import UTC, date, datetime
from pathlib import Path
from typing import Any

import pytest
from sqlalchemy import select, text
from sqlalchemy.orm import Session

from imucalib.records import open_records
from imucalib.records.canonical import chain_hash, row_content
from imucalib.records.chain import children_of
from imucalib.records.schema import CHAINED, Result, Review, SigningKey, Unit
from imucalib.records.signing import StationKey, fingerprint, row_message

#: The populated database's ids (the attacks refer to them).
RESULTS = (1, 2, 3, 4)       # 4 amends 3
REVIEWS = (1, 2, 3)          # reviews of 1, 2, 4


def _small_result(serial: str, bias: float) -> Any:
    import importlib.util

    spec = importlib.util.spec_from_file_location("records_conftest",
                                                  Path(__file__).with_name("conftest.py"))
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.small_result(serial, bias)


@pytest.fixture(scope="module")
def populated(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A populated records database with its key folder (copied by each case)."""
    folder = tmp_path_factory.mktemp("tamper-template")
    recording = folder / "run.h5"
    recording.write_bytes(b"\x89HDF\r\n\x1a\n" + bytes(range(256)) * 4)
    url = f"sqlite:///{folder / 'records.db'}"
    with open_records(url) as rec:
        rec.add_user("Ada Admin", "AA", "admin")
        rec.add_user("Rae Reviewer", "RR", "reviewer", by="Ada Admin")
        rec.add_user("Oli Operator", "OO", "operator", by="Ada Admin")
        rec.add_user("Max Moved", "MM", "operator", by="Ada Admin")
        rec.disable_user("Max Moved", "left the lab", by="Ada Admin")
        lab = rec.add_station("lab 1", location="building 4")
        rec.add_unit("IMU-0", recal_interval_days=180)
        table = rec.add_equipment(lab, "rate table", serial="T-1", certificate="C-1",
                                  calibrated_on=date(2026, 1, 5), due_on=date(2027, 1, 5))
        rec.recertify_equipment(table, "C-2", date(2026, 6, 1), date(2027, 6, 1))
        run = rec.record_run(plan_name="p1", recording=recording, operator="Oli Operator",
                             station=lab, equipment=[table],
                             started_utc=datetime(2026, 3, 1, tzinfo=UTC))
        ids = [rec.record_result(run, _small_result(f"IMU-{i}", 0.01 * i), passed=True)
               for i in range(1, 4)]
        rec.review(ids[0], "Rae Reviewer", approved=True, comment="ok")
        rec.review(ids[1], "Rae Reviewer", approved=False, comment="bias")
        new = rec.amend(ids[2], _small_result("IMU-3", 0.031), reason="offset", passed=False)
        rec.review(new, "Ada Admin", approved=True, comment="ok 4")
        assert (*ids, new) == RESULTS
        report = rec.verify_report()
        assert report.problems == (), report.problems
    return folder


@dataclass
class Copy:
    """A copy of the populated database for one attack."""

    folder: Path
    url: str

    def sql(self, statement: str, **params: Any) -> None:
        with _engine(self.url).begin() as conn:
            conn.execute(text(statement), params)

    def session(self) -> Session:
        return Session(_engine(self.url))


_ENGINES: dict[str, Any] = {}


def _engine(url: str) -> Any:
    from sqlalchemy import create_engine

    if url not in _ENGINES:
        _ENGINES[url] = create_engine(url)
    return _ENGINES[url]


@pytest.fixture
def copy(populated: Path, tmp_path: Path) -> Copy:
    shutil.copyfile(populated / "records.db", tmp_path / "records.db")
    shutil.copytree(populated / "records.db.signing", tmp_path / "records.db.signing")
    return Copy(tmp_path, f"sqlite:///{tmp_path / 'records.db'}")


# --- what an intruder with write access to the database (but not the key) can do -----------
def _rehash_from(c: Copy, model: type[Any], seq: int) -> None:
    """Recompute Eq. (R.1) from row `seq` to the end of `model`'s chain (no key: the
    signatures stay as they were)."""
    with c.session() as s:
        rows = s.scalars(select(model).order_by(model.seq)).all()
        prev = None
        for row in rows:
            if row.seq >= seq:
                row.prev_hash = prev if prev is not None else row.prev_hash
                row.row_hash = chain_hash(row.prev_hash,
                                          row_content(row, **children_of(s, row)))
            prev = row.row_hash
        s.commit()


def _intruder_key() -> StationKey:
    from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PrivateKey
    from cryptography.hazmat.primitives.serialization import Encoding, PublicFormat

    private = Ed25519PrivateKey.generate()
    pub = private.public_key().public_bytes(Encoding.Raw, PublicFormat.Raw).hex()
    return StationKey(Path("/nonexistent"), private, pub)


def _append(c: Copy, row: Any, key: StationKey | None, key_id: int | None, *,
            signature: str | None = None) -> int:
    """Append a row with a correct hash, signed by `key` (or given `signature`)."""
    model = type(row)
    with c.session() as s:
        head = s.execute(select(model.seq, model.row_hash).order_by(model.seq.desc())
                         .limit(1)).first()
        seq = 1 if head is None else head[0] + 1
        row.id = row.seq = seq
        row.prev_hash = "0" * 64 if head is None else head[1]
        row.created_utc = datetime.now(UTC)
        row.hash_version, row.key_id = 2, key_id if key_id is not None else seq
        for column in row.__table__.columns:
            if getattr(row, column.key) is None and column.default is not None \
                    and column.default.is_scalar:
                setattr(row, column.key, column.default.arg)
        row.row_hash = chain_hash(row.prev_hash, row_content(row, **children_of(s, row)))
        row.signature = (signature if signature is not None
                         else key.sign(row_message(row.row_hash)) if key else "")
        s.add(row)
        s.commit()
        return seq


def _forged_review(result_id: int = 2) -> Review:
    return Review(result_id=result_id, reviewer="Rae Reviewer", approved=True, comment="fine",
                  reviewed_utc=datetime.now(UTC))


def _stolen_signature(c: Copy) -> str:
    with c.session() as s:
        return str(s.get(Review, 1).signature)


# --- the attacks ------------------------------------------------------------------------------
def edit(table: str, setting: str, seq: int) -> Callable[[Copy], None]:
    return lambda c: c.sql(f"UPDATE {table} SET {setting} WHERE seq = {seq}")


def a_middle_result_edited_and_chain_rehashed(c: Copy) -> None:
    c.sql("UPDATE results SET passed = 0 WHERE seq = 2")
    _rehash_from(c, Result, 2)


def a_middle_review_deleted_and_chain_rehashed(c: Copy) -> None:
    c.sql("DELETE FROM reviews WHERE seq = 2")
    c.sql("UPDATE reviews SET id = 2, seq = 2 WHERE seq = 3")
    _rehash_from(c, Review, 2)


def the_last_result_edited_and_rehashed(c: Copy) -> None:
    c.sql("UPDATE results SET passed = 1 WHERE seq = 4")
    _rehash_from(c, Result, 4)


def a_forged_last_review_with_a_stolen_signature(c: Copy) -> None:
    _append(c, _forged_review(), None, 1, signature=_stolen_signature(c))


def a_forged_last_review_unsigned_with_a_correct_hash(c: Copy) -> None:
    _append(c, _forged_review(), None, 1, signature="")


def a_forged_review_by_an_intruders_own_registered_key(c: Copy) -> None:
    mine = _intruder_key()
    kid = _append(c, SigningKey(public_key=mine.public_hex, fingerprint=mine.fingerprint,
                                previous_key_id=1, endorsement="", reason="rotation",
                                heads_json="{}"), mine, None)
    _append(c, _forged_review(), mine, kid)


def a_review_signed_by_a_key_that_is_not_registered(c: Copy) -> None:
    _append(c, _forged_review(), _intruder_key(), 7)


def the_key_replaced_and_every_row_resigned(c: Copy) -> None:
    """The intruder swaps the registered public key for theirs and re-signs everything."""
    mine = _intruder_key()
    with c.session() as s:
        for model in CHAINED:
            for row in s.scalars(select(model).order_by(model.seq)):
                if isinstance(row, SigningKey):
                    row.public_key, row.fingerprint = mine.public_hex, mine.fingerprint
        s.commit()
    for model in CHAINED:
        _rehash_from(c, model, 1)
    with c.session() as s:
        for model in CHAINED:
            for row in s.scalars(select(model)):
                row.signature = mine.sign(row_message(row.row_hash))
        s.commit()


def the_last_unit_downgraded_to_unsigned(c: Copy) -> None:
    with c.session() as s:
        row = s.scalars(select(Unit).order_by(Unit.seq.desc())).first()
        row.hash_version, row.key_id, row.signature, row.model = 1, None, "", "forged"
        row.row_hash = chain_hash(row.prev_hash, row_content(row))
        s.commit()


def the_last_review_deleted(c: Copy) -> None:
    c.sql("DELETE FROM reviews WHERE seq = 3")


def the_last_review_deleted_with_an_older_backups_anchors(c: Copy) -> None:
    c.sql("DELETE FROM reviews WHERE seq = 3")        # verify also gets the old heads below


def two_referenced_last_results_deleted(c: Copy) -> None:
    with _engine(c.url).begin() as conn:
        conn.exec_driver_sql("PRAGMA foreign_keys = OFF")
        conn.exec_driver_sql("DELETE FROM result_parameters WHERE result_id IN (3, 4)")
        conn.exec_driver_sql("DELETE FROM results WHERE seq IN (3, 4)")


def the_last_user_event_deleted(c: Copy) -> None:
    c.sql("DELETE FROM user_events WHERE seq = 1")


def the_only_key_deleted(c: Copy) -> None:
    c.sql("DELETE FROM signing_keys")


def an_anchor_log_line_edited(c: Copy) -> None:
    log = c.folder / "records.db.signing" / "anchors.jsonl"
    lines = log.read_text().splitlines()
    lines[2] = lines[2].replace('"heads":{', '"heads":{"zz":[1,"00"],', 1)
    log.write_text("\n".join(lines) + "\n")


def a_parameter_edited(c: Copy) -> None:
    c.sql("UPDATE result_parameters SET value = value + 1 WHERE result_id = 2 AND "
          "name = 'accel_b_x'")


def a_parameter_deleted(c: Copy) -> None:
    c.sql("DELETE FROM result_parameters WHERE result_id = 1 AND name = 'gyro_b_z'")


def a_parameter_added(c: Copy) -> None:
    c.sql("INSERT INTO result_parameters (result_id, name, value, std, unit) VALUES "
          "(2, 'extra', 1.0, 0.1, '1')")


def a_parameter_value_stored_as_text(c: Copy) -> None:
    c.sql("UPDATE result_parameters SET std = 'abc' WHERE result_id = 3 AND name = 'accel_b_x'")


def an_equipment_link_removed(c: Copy) -> None:
    c.sql("DELETE FROM run_equipment WHERE run_id = 1")


def an_equipment_link_added(c: Copy) -> None:
    c.sql("INSERT INTO run_equipment (run_id, equipment_id) VALUES (1, 2)")


def a_timestamp_with_trailing_junk(c: Copy) -> None:
    c.sql("UPDATE reviews SET reviewed_utc = reviewed_utc || 'junk' WHERE seq = 2")


def a_seq_of_1e308(c: Copy) -> None:
    c.sql("UPDATE units SET seq = 1e308 WHERE seq = 2")


def a_dangling_run_reference(c: Copy) -> None:
    with _engine(c.url).begin() as conn:
        conn.exec_driver_sql("PRAGMA foreign_keys = OFF")
        conn.exec_driver_sql("UPDATE results SET run_id = 99 WHERE seq = 1")


def the_recording_edited(c: Copy) -> None:
    with c.session() as s:
        path = Path(s.execute(text("SELECT recording_path FROM runs")).scalar_one())
    copy = c.folder / "run.h5"
    data = bytearray(path.read_bytes())
    data[50] ^= 1
    copy.write_bytes(bytes(data))
    c.sql("UPDATE runs SET recording_path = :p", p=str(copy))   # (edits the run too)


def the_recording_missing(c: Copy) -> None:
    c.sql("UPDATE runs SET recording_path = :p", p=str(c.folder / "gone.h5"))


@dataclass(frozen=True)
class Case:
    attack: Callable[[Copy], None]
    table: str
    key: int
    kind: str
    needs: str
    name: str = ""


CASES = [
    # the hash chain alone (R.1)–(R.3)
    Case(edit("results", "passed = 0", 1), "results", 1, "edited", "hash", "result decision"),
    Case(edit("runs", "operator = 'mallory'", 1), "runs", 1, "edited", "hash", "run operator"),
    Case(edit("reviews", "reviewer = 'Mallory'", 1), "reviews", 1, "edited", "hash",
         "reviewer"),
    Case(edit("reviews", "approved = 1", 2), "reviews", 2, "edited", "hash", "decision"),
    Case(edit("users", "role = 'admin'", 3), "users", 3, "edited", "hash", "user role"),
    Case(edit("user_events", "reason = 'x'", 1), "user_events", 1, "edited", "hash",
         "user event"),
    Case(edit("equipment", "due_on = '2099-01-01'", 2), "equipment", 2, "edited", "hash",
         "certificate due date"),
    Case(edit("units", "recal_interval_days = 9999", 1), "units", 1, "edited", "hash",
         "unit interval"),
    Case(edit("stations", "location = 'elsewhere'", 1), "stations", 1, "edited", "hash",
         "station"),
    Case(edit("results", "created_utc = '2020-01-01 00:00:00.000000'", 2), "results", 2,
         "edited", "hash", "created time"),
    Case(edit("results", "amendment_reason = 'none'", 4), "results", 4, "edited", "hash",
         "amendment reason"),
    Case(edit("signing_keys", "reason = 'x'", 1), "signing_keys", 1, "edited", "hash",
         "key row"),
    Case(edit("signing_keys", "public_key = '" + "ab" * 32 + "'", 1), "signing_keys", 1,
         "forged", "signature", "registered public key"),
    Case(a_parameter_edited, "results", 2, "edited", "hash", "parameter edited"),
    Case(a_parameter_deleted, "results", 1, "edited", "hash", "parameter deleted"),
    Case(a_parameter_added, "results", 2, "edited", "hash", "parameter added"),
    Case(an_equipment_link_removed, "runs", 1, "edited", "hash", "equipment link removed"),
    Case(an_equipment_link_added, "runs", 1, "edited", "hash", "equipment link added"),
    Case(edit("reviews", "seq = 9, id = 9", 2), "reviews", 2, "deleted", "hash",
         "seq moved"),
    Case(lambda c: c.sql("DELETE FROM reviews WHERE seq = 2"), "reviews", 2, "deleted",
         "hash", "middle review deleted"),
    Case(the_last_user_event_deleted, "user_events", 1, "deleted", "anchor log",
         "only user event deleted"),
    # values that are not of their column's type (never a crash)
    Case(a_parameter_value_stored_as_text, "results", 3, "bad value", "hash",
         "std stored as text"),
    Case(a_timestamp_with_trailing_junk, "reviews", 2, "bad value", "hash",
         "timestamp with junk"),
    Case(a_seq_of_1e308, "units", 2, "bad value", "hash", "seq 1e308"),
    Case(edit("results", "passed = 7", 1), "results", 1, "bad value", "hash",
         "boolean 7"),
    Case(edit("runs", "station_id = 'abc'", 1), "runs", 1, "bad value", "hash",
         "id as text"),
    Case(edit("units", "hash_version = 7", 1), "units", 1, "bad value", "hash",
         "unknown hash version"),
    Case(a_dangling_run_reference, "results", 1, "dangling", "hash", "dangling run"),
    # the signature (R.7)
    Case(a_middle_result_edited_and_chain_rehashed, "results", 2, "forged", "signature",
         "middle row edited, chain re-hashed"),
    Case(a_middle_review_deleted_and_chain_rehashed, "reviews", 2, "forged", "signature",
         "middle row deleted, chain re-hashed"),
    Case(the_last_result_edited_and_rehashed, "results", 4, "forged", "signature",
         "last row edited and re-hashed"),
    Case(a_forged_last_review_with_a_stolen_signature, "reviews", 4, "forged", "signature",
         "forged review, stolen signature"),
    Case(a_forged_last_review_unsigned_with_a_correct_hash, "reviews", 4, "forged",
         "signature", "forged review, correct hash"),
    Case(a_forged_review_by_an_intruders_own_registered_key, "reviews", 4, "untrusted key",
         "signature", "intruder's own key"),
    Case(a_review_signed_by_a_key_that_is_not_registered, "reviews", 4, "forged",
         "signature", "unregistered key"),
    Case(the_key_replaced_and_every_row_resigned, "signing_keys", 1, "untrusted key",
         "signature", "key replaced, all re-signed"),
    Case(the_last_unit_downgraded_to_unsigned, "units", 4, "unsigned", "signature",
         "downgraded to unsigned"),
    # the anchor log (R.10)
    Case(the_last_review_deleted, "reviews", 3, "deleted", "anchor log",
         "last row deleted"),
    Case(the_last_review_deleted_with_an_older_backups_anchors, "reviews", 3, "deleted",
         "anchor log", "last row deleted, old anchors"),
    Case(two_referenced_last_results_deleted, "results", 4, "deleted", "anchor log",
         "two referenced last rows deleted"),
    Case(the_only_key_deleted, "signing_keys", 1, "deleted", "anchor log",
         "the key row deleted"),
    Case(an_anchor_log_line_edited, "anchor log", 3, "anchor log", "anchor log",
         "anchor log line edited"),
    # the recordings
    Case(the_recording_edited, "recordings", 1, "recording", "recording", "recording edited"),
    Case(the_recording_missing, "recordings", 1, "recording", "recording",
         "recording missing"),
]


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_every_tampering_is_caught_naming_the_row_and_the_kind(copy: Copy, case: Case) -> None:
    old_heads = None
    if case.attack is the_last_review_deleted_with_an_older_backups_anchors:
        with open_records(copy.url) as rec:
            old_heads = [h for h in rec.heads() if h.table != "reviews"]  # before review 3
    case.attack(copy)
    with open_records(copy.url) as rec:
        report = rec.verify_report(anchors=old_heads or ())
    found = [(p.table, p.key, p.kind) for p in report.problems]
    assert (case.table, case.key, case.kind) in found, (case.name, report.problems)
    for p in report.problems:        # each names its row in one line
        assert "\n" not in str(p) and str(p).startswith(f"{p.table} row {p.key}: ")


def test_the_suite_has_every_class_of_the_issue():
    assert len(CASES) >= 35
    assert {c.needs for c in CASES} == {"hash", "signature", "anchor log", "recording"}


def test_anchor_log_cases_need_the_log(copy: Copy) -> None:
    """Without the anchor log a deleted last row leaves no trace: what the log is for."""
    the_last_review_deleted(copy)
    with open_records(copy.url) as rec:
        gone = copy.folder / "no-log.jsonl"
        found = [(p.table, p.key) for p in rec.verify_report(anchor_log=gone).problems]
    assert ("reviews", 3) not in found and ("anchor log", 0) in found


def test_signature_cases_need_the_key(copy: Copy) -> None:
    """Without signatures a re-hashed chain is consistent: only the signature (and the anchor
    log) tell. Here the key check is shown by the kinds found."""
    the_last_result_edited_and_rehashed(copy)
    with open_records(copy.url) as rec:
        problems = rec.verify_report(anchor_log=copy.folder / "no-log.jsonl").problems
    assert [(p.table, p.key, p.kind) for p in problems if p.table == "results"] == [
        ("results", 4, "forged")]


def test_fingerprints_are_short_sha256():
    assert len(fingerprint("00" * 32)) == 16
