"""The command line starts without the heavy libraries.

The rule (docs/architecture.md, "The command line starts light"): a command imports what it
needs when it runs; the CLI modules import nothing heavy. Each case runs in a fresh
interpreter and lists which of the heavy libraries ``sys.modules`` then holds: nothing is timed
(``bench/bench_cli_startup.py`` measures the wall times).
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from typer.testing import CliRunner

from imucalib.cli import app

#: Never needed to start the command line, print its help or its version ("sqlalchemy" covers
#: its ORM, "pydantic" Typer's conversion of the options: ``cli/_plain_params.py``).
HEAVY = ("scipy", "matplotlib", "pandas", "sqlalchemy", "alembic", "numba", "reportlab", "h5py",
         "hdf5plugin", "numpy", "pydantic")
#: Needed by no command that reads a plan or describes a procedure's options (a procedure's
#: options module is loaded to build ``plan new NAME`` and ``calibrate NAME --help``).
ANALYSIS = ("scipy", "matplotlib", "pandas", "sqlalchemy", "alembic", "numba", "reportlab")


def _loaded(args: list[str] | None, among: tuple[str, ...]) -> tuple[list[str], str]:
    """Import ``imucalib.cli`` in a fresh interpreter, run `args` (None: nothing) through its
    Typer app in-process, and return which of `among` were imported, and the output."""
    code = (
        "import json, sys\n"
        "import imucalib.cli\n"
        "from typer.testing import CliRunner\n"
        f"args = {args!r}\n"
        "out = ''\n"
        "if args is not None:\n"
        "    res = CliRunner().invoke(imucalib.cli.app, args, terminal_width=200)\n"
        "    assert res.exit_code == 0, res.output\n"
        "    out = res.output\n"
        f"print(json.dumps([[m for m in {among!r} if m in sys.modules], out]))\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr
    loaded, out = json.loads(done.stdout.splitlines()[-1])
    return loaded, out


@pytest.mark.parametrize("args", [None, ["--help"], ["--version"]],
                         ids=["import", "help", "version"])
def test_the_command_line_starts_without_heavy_libraries(args):
    loaded, _ = _loaded(args, HEAVY)
    assert loaded == [], f"{args or 'import imucalib.cli'} imported {loaded}"


def test_plan_show_reads_the_plan_without_analysis_libraries(tmp_path):
    plan = tmp_path / "p1.toml"
    res = CliRunner().invoke(app, ["plan", "new", "p1", "--out", str(plan)])
    assert res.exit_code == 0, res.output
    loaded, out = _loaded(["plan", "show", str(plan)], ANALYSIS)
    assert loaded == [], f"plan show imported {loaded}"
    assert "steps; at least" in out


def test_records_list_of_an_up_to_date_database_needs_no_alembic_numpy_nor_pydantic(tmp_path):
    """SQLAlchemy and its ORM are what the records API needs; Alembic only to migrate, numpy
    only to record a result, pydantic never: its options are plain (``_plain_params``)."""
    from imucalib.records import open_records

    db = str(tmp_path / "lab.db")
    open_records(db).close()  # created and migrated here: opening it again migrates nothing
    loaded, out = _loaded(["records", "list", "--db", db],
                          (*(m for m in HEAVY if m != "sqlalchemy"), "argon2", "cryptography",
                           "rich.progress", "imucalib.records.backup", "imucalib.cli.users"))
    assert loaded == [], f"records list imported {loaded}"
    assert "serial" in out


@pytest.mark.parametrize(("args", "flag"), [
    (["plan", "new", "p1", "--help"], "--held-out-rates-dps"),
    (["calibrate", "p1", "--help"], "--set model="),
])
def test_a_procedures_options_load_without_analysis_libraries(args, flag):
    """The flags built from a procedure's options dataclass are all there, and building them
    imported none of the analysis (its options module stays cheap)."""
    loaded, out = _loaded(args, ANALYSIS)
    assert loaded == [], f"{' '.join(args)} imported {loaded}"
    assert flag in out



def _loaded_by_entry_point(args: list[str], among: tuple[str, ...]) -> list[str]:
    """Run ``imucalib ARGS`` through its console entry point (:func:`imucalib.cli.main`, as a
    user does) in a fresh interpreter; return which of `among` it imported."""
    code = ("import json, runpy, sys\n"
            f"sys.argv = ['imucalib', *{args!r}]\n"
            "try:\n"
            "    runpy.run_module('imucalib.cli', run_name='__main__')\n"
            "except SystemExit as exc:\n"
            "    assert exc.code in (0, None), exc.code\n"
            f"print(json.dumps([m for m in {among!r} if m in sys.modules]))\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.splitlines()[-1])


#: What no start of the command line needs, named module by module (the ORM, Typer's pydantic
#: adapters, the result models, the web server).
NEVER_AT_START = (*HEAVY, "sqlalchemy.orm", "typer._adapters", "pydantic_core", "argon2",
                  "cryptography", "fastapi", "uvicorn", "imucalib.models.result")


@pytest.mark.parametrize("args", [["--help"], ["--version"], ["records", "--help"]],
                         ids=["help", "version", "records-help"])
def test_the_entry_point_starts_without_heavy_libraries(args):
    assert _loaded_by_entry_point(args, NEVER_AT_START) == []


def test_the_entry_points_records_list_needs_only_sqlalchemy_and_its_orm(tmp_path):
    from imucalib.records import open_records

    db = str(tmp_path / "lab.db")
    open_records(db).close()
    loaded = _loaded_by_entry_point(["records", "list", "--db", db], NEVER_AT_START)
    assert loaded == ["sqlalchemy", "sqlalchemy.orm"]
