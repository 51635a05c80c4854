"""Tamper evidence: verify names an edited row, a deleted row, an edited parameter, an edited or
missing recording; the canonical form can be re-hashed by hand (docs/records.md, Eq. (R.1))."""

from __future__ import annotations

import hashlib
import json
from datetime import UTC, datetime

from sqlalchemy import text
from sqlalchemy.orm import Session

from imucalib.records.canonical import chain_hash, row_content
from imucalib.records.chain import children_of
from imucalib.records.schema import Result


def _populate(records, make_result, recording_file):
    lab = records.add_station("lab 1")
    records.add_equipment(lab, "rate table", serial="T-1", certificate="C-1")
    run = records.record_run(plan_name="p1", recording=recording_file,
                             started_utc=datetime(2026, 1, 1, tzinfo=UTC), equipment=[1])
    ids = [records.record_result(run, make_result(f"IMU-{i}", 0.01 * i), passed=True)
           for i in range(1, 4)]
    reviews = [records.review(r, "bo", approved=True, comment=f"ok {r}") for r in ids]
    assert records.verify() == []
    return run, ids, reviews


def _sql(records, statement, **params):
    with records.engine.begin() as conn:
        conn.execute(text(statement), params)


def test_an_edited_row_is_named(records, make_result, recording_file):
    _, ids, _ = _populate(records, make_result, recording_file)
    _sql(records, "UPDATE results SET passed = :f WHERE id = :i", f=False, i=ids[1])
    problems = records.verify()
    assert [(p.table, p.key) for p in problems] == [("results", ids[1])]
    assert "(edited)" in problems[0].what


def test_an_edited_run_environment_is_named(records, make_result, recording_file):
    run, _, _ = _populate(records, make_result, recording_file)
    _sql(records, "UPDATE runs SET operator = 'mallory' WHERE id = :i", i=run)
    assert [(p.table, p.key) for p in records.verify()] == [("runs", run)]


def test_a_deleted_row_is_named(records, make_result, recording_file):
    _, _, reviews = _populate(records, make_result, recording_file)
    _sql(records, "DELETE FROM reviews WHERE id = :i", i=reviews[1])
    problems = records.verify()
    assert [(p.table, p.key) for p in problems] == [("reviews", reviews[1]),
                                                    ("reviews", reviews[2])]
    assert "missing (deleted)" in problems[0].what and "chain broken" in problems[1].what


def test_a_deleted_last_row_is_caught_by_an_anchor(records, make_result, recording_file):
    _, _, reviews = _populate(records, make_result, recording_file)
    heads = records.heads()
    assert {h.table: h.seq for h in heads}["reviews"] == reviews[-1]
    _sql(records, "DELETE FROM reviews WHERE id = :i", i=reviews[-1])
    problems = records.verify()            # the anchor log names it
    assert [(p.table, p.key, p.kind) for p in problems] == [("reviews", reviews[-1], "deleted")]
    assert "anchor log" in problems[0].what
    gone = records.signing_folder / "none.jsonl"    # without the log: its absence, and an anchor
    assert [p.kind for p in records.verify_report(anchor_log=gone).problems] == ["anchor log"]
    problems = list(records.verify_report(anchor_log=gone, anchors=heads).problems)
    assert [(p.table, p.key) for p in problems] == [("anchor log", 0), ("reviews", reviews[-1])]


def test_an_edited_added_or_removed_parameter_is_named(records, make_result, recording_file):
    _, ids, _ = _populate(records, make_result, recording_file)
    _sql(records, "UPDATE result_parameters SET std = std * 0.5 "
                  "WHERE result_id = :i AND name = 'gyro_b_z'", i=ids[0])
    _sql(records, "DELETE FROM result_parameters WHERE result_id = :i AND name = 'accel_K_y'",
         i=ids[2])
    problems = records.verify()
    assert [(p.table, p.key) for p in problems] == [("results", ids[0]), ("results", ids[2])]


def test_an_edited_and_a_missing_recording_are_named(records, make_result, recording_file,
                                                     tmp_path):
    run, _, _ = _populate(records, make_result, recording_file)
    other = tmp_path / "other.h5"
    other.write_bytes(b"second recording")
    run2 = records.record_run(plan_name="p1", recording=other)
    data = bytearray(recording_file.read_bytes())
    data[100] ^= 0x01
    recording_file.write_bytes(bytes(data))
    other.unlink()
    problems = records.verify()
    assert [(p.table, p.key) for p in problems] == [("recordings", run), ("recordings", run2)]
    assert "changed" in problems[0].what and "missing" in problems[1].what
    assert records.verify(recordings=False) == []


def test_a_row_can_be_rehashed_by_hand(records, make_result, recording_file):
    _populate(records, make_result, recording_file)
    with records.engine.connect() as conn:
        rows = conn.execute(text("SELECT id, seq, prev_hash, row_hash, created_utc, result_id, "
                                 "reviewer, reviewed_utc, approved, comment FROM reviews "
                                 "ORDER BY seq")).mappings().all()
    with records.engine.connect() as conn:
        signed = conn.execute(text("SELECT hash_version, key_id FROM reviews ORDER BY seq")).all()
    prev = "0" * 64
    for row, (version, key_id) in zip(rows, signed, strict=True):
        content = {k: row[k] for k in ("id", "seq", "result_id", "reviewer", "comment")}
        content.update(_table="reviews", hash_version=version, key_id=key_id)  # version 2
        assert version == 2
        content["approved"] = bool(row["approved"])
        for key in ("created_utc", "reviewed_utc"):
            value = row[key]
            if isinstance(value, str):  # SQLite hands back text
                value = datetime.fromisoformat(value)
            content[key] = value.astimezone(UTC).strftime("%Y-%m-%dT%H:%M:%S.%fZ") \
                if value.tzinfo else value.strftime("%Y-%m-%dT%H:%M:%S.%fZ")
        canonical = json.dumps(content, sort_keys=True, separators=(",", ":"),
                               ensure_ascii=False)
        assert row["prev_hash"] == prev
        assert hashlib.sha256((prev + canonical).encode()).hexdigest() == row["row_hash"]
        prev = row["row_hash"]


def test_a_rehashed_edit_breaks_the_link_to_the_next_row(records, make_result, recording_file):
    _, ids, _ = _populate(records, make_result, recording_file)
    with Session(records.engine) as session:  # the forger recomputes the edited row's hash
        row = session.get(Result, ids[0])
        row.amendment_reason = "forged"
        forged = chain_hash(row.prev_hash, row_content(row, **children_of(session, row)))
    _sql(records, "UPDATE results SET amendment_reason = 'forged', row_hash = :h WHERE id = :i",
         h=forged, i=ids[0])
    problems = records.verify()
    assert [(p.table, p.key, p.kind) for p in problems] == [
        ("results", ids[0], "forged"), ("results", ids[1], "chain broken"),
        ("results", ids[0], "re-hashed")]   # the signature, the next link, the anchor log
    assert "chain broken" in problems[1].what


def test_a_removed_equipment_link_is_named(records, make_result, recording_file):
    run, _, _ = _populate(records, make_result, recording_file)
    _sql(records, "DELETE FROM run_equipment WHERE run_id = :i", i=run)
    assert [(p.table, p.key) for p in records.verify()] == [("runs", run)]


def _users(records):
    records.add_user("Ada Admin", "AA", "admin")
    records.add_user("Rae Reviewer", "RR", "reviewer", by="Ada Admin")
    records.add_user("Oli Operator", "OO", "operator", by="Ada Admin")
    records.disable_user("Oli Operator", "left", by="Ada Admin")
    records.enable_user("Oli Operator", "back", by="Ada Admin")
    assert records.verify() == []


def test_an_edited_or_deleted_user_is_named(records):
    _users(records)
    _sql(records, "UPDATE users SET role = 'admin' WHERE name = 'Oli Operator'")
    problems = records.verify()
    assert [(p.table, p.key) for p in problems] == [("users", 3)]
    assert "(edited)" in problems[0].what
    _sql(records, "UPDATE users SET role = 'operator' WHERE name = 'Oli Operator'")
    assert records.verify() == []
    _sql(records, "DELETE FROM users WHERE name = 'Rae Reviewer'")
    problems = records.verify()
    assert [(p.table, p.key) for p in problems] == [("users", 2), ("users", 3)]
    assert "missing (deleted)" in problems[0].what and "chain broken" in problems[1].what


def test_a_deleted_or_edited_user_event_is_named(records):
    _users(records)
    _sql(records, "UPDATE user_events SET reason = 'forged' WHERE seq = 2")
    assert [(p.table, p.key) for p in records.verify()] == [("user_events", 2)]
    _sql(records, "UPDATE user_events SET reason = 'back' WHERE seq = 2")
    records.disable_user("Rae Reviewer", "moved", by="Ada Admin")
    heads = records.heads()
    assert {h.table: h.seq for h in heads}["user_events"] == 3
    _sql(records, "DELETE FROM user_events WHERE seq = 3")   # a last row: the anchor log sees
    assert [(p.table, p.key) for p in records.verify()] == [("user_events", 3)]
    assert [(p.table, p.key) for p in records.verify(anchors=heads)] == [("user_events", 3)]
    _sql(records, "DELETE FROM user_events WHERE seq = 1")   # Oli's disable: the chain breaks
    problems = records.verify()
    assert [(p.table, p.key) for p in problems] == [("user_events", 1), ("user_events", 2),
                                                    ("user_events", 3)]
    assert "missing (deleted)" in problems[0].what and "chain broken" in problems[1].what


def test_an_edited_reviewer_or_decision_is_named(records, make_result, recording_file):
    _, _, reviews = _populate(records, make_result, recording_file)
    _sql(records, "UPDATE reviews SET reviewer = 'Rae Reviewer' WHERE id = :i", i=reviews[0])
    _sql(records, "UPDATE reviews SET approved = :f WHERE id = :i", f=False, i=reviews[2])
    assert [(p.table, p.key) for p in records.verify()] == [("reviews", reviews[0]),
                                                            ("reviews", reviews[2])]
