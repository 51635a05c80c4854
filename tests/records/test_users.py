"""Users and roles, who is acting, the review control and release (docs/records.md, "Users and
roles"; rules (U.1)-(U.4) of imucalib.records.users)."""

from __future__ import annotations

import pytest

from imucalib.errors import InvalidInputError, RecordsError
from imucalib.records.users import USER_ENV, resolve_user


def _lab(records):
    """An admin, an operator, two reviewers (one of them also operates), an engineer."""
    records.add_user("Ada Admin", "AA", "admin")
    records.add_user("Oli Operator", "OO", "operator", by="Ada Admin")
    records.add_user("Rae Reviewer", "RR", "reviewer", by="Ada Admin")
    records.add_user("Sam Both", "SB", "reviewer", by="Ada Admin")
    records.add_user("Eve Engineer", "EE", "engineer", by="Ada Admin")


def _result(records, make_result, operator, serial="IMU-1"):
    run = records.record_run(plan_name="p1", operator=operator)
    return records.record_result(run, make_result(serial), passed=True)


def test_users_are_added_listed_disabled_and_enabled(records):
    first = records.add_user("Ada Admin", "AA", "admin")
    records.add_user("Oli Operator", "OO", "operator", by="Ada Admin")
    assert [(u.user_id, u.name, u.initials, u.role, u.active, u.added_by)
            for u in records.users()] == [(first, "Ada Admin", "AA", "admin", True, ""),
                                          (2, "Oli Operator", "OO", "operator", True,
                                           "Ada Admin")]
    records.disable_user("Oli Operator", "left the lab", by="Ada Admin")
    oli = records.user("Oli Operator")
    assert not oli.active
    assert [(e.event, e.reason, e.by) for e in oli.events] == [
        ("disable", "left the lab", "Ada Admin")]
    records.enable_user("Oli Operator", "came back", by="Ada Admin")
    assert records.user("Oli Operator").active
    assert [e.event for e in records.user("Oli Operator").events] == ["disable", "enable"]
    with pytest.raises(RecordsError, match=r"no user named 'Nobody'.*Ada Admin"):
        records.user("Nobody")
    assert records.verify() == []


def test_what_adding_and_disabling_refuse(records):
    with pytest.raises(InvalidInputError, match="role must be one of operator, engineer, "
                                                "reviewer, admin; got 'boss'"):
        records.add_user("X", "X", "boss")
    with pytest.raises(InvalidInputError, match="needs a name"):
        records.add_user("  ", "X", "operator")
    records.add_user("Oli Operator", "OO", "operator")          # (U.1): the first, by anyone
    with pytest.raises(RecordsError, match="name who is acting"):
        records.add_user("Ada Admin", "AA", "admin")
    with pytest.raises(RecordsError, match="'Mallory' is not a user"):
        records.add_user("Ada Admin", "AA", "admin", by="Mallory")
    records.add_user("Ada Admin", "AA", "admin", by="Oli Operator")  # no admin yet: any user
    with pytest.raises(RecordsError, match=r"only an admin may add a user; Oli Operator is an "
                                           r"operator \(admins: Ada Admin \(admin\)\)"):
        records.add_user("Rae Reviewer", "RR", "reviewer", by="Oli Operator")
    with pytest.raises(RecordsError, match="a user named 'Ada Admin' is already recorded"):
        records.add_user("ada  admin", "A2", "operator", by="Ada Admin")
    with pytest.raises(RecordsError, match="last active admin"):
        records.disable_user("Ada Admin", "leaving", by="Ada Admin")
    with pytest.raises(InvalidInputError, match="give a reason"):
        records.disable_user("Oli Operator", " ", by="Ada Admin")
    records.disable_user("Oli Operator", "left", by="Ada Admin")
    with pytest.raises(RecordsError, match="already disabled"):
        records.disable_user("Oli Operator", "again", by="Ada Admin")
    with pytest.raises(RecordsError, match="'Oli Operator' is disabled"):
        records.add_user("Rae Reviewer", "RR", "reviewer", by="Oli Operator")
    assert records.verify() == []


def test_the_last_active_user_cannot_be_disabled(records):
    records.add_user("Solo", "S", "reviewer")
    with pytest.raises(RecordsError, match="last active user"):
        records.disable_user("Solo", "going", by="Solo")


def test_who_is_acting(records, monkeypatch):
    monkeypatch.delenv(USER_ENV, raising=False)
    # (U.1) no users: the name as given, from --user, the environment or the configuration
    assert resolve_user(records, None) == ""
    assert resolve_user(records, None, configured="cfg") == "cfg"
    monkeypatch.setenv(USER_ENV, "env")
    assert resolve_user(records, None, configured="cfg") == "env"
    assert resolve_user(records, " given ", configured="cfg") == "given"
    _lab(records)
    monkeypatch.delenv(USER_ENV)
    with pytest.raises(RecordsError, match=r"who is acting\? the records database .* has users, "
                                           r"so to review a result pass --user NAME or set "
                                           r"IMUCALIB_USER \(active users: Ada Admin"):
        resolve_user(records, None, action="review a result")
    assert resolve_user(records, None, configured="Rae Reviewer") == "Rae Reviewer"
    assert resolve_user(records, "rr") == "Rae Reviewer"                # initials, any case
    assert resolve_user(records, "sam both") == "Sam Both"
    monkeypatch.setenv(USER_ENV, "Mallory")
    with pytest.raises(RecordsError, match="IMUCALIB_USER names 'Mallory', who is not a user"):
        resolve_user(records, None)
    records.disable_user("Oli Operator", "left the lab", by="Ada Admin")
    with pytest.raises(RecordsError, match=r"user 'Oli Operator' \(--user\) is disabled "
                                           r"\(left the lab\)"):
        resolve_user(records, "OO")


def test_a_reviewer_approves_another_users_run_and_releases_it(records, make_result):
    _lab(records)
    rid = _result(records, make_result, "Oli Operator")
    status = records.release_status(rid)
    assert not status.released and status.decision is None
    assert status.reason == f"result {rid} has no review"
    records.review(rid, "Rae Reviewer", approved=True, comment="residuals within limits")
    status = records.release_status(rid)
    assert status.released and status.authorised and status.decision == "approve"
    assert (status.reviewer, status.reviewer_initials, status.reviewer_role) == (
        "Rae Reviewer", "RR", "reviewer")
    assert status.comment == "residuals within limits" and status.reviewed_utc is not None
    assert status.text().startswith("released: approved by Rae Reviewer (RR, reviewer) on ")
    # a reviewer disabled later does not un-release what they approved when active
    records.disable_user("Rae Reviewer", "left", by="Ada Admin")
    assert records.release_status(rid).released
    # the latest review decides: a rejection by an authorised reviewer withdraws the release
    records.review(rid, "Ada Admin", approved=False, comment="table offset wrong")
    status = records.release_status(rid)
    assert not status.released and status.decision == "reject" and status.authorised
    assert "rejected by Ada Admin (AA, admin)" in status.reason
    assert records.verify() == []


def test_self_approval_and_unauthorised_reviews_are_refused(records, make_result):
    by_initials = _result(records, make_result, "sb", serial="IMU-2")  # before users: initials
    _lab(records)
    mine = _result(records, make_result, "Sam Both")
    with pytest.raises(RecordsError, match=r"review of result \d+ refused: Sam Both is the "
                                           r"operator of run \d+: a result is reviewed by "
                                           r"someone other than its operator"):
        records.review(mine, "Sam Both", approved=True)
    with pytest.raises(RecordsError, match="is the operator of run"):
        records.review(by_initials, "Sam Both", approved=True)
    other = _result(records, make_result, "Sam Both", serial="IMU-3")
    for who, why in (("Oli Operator", "Oli Operator is an operator: only a reviewer or an "
                                      "admin may review"),
                     ("Eve Engineer", "Eve Engineer is an engineer"),
                     ("Mallory", "Mallory is not a registered user")):
        with pytest.raises(RecordsError, match=why):
            records.review(other, who, approved=True)
    records.disable_user("Rae Reviewer", "left", by="Ada Admin")
    with pytest.raises(RecordsError, match="Rae Reviewer is disabled"):
        records.review(other, "Rae Reviewer", approved=True)
    with pytest.raises(InvalidInputError, match="a rejection needs a comment"):
        records.review(other, "Ada Admin", approved=False)
    records.review(other, "Ada Admin", approved=True)
    assert records.release_status(other).released
    assert records.release_status(mine).reason == f"result {mine} has no review"


def test_only_the_current_version_is_reviewed_and_released(records, make_result):
    _lab(records)
    first = _result(records, make_result, "Oli Operator")
    records.review(first, "Rae Reviewer", approved=True)
    second = records.amend(first, make_result("IMU-1", 0.02), reason="wrong table offset")
    old = records.release_status(first)
    assert not old.released and old.current_id == second
    assert f"result {first} was amended (current version: result {second})" in old.reason
    with pytest.raises(RecordsError, match=f"result {first} was amended by result {second}; "
                                           "review the current version"):
        records.review(first, "Rae Reviewer", approved=True)
    assert not records.release_status(second).released
    records.review(second, "Rae Reviewer", approved=True, comment="re-checked")
    assert records.release_status(second).released


def test_without_users_reviews_are_kept_but_release_nothing(records, make_result):
    """(U.1) a single-person setup reviews as before; (U.4) nothing is released by it."""
    rid = _result(records, make_result, "bo")
    records.review(rid, "bo", approved=True, comment="own check")      # accepted, unchecked
    status = records.release_status(rid)
    assert not status.released and not status.authorised and status.decision == "approve"
    assert "no users were registered when it was reviewed" in status.reason
    # registering reviewers later does not turn that review into an authorisation
    records.add_user("bo", "B", "reviewer")
    assert not records.release_status(rid).released
    records.add_user("Cy", "C", "reviewer", by="bo")
    records.review(rid, "Cy", approved=True)
    assert records.release_status(rid).released
    with pytest.raises(RecordsError, match="no result with id 99"):
        records.release_status(99)


def test_once_users_exist_a_runs_operator_is_an_active_user(records):
    assert records.run(records.record_run(operator="root")).operator == "root"   # (U.1)
    _lab(records)
    assert records.run(records.record_run(operator="Oli Operator")).operator == "Oli Operator"
    with pytest.raises(RecordsError, match=r"a run's operator must be an active user once the "
                                           r"records have users; the operator 'root' is not a "
                                           r"user of the records \(name one with "
                                           r"--operator/--user NAME or IMUCALIB_USER"):
        records.record_run(operator="root")
    with pytest.raises(RecordsError, match="no operator was named"):
        records.record_run(operator="")
    records.disable_user("Oli Operator", "left", by="Ada Admin")
    with pytest.raises(RecordsError, match="the operator 'Oli Operator' is disabled"):
        records.record_run(operator="Oli Operator")
