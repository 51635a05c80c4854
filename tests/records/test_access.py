"""Passwords, web sessions, the audit trail and the station lock (records/access.py,
records/station_lock.py; docs/web.md), on every backend the records tests run on."""

from __future__ import annotations

from datetime import UTC, datetime, timedelta

import pytest
import sqlalchemy as sa

from imucalib.errors import InvalidInputError, RecordsError
from imucalib.records import access
from imucalib.records.schema import WebSession
from imucalib.records.station_lock import StationLockedError


@pytest.fixture(autouse=True)
def _cheap_argon2(monkeypatch):
    monkeypatch.setattr(access, "ARGON2_PARAMS",
                        {"time_cost": 1, "memory_cost": 1024, "parallelism": 1})


@pytest.fixture
def lab(records):
    records.add_user("Ada Admin", "AA", "admin")
    records.add_user("Oli Operator", "OO", "operator", by="Ada Admin")
    records.add_user("Obi Observer", "OB", "observer", by="Ada Admin")
    return records


def test_who_sets_a_password(lab):
    lab.set_password("Oli Operator", "first password", by="Oli Operator")      # themselves
    lab.set_password("Oli Operator", "second password", by="Ada Admin")        # an admin
    with pytest.raises(RecordsError, match="only an admin may set another user's password"):
        lab.set_password("Ada Admin", "takeover!!", by="Oli Operator")
    with pytest.raises(InvalidInputError, match="at least 8 characters; got 5"):
        lab.set_password("Oli Operator", "short", by="Ada Admin")
    with pytest.raises(RecordsError, match="no user named 'Nobody'"):
        lab.set_password("Nobody", "long enough", by="Ada Admin")
    assert lab.login("Oli Operator", "first password") is None      # the newest one counts
    user, token, csrf, expires = lab.login("Oli Operator", "second password", station="s")
    assert user.name == "Oli Operator" and len(token) >= 40 and len(csrf) >= 40
    assert expires > datetime.now(UTC) + timedelta(hours=7)


def test_the_stored_hash_is_argon2id_and_the_token_only_hashed(lab):
    lab.set_password("Oli Operator", "a password", by="Ada Admin")
    _user, token, _csrf, _exp = lab.login("Oli Operator", "a password")
    with lab.engine.connect() as conn:
        stored = conn.execute(sa.text("SELECT password_hash FROM user_credentials")).scalar()
        tokens = conn.execute(sa.text("SELECT token_hash FROM web_sessions")).scalars().all()
    assert stored.startswith("$argon2id$") and "a password" not in stored
    assert tokens == [access.token_hash(token)]


def test_a_session_ends_by_logout_expiry_or_disabling(lab):
    lab.set_password("Oli Operator", "a password", by="Ada Admin")
    _u, token, csrf, _e = lab.login("Oli Operator", "a password")
    assert lab.web_session(token).csrf_token == csrf
    assert lab.web_session("not a token") is None
    assert lab.logout(token) == "Oli Operator" and lab.web_session(token) is None
    _u, token, _c, _e = lab.login("Oli Operator", "a password")
    with lab.engine.begin() as conn:
        conn.execute(sa.update(WebSession).values(
            expires_utc=datetime.now(UTC) - timedelta(seconds=1)))
    assert lab.web_session(token) is None
    _u, token, _c, _e = lab.login("Oli Operator", "a password")
    lab.disable_user("Oli Operator", "left the lab", by="Ada Admin")
    assert lab.web_session(token) is None
    assert lab.login("Oli Operator", "a password") is None


def test_the_audit_rows_are_chained_and_verified(lab):
    lab.set_password("Oli Operator", "a password", by="Ada Admin")
    lab.login("Oli Operator", "wrong one")
    lab.audit("Oli Operator", "start", station="s", run_ref="r1", details={"plan": "p1"})
    with pytest.raises(InvalidInputError, match="audit action must be one of"):
        lab.audit("Oli Operator", "delete_everything")
    rows = lab.audit_log()
    assert [(r.actor, r.action) for r in rows] == [
        ("Oli Operator", "start"), ("Oli Operator", "login_failed"),
        ("Ada Admin", "set_password")]
    assert lab.audit_log(run_ref="r1")[0].details == {"plan": "p1"}
    assert lab.verify(recordings=False) == []
    with lab.engine.begin() as conn:
        conn.execute(sa.text("UPDATE audit_events SET details_json = '{}' WHERE seq = 3"))
    assert [(p.table, p.key) for p in lab.verify(recordings=False)] == [("audit_events", 3)]


def test_the_station_lock(lab):
    assert lab.station_lock("s").holder == ""
    assert lab.take_station("s", "Oli Operator").holder == "Oli Operator"
    assert lab.take_station("s", "Oli Operator").holder == "Oli Operator"    # already held
    with pytest.raises(StationLockedError, match="held by Oli Operator"):
        lab.take_station("s", "Ada Admin")
    assert lab.request_station("s", "Ada Admin").requested_by == "Ada Admin"
    with pytest.raises(StationLockedError, match="only its holder"):
        lab.release_station("s", "Ada Admin")
    assert lab.release_station("s", "Ada Admin", force=True) == "Oli Operator"
    with pytest.raises(RecordsError, match="not held by anyone"):
        lab.release_station("s", "Oli Operator")
    assert lab.take_station("other", "Ada Admin").holder == "Ada Admin"       # per station
    assert [r.action for r in lab.audit_log()] == ["lock", "unlock", "lock_request", "lock"]


def test_an_observer_is_no_run_operator(lab):
    from sqlalchemy.orm import Session

    from imucalib.records.users import check_operator

    with Session(lab.engine) as session:
        with pytest.raises(RecordsError, match="must not be an observer"):
            check_operator(session, "Obi Observer")
        assert check_operator(session, "Oli Operator") == "Oli Operator"


def test_too_many_failed_logins_stop_a_name_until_a_new_password(lab):
    lab.set_password("Oli Operator", "a password", by="Ada Admin")
    for _ in range(access.MAX_FAILED_LOGINS):
        assert lab.login("Oli Operator", "guess") is None
    with pytest.raises(access.LoginThrottledError, match="failed logins of 'Oli Operator'"):
        lab.login("Oli Operator", "a password")
    assert lab.login("Ada Admin", "anything") is None            # other names are not stopped
    lab.set_password("Oli Operator", "a new password", by="Ada Admin")
    assert lab.login("Oli Operator", "a new password") is not None
