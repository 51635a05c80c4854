"""Rough edges of the command line: --version, refused plan options, help text, packaging."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

from imucalib import __version__
from imucalib.cli import app

runner = CliRunner()

#: An escape sequence of a terminal (colour, cursor movement): progress bars draw with them.
ANSI = re.compile(r"\x1b\[")


def test_version_prints_the_version_and_exits_0():
    result = runner.invoke(app, ["--version"])
    assert result.exit_code == 0, result.output
    assert __version__ in result.output


@pytest.mark.parametrize("option", ["--temperatures=-10,20,60", "--n-imus=4"])
def test_plan_new_p1_refuses_an_option_its_plan_does_not_take(tmp_path, option):
    out = tmp_path / "p1.toml"
    result = runner.invoke(app, ["plan", "new", "p1", "--out", str(out), option])
    assert result.exit_code == 2, result.output
    assert not out.exists()
    text = " ".join(result.output.split())
    name = option.split("=")[0]
    assert f"p1 plan takes no {name}" in text
    if name == "--temperatures":
        assert "allan" in text  # which procedure's plan does take it


def test_plan_new_allan_takes_temperatures(tmp_path):
    out = tmp_path / "allan.toml"
    result = runner.invoke(app, ["plan", "new", "allan", "--out", str(out), "--record-s=600",
                                 "--temperatures=-10,20"])
    assert result.exit_code == 0, result.output
    assert out.exists()


def test_plan_new_refuses_options_of_p1_for_allan(tmp_path):
    result = runner.invoke(app, ["plan", "new", "allan", "--out", str(tmp_path / "a.toml"),
                                 "--repetitions=2"])
    assert result.exit_code == 2, result.output
    assert "--repetitions" in result.output


def _commands(group, path=()):
    """(argv, click command) of every command and group under the Typer app (the root group
    builds a command when it is asked for: every one is asked for here)."""
    yield path, group
    if hasattr(group, "commands"):  # a group
        names = group.list_commands(None) if not path else list(group.commands)
        for name in names:
            yield from _commands(group.get_command(None, name), (*path, name))


def _help_strings(cmd) -> list[str]:
    texts = [cmd.help or ""]
    texts += [getattr(p, "help", None) or "" for p in cmd.params]
    return [t for t in texts if t]


BRACKETED = re.compile(r"\[[^\[\]\s][^\[\]]*\]")


def test_help_keeps_every_bracketed_token_of_the_help_texts():
    import typer

    root = typer.main.get_command(app)
    checked = 0
    for path, cmd in _commands(root):
        result = runner.invoke(app, [*path, "--help"])
        assert result.exit_code == 0, (path, result.output)
        shown = " ".join(result.output.split())
        assert not ANSI.search(result.output)
        for text in _help_strings(cmd):
            for token in BRACKETED.findall(" ".join(text.split())):
                checked += 1
                assert token in shown, (path, token, result.output)
        assert " ()" not in shown and "[]" not in shown, (path, result.output)
    assert checked > 10  # "[s]", "[Hz]", "[twin]", … are there to check


def test_pyproject_uses_the_spdx_license_form():
    import tomllib

    doc = tomllib.loads((Path(__file__).resolve().parents[2] / "pyproject.toml")
                        .read_text(encoding="utf-8"))
    assert doc["project"]["license"] == "MIT"
    assert any(r.replace(" ", "").startswith("setuptools>=77")
               for r in doc["build-system"]["requires"])
