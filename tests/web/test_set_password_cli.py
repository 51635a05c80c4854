"""``imucalib users set-password NAME``: from a prompt or --password-stdin, one line if refused."""

from __future__ import annotations

from typer.testing import CliRunner

from imucalib.cli import users as _users  # noqa: F401 (registers the command)
from imucalib.cli._app import app


def test_set_password_from_stdin_and_the_refusals(tmp_path, monkeypatch):
    from imucalib.records import open_records

    db = f"sqlite:///{tmp_path / 'r.db'}"
    monkeypatch.delenv("IMUCALIB_USER", raising=False)
    with open_records(db) as records:
        records.add_user("Ada Admin", "AA", "admin")
        records.add_user("Oli Operator", "OO", "operator", by="Ada Admin")
    run = CliRunner()
    ok = run.invoke(app, ["users", "set-password", "Oli Operator", "--password-stdin",
                          "--user", "Ada Admin", "--db", db], input="a good password\n")
    assert ok.exit_code == 0, ok.output
    assert "password of Oli Operator set" in ok.output
    short = run.invoke(app, ["users", "set-password", "Oli Operator", "--password-stdin",
                             "--db", db], input="short\n")
    assert short.exit_code == 2 and "at least 8 characters; got 5" in short.output
    other = run.invoke(app, ["users", "set-password", "Ada Admin", "--password-stdin",
                             "--user", "Oli Operator", "--db", db], input="long enough\n")
    assert other.exit_code == 2
    assert "only an admin may set another user's password" in other.output
    prompted = run.invoke(app, ["users", "set-password", "Oli Operator", "--db", db],
                          input="typed twice!\ntyped twice!\n")
    assert prompted.exit_code == 0, prompted.output
    with open_records(db) as records:
        assert records.login("Oli Operator", "typed twice!") is not None
        assert records.login("Oli Operator", "a good password") is None
    for result in (short, other):
        assert "Traceback" not in result.output
