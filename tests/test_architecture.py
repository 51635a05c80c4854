"""The layers of docs/architecture.md: no module imports a package above its own.

Every ``import imucalib.X`` / ``from imucalib.X import …`` / ``from imucalib import X`` in
``src/imucalib`` (at any depth, deferred imports inside functions included) is checked against the
layer ranks below; a package may import its own modules and packages of a lower rank only. A
light-package check imports single modules in a fresh interpreter and looks at ``sys.modules``.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "imucalib"

#: Layer of each top-level module or package (docs/architecture.md, "Layers").
RANK = {
    "errors": 0,
    "units": 1, "conventions": 1, "_checks": 1, "_lazy": 1, "config": 1,
    "models": 2,
    "io": 3, "estimation": 3, "analysis": 3,
    "plan": 4, "processing": 4,
    "sim": 5,
    "station": 6, "report": 6,
    "drivers": 7, "procedures": 7,
    "exports": 9, "records": 9,
    "calibration": 10,
    "web": 11,
    "demo": 12, "cli": 12,
    "__main__": 13, "__init__": 13,
}


def _top(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def _imports(path: Path) -> list[tuple[str, int]]:
    """(top-level imucalib package imported, line) for every import in `path`."""
    out: list[tuple[str, int]] = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            if node.module == "imucalib":
                out += [(alias.name, node.lineno) for alias in node.names]
            elif node.module.startswith("imucalib."):
                out.append((_top(node.module), node.lineno))
        elif isinstance(node, ast.Import):
            out += [(_top(a.name), node.lineno) for a in node.names
                    if a.name.startswith("imucalib.")]
    return out


def test_every_top_level_module_has_a_layer():
    names = {p.stem if p.is_file() else p.name for p in SRC.iterdir()
             if (p.suffix == ".py" or (p.is_dir() and (p / "__init__.py").exists()))}
    assert names - set(RANK) == set(), "add the new package to RANK and docs/architecture.md"


def test_no_module_imports_a_higher_layer():
    upward = []
    for path in sorted(SRC.rglob("*.py")):
        me = _top("imucalib." + ".".join(path.relative_to(SRC).with_suffix("").parts))
        for target, line in _imports(path):
            if target != me and target in RANK and RANK[target] >= RANK[me]:
                upward.append(f"{path.relative_to(SRC.parent)}:{line}: {me} (layer {RANK[me]}) "
                              f"imports {target} (layer {RANK[target]})")
    assert upward == [], "imports against the flow:\n" + "\n".join(upward)


@pytest.mark.parametrize(("module", "must_not_load"), [
    ("imucalib.drivers.watlow_f4t", "imucalib.sim"),
    ("imucalib.drivers.acl", "imucalib.sim"),
    ("imucalib.drivers.transport", "imucalib.station"),
    ("imucalib.station.devices", "imucalib.sim"),
    ("imucalib.plan", "imucalib.sim"),
    ("imucalib.io", "imucalib.plan"),
    ("imucalib.procedures.registry", "imucalib.procedures.p1.analysis"),
    ("imucalib.records", "sqlalchemy"),
])
def test_importing_one_module_loads_no_unrelated_layer(module, must_not_load):
    code = (f"import sys, {module}; "
            f"print(sorted(m for m in sys.modules if m == {must_not_load!r} "
            f"or m.startswith({must_not_load + '.'!r})))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]", f"importing {module} loaded {done.stdout.strip()}"


def _imported_modules(path: Path) -> list[tuple[str, int]]:
    """(full imucalib module imported, line) for every import in `path` (the walk of `_imports`).

    Relative imports are resolved against `path`'s package; ``from imucalib.procedures import X``
    names the module ``imucalib.procedures.X``.
    """
    package = list(path.relative_to(SRC.parent).with_suffix("").parts[:-1])
    out: list[tuple[str, int]] = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            base = package[:len(package) - node.level + 1] if node.level else []
            module = ".".join([*base, *([node.module] if node.module else [])])
            if module in ("imucalib", "imucalib.procedures") or not node.module:
                out += [(f"{module}.{alias.name}", node.lineno) for alias in node.names]
            if module.startswith("imucalib."):
                out.append((module, node.lineno))
        elif isinstance(node, ast.Import):
            out += [(a.name, node.lineno) for a in node.names if a.name.startswith("imucalib.")]
    return out


def test_no_procedure_folder_imports_another():
    """A procedure folder imports only itself, ``common`` and lower layers (docs/procedures.md)."""
    procedures = SRC / "procedures"
    folders = {p.name for p in procedures.iterdir() if (p / "__init__.py").exists()}
    crossing = []
    for path in sorted(procedures.glob("*/**/*.py")):
        me = path.relative_to(procedures).parts[0]
        if me == "common":
            continue
        for module, line in _imported_modules(path):
            parts = module.split(".")
            if len(parts) < 3 or parts[:2] != ["imucalib", "procedures"]:
                continue
            other = parts[2]
            if other in folders and other not in (me, "common", "registry"):
                crossing.append(f"{path.relative_to(SRC.parent)}:{line}: {me} imports {module}")
    assert crossing == [], ("a procedure folder imports another; move the shared piece to "
                            "procedures/common/:\n" + "\n".join(crossing))


#: The packages that know procedures only through the registry and the hooks of ``Procedure``
#: (docs/architecture.md, "Where a new thing goes"): none imports a procedure's folder.
_PROCEDURE_FREE = ("report", "exports", "records", "cli", "io")

#: (module, procedure module) imports that remain, each with its reason; the list shrinks as
#: a procedure hook takes each over. A stale entry fails the test as much as a new import does.
KNOWN_EXCEPTIONS: set[tuple[str, str]] = set()


def test_the_frameworks_import_no_procedure():
    """``report/`` (the report and terminal frameworks), ``exports/``, ``records/``, ``cli/`` and
    ``io/`` import no procedure's folder (``imucalib.procedures.<name>`` other than ``common``
    and ``registry``), deferred imports included: they reach a procedure through
    ``registry.get(name)`` and its hooks (``report_content``, ``render_console``,
    ``summary_report``), save for :data:`KNOWN_EXCEPTIONS`."""
    procedures = SRC / "procedures"
    folders = {p.name for p in procedures.iterdir() if (p / "__init__.py").exists()} - {"common"}
    found = set()
    for package in _PROCEDURE_FREE:
        for path in sorted((SRC / package).rglob("*.py")):
            for module, _line in _imported_modules(path):
                parts = module.split(".")
                if len(parts) >= 3 and parts[:2] == ["imucalib", "procedures"] \
                        and parts[2] in folders:
                    found.add((path.relative_to(SRC).as_posix(), ".".join(parts[:4])))
    assert found - KNOWN_EXCEPTIONS == set(), (
        "a framework imports a procedure; give the procedure a hook (procedures/common/"
        "procedure.py) instead:\n" + "\n".join(sorted(map(str, found - KNOWN_EXCEPTIONS))))
    assert KNOWN_EXCEPTIONS - found == set(), (
        "no longer imported: remove from KNOWN_EXCEPTIONS:\n"
        + "\n".join(sorted(map(str, KNOWN_EXCEPTIONS - found))))


def _code_strings(path: Path) -> list[tuple[str, int]]:
    """(string, line) of every string constant in `path` that is not a docstring or comment-like
    bare string (an expression statement)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    bare = {id(n.value) for n in ast.walk(tree)
            if isinstance(n, ast.Expr) and isinstance(n.value, ast.Constant)}
    return [(n.value, n.lineno) for n in ast.walk(tree)
            if isinstance(n, ast.Constant) and isinstance(n.value, str) and id(n) not in bare]


#: Strings of ``io/`` that name a procedure's module or role, each with its reason; a stale entry
#: fails the test as much as a new one does.
IO_PROCEDURE_STRINGS = {
    # the frozen version 1 mapping (role_from_tags): a fact of the file format
    ("io/step_roles.py", "p1.accel-position"),
    ("io/step_roles.py", "p1.gyro-bias"),
    ("io/step_roles.py", "p1.gyro-rate"),
    ("io/step_roles.py", "p1.held-out-position"),
    ("io/step_roles.py", "p1.held-out-rate"),
    ("io/step_roles.py", "allan.static"),
}


def test_io_names_no_procedure_role_or_module():
    """``io/`` (the file format) knows the role grammar, not the procedures' roles: no code string
    in it is a built-in procedure's role or names a procedure's module (save for
    :data:`IO_PROCEDURE_STRINGS`); each procedure's roles are in its own ``roles.py``."""
    from imucalib.procedures import registry

    roles = {r for name in registry.BUILTIN for r in registry.get(name).roles}
    found = set()
    for path in sorted((SRC / "io").rglob("*.py")):
        for text, _line in _code_strings(path):
            if text in roles or text.startswith("imucalib.procedures."):
                found.add((path.relative_to(SRC).as_posix(), text))
    assert found - IO_PROCEDURE_STRINGS == set(), (
        "io/ names a procedure's role or module; the roles belong in procedures/<name>/roles.py:"
        "\n" + "\n".join(sorted(map(str, found - IO_PROCEDURE_STRINGS))))
    assert IO_PROCEDURE_STRINGS - found == set(), (
        "no longer in io/: remove from IO_PROCEDURE_STRINGS:\n"
        + "\n".join(sorted(map(str, IO_PROCEDURE_STRINGS - found))))


#: The attributes of a procedure's result (the contract of
#: :mod:`imucalib.models.procedure_result` and the ad-hoc ones it replaced): a framework reads
#: them as members of the contract, never by probing whether a result has them.
_RESULT_ATTRIBUTES = frozenset({
    "procedure", "unit", "decision", "passed", "fit_quality", "notes", "calibration",
    "provenance", "members", "error", "parameter_rows", "triad_parameters", "to_dict",
    "result", "results", "reasons", "models", "observations", "sensor_id", "param_names",
    "std", "model", "details"})


def test_no_framework_probes_a_result_for_its_attributes():
    """``report/``, ``exports/``, ``records/``, ``cli/``, the pipeline and the demo read a result
    through the contract: no ``getattr``/``hasattr`` of a result attribute (by its literal
    name) in them."""
    probes = []
    files = [p for package in ("report", "exports", "records", "cli")
             for p in sorted((SRC / package).rglob("*.py"))]
    files += [SRC / "calibration.py", SRC / "demo.py"]
    for path in files:
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                    and node.func.id in ("getattr", "hasattr") and len(node.args) >= 2
                    and isinstance(node.args[1], ast.Constant)
                    and node.args[1].value in _RESULT_ATTRIBUTES):
                probes.append(f"{path.relative_to(SRC).as_posix()}:{node.lineno}: "
                              f"{node.func.id}(…, {node.args[1].value!r})")
    assert probes == [], ("read the result through its contract "
                          "(imucalib.models.procedure_result), not by probing:\n"
                          + "\n".join(probes))
