"""The station key: created on the first write, owner-only, registered, rotated, lost
(docs/records.md, "Signing", "A lost key"); the anchor log; the backup manifest's keys."""

from __future__ import annotations

import json
import os
import stat
from datetime import UTC, datetime

import pytest
from sqlalchemy import text

from imucalib.errors import RecordsError
from imucalib.records import open_records
from imucalib.records.signing import KEY_FILE, LOG_FILE, PUB_FILE, load_key, read_public


def test_the_first_write_creates_an_owner_only_key_and_registers_it(records):
    folder = records.signing_folder
    assert not (folder / KEY_FILE).exists()          # opening writes nothing
    records.add_unit("IMU-1")
    key = load_key(folder / KEY_FILE)
    assert key is not None
    assert stat.S_IMODE((folder / KEY_FILE).stat().st_mode) == 0o600
    assert read_public(folder / PUB_FILE) == key.public_hex
    report = records.verify_report()
    assert report.problems == ()
    assert [(k.key_id, k.fingerprint, k.trusted, k.rows) for k in report.keys] == [
        (1, key.fingerprint, True, {"signing_keys": 1, "units": 1})]
    lines = (folder / LOG_FILE).read_text().splitlines()
    assert len(lines) == 1 and json.loads(lines[0])["heads"]["units"][0] == 1
    with records.engine.connect() as conn:
        row = conn.execute(text("SELECT hash_version, key_id, signature FROM units")).one()
    assert row[0] == 2 and row[1] == 1 and len(row[2]) == 128


def test_a_key_readable_by_others_is_refused_with_one_line(records):
    records.add_unit("IMU-1")
    path = records.signing_folder / KEY_FILE
    os.chmod(path, 0o644)
    fresh = open_records(records.engine.url.render_as_string(hide_password=False))
    try:
        with pytest.raises(RecordsError, match=r"readable by others \(mode 0644\).*chmod 600"):
            fresh.add_unit("IMU-2")
    finally:
        fresh.close()


def test_without_the_key_file_signed_records_refuse_writes(records):
    records.add_unit("IMU-1")
    (records.signing_folder / KEY_FILE).unlink()
    records._key = None
    with pytest.raises(RecordsError, match=r"key file .* is missing.*rekey --lost-key"):
        records.add_unit("IMU-2")


def test_rekey_endorses_the_new_key_and_verify_says_who_signed_what(records):
    records.add_unit("IMU-1")
    old = load_key(records.signing_folder / KEY_FILE)
    new_id = records.rekey("yearly rotation")
    assert new_id == 2
    new = load_key(records.signing_folder / KEY_FILE)
    assert new is not None and old is not None and new.public_hex != old.public_hex
    assert (records.signing_folder / f"{KEY_FILE}.{old.fingerprint}.retired").is_file()
    records.add_unit("IMU-2")
    report = records.verify_report()
    assert report.problems == ()
    assert [(k.key_id, k.trusted, k.rows) for k in report.keys] == [
        (1, True, {"signing_keys": 1, "units": 1}),
        (2, True, {"signing_keys": 1, "units": 1})]
    # the old key, kept by someone, no longer signs
    os.replace(records.signing_folder / f"{KEY_FILE}.{old.fingerprint}.retired",
               records.signing_folder / KEY_FILE)
    records._key = None
    with pytest.raises(RecordsError, match="which key 2 replaced"):
        records.add_unit("IMU-3")


def test_a_lost_key_is_replaced_by_a_new_one_that_vouches_for_it(records):
    records.add_unit("IMU-1")
    (records.signing_folder / KEY_FILE).unlink()
    records._key = None
    with pytest.raises(RecordsError, match="pass --lost-key"):
        records.rekey("disk failed")
    assert records.rekey("disk failed", lost=True) == 2
    records.add_unit("IMU-2")
    report = records.verify_report()
    assert report.problems == ()
    assert [(k.key_id, k.trusted) for k in report.keys] == [(1, True), (2, True)]
    with records.engine.connect() as conn:
        assert conn.execute(text("SELECT endorsement FROM signing_keys WHERE seq = 2")
                            ).scalar() == ""


def test_an_existing_database_of_another_key_is_not_signed_with_it(records, tmp_path):
    records.add_unit("IMU-1")
    other = open_records(f"sqlite:///{tmp_path / 'other.db'}")
    try:
        other.add_unit("X")
    finally:
        other.close()
    os.replace(tmp_path / "other.db.signing" / KEY_FILE, records.signing_folder / KEY_FILE)
    records._key = None
    with pytest.raises(RecordsError, match="not registered in these records"):
        records.add_unit("IMU-2")


def test_amend_keeps_the_decision_it_amends(records, make_result):
    run = records.record_run(plan_name="p", started_utc=datetime(2026, 1, 1, tzinfo=UTC))
    failed = records.record_result(run, make_result("IMU-1"), passed=False)
    new = records.amend(failed, make_result("IMU-1", 0.02), reason="re-analysed")
    assert records.result(new).passed is False
    assert records.due_units()[0].last_calibrated is None        # still not a good one
    newer = records.amend(new, make_result("IMU-1", 0.02), reason="decided", passed=True)
    assert records.result(newer).passed is True


def test_commands_on_dangling_or_type_confused_rows_say_the_database_has_a_problem(
        records, make_result):
    run = records.record_run(plan_name="p")
    records.record_result(run, make_result("IMU-1"), passed=True)
    if records.engine.dialect.name == "sqlite":
        import sqlite3

        with sqlite3.connect(records.engine.url.database) as conn:   # foreign keys off
            conn.execute("UPDATE results SET run_id = 9")
    else:
        with records.engine.begin() as conn:
            conn.execute(text("ALTER TABLE results DROP CONSTRAINT fk_results_run_id_runs"))
            conn.execute(text("UPDATE results SET run_id = 9"))
    for query in (records.due_units, lambda: records.history("IMU-1"),
                  lambda: records.result(1)):
        with pytest.raises(RecordsError, match=r"results row 1 names run 9.*records verify"):
            query()
    kinds = {(p.table, p.key, p.kind) for p in records.verify()}
    assert ("results", 1, "dangling") in kinds and ("results", 1, "edited") in kinds


def test_backups_carry_the_keys_and_the_anchor_log(records, make_result, tmp_path):
    from typer.testing import CliRunner

    from imucalib.cli import app

    run = records.record_run(plan_name="p")
    records.record_result(run, make_result("IMU-1"), passed=True)
    url = records.engine.url.render_as_string(hide_password=False)
    runner = CliRunner()
    res = runner.invoke(app, ["records", "backup", str(tmp_path / "b"), "--db", url])
    assert res.exit_code == 0, res.output
    manifest = json.loads((tmp_path / "b" / "manifest.json").read_text())
    key = load_key(records.signing_folder / KEY_FILE)
    assert key is not None
    assert manifest["signing_keys"] == [{"id": 1, "fingerprint": key.fingerprint,
                                         "public_key": key.public_hex}]
    assert (tmp_path / "b" / "signing" / LOG_FILE).is_file()
    assert not (tmp_path / "b" / "signing" / KEY_FILE).exists()    # never the private key
    restored = f"sqlite:///{tmp_path / 'restored.db'}"
    res = runner.invoke(app, ["records", "restore", str(tmp_path / "b"), "--db", restored])
    assert res.exit_code == 0 and "the restored records verify" in res.output, res.output
    assert (tmp_path / "restored.db.signing" / PUB_FILE).is_file()
