"""The pytest markers: each declared one is used, and neither CI nor ``make test`` deselects any.

``slow`` marks statistical and long-running checks (README.md, "The two commands"); it exists
for a quick local loop (``-m "not slow"``), so every test still runs under ``make test``, which
is what CI runs (``.ci/run``).
"""

from __future__ import annotations

import re
import shlex
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _ini() -> dict:
    with open(ROOT / "pyproject.toml", "rb") as fh:
        return tomllib.load(fh)["tool"]["pytest"]["ini_options"]


def _declared() -> set[str]:
    return {m.split(":")[0].strip() for m in _ini()["markers"]}


def test_every_declared_marker_is_used():
    used = set()
    for path in (ROOT / "tests").rglob("*.py"):
        used |= set(re.findall(r"pytest\.mark\.([a-z_]+)", path.read_text(encoding="utf-8")))
    assert _declared() - used == set(), "a declared marker no test uses: drop it from pyproject"


def _deselecting(args: list[str]) -> list[str]:
    """The arguments among `args` that select tests by marker or name, or deselect some."""
    return [a for a in args if a in ("-m", "-k", "--deselect")
            or re.match(r"-[mk]\S|--deselect=", a)]


def test_neither_the_default_options_nor_make_test_deselect_a_test():
    assert _deselecting(shlex.split(_ini()["addopts"])) == []
    makefile = (ROOT / "Makefile").read_text(encoding="utf-8")
    runs = [line.split("pytest", 1)[1] for line in makefile.splitlines()
            if re.search(r"-m pytest\b", line)]
    assert runs, "the Makefile runs pytest"
    for args in runs:
        assert _deselecting(shlex.split(args)) == [], f"make runs pytest with {args.strip()!r}"
