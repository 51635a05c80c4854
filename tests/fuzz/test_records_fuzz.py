"""Property-based fuzzing of the records commands on a mutated records database.

A small records database (users, a station and its equipment, a run with its recording, results
with parameters, reviews, an amendment, all signed, with its anchor log) is copied for each
example; one or two of its stored values are replaced by odd ones (text in a number column, a
timestamp with junk after it, 1e308, NULL, a dangling id …), a row is deleted, or a table the
software needs is dropped; then ``records verify``, ``due``, ``list``, ``history``, ``show``,
``drift``, ``equipment``, ``users list`` (and, fewer times, ``report --result-id``) run through
:func:`imucalib.cli.main` in this process. Each must end in exit 0, exit 1 (``verify``: problems
named) or exit 2 with one ``error:`` line: never a traceback, never the ``internal error``
safety net. The hypothesis search is derandomised; ``IMUCALIB_FUZZ_EXAMPLES`` multiplies the
examples for a longer campaign (as in tests/fuzz/test_cli_fuzz.py).

The reproducers of issue 27 are kept as ``tests/fuzz/cases/records_*.json``: SQL applied to
the same database, the commands to run, and what each must print.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import sqlite3
import tempfile
import time
from datetime import UTC, date, datetime
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from ._harness import run_cli  # the CLI in this process, a case running too long a hang

SCALE = int(os.environ.get("IMUCALIB_FUZZ_EXAMPLES", "1"))
FUZZ = settings(max_examples=12 * SCALE, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.function_scoped_fixture,
                                       HealthCheck.too_slow])
CASES = Path(__file__).with_name("cases")
ODD_VALUES = st.sampled_from([
    "abc", "", "2026-01-01 00:00:00.000000junk", "2026-13-45", 1e308, -1e308, 1.5, -1,
    0, 2**62, None, "null", "{", "[1, 2]", '{"a": 1}', 7, "9" * 40, "1e999", b"\x00\xff",
    "2026-01-01", "x" * 300,
])
TABLES = ("units", "stations", "equipment", "runs", "run_equipment", "results",
          "result_parameters", "reviews", "users", "user_events", "signing_keys")


#: ``IMUCALIB_FUZZ_TALLY=FILE``: each outcome appended as a JSON line (the rows of
#: tests/fuzz/_harness.py's tally, door ``records`` or ``report``), for the campaign's count table.
TALLY = os.environ.get("IMUCALIB_FUZZ_TALLY")


def check_outcome(code: int, out: str, err: str, what: str) -> None:
    text = out + err
    if TALLY:
        door = "report" if what.startswith("report") else "records"
        lines = [ln for ln in err.splitlines() if ln.strip()]
        row = {"door": door, "what": door, "code": code,
               "one_line": code == 2 and len(lines) == 1 and lines[0].startswith("error: "),
               "error": code == 2 and err.startswith("error: "), "usage": False,
               "traceback": "Traceback" in text, "internal": "internal error" in text,
               "hang": False, "signal": None}
        with open(TALLY, "a", encoding="utf-8") as f:
            f.write(json.dumps(row) + "\n")
    assert "Traceback" not in text, f"{what}: traceback\n{text}"
    assert "internal error" not in text, f"{what}: an unexpected exception\n{text}"
    assert code in (0, 1, 2), f"{what}: exit {code}\n{text}"
    if code == 1:
        assert what.startswith("records verify"), f"{what}: exit 1\n{text}"
    if code == 2:
        assert err.startswith("error: "), f"{what}: exit 2 without a message\n{text}"
        assert err.strip().count("\n") == 0, f"{what}: more than one error line\n{text}"


def _small_result(serial: str, bias: float, passed: bool | None = True) -> Any:
    import numpy as np

    from imucalib.models.result import CalibrationResult, Provenance, triad_parameter_names

    names = triad_parameter_names("accel", "per-axis")
    values = np.array([1.0, 1.001, 0.999, bias, -bias, 2 * bias])
    return CalibrationResult(
        sensor_id=serial, procedure="p1", model="per-axis", param_names=names, values=values,
        covariance=np.eye(6) * 1e-8, units={n: "1" if "_K_" in n else "m/s^2" for n in names},
        provenance=Provenance(plan_hash="ab" * 32, recording="run.h5", software_version="0.1",
                              created_utc="2026-11-23T00:00:00Z"))


@pytest.fixture(scope="module")
def template(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The records database every example starts from, with its key folder and a result file."""
    from imucalib.records import open_records

    folder = tmp_path_factory.mktemp("records-fuzz")
    recording = folder / "run.bin"        # (not an .h5: the report must not analyse it)
    recording.write_bytes(bytes(range(256)))
    with open_records(f"sqlite:///{folder / 'records.db'}") as rec:
        rec.add_user("Ada Admin", "AA", "admin")
        rec.add_user("Rae Reviewer", "RR", "reviewer", by="Ada Admin")
        rec.add_user("Oli Operator", "OO", "operator", by="Ada Admin")
        rec.disable_user("Oli Operator", "moved", by="Ada Admin")
        rec.enable_user("Oli Operator", "back", by="Ada Admin")
        lab = rec.add_station("lab 1")
        eq = rec.add_equipment(lab, "rate table", serial="T-1", certificate="C-1",
                               calibrated_on=date(2026, 1, 5), due_on=date(2027, 1, 5))
        run = rec.record_run(plan_name="p1", recording=recording, operator="Oli Operator",
                             station=lab, equipment=[eq],
                             started_utc=datetime(2026, 3, 1, tzinfo=UTC))
        first = rec.record_result(run, _small_result("IMU-1", 0.01), passed=True)
        second = rec.record_result(run, _small_result("IMU-2", 0.02), passed=False)
        rec.review(first, "Rae Reviewer", approved=True, comment="ok")
        rec.review(second, "Rae Reviewer", approved=False, comment="bias")
        rec.amend(second, _small_result("IMU-2", 0.021), reason="offset")
        assert rec.verify() == []
    (folder / "IMU-1.result.json").write_text(_small_result("IMU-1", 0.01).to_json(),
                                              encoding="utf-8")
    return folder


def _copy(template: Path) -> Path:
    work = Path(tempfile.mkdtemp(prefix="records-fuzz-"))
    shutil.copyfile(template / "records.db", work / "records.db")
    shutil.copytree(template / "records.db.signing", work / "records.db.signing")
    return work


def _columns(db: Path) -> dict[str, list[str]]:
    with contextlib.closing(sqlite3.connect(db)) as conn:
        return {t: [r[1] for r in conn.execute(f"PRAGMA table_info({t})")] for t in TABLES}


COMMANDS = (("records", "verify"), ("records", "due"), ("records", "list"),
            ("records", "history", "IMU-2"), ("records", "show", "1"),
            ("records", "show", "3", "--json"), ("records", "drift", "IMU-1", "accel_b_x"),
            ("records", "equipment", "--all"), ("users", "list"))


def _mutate(db: Path, data: st.DataObject, columns: dict[str, list[str]]) -> str:
    """Apply one or two random changes to `db` (no foreign keys checked); describe them."""
    done = []
    with contextlib.closing(sqlite3.connect(db)) as conn:
        for _ in range(data.draw(st.integers(1, 2))):
            action = data.draw(st.sampled_from(["set", "set", "set", "delete", "drop"]))
            table = data.draw(st.sampled_from(TABLES))
            try:
                rowids = [r[0] for r in conn.execute(f"SELECT rowid FROM {table}")]
                if action == "drop":
                    victim = data.draw(st.sampled_from(["alembic_version", "signing_keys",
                                                        "run_equipment", "reviews"]))
                    conn.execute(f"DROP TABLE {victim}")
                    done.append(f"drop {victim}")
                elif rowids and action == "delete":
                    rowid = data.draw(st.sampled_from(rowids))
                    conn.execute(f"DELETE FROM {table} WHERE rowid = ?", (rowid,))
                    done.append(f"delete {table} {rowid}")
                elif rowids:
                    rowid = data.draw(st.sampled_from(rowids))
                    column = data.draw(st.sampled_from(columns[table]))
                    value = data.draw(ODD_VALUES)
                    conn.execute(f"UPDATE {table} SET {column} = ? WHERE rowid = ?",
                                 (value, rowid))
                    done.append(f"{table} {rowid} {column} = {value!r}"[:120])
                conn.commit()
            except sqlite3.Error as exc:    # a constraint the database keeps: nothing done
                conn.rollback()
                done.append(f"({action} {table} refused: {exc})")
    return "; ".join(done)


@FUZZ
@given(data=st.data())
def test_mutated_records_give_findings_or_one_error_line(template, data):
    work = _copy(template)
    try:
        db = work / "records.db"
        change = _mutate(db, data, _columns(db))
        for command in COMMANDS:
            start = time.monotonic()
            code, out, err = run_cli(*command, "--db", str(db))
            check_outcome(code, out, err, f"{' '.join(command)} after {change}")
            assert time.monotonic() - start < 10, f"{command} took too long after {change}"
    finally:
        shutil.rmtree(work, ignore_errors=True)


@settings(max_examples=3 * SCALE, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(data=st.data())
def test_mutated_records_never_break_the_report(template, data):
    work = _copy(template)
    try:
        db = work / "records.db"
        change = _mutate(db, data, _columns(db))
        code, out, err = run_cli("report", str(template / "IMU-1.result.json"), "--result-id",
                                 "1", "--db", str(db), "--format", "html",
                                 "-o", str(work / "r.html"))
        check_outcome(code, out, err, f"report after {change}")
    finally:
        shutil.rmtree(work, ignore_errors=True)


# --- the reproducers of issue 27 ---------------------------------------------------------------
def _cases() -> list[Path]:
    return sorted(CASES.glob("records_*.json"))


@pytest.mark.parametrize("case", _cases(), ids=lambda p: p.stem)
def test_records_reproducers(template, case: Path) -> None:
    spec = json.loads(case.read_text(encoding="utf-8"))
    work = _copy(template)
    try:
        db = work / "records.db"
        with contextlib.closing(sqlite3.connect(db)) as conn:
            for statement in spec["sql"]:
                conn.execute(statement)
            conn.commit()
        for step in spec["commands"]:
            args = [a.replace("{template}", str(template)).replace("{work}", str(work))
                    for a in step["args"]]
            start = time.monotonic()
            code, out, err = run_cli(*args, "--db", str(db))
            elapsed = time.monotonic() - start
            what = f"{' '.join(step['args'])} ({case.stem})"
            check_outcome(code, out, err, what)
            assert code == step["exit"], f"{what}: exit {code}\n{out}{err}"
            flat = " ".join((out + err).split())
            for expected in step.get("says", []):
                assert expected in flat, f"{what}: {expected!r} not in\n{out}{err}"
            for absent in step.get("not", []):
                assert absent not in flat, f"{what}: {absent!r} in\n{out}{err}"
            assert elapsed < step.get("within_s", 10), f"{what}: took {elapsed:.1f} s"
    finally:
        shutil.rmtree(work, ignore_errors=True)
