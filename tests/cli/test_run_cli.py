"""`imucalib run` from the command line: the twin, the live view, operator checks, resume."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.io import open_recording

runner = CliRunner()


@pytest.fixture(autouse=True)
def wide_console(monkeypatch):
    from imucalib.cli import _app

    monkeypatch.setattr(_app.console, "width", 240)


def test_run_on_the_twin_with_the_live_view(tmp_path, p1_tools):
    plan = p1_tools.small_plan_file(tmp_path)
    result = runner.invoke(app, ["run", str(plan), "--station", "sim", "--out",
                                 str(tmp_path / "runs"), "--yes", "--operator", "A. Tester"])
    assert result.exit_code == 0, result.output
    assert "done:" in result.output and "0 invalid attempt(s)" in result.output
    path = next((tmp_path / "runs").glob("cli-run-*.h5"))
    with open_recording(path) as rec:
        assert all(s.status == "done" for s in rec.steps)
        assert rec.steps[0].note.startswith("confirmed by A. Tester at ")
        assert any(e.source == "operator:A. Tester" for e in rec.log)


def test_operator_checks_need_a_terminal_or_yes(tmp_path, p1_tools):
    plan = p1_tools.small_plan_file(tmp_path)
    result = runner.invoke(app, ["run", str(plan), "--out", str(tmp_path / "runs"),
                                 "--no-live"])
    assert result.exit_code == 2
    assert "has operator checks; run it at a terminal or pass --yes" in result.output
    assert not (tmp_path / "runs").exists() or not list((tmp_path / "runs").glob("*.h5"))


@pytest.mark.parametrize(("args", "message"), [
    (["run"], "give a PLAN file, or --resume FILE"),
    (["run", "missing.toml"], "plan file missing.toml does not exist"),
    (["run", "--resume", "missing.h5"], "no such recording"),
])
def test_run_errors(args, message):
    result = runner.invoke(app, args)
    assert result.exit_code == 2 and message in result.output


def test_station_file_errors_name_the_field(tmp_path, p1_tools):
    plan = p1_tools.small_plan_file(tmp_path)
    bad = tmp_path / "lab.toml"
    bad.write_text('name = "lab"\n[table]\nkind = "contraves"\ntransport = "tcp://127.0.0.1:1"\n')
    result = runner.invoke(app, ["run", str(plan), "--station", str(bad), "--yes", "--no-live",
                                 "--out", str(tmp_path / "runs")])
    assert result.exit_code == 2 and "table.kind" in result.output
