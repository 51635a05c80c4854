"""The pydantic-free conversion of plain ``str``, ``bool`` and ``Path`` parameters gives what
Typer's own conversion gives: the same values and the same error messages, for values from the
command line, defaults of other types, and every path check (:mod:`imucalib.cli._plain_params`).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Annotated, Any

import pytest
import typer
import typer.main
from typer._click import Context
from typer._click.exceptions import BadParameter
from typer._coercion import build_runtime_param
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.cli._plain_params import _light, lighten

probe = typer.Typer()


@probe.command()
def _probe(
    text: Annotated[str, typer.Option()] = "x",
    maybe: Annotated[str | None, typer.Option()] = None,
    flag: Annotated[bool, typer.Option()] = False,
    path: Annotated[Path, typer.Option()] = Path("."),
    existing: Annotated[Path, typer.Option(exists=True)] = Path("."),
    a_dir: Annotated[Path, typer.Option(file_okay=False)] = Path("."),
    a_file: Annotated[Path, typer.Option(dir_okay=False, exists=True)] = Path("."),
    resolved: Annotated[Path, typer.Option(resolve_path=True)] = Path("."),
    readable: Annotated[Path, typer.Option(readable=True, writable=True)] = Path("."),
) -> None:
    """Print what the command received."""
    typer.echo(repr((text, maybe, flag, path, existing, a_dir, a_file, resolved, readable)))


def _outcome(runtime: Any, value: Any, param: Any, ctx: Context) -> tuple[str, Any]:
    try:
        return "value", runtime.coerce(value, param=param, ctx=ctx)
    except BadParameter as exc:
        return "error", exc.format_message()


@pytest.fixture
def files(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "a.txt").write_text("a")
    (tmp_path / "d").mkdir()
    os.symlink(tmp_path / "a.txt", tmp_path / "link")
    return tmp_path


TEXTS = ["", "-", "a.txt", "d", "d/", "./a.txt", "missing", "d//../a.txt", "link", "~",
         " spaced ", "ünïcode", "yes", "0", "nul\x00byte", "a.txt/"]
OTHERS = [None, Path("a.txt"), Path("missing"), True, 3]


def test_every_plain_parameter_converts_as_typer_does(files):
    command = typer.main.get_command(probe)
    ctx = Context(command)
    checked = 0
    for param in command.params:
        light = _light(param)
        assert light is not None, param.name  # all of the probe's parameters are plain
        own = build_runtime_param(param.type_descriptor)
        for value in [*TEXTS, *OTHERS]:
            if param.type_descriptor.annotation is bool and isinstance(value, str | Path):
                continue  # a flag takes no value on the command line (Typer's own converts it)
            assert _outcome(light, value, param, ctx) == _outcome(own, value, param, ctx), \
                (param.name, value)
            checked += 1
    assert checked > 100


def _run(command: Any, args: list[str]) -> tuple[int | str | None, str]:
    """Run a Click command as the console would; return its exit code and what it printed."""
    with CliRunner().isolation() as (_out, _err, output):
        try:
            command.main(args=args, prog_name="probe")
            code: int | str | None = 0
        except SystemExit as exc:
            code = exc.code
        return code, output.getvalue().decode()


def _both(args: list[str]) -> tuple[tuple[int | str | None, str], tuple[int | str | None, str]]:
    """The probe run with Typer's own conversion, then with the light one."""
    light = typer.main.get_command(probe)
    lighten(light)
    assert all(getattr(p, "_runtime_param", None) is not None for p in light.params)
    return _run(typer.main.get_command(probe), args), _run(light, args)


def test_a_probe_run_prints_the_same_with_and_without_the_light_conversion(files):
    own, light = _both(["--text", "t", "--maybe", "m", "--flag", "--path", "d//x",
                        "--existing", "a.txt", "--a-dir", "d", "--a-file", "link",
                        "--resolved", "d/../a.txt", "--readable", "d"])
    assert own == light
    assert own[0] == 0 and "Path('d/x')" in own[1], own


@pytest.mark.parametrize(("args", "message"), [
    (["--existing", "missing"], "'missing' does not exist"),
    (["--a-dir", "a.txt"], "'a.txt' is a file"),
    (["--a-file", "d"], "'d' is a directory"),
])
def test_a_refused_path_is_the_same_error_line(files, args, message):
    own, light = _both(args)
    assert own == light
    assert own[0] == 2 and message in own[1], own


def test_the_other_kinds_keep_typers_conversion():
    numbers = typer.Typer(add_completion=False)

    @numbers.command()
    def _numbers(count: int = 1, ratio: float = 1.0, names: list[str] | None = None,
                 parsed: Annotated[str, typer.Option(parser=str.upper)] = "x") -> None:
        """Numbers, lists and parsed values are Typer's."""

    command = typer.main.get_command(numbers)
    assert [_light(p) for p in command.params] == [None] * 4


def test_the_records_list_parameters_and_its_help_option_are_light():
    import typer.main as tm

    root = tm.get_command(app)
    records = root.get_command(None, "records")  # type: ignore[attr-defined,arg-type]
    listing = records.get_command(None, "list")
    assert {p.name for p in listing.params} == {"db", "as_json"}
    for command in (root, records, listing):
        for param in [*command.params, command.get_help_option(Context(command))]:
            assert type(param._runtime_param).__name__ in ("_PlainStr", "_PlainBool"), \
                (command.name, param.name)
