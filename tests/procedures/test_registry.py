"""The procedure registry: names, lookup, registration, and which procedure a recording is."""

from __future__ import annotations

import dataclasses
import subprocess
import sys
from types import SimpleNamespace
from typing import ClassVar

import pytest

from imucalib.errors import ConfigurationError, InvalidInputError
from imucalib.io.step_roles import split_role
from imucalib.procedures import registry
from imucalib.procedures.common.procedure import Procedure, ProcedureResult


def test_builtins_are_known_and_satisfy_the_protocol():
    assert registry.names()[:2] == ("p1", "allan")
    for name in ("p1", "allan"):
        proc = registry.get(name)
        assert isinstance(proc, Procedure) and proc.name == name and proc.description
        assert proc.outputs
    assert registry.get("p1").analysis_options == {"model", "workers", "terms", "term_criterion",
                                                   "term_level"}
    with pytest.raises(ConfigurationError, match="unknown procedure 'p9'; known: p1, allan"):
        registry.get("p9")


def test_importing_the_registry_imports_no_analysis():
    code = ("import sys, imucalib.procedures.registry as r; r.get('p1'); r.get('allan'); "
            "print(any(m.startswith(('imucalib.procedures.p1.analysis', "
            "'imucalib.procedures.allan.analysis', 'imucalib.estimation')) "
            "for m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "False"


@dataclasses.dataclass(frozen=True)
class _DummyPlanOptions:
    pass


@dataclasses.dataclass(frozen=True)
class _DummyAnalysisOptions:
    pass


class _Dummy:
    name = "p-test"
    description = "a test procedure"
    roles: ClassVar[dict[str, str]] = {}
    plan_options_type = _DummyPlanOptions
    plan_options: frozenset[str] = frozenset()
    analysis_options_type = _DummyAnalysisOptions
    analysis_options: frozenset[str] = frozenset()
    outputs = ("report-json",)

    def generate_plan(self, **options):
        raise NotImplementedError

    def analyze(self, recording, *, unit=None, options=None):
        from imucalib.models.decision import no_decision
        from imucalib.models.procedure_result import ResultDefaults

        name, serial = self.name, unit or "IMU-1"

        class _Result(ResultDefaults):
            procedure, unit, fit_quality, notes = name, serial, (), ()
            decision = no_decision("a test procedure")

            def to_dict(self):
                return {"ok": 1}

        return _Result()

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


def test_register_a_new_procedure(monkeypatch):
    monkeypatch.setattr(registry, "_registered", dict(registry._registered))
    proc = registry.register(_Dummy())
    assert registry.get("p-test") is proc and registry.names()[-1] == "p-test"
    with pytest.raises(ConfigurationError, match="already registered"):
        registry.register(_Dummy())
    with pytest.raises(ConfigurationError, match="is not a Procedure"):
        registry.register(object())  # type: ignore[arg-type]
    bad = _Dummy()
    bad.name = "a.b"
    with pytest.raises(ConfigurationError, match="hold no dot"):
        registry.register(bad)
    assert isinstance(proc.analyze("x"), ProcedureResult)


def test_step_roles_name_the_procedure():
    assert registry.procedure_of_roles(["warm-up", "p1.accel-position", None,
                                        "p1.gyro-rate"]) == "p1"
    assert registry.procedure_of_roles(["allan.record"]) == "allan"
    assert registry.procedure_of_roles(["warm-up", "x9.thing"]) is None
    with pytest.raises(ConfigurationError, match="several procedures"):
        registry.procedure_of_roles(["p1.accel-position", "allan.record"])


@pytest.mark.parametrize("name", list(registry.BUILTIN))
def test_a_builtin_names_its_roles_and_its_plan_uses_no_other(name):
    """Each built-in's ``roles`` is its folder's ``roles.py``; every role is ``<name>.<purpose>``
    with a one-line meaning, and its default plan gives no step another role."""
    import importlib

    proc = registry.get(name)
    module = importlib.import_module(registry.BUILTIN[name].rsplit(".", 1)[0] + ".roles")
    assert proc.roles is module.ROLES and proc.roles
    for role, meaning in proc.roles.items():
        assert split_role(role)[0] == name
        assert meaning and "\n" not in meaning
    used = {s.role for s in proc.generate_plan().steps if s.role}
    assert used <= set(proc.roles), used - set(proc.roles)
    registry.check_roles(used)


def test_the_builtin_p1_scenario_gives_p1_roles():
    """``sim`` lies below the procedures, so its P1 scenario writes P1's roles as data."""
    from imucalib.sim.scenario import load_scenario

    used = {s.role for s in load_scenario("dual-axis-p1").steps if s.role}
    assert used and used <= set(registry.get("p1").roles)


@pytest.mark.parametrize(("roles", "message"), [
    (["tumble.positoin"], "step role 'tumble.positoin' is not a role of procedure tumble; its "
                          "roles: tumble.mount, tumble.position, tumble.drift"),
    (["p1.accel-position", "p9.thing"], "step role 'p9.thing' names no known procedure ('p9'); "
                                        "known: p1, allan"),
    (["warm-up"], "step role 'warm-up' is not '<procedure>.<purpose>'"),
])
def test_check_roles_names_the_unknown_role_and_the_roles_of_its_procedure(roles, message):
    with pytest.raises(ConfigurationError) as err:
        registry.check_roles(roles)
    assert message in str(err.value) and "\n" not in str(err.value)


def test_check_roles_takes_any_procedures_roles_and_a_registered_ones(monkeypatch):
    registry.check_roles(["p1.gyro-rate", "tumble.position", "rate-transfer.rate",
                          "field.pose", "p3.rate"])
    monkeypatch.setattr(registry, "_registered", dict(registry._registered))
    dummy = _Dummy()
    dummy.roles = {"p-test.record": "a record"}  # type: ignore[misc]
    registry.register(dummy)
    registry.check_roles(["p-test.record"])
    with pytest.raises(ConfigurationError, match=r"its roles: p-test\.record"):
        registry.check_roles(["p-test.other"])


def _rec(steps=(), plan_toml=None):
    meta = {} if plan_toml is None else {"plan_toml": plan_toml}
    return SimpleNamespace(path="r.h5", steps=list(steps), metadata=meta)


def test_identify_prefers_roles_then_the_plan():
    from imucalib.plan.io import plan_to_toml

    plan = plan_to_toml(registry.get("allan").generate_plan(record_s=600.0))
    roles = [SimpleNamespace(role="p1.accel-position")]
    assert registry.identify(_rec(roles, plan)) == "p1"
    assert registry.identify(_rec([SimpleNamespace()], plan)) == "allan"
    with pytest.raises(ConfigurationError, match="holds no plan"):
        registry.identify(_rec())
    plan9 = plan.replace('procedure = "allan"', 'procedure = "p9"')
    assert plan9 != plan
    with pytest.raises(ConfigurationError, match="plan procedure 'p9' has no analysis here"):
        registry.identify(_rec([], plan9))


def test_p1_options_are_checked():
    p1 = registry.get("p1")
    with pytest.raises(InvalidInputError, match="got \\['colour'\\]"):
        p1.analyze("x.h5", options={"colour": "red"})
    with pytest.raises(InvalidInputError, match="'triad' or 'per-axis'; got 'full'"):
        p1.analyze("x.h5", options={"model": "full"})
    with pytest.raises(InvalidInputError,
                       match=r"takes the option\(s\) \['import_spec'\]; got \['model'\]"):
        registry.get("allan").analyze("x.h5", options={"model": "triad"})


def test_the_demo_imports_no_cli_module():
    import ast
    from pathlib import Path

    import imucalib.demo

    tree = ast.parse(Path(imucalib.demo.__file__).read_text(encoding="utf-8"))
    imported = {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
    imported |= {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    assert not any(m and m.startswith("imucalib.cli") for m in imported)
    assert "imucalib.procedures" in imported and "imucalib.calibration" in imported  # the pipeline


def test_every_procedure_refuses_an_option_it_does_not_take():
    """One rule for all (procedures/common/procedure.accepted_options): the message lists what
    the procedure takes."""
    for name in registry.names():
        proc = registry.get(name)
        with pytest.raises(InvalidInputError, match=rf"procedure {name} takes"):
            proc.analyze("/nonexistent.h5", options={"no_such_option": 1})
