"""Options of a procedure as dataclass fields that describe themselves.

A procedure declares the keywords of its plan generator (and of its analysis) as the fields of
one frozen dataclass in its own folder (``procedures/<name>/options.py``). Each field is made by
:func:`option`, which stores an :class:`OptionInfo` in the field's metadata: the help line, the
unit, the range, the command-line flag and the help section it appears under, and whether the
command line can give it at all (a mapping of truth values or a twin object is Python-only, with
the reason said). Everything else is derived from the dataclass, never kept by hand: the
procedure's ``plan_options`` (:func:`option_names`), the flags and the grouped ``--help`` of
``imucalib plan new NAME`` (:mod:`imucalib.cli.procedure_options`), and the test that walks every
procedure's options (docs/plugins.md).

Values given on the command line arrive as text and are parsed by the field's type
(:func:`parse_text`): numbers, ``true``/``false``, a comma list (``-10,20,60``), pairs
(``0:0,90:0``: pitch:roll positions) and ``a,b,n`` triples.

Contents
--------
:func:`option`, :class:`OptionInfo`, :class:`OptionSpec`, :func:`option_specs`,
:func:`option_names`, :func:`parse_text`, :func:`parse_assignment`, :func:`defaults`
"""

from __future__ import annotations

import dataclasses
import math
import types
import typing
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

from imucalib.errors import ConfigurationError

__all__ = ["OptionInfo", "OptionSpec", "defaults", "option", "option_names", "option_specs",
           "parse_assignment", "parse_text"]

#: The key of :class:`OptionInfo` in a field's metadata.
METADATA_KEY = "imucalib.option"

#: Help sections, in the order ``--help`` shows them.
GROUPS = ("procedure", "timing", "unit", "twin", "plan")

#: What each help section holds (its heading in ``--help``).
GROUP_TITLES = {
    "procedure": "Procedure",
    "timing": "Durations and lengths (a short trial run)",
    "unit": "The unit under test",
    "twin": "The digital twin",
    "plan": "The plan file",
}


@dataclass(frozen=True)
class OptionInfo:
    """What the command line and ``--help`` know of one option.

    Attributes
    ----------
    help : str
        One line; the unit is appended in brackets by the help text, not written here.
    unit : str
        The value's unit as the user gives it (``"s"``, ``"°/s"``, ``"°C"``); empty for none.
    min, max : float, optional
        The inclusive range of a number (of each number of a list).
    flag : str, optional
        The command-line flag without ``--`` when it is not the field's name with dashes
        (``radius-m`` for ``static_radius_m``).
    group : str
        The help section (:data:`GROUPS`).
    cli : bool
        False for a Python-only option (:attr:`python_only` says why).
    python_only : str
        Why the command line cannot give it (a mapping, an object); empty when it can.
    choices : tuple of str, optional
        The allowed values of a text option (taken from a ``Literal`` annotation when omitted).
    """

    help: str
    unit: str = ""
    min: float | None = None
    max: float | None = None
    flag: str | None = None
    group: str = "procedure"
    cli: bool = True
    python_only: str = ""
    choices: tuple[str, ...] | None = None


def option(default: Any, *, help: str, unit: str = "", min: float | None = None,
           max: float | None = None, flag: str | None = None, group: str = "procedure",
           python_only: str = "", choices: Sequence[str] | None = None) -> Any:
    """Return a dataclass field holding `default` and its :class:`OptionInfo`.

    A non-empty `python_only` marks an option the command line cannot give and says why.

    Raises
    ------
    ConfigurationError
        An unknown `group`, or a mutable default (a list or dict: give a tuple or None).
    """
    if group not in GROUPS:
        raise ConfigurationError(f"option group {group!r} is not one of {GROUPS}")
    if isinstance(default, list | dict | set):
        raise ConfigurationError("an option's default must be immutable (a tuple, not a list)")
    info = OptionInfo(help=help, unit=unit, min=min, max=max, flag=flag, group=group,
                      cli=not python_only, python_only=python_only,
                      choices=tuple(choices) if choices is not None else None)
    return dataclasses.field(default=default, metadata={METADATA_KEY: info})


#: How a value is read from text: one scalar, a comma list of scalars, pairs, or one triple.
Shape = Literal["scalar", "list", "pairs", "triple"]


@dataclass(frozen=True)
class OptionSpec:
    """One option of a procedure, resolved from its dataclass field.

    Attributes
    ----------
    name : str
        The keyword (the field's name).
    default : Any
        The field's default.
    info : OptionInfo
        Its help, unit, range, flag, group and CLI reachability.
    kind : type
        The scalar type: ``bool``, ``int``, ``float`` or ``str``.
    shape : {"scalar", "list", "pairs", "triple"}
        How text is read (:func:`parse_text`).
    optional : bool
        Whether None is allowed (the generator then chooses, e.g. a grade's warm-up).
    choices : tuple of str, optional
        Allowed values of a text option.
    """

    name: str
    default: Any
    info: OptionInfo
    kind: type
    shape: Shape
    optional: bool
    choices: tuple[str, ...] | None

    @property
    def flag(self) -> str:
        """The command-line flag, with its dashes (``--record-s``)."""
        return "--" + (self.info.flag or self.name.replace("_", "-"))

    @property
    def cli(self) -> bool:
        """Whether the command line can give it."""
        return self.info.cli

    def metavar(self) -> str:
        """Return the value's placeholder in ``--help``."""
        if self.choices:
            one = "[" + "|".join(self.choices) + "]"
            return one if self.shape == "scalar" else f"{one},…"
        word = {bool: "BOOL", int: "INTEGER", float: "NUMBER", str: "TEXT"}[self.kind]
        return {"scalar": word, "list": f"{word},…", "pairs": "A:B,…",
                "triple": "LO,HI,N"}[self.shape]

    def default_text(self) -> str:
        """Return the default as ``--help`` shows it."""
        d = self.default
        if d is None:
            return "chosen by the procedure"
        if isinstance(d, bool):
            return "yes" if d else "no"
        if isinstance(d, tuple):
            if self.shape == "pairs":
                return ",".join(":".join(f"{v:g}" for v in p) for p in d)
            return ",".join(f"{v:g}" if isinstance(v, float | int) else str(v) for v in d)
        if isinstance(d, float):
            return f"{d:g}"
        return str(d) if d != "" else "none"

    def help_text(self) -> str:
        """Return the help line with its unit in brackets."""
        return f"{self.info.help} [{self.info.unit}]" if self.info.unit else self.info.help

    def help_with_default(self) -> str:
        """Return the help line, its unit and its default (unless the help says the default)."""
        if self.default is None and "(default" in self.info.help:
            return self.help_text()
        return f"{self.help_text()}  (default: {self.default_text()})"


def _strip_optional(tp: Any) -> tuple[Any, bool]:
    """Return (`tp` without None, whether None was part of it)."""
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        optional = len(args) < len(typing.get_args(tp))
        if len(args) == 1:
            return args[0], optional
        raise TypeError(f"an option's type must be one type or None; got {tp}")
    return tp, False


def _scalar(tp: Any) -> tuple[type, tuple[str, ...] | None]:
    """Return the scalar type of `tp` and its choices when it is a Literal of strings."""
    if typing.get_origin(tp) is Literal:
        values = typing.get_args(tp)
        return str, tuple(str(v) for v in values)
    if tp in (bool, int, float, str):
        return tp, None
    raise TypeError(f"an option's scalar type must be bool, int, float, str or a Literal; "
                    f"got {tp}")


def _resolve(tp: Any) -> tuple[type, Shape, bool, tuple[str, ...] | None]:
    """(scalar kind, shape, optional, choices) of an annotation."""
    tp, optional = _strip_optional(tp)
    origin = typing.get_origin(tp)
    if origin in (tuple, Sequence, list) or tp in (tuple, list):
        args = typing.get_args(tp)
        if origin is tuple and args and args[-1] is not Ellipsis:
            kind, choices = _scalar(args[0])
            return kind, "triple", optional, choices
        inner = args[0] if args else float
        if typing.get_origin(inner) is tuple:
            kind, choices = _scalar(typing.get_args(inner)[0])
            return kind, "pairs", optional, choices
        kind, choices = _scalar(inner)
        return kind, "list", optional, choices
    kind, choices = _scalar(tp)
    return kind, "scalar", optional, choices


def option_specs(options_type: type) -> tuple[OptionSpec, ...]:
    """Return the :class:`OptionSpec` of every field of the dataclass `options_type`.

    A field made without :func:`option` is Python-only (its help is its name); its type need not
    be one the command line reads.

    Raises
    ------
    TypeError
        `options_type` is not a dataclass, or a command-line option has a type the command line
        cannot read.
    """
    if not dataclasses.is_dataclass(options_type):
        raise TypeError(f"{options_type!r} is not a dataclass")
    hints = typing.get_type_hints(options_type)
    out = []
    for f in dataclasses.fields(options_type):
        info = f.metadata.get(METADATA_KEY)
        default = f.default if f.default is not dataclasses.MISSING else None
        if info is None:
            info = OptionInfo(help=f.name.replace("_", " "), cli=False,
                              python_only="declared without option()")
        try:
            kind, shape, optional, choices = _resolve(hints[f.name])
        except TypeError:
            if info.cli:
                raise
            kind, shape, optional, choices = str, "scalar", True, None
        out.append(OptionSpec(name=f.name, default=default, info=info, kind=kind, shape=shape,
                              optional=optional, choices=info.choices or choices))
    return tuple(out)


def option_names(options_type: type) -> frozenset[str]:
    """Return the keywords `options_type` declares (a procedure's ``plan_options``)."""
    return frozenset(f.name for f in dataclasses.fields(options_type))


def defaults(options_type: type) -> dict[str, Any]:
    """Return {keyword: default} of `options_type`."""
    return {s.name: s.default for s in option_specs(options_type)}


def _number(text: str, spec: OptionSpec) -> Any:
    text = text.strip()
    if spec.kind is bool:
        low = text.lower()
        if low in ("1", "true", "yes", "on"):
            return True
        if low in ("0", "false", "no", "off"):
            return False
        raise ValueError(text)
    if spec.kind is str:
        if spec.choices and text not in spec.choices:
            raise ValueError(text)
        return text
    value = int(text) if spec.kind is int else float(text)
    if spec.kind is float and not math.isfinite(value):
        raise ValueError(text)
    lo, hi = spec.info.min, spec.info.max
    if (lo is not None and value < lo) or (hi is not None and value > hi):
        raise ValueError(text)
    return value


def _expected(spec: OptionSpec) -> str:
    """Return what `spec` expects, in words, for an error line."""
    word, words = {bool: ("true or false", "true or false values"),
                   int: ("an integer", "integers"), float: ("a number", "numbers"),
                   str: ("text", "words")}[spec.kind]
    if spec.choices:
        word = words = "one of " + ", ".join(spec.choices)
    rng = ""
    if spec.info.min is not None or spec.info.max is not None:
        lo = "−∞" if spec.info.min is None else f"{spec.info.min:g}"
        hi = "∞" if spec.info.max is None else f"{spec.info.max:g}"
        rng = f" in [{lo}, {hi}]"
    unit = f" [{spec.info.unit}]" if spec.info.unit else ""
    return {"scalar": f"{word}{rng}{unit}",
            "list": f"{words}{rng} separated by commas{unit}",
            "pairs": f"pairs A:B of {words}{rng} separated by commas{unit}",
            "triple": f"three values LO,HI,N{unit}"}[spec.shape]


def parse_text(spec: OptionSpec, text: str) -> Any:
    """Return the value of option `spec` given as `text` on the command line.

    Raises
    ------
    ConfigurationError
        Text that is not what the option takes (the message names the flag, what it expects
        and what it got).
    """
    try:
        if spec.optional and text.strip().lower() in ("none", "default"):
            return None
        if spec.shape == "scalar":
            return _number(text, spec)
        items = [t for t in text.split(",") if t.strip()]
        if spec.shape == "list":
            return tuple(_number(t, spec) for t in items)
        if spec.shape == "pairs":
            pairs = [t.split(":") for t in items]
            if any(len(p) != 2 for p in pairs):
                raise ValueError(text)
            return tuple((_number(a, spec), _number(b, spec)) for a, b in pairs)
        if len(items) != 3:
            raise ValueError(text)
        return (float(items[0]), float(items[1]), int(items[2]))
    except ValueError:
        raise ConfigurationError(f"{spec.flag} takes {_expected(spec)}; got {text!r}") from None


def parse_assignment(options_type: type, text: str, *, what: str) -> tuple[str, Any]:
    """Return (keyword, value) of ``NAME=VALUE`` for the options of `options_type`.

    NAME is the option's flag without dashes (``noise-block-s``) or its keyword
    (``noise_block_s``); VALUE is read by the option's type (:func:`parse_text`). `what` names
    whose options they are in messages (``"the tumble analysis"``).

    Raises
    ------
    ConfigurationError
        No ``=``, an unknown or Python-only NAME (the message lists the names it takes), or a
        VALUE the option does not take.
    """
    name, sep, value = text.partition("=")
    specs = {s.name: s for s in option_specs(options_type)}
    by_flag = {s.flag[2:]: s for s in specs.values()}
    spec = specs.get(name.strip()) or by_flag.get(name.strip())
    takes = ", ".join(s.flag[2:] for s in specs.values() if s.cli) or "no options"
    if not sep or not name.strip():
        raise ConfigurationError(f"--set wants NAME=VALUE (an option of {what}: {takes}); "
                                 f"got {text!r}")
    if spec is None:
        raise ConfigurationError(f"{what} takes no option {name.strip()!r}; it takes: {takes}")
    if not spec.cli:
        raise ConfigurationError(f"{what}'s option {spec.name!r} cannot be given on the command "
                                 f"line: {spec.info.python_only}")
    return spec.name, parse_text(spec, value)
