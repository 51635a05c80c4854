"""The root group imports a command's module only when the command is asked for.

:data:`imucalib.cli._commands.COMMANDS` must name every top-level command with the module that
registers it, in the order ``--help`` lists them; a command run in a fresh interpreter imports
its own module and none of the other command modules (nothing is timed here:
``bench/bench_cli_startup.py`` measures the start-up).
"""

from __future__ import annotations

import importlib
import json
import subprocess
import sys
from typing import Any

import pytest
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.cli._commands import COMMANDS

runner = CliRunner()

#: The command line's own modules that are not commands (every command imports some of them).
HELPERS = {"imucalib.cli", "imucalib.cli._app", "imucalib.cli._commands",
           "imucalib.cli._plain_params"}


def _registered() -> dict[str, str]:
    """{name: module} of everything the command modules register on the app, once all are
    imported: a command's module is its function's, a group's that of its commands."""
    for module in dict.fromkeys(COMMANDS.values()):
        importlib.import_module(module)
    import typer.main

    out = {}
    for info in app.registered_commands:
        assert info.callback is not None
        out[info.name or typer.main.get_command_name(info.callback.__name__)] = \
            info.callback.__module__
    for group in app.registered_groups:
        assert group.name and group.typer_instance is not None
        modules = {c.callback.__module__ for c in group.typer_instance.registered_commands
                   if c.callback is not None}
        assert len(modules) == 1, (group.name, modules)
        out[group.name] = modules.pop()
    return out


def test_the_table_names_every_command_with_the_module_that_registers_it():
    assert _registered() == COMMANDS


def test_help_lists_every_command_in_the_tables_order():
    result = runner.invoke(app, ["--help"], terminal_width=200)
    assert result.exit_code == 0, result.output
    section = result.output.split("Commands:", 1)[1]
    listed = [line.split()[0] for line in section.splitlines() if line.strip()]
    assert listed == list(COMMANDS)


def test_the_table_lists_the_commands_before_the_groups_as_typer_does():
    """Typer lists a group's commands, then its subgroups: the table keeps that order, so
    ``--help`` reads as it did when every module was imported up front."""
    kinds = ["group" if hasattr(app_command, "commands") else "command"
             for app_command in _click_commands()]
    assert kinds == sorted(kinds, key=lambda k: k == "group")
    assert "group" in kinds and "command" in kinds


def _click_commands() -> list[object]:
    import typer.main

    root: Any = typer.main.get_command(app)
    commands = [root.get_command(None, name) for name in root.list_commands(None)]
    assert None not in commands
    return commands


def test_an_unknown_command_is_refused_with_the_suggestion_from_every_command():
    result = runner.invoke(app, ["recrods", "list"])
    assert result.exit_code == 2
    assert "No such command 'recrods'" in result.output
    assert "Did you mean 'records'?" in result.output


def _command_modules_after(argv: list[str]) -> list[str]:
    """Run ``imucalib ARGV`` through its entry point in a fresh interpreter; return the
    ``imucalib.cli`` modules it imported."""
    code = ("import json, runpy, sys\n"
            f"sys.argv = ['imucalib', *{argv!r}]\n"
            "try:\n"
            "    runpy.run_module('imucalib.cli', run_name='__main__')\n"
            "except SystemExit as exc:\n"
            "    assert exc.code in (0, None), exc.code\n"
            "print(json.dumps(sorted(m for m in sys.modules if m.startswith('imucalib.cli'))))\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.splitlines()[-1])


@pytest.mark.parametrize(("argv", "own"), [
    (["--version"], set()),
    (["scenarios"], {"imucalib.cli.twin", "imucalib.cli._progress"}),
    (["records", "--help"], {"imucalib.cli.records"}),
])
def test_a_command_imports_its_own_module_and_no_other_command_module(argv, own):
    assert set(_command_modules_after(argv)) - {"imucalib.cli.__main__"} == HELPERS | own


def test_records_list_imports_only_the_records_commands(tmp_path):
    from imucalib.records import open_records

    db = str(tmp_path / "lab.db")
    open_records(db).close()
    loaded = set(_command_modules_after(["records", "list", "--db", db]))
    assert loaded - {"imucalib.cli.__main__"} == HELPERS | {"imucalib.cli.records"}


def test_help_imports_every_command_module():
    loaded = set(_command_modules_after(["--help"]))
    assert set(COMMANDS.values()) <= loaded


def test_records_list_builds_the_records_list_command_alone(tmp_path):
    """The ``records`` group lists all its commands by name but builds only the one run."""
    from imucalib.records import open_records

    db = str(tmp_path / "lab.db")
    open_records(db).close()
    code = ("import json, typer.main\n"
            "from imucalib.cli import app\n"
            "root = typer.main.get_command(app)\n"
            f"root.main(['records', 'list', '--db', {db!r}], standalone_mode=False)\n"
            "records = root.commands['records']\n"
            "print(json.dumps([sorted(root.commands), list(records.commands),\n"
            "                  sorted(records.commands._built)]))\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr
    roots, names, built = json.loads(done.stdout.splitlines()[-1])
    assert roots == ["records"]
    assert names[:3] == ["list", "history", "runs"] and len(names) > 10
    assert built == ["list"]


def test_commands_built_on_demand_keep_typers_names_order_and_lookups():
    from imucalib.cli._commands import BuiltOnDemand

    made: list[str] = []

    def build(info: str) -> str:
        made.append(info)
        return info.upper()

    registered: dict[str, Any] = {"b": "b-info", "a": "a-info"}
    commands = BuiltOnDemand(registered, {"sub": "SUB"}, build)
    assert list(commands) == ["b", "a", "sub"] and len(commands) == 3
    assert "a" in commands and "zz" not in commands and made == []
    assert commands.get("a") == "A-INFO" and commands["a"] == "A-INFO" and made == ["a-info"]
    assert commands.get("zz") is None
    assert dict(commands.items()) == {"b": "B-INFO", "a": "A-INFO", "sub": "SUB"}
    assert made == ["a-info", "b-info"]
    del commands["b"]
    commands["c"] = "C"
    assert list(commands) == ["a", "sub", "c"]
    with pytest.raises(KeyError):
        del commands["b"]
