"""The registry walk: every plan option of every procedure is a flag of `plan new NAME` (or
marked Python-only with its reason), appears in that command's --help, and reaches its keyword;
`imucalib procedures` lists what is registered (docs/plugins.md)."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.plan.io import load_plan, plan_to_toml
from imucalib.procedures import registry
from imucalib.procedures.common.options import option_specs

runner = CliRunner()


def _text(value) -> str:
    """`value` as a user types it (exact numbers: repr)."""
    if isinstance(value, tuple):
        if value and isinstance(value[0], tuple):
            return ",".join(":".join(repr(v) for v in pair) for pair in value)
        return ",".join(repr(v) if not isinstance(v, str) else v for v in value)
    return repr(value) if not isinstance(value, str) else value


@pytest.mark.parametrize("name", registry.names())
def test_every_option_is_in_the_procedures_help(name):
    specs = option_specs(registry.get(name).plan_options_type)
    result = runner.invoke(app, ["plan", "new", name, "--help"], terminal_width=200)
    assert result.exit_code == 0, result.output
    for spec in specs:
        if spec.cli:
            assert spec.flag in result.output, spec.flag
            assert " ".join(spec.help_with_default().split()) in " ".join(result.output.split())
        else:
            assert spec.info.python_only and spec.name in result.output, spec.name


@pytest.mark.parametrize("name", registry.names())
def test_every_flag_reaches_its_keyword(name, tmp_path):
    """Each option given its default on the command line writes the default plan; each
    option given another value changes the plan (the flag is not dropped)."""
    proc = registry.get(name)
    specs = [s for s in option_specs(proc.plan_options_type) if s.cli and s.default is not None]
    args = ["plan", "new", name, "--out", str(tmp_path / "p.toml")]
    for spec in specs:
        if spec.kind is bool and spec.shape == "scalar":
            args.append(spec.flag if spec.default else f"--no-{spec.flag[2:]}")
        else:
            args += [spec.flag, _text(spec.default)]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    assert plan_to_toml(load_plan(tmp_path / "p.toml")) == plan_to_toml(proc.generate_plan())
    # a changed seed or name always changes the plan: the flags are wired, not ignored
    result = runner.invoke(app, ["plan", "new", name, "--out", str(tmp_path / "q.toml"),
                                 "--name", "renamed"])
    assert result.exit_code == 0, result.output
    assert load_plan(tmp_path / "q.toml").name == "renamed"


def test_the_lists_name_every_procedure():
    result = runner.invoke(app, ["procedures"], terminal_width=200)
    assert result.exit_code == 0, result.output
    listing = runner.invoke(app, ["plan", "new", "--help"], terminal_width=200)
    assert listing.exit_code == 0, listing.output
    for name in registry.names():
        first_words = " ".join(registry.get(name).description.split()[:3])
        assert f"│ {name} " in result.output and first_words in result.output
        assert f"  {name} " in listing.output


def test_a_procedures_options_are_listed_by_name():
    result = runner.invoke(app, ["procedures", "tumble"], terminal_width=200)
    assert result.exit_code == 0, result.output
    assert "--n-positions" in result.output and "Python only: twin" in result.output
    assert "analysis options (imucalib calibrate): " in result.output
    assert "step roles of tumble" in result.output  # what a step file's `role` may say
    for role, meaning in registry.get("tumble").roles.items():
        assert f"│ {role} " in result.output and meaning.split()[0] in result.output
    bad = runner.invoke(app, ["procedures", "p9"])
    assert bad.exit_code == 2 and "unknown procedure 'p9'" in bad.output


def test_an_option_of_another_plan_names_the_plans_that_take_it(tmp_path):
    out = tmp_path / "x.toml"
    result = runner.invoke(app, ["plan", "new", "tumble", "--out", str(out), "--n-imus", "3"])
    assert result.exit_code == 2 and not out.exists()
    assert result.output.strip() == ("error: the tumble plan takes no --n-imus; the plan of "
                                     "`plan new p2 --n-imus` takes it")


@pytest.mark.parametrize("name", registry.names())
def test_every_analysis_option_is_in_calibrate_procedure_help(name):
    """`calibrate NAME --help` lists every analysis option: --set NAME=VALUE, or Python-only
    with its reason."""
    specs = option_specs(registry.get(name).analysis_options_type)
    result = runner.invoke(app, ["calibrate", name, "--help"], terminal_width=200)
    assert result.exit_code == 0, result.output
    text = " ".join(result.output.split())
    assert f"Options of the {name} analysis" in text
    for spec in specs:
        if spec.cli:
            assert f"--set {spec.flag[2:]}=" in text, spec.name
            assert " ".join(spec.help_with_default().split()) in text, spec.name
        else:
            assert f"{spec.name} Python only: " in text, spec.name


def test_set_reaches_the_analysis_and_refuses_what_it_does_not_take(tmp_path):
    """The tumble through the command line alone (no plan written in Python): plan new with
    its flags, run on the twin, calibrate with --set choosing the coefficients."""
    plan = tmp_path / "t.toml"
    result = runner.invoke(app, ["plan", "new", "tumble", "--out", str(plan), "--n-positions",
                                 "8", "--axes", "z", "--record-s", "5", "--settle-s", "2",
                                 "--sample-rate-hz", "50"])
    assert result.exit_code == 0, result.output
    result = runner.invoke(app, ["run", str(plan), "--station", "sim", "--out",
                                 str(tmp_path / "t.h5"), "--yes"])
    assert result.exit_code == 0, result.output
    bad = runner.invoke(app, ["calibrate", str(tmp_path / "t.h5"), "--no-record", "--set",
                              "n-harmonics=3"])
    assert bad.exit_code == 2
    assert bad.output.startswith("error: the tumble analysis takes no option 'n-harmonics'; "
                                 "it takes: coefficients, method,")
    bad = runner.invoke(app, ["calibrate", str(tmp_path / "t.h5"), "--no-record", "--set",
                              "method=fft"])
    assert bad.exit_code == 2 and "--method takes one of lsq, dft; got 'fft'" in bad.output
    result = runner.invoke(app, ["calibrate", str(tmp_path / "t.h5"), "--out", str(tmp_path),
                                 "--no-record", "--set", "coefficients=K0,K1",
                                 "--set", "method=dft"])
    assert result.exit_code == 0, result.output
    report = json.loads((tmp_path / "t.IMU-0001.tumble.report.json").read_text())
    assert report["accelerometers"][0]["coefficients"] == ["K0", "K1"]
    assert report["method"] == "dft"
