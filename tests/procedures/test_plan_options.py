"""Every procedure's plan options are one dataclass (procedures/<name>/options.py) true to its
generator: the same keywords, the same defaults, and a plan made from the defaults is the plan the
generator makes on its own (docs/plugins.md)."""

from __future__ import annotations

import dataclasses
import importlib
import inspect

import pytest

from imucalib.errors import ConfigurationError
from imucalib.plan.io import plan_to_toml
from imucalib.procedures import registry
from imucalib.procedures.common.options import (
    defaults,
    option,
    option_names,
    option_specs,
    parse_text,
)


def _generator(name: str):
    """The built-in procedure's plan generator: ``<folder>.plan.generate_*_plan``."""
    folder = type(registry.get(name)).__module__.rsplit(".", 1)[0]
    module = importlib.import_module(folder + ".plan")
    found = [f for n, f in vars(module).items()
             if n.startswith("generate_") and n.endswith("_plan") and inspect.isfunction(f)
             and f.__module__ == module.__name__]
    assert len(found) == 1, (name, [f.__name__ for f in found])
    return found[0]


def _norm(value):
    if isinstance(value, list | tuple):
        return tuple(_norm(v) for v in value)
    return value


@pytest.mark.parametrize("name", list(registry.BUILTIN))
def test_the_options_dataclass_is_the_generators_signature(name):
    proc = registry.get(name)
    cls = proc.plan_options_type
    assert dataclasses.is_dataclass(cls) and cls.__dataclass_params__.frozen
    assert proc.plan_options == option_names(cls)
    params = {p.name: p for p in inspect.signature(_generator(name)).parameters.values()
              if p.kind is p.KEYWORD_ONLY}
    assert set(params) == set(option_names(cls))
    for spec in option_specs(cls):
        assert _norm(spec.default) == _norm(params[spec.name].default), spec.name
        assert spec.info.help and spec.info.help[0].isupper(), spec.name
        assert spec.cli or spec.info.python_only, spec.name


@pytest.mark.parametrize("name", list(registry.BUILTIN))
def test_a_plan_from_the_defaults_is_the_default_plan(name):
    proc = registry.get(name)
    given = {k: v for k, v in defaults(proc.plan_options_type).items()}
    assert plan_to_toml(proc.generate_plan(**given)) == plan_to_toml(proc.generate_plan())


@dataclasses.dataclass(frozen=True)
class _Opts:
    n: int = option(3, help="Count.", min=1, max=10)
    t_s: float = option(1.5, help="Time.", unit="s", min=0.0)
    temps_degc: tuple[float, ...] | None = option(None, help="Temps.", unit="°C")
    pos_deg: tuple[tuple[float, float], ...] = option(((0.0, 0.0),), help="Positions.")
    span: tuple[float, float, int] | None = option(None, help="Span.")
    flag: bool = option(False, help="Flag.")
    mode: str = option("a", help="Mode.", choices=("a", "b"))
    other: object = option(None, help="An object.", python_only="an object")


def test_text_is_parsed_by_the_fields_type():
    specs = {s.name: s for s in option_specs(_Opts)}
    assert parse_text(specs["n"], "7") == 7
    assert parse_text(specs["t_s"], "2.5") == 2.5
    assert parse_text(specs["temps_degc"], "-10, 20,60") == (-10.0, 20.0, 60.0)
    assert parse_text(specs["temps_degc"], "none") is None
    assert parse_text(specs["pos_deg"], "0:0,90:180") == ((0.0, 0.0), (90.0, 180.0))
    assert parse_text(specs["span"], "1,100,5") == (1.0, 100.0, 5)
    assert parse_text(specs["flag"], "yes") is True
    assert parse_text(specs["mode"], "b") == "b"
    assert not specs["other"].cli and specs["other"].info.python_only == "an object"
    assert specs["t_s"].help_text() == "Time. [s]" and specs["t_s"].flag == "--t-s"
    assert specs["pos_deg"].default_text() == "0:0"


@pytest.mark.parametrize(("field", "text", "message"), [
    ("n", "11", r"--n takes an integer in \[1, 10\]; got '11'"),
    ("n", "2.5", "--n takes an integer"),
    ("t_s", "nan", "--t-s takes a number in \\[0, ∞\\] \\[s\\]; got 'nan'"),
    ("temps_degc", "1,x", "--temps-degc takes numbers separated by commas"),
    ("pos_deg", "0:0:0", "--pos-deg takes pairs A:B"),
    ("span", "1,2", "--span takes three values LO,HI,N"),
    ("mode", "c", "--mode takes one of a, b; got 'c'"),
    ("flag", "maybe", "--flag takes true or false"),
])
def test_bad_text_gets_one_line_naming_what_was_expected(field, text, message):
    spec = {s.name: s for s in option_specs(_Opts)}[field]
    with pytest.raises(ConfigurationError, match=message):
        parse_text(spec, text)


def test_a_mutable_default_or_unknown_group_is_refused():
    with pytest.raises(ConfigurationError, match="immutable"):
        option([1.0], help="x")
    with pytest.raises(ConfigurationError, match="group"):
        option(1.0, help="x", group="misc")
