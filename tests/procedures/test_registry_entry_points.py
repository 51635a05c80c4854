"""The registry's entry points: discovery, lazy loading, broken plug-ins, shadowed names.

``importlib.metadata.entry_points`` is replaced by a list of entry points of made-up
distributions whose objects live in a module written to a temporary folder.
"""

from __future__ import annotations

import importlib.metadata
import re
import sys
import tomllib
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from imucalib.errors import ConfigurationError
from imucalib.procedures import registry

PLUGINS = '''
import dataclasses

@dataclasses.dataclass(frozen=True)
class Options:
    pass

class Good:
    description = "a plug-in procedure"
    roles = {}
    plan_options_type = Options
    plan_options = frozenset()
    analysis_options_type = Options
    analysis_options = frozenset()
    outputs = ("report-json",)

    def __init__(self, name):
        self.name = name

    def generate_plan(self, **options):
        raise NotImplementedError

    def analyze(self, recording, *, unit=None, options=None, progress=None):
        raise NotImplementedError

    def report_content(self, result, meta):
        raise NotImplementedError

    def render_console(self, console, result, written):
        raise NotImplementedError

    def analyze_many(self, recordings, *, units=None, options=None, progress=None):
        raise NotImplementedError

    def summary_report(self, batch, *, recordings=None, report_ids=None):
        raise NotImplementedError

    def output_writers(self):
        return {}

    def batch_outputs(self, batch, folder, stem):
        return []

ALPHA = Good("alpha-test")
ZETA = Good("zeta-test")
MISNAMED = Good("something-else")
NOT_A_PROCEDURE = object()
'''


@dataclass(frozen=True)
class _EntryPoint:
    """An entry point of a made-up distribution (name, value, dist, load as the real one)."""

    name: str
    value: str
    dist: Any
    group: str = registry.ENTRY_POINT_GROUP

    def load(self) -> Any:
        return importlib.metadata.EntryPoint(self.name, self.value, self.group).load()


def _dist(name: str, version: str = "1.2") -> Any:
    return SimpleNamespace(name=name, version=version, metadata={"Name": name})


@pytest.fixture
def plugins(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[list[_EntryPoint]]:
    """Replace the entry points by a list the test fills; restore the registry afterwards."""
    (tmp_path / "fake_plugins.py").write_text(PLUGINS, encoding="utf-8")
    (tmp_path / "broken_plugin.py").write_text("raise ImportError('no module named numpyy')\n",
                                                encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    found: list[_EntryPoint] = []
    monkeypatch.setattr(registry, "entry_points",
                        lambda *, group: [e for e in found if e.group == group])
    monkeypatch.setattr(registry, "_discovered", None)
    monkeypatch.setattr(registry, "_registered", dict(registry._registered))
    yield found
    for name in ("fake_plugins", "broken_plugin"):
        sys.modules.pop(name, None)


def test_plugins_are_listed_after_the_builtins_sorted_and_loaded_lazily(plugins):
    vendor = _dist("vendor-procedures")
    plugins += [_EntryPoint("zeta-test", "fake_plugins:ZETA", vendor),
                _EntryPoint("alpha-test", "fake_plugins:ALPHA", vendor)]
    assert registry.names() == (*registry.BUILTIN, "alpha-test", "zeta-test")
    assert "fake_plugins" not in sys.modules  # listing loads nothing
    assert registry.get("alpha-test").name == "alpha-test"
    assert "fake_plugins" in sys.modules
    assert registry.get("alpha-test") is registry.get("alpha-test")
    assert "vendor-procedures 1.2" in registry.origin("zeta-test")
    assert registry.origin("p1") == "built-in"
    assert registry.procedure_of_roles(["zeta-test.rate", "warm-up"]) == "zeta-test"
    with pytest.raises(ConfigurationError, match="already registered"):
        registry.register(registry.get("zeta-test"))


def test_a_broken_entry_point_is_refused_by_name_and_spoils_nothing_else(plugins):
    bad = _dist("bad-plugins", "0.3")
    plugins += [_EntryPoint("broken", "broken_plugin:PROCEDURE", bad),
                _EntryPoint("missing", "fake_plugins:NO_SUCH_OBJECT", bad),
                _EntryPoint("not-one", "fake_plugins:NOT_A_PROCEDURE", bad),
                _EntryPoint("misnamed", "fake_plugins:MISNAMED", bad),
                _EntryPoint("orphan", "broken_plugin:PROCEDURE", None),
                _EntryPoint("alpha-test", "fake_plugins:ALPHA", _dist("good"))]
    assert set(registry.names()) >= {"broken", "missing", "not-one", "misnamed", "alpha-test"}
    with pytest.raises(ConfigurationError, match=r"'orphan = broken_plugin:PROCEDURE' \(group "
                                                 r"imucalib.procedures\) of an unknown "
                                                 r"distribution failed to load"):
        registry.get("orphan")
    with pytest.raises(ConfigurationError,
                       match=r"procedure 'broken': the entry point 'broken = broken_plugin:"
                             r"PROCEDURE' \(group imucalib.procedures\) of the distribution "
                             r"bad-plugins 0.3 failed to load \(ImportError: no module named "
                             r"numpyy\)"):
        registry.get("broken")
    with pytest.raises(ConfigurationError, match=r"'missing = fake_plugins:NO_SUCH_OBJECT'.*"
                                                 r"bad-plugins 0.3 failed to load"):
        registry.get("missing")
    with pytest.raises(ConfigurationError,
                       match=r"'not-one = fake_plugins:NOT_A_PROCEDURE'.* of the distribution "
                             r"bad-plugins 0.3 is not a Procedure \(it lacks name, description"):
        registry.get("not-one")
    with pytest.raises(ConfigurationError, match="is named 'something-else'; the entry point's "
                                                 "name must be the procedure's name"):
        registry.get("misnamed")
    assert registry.get("alpha-test").name == "alpha-test"  # the others still work
    assert registry.get("p1").name == "p1"
    assert registry.procedure_of_roles(["p1.accel-position"]) == "p1"


def test_a_plugin_may_not_shadow_a_builtin(plugins):
    plugins += [_EntryPoint("p1", "fake_plugins:ALPHA", _dist("evil-p1", "6.6")),
                _EntryPoint("bad.name", "fake_plugins:ALPHA", _dist("dotted")),
                _EntryPoint("alpha-test", "fake_plugins:ALPHA", _dist("good"))]
    names = registry.names()  # no warning: the refusals are listed by `imucalib procedures`
    assert names == (*registry.BUILTIN, "alpha-test")
    refused = registry.problems()
    assert len(refused) == 2
    assert re.fullmatch(r"the entry point 'p1 = fake_plugins:ALPHA' \(group imucalib."
                        r"procedures\) of the distribution evil-p1 6.6 is refused: a plug-in "
                        r"may not shadow the built-in procedure 'p1' \(the built-in is used\); "
                        r"rename the plug-in's procedure", refused[0]), refused[0]
    assert "'bad.name = fake_plugins:ALPHA'" in refused[1] and "hold no dot" in refused[1]
    p1 = registry.get("p1")
    assert type(p1).__module__ == "imucalib.procedures.p1.procedure"
    with pytest.raises(ConfigurationError, match="already registered"):
        registry.register(registry.get("alpha-test"))


def test_one_name_from_two_distributions_is_refused(plugins):
    plugins += [_EntryPoint("alpha-test", "fake_plugins:ALPHA", _dist("one")),
                _EntryPoint("alpha-test", "fake_plugins:ALPHA", _dist("two"))]
    assert registry.names().count("alpha-test") == 1
    with pytest.raises(ConfigurationError, match=r"declared by several entry points: .*one "
                                                 r"1.2.*two 1.2; uninstall all but one"):
        registry.get("alpha-test")


def test_imucalibs_own_entry_points_load_the_builtins_and_without_metadata_builtin_does(plugins):
    plugins.append(_EntryPoint("allan", "imucalib.procedures.allan.procedure:PROCEDURE",
                               _dist("imucalib", "0.1.0")))
    registry._registered.pop("allan", None)
    assert registry.get("allan").name == "allan" and registry.problems() == ()
    plugins.clear()
    registry.refresh()
    registry._registered.pop("allan", None)
    assert registry.names() == tuple(registry.BUILTIN)  # a source tree: no metadata at all
    assert registry.get("allan").name == "allan"
    with pytest.raises(ConfigurationError, match="unknown procedure 'alpha-test'"):
        registry.get("alpha-test")


def test_the_builtin_entry_points_are_the_builtin_table():
    """pyproject.toml declares exactly BUILTIN (the fallback), and so does the installed
    metadata when imucalib is installed (reinstall after editing pyproject.toml)."""
    expected = {name: f"{module}:PROCEDURE" for name, module in registry.BUILTIN.items()}
    pyproject = Path(__file__).resolve().parents[2] / "pyproject.toml"
    declared = tomllib.loads(pyproject.read_text(encoding="utf-8"))["project"]["entry-points"]
    assert declared[registry.ENTRY_POINT_GROUP] == expected
    try:
        dist = importlib.metadata.distribution("imucalib")
    except importlib.metadata.PackageNotFoundError:
        pytest.skip("imucalib runs from a source tree (no metadata)")
    installed = {e.name: e.value for e in dist.entry_points
                 if e.group == registry.ENTRY_POINT_GROUP}
    assert installed == expected, "stale metadata: pip install --no-deps -e ."
