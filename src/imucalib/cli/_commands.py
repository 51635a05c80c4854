"""Which module defines each ``imucalib`` command, and the groups that build commands on demand.

Starting a command costs what its module imports and what Typer does to turn every registered
command into a Click command (each signature read, each option built). The root group
(:class:`CommandsOnDemand`) knows the commands by name (:data:`COMMANDS`) and imports a
command's module only when that command is asked for; a group it builds (``records``, ``plan``,
…) builds each of its own commands only when asked for too (:class:`BuiltOnDemand`). So
``imucalib records list`` imports ``cli/records.py`` alone and builds ``records list`` alone,
while ``imucalib --help``, ``imucalib records --help``, an unknown name (its "did you mean"
list) and shell completion build them all. Every command built gets the pydantic-free
conversion of its plain parameters (:mod:`imucalib.cli._plain_params`).

A module still registers its commands on the one Typer app (:mod:`imucalib.cli._app`) as it
always has; ``tests/cli/test_commands_on_demand.py`` checks that :data:`COMMANDS` names every
command there, with the module that registers it, in the order ``--help`` lists them.
"""

from __future__ import annotations

import copy
import importlib
from collections.abc import Callable, Iterator, MutableMapping
from typing import TYPE_CHECKING, Any, Final

import typer.main
from typer.core import TyperGroup

from imucalib.cli._plain_params import lighten

if TYPE_CHECKING:
    from typer.models import CommandInfo, TyperInfo

__all__ = ["COMMANDS", "BuiltOnDemand", "CommandsOnDemand"]

_CLI = "imucalib.cli."
#: Every top-level command and group, in the order ``imucalib --help`` lists them (Typer's:
#: the commands, then the groups), with the module that registers it on the app.
COMMANDS: Final[dict[str, str]] = {
    "allan": _CLI + "allan",
    "calibrate": _CLI + "calibrate",
    "apply": _CLI + "calibrate",
    "procedures": _CLI + "procedures",
    "inspect": _CLI + "recording",
    "recover": _CLI + "recording",
    "compact": _CLI + "recording",
    "export": _CLI + "recording",
    "import": _CLI + "recording",
    "segments": _CLI + "recording",
    "report": _CLI + "report",
    "combine": _CLI + "results",
    "run": _CLI + "run",
    "serve": _CLI + "serve",
    "scenarios": _CLI + "twin",
    "simulate": _CLI + "twin",
    "plan": _CLI + "plan",
    "records": _CLI + "records",
    "schema": _CLI + "results",
    "station": _CLI + "station",
    "users": _CLI + "users",
}


class CommandsOnDemand(TyperGroup):
    """The root group: it imports a command's module, and builds its Click command, on demand.

    A command is built when it is first asked for: by name, or by a listing of all of them.
    """

    def __init__(self, **attrs: Any) -> None:
        super().__init__(**attrs)
        lighten(self)  # what Typer built already: the modules imported before the app ran

    def list_commands(self, ctx: Any) -> list[str]:
        """Return every command's name, in :data:`COMMANDS` order (any other after them)."""
        return [*COMMANDS, *(name for name in self.commands if name not in COMMANDS)]

    def get_command(self, ctx: Any, cmd_name: str) -> Any:
        """Return the command `cmd_name`, importing its module first if needed.

        None if there is no such command; every module is imported then, so that Typer's "did
        you mean" suggestions come from every command.
        """
        if cmd_name not in self.commands:
            modules = [COMMANDS[cmd_name]] if cmd_name in COMMANDS else list(COMMANDS.values())
            for module in dict.fromkeys(modules):
                importlib.import_module(module)
            self._adopt()
        return self.commands.get(cmd_name)

    def _adopt(self) -> None:
        """Add the commands and groups registered on the app since this group was built."""
        from imucalib.cli._app import app

        for info in app.registered_commands:
            name = command_name(info)
            if name not in self.commands:
                self.add_command(build_command(info, app), name)
        for group_info in app.registered_groups:
            if group_info.name in self.commands:
                continue
            group = build_group(group_info, app)
            if group.name:
                self.add_command(group, group.name)
            else:  # a group added without a name: its commands join the root (as in Typer)
                for name in group.commands:
                    self.commands.setdefault(name, group.commands[name])


class BuiltOnDemand(MutableMapping[str, Any]):
    """A group's ``commands``: each built from its Typer registration when first looked up.

    Names, membership and order (Typer's: the commands, then the subgroups) need no building;
    looking a command up (``get``, ``[]``, ``values``, ``items``) builds it once.
    """

    def __init__(self, registered: dict[str, CommandInfo], built: dict[str, Any],
                 build: Callable[[CommandInfo], Any]) -> None:
        self._registered = registered
        self._built = built
        self._build = build

    def __getitem__(self, name: str) -> Any:
        if name not in self._built:
            self._built[name] = self._build(self._registered[name])
        return self._built[name]

    def __setitem__(self, name: str, command: Any) -> None:
        self._built[name] = command

    def __delitem__(self, name: str) -> None:
        if name not in self:
            raise KeyError(name)
        self._registered.pop(name, None)
        self._built.pop(name, None)

    def __contains__(self, name: object) -> bool:
        return name in self._registered or name in self._built

    def __iter__(self) -> Iterator[str]:
        yield from self._registered
        yield from (name for name in self._built if name not in self._registered)

    def __len__(self) -> int:
        return sum(1 for _ in self)


def command_name(info: CommandInfo) -> str:
    """Return the name Typer gives a registered command (its own, else its function's)."""
    return info.name or typer.main.get_command_name(getattr(info.callback, "__name__", ""))


def build_command(info: CommandInfo, app: typer.Typer) -> Any:
    """Build the Click command of a registered command, as Typer does, with light parameters."""
    command = typer.main.get_command_from_info(
        info, pretty_exceptions_short=app.pretty_exceptions_short,
        rich_markup_mode=app.rich_markup_mode)
    lighten(command)
    return command


def build_group(group_info: TyperInfo, app: typer.Typer) -> TyperGroup:
    """Build the Click group of a registered Typer group, its commands built on demand.

    Typer builds the group (its callback, options, help, subgroups) from a copy of the group's
    app that has no commands; the commands are then registered in :class:`BuiltOnDemand`.
    """
    sub = group_info.typer_instance
    assert sub is not None, "a Typer group has its app"
    shell = copy.copy(sub)
    shell.registered_commands = []
    shell_info = copy.copy(group_info)
    shell_info.typer_instance = shell
    group = typer.main.get_group_from_info(
        shell_info, pretty_exceptions_short=app.pretty_exceptions_short,
        rich_markup_mode=app.rich_markup_mode, suggest_commands=app.suggest_commands)
    lighten(group)  # its own parameters and its subgroups, built already
    registered = {command_name(info): info for info in sub.registered_commands}
    group.commands = BuiltOnDemand(registered, dict(group.commands),
                                   lambda info: build_command(info, app))
    return group
