"""Plain ``str``, ``bool`` and ``Path`` parameters converted without pydantic.

Typer (0.2x) converts every parameter through a pydantic ``TypeAdapter`` that it builds the
first time the parameter is parsed; for a command like ``records list`` importing pydantic and
building the adapters is a tenth of its start-up (``bench/bench_cli_startup.py``). Most of the
command line's parameters are a plain ``str``, ``bool`` or ``Path`` (``--help`` is a ``bool``
too), whose conversion needs no pydantic: Typer's adapter returns a ``str`` or a ``bool`` as it
is, and turns a ``Path`` argument into ``Path(value)`` before its own checks (``exists``,
``dir_okay``, …, Typer's ``coerce_cli_path``), which are kept.
:func:`lighten` gives such parameters that conversion, so pydantic is imported only by a
command that has another kind of parameter (a number, a list, a choice) and uses it.

Anything else reaches Typer's own conversion unchanged: a parameter with a parser, a list, a
dash for standard input, any value that is not a ``str`` or ``bool`` (a default of another
type), and a path its checks refuse (Typer's error message then, word for word).
``tests/cli/test_plain_params.py`` checks that both give the same values and the same errors.
With a Typer that has no pydantic conversion (its private modules differ), nothing is changed.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

__all__ = ["lighten"]

try:
    from typer._click.exceptions import BadParameter
    from typer._coercion import RuntimeParam, build_runtime_param
    from typer._param_types import coerce_cli_path
    from typer.core import TyperGroup, _TyperParameter
except ImportError:  # pragma: no cover - a Typer without pydantic conversion: nothing to avoid
    _LIGHT = False
else:
    _LIGHT = True

    @dataclass(frozen=True)
    class _PlainStr(RuntimeParam):
        """A ``str`` parameter: the text as given (Typer's ``_parse_cli_str`` of a ``str``)."""

        def _coerce_value(self, value: Any, param: _TyperParameter, ctx: Any) -> Any:
            if type(value) is str:
                return value
            return build_runtime_param(param.type_descriptor)._coerce_value(value, param, ctx)

    @dataclass(frozen=True)
    class _PlainBool(RuntimeParam):
        """A ``bool`` flag: a ``bool`` as it is.

        Typer skips the conversion of a ``bool`` itself, but builds the adapter first for a
        flag without a value (``--help`` not given).
        """

        def _coerce_value(self, value: Any, param: _TyperParameter, ctx: Any) -> Any:
            if type(value) is bool:
                return value
            return build_runtime_param(param.type_descriptor)._coerce_value(value, param, ctx)

    @dataclass(frozen=True)
    class _PlainPath(RuntimeParam):
        """A ``Path`` parameter: ``Path(text)`` through Typer's checks.

        A path the checks refuse (or that ``os.stat`` cannot take: a NUL in it) is converted
        again by Typer's own conversion, for its error message in its words.
        """

        def _coerce_value(self, value: Any, param: _TyperParameter, ctx: Any) -> Any:
            if type(value) is str:
                try:
                    return coerce_cli_path(Path(value), self.parameter_info, path_type=Path,
                                           param=param, ctx=ctx)
                except (BadParameter, ValueError):  # refused, or a NUL in the text
                    pass
            return build_runtime_param(param.type_descriptor)._coerce_value(value, param, ctx)


def lighten(command: Any) -> None:
    """Give the plain parameters of `command` their conversion without pydantic.

    The plain ``str``, ``bool`` and ``Path`` parameters, ``--help`` among them, of the command
    and, when it is a group, of its subcommands.

    Parameters
    ----------
    command : click.Command
        A command or group made by Typer (``typer.main.get_command``).
    """
    if not _LIGHT:  # pragma: no cover - see the module docstring
        return
    for param in getattr(command, "params", ()):
        _lighten_param(param)
    help_option = getattr(command, "get_help_option", None)
    if help_option is not None and not hasattr(help_option, "lightened"):
        setattr(command, "get_help_option", _lightened_help(help_option))  # noqa: B010
    if isinstance(command, TyperGroup) and isinstance(command.commands, dict):
        for sub in command.commands.values():  # (commands built on demand are lightened then)
            lighten(sub)


def _lightened_help(get_help_option: Callable[[Any], Any]) -> Callable[[Any], Any]:
    """Wrap a command's ``get_help_option`` so that its ``--help`` is light too.

    The option is made on first use, and every run parses it, given or not.
    """

    def lightened(ctx: Any) -> Any:
        option = get_help_option(ctx)
        if option is not None:
            _lighten_param(option)
        return option

    lightened.lightened = True  # type: ignore[attr-defined]
    return lightened


def _lighten_param(param: Any) -> None:
    light = _light(param)
    if light is not None:
        param._runtime_param = light


def _light(param: Any) -> RuntimeParam | None:
    """Return the pydantic-free conversion of `param`, or None where Typer's own is needed."""
    if (not isinstance(param, _TyperParameter) or param._runtime_param is not None
            or param.multiple or param.nargs != 1):
        return None
    desc = param.type_descriptor
    info = desc.parameter_info
    if desc.file_annotation is not None or info.parser is not None:
        return None
    if desc.annotation is str:
        return _PlainStr(annotation=str, parameter_info=info)
    if desc.annotation is bool:
        return _PlainBool(annotation=bool, parameter_info=info)
    if desc.annotation is Path and info.path_type is None and not info.allow_dash:
        return _PlainPath(annotation=Path, parameter_info=info)
    return None
