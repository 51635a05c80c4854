"""The repository stands on its own: no citation of files a reader of it does not have.

Docstrings, docs, benchmarks and the comments of the TOML files (``pyproject.toml``, the
examples' ``pyproject.toml``) may cite the project's own ``docs/`` pages and the published
literature, never the private working notes outside the repository (the project brief, its
design and style notes, the reference notes on standards and devices, or anything else in
the working folder beside the repository). Every ``docs/<name>.md`` that a docstring, a page
or a TOML file cites must exist.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: Where the citations are looked for: the package, the docs, the README, the benchmarks and
#: the tests (this file excepted: it has to name what it looks for); and every ``*.toml`` file
#: of the repository, wherever it is (:func:`_toml_files`).
SCANNED = ("src", "docs", "README.md", "bench", "tests")
SELF = Path(__file__).resolve()

#: Names of the private files (and the folder) that must not be cited.
PRIVATE = re.compile(r"SPEC\.md|DESIGN\.md|STYLE\.md|standards\.md|devices\.md|\.\./shared"
                     r"|shared/reference")

#: A cited project page.
DOC_PAGE = re.compile(r"docs/[a-z0-9_-]+\.md")

#: Paths allowed to cite the private files for a while, each with the reason in a comment (a
#: branch restructuring them, cleaned up right after it is merged). Empty: every path is checked.
#: An entry must still hold a citation (asserted below), so the set cannot go stale: remove an
#: entry as soon as its path is clean.
PENDING: frozenset[str] = frozenset()

_SKIPPED_PARTS = {"__pycache__", ".pytest_cache", ".mypy_cache", ".ruff_cache"}
#: Folders of a working tree that hold no file of the repository (environments, builds, runs).
_NOT_THE_REPOSITORY = {".git", ".venv", "venv", "build", "dist", "out", ".hypothesis",
                       "node_modules"}


def _skipped(path: Path) -> bool:
    return bool(_SKIPPED_PARTS.intersection(path.parts)) \
        or any(part.endswith(".egg-info") for part in path.parts)


def _toml_files() -> list[Path]:
    """Every ``*.toml`` file under the root, outside environments, builds and caches."""
    found: list[Path] = []
    for folder, subfolders, files in os.walk(ROOT):
        subfolders[:] = sorted(d for d in subfolders if d not in _NOT_THE_REPOSITORY
                               and d not in _SKIPPED_PARTS and not d.endswith(".egg-info"))
        found += [Path(folder) / f for f in sorted(files) if f.endswith(".toml")]
    return found


def _text_files() -> Iterator[tuple[str, list[str]]]:
    """Yield (path relative to the root, lines) of every text file scanned, each once."""
    seen: set[Path] = set()
    trees = [ROOT / top for top in SCANNED]
    for base in [*trees, *_toml_files()]:
        paths = [base] if base.is_file() else sorted(p for p in base.rglob("*") if p.is_file())
        for path in paths:
            if path.resolve() == SELF or path in seen or _skipped(path):
                continue
            seen.add(path)
            data = path.read_bytes()
            if b"\0" in data:
                continue  # binary (an HDF5 test file, an image)
            try:
                text = data.decode("utf-8")
            except UnicodeDecodeError:
                continue
            yield path.relative_to(ROOT).as_posix(), text.splitlines()


def _is_pending(rel: str) -> bool:
    return any(rel == p or (p.endswith("/") and rel.startswith(p)) for p in PENDING)


def _private_citations() -> list[tuple[str, int, str]]:
    return [(rel, n, line.strip())
            for rel, lines in _text_files()
            for n, line in enumerate(lines, 1) if PRIVATE.search(line)]


def test_no_citation_of_private_files() -> None:
    found = [f"{rel}:{n}: {line}" for rel, n, line in _private_citations()
             if not _is_pending(rel)]
    assert not found, ("cite docs/ or the published source instead of private notes:\n"
                       + "\n".join(found))


def test_every_pending_path_still_cites_a_private_file() -> None:
    cited = {rel for rel, _, _ in _private_citations()}
    stale = sorted(p for p in PENDING
                   if not any(rel == p or (p.endswith("/") and rel.startswith(p))
                              for rel in cited))
    assert not stale, f"clean now, remove from PENDING: {stale}"


def test_pending_paths_exist() -> None:
    missing = sorted(p for p in PENDING if not (ROOT / p).exists())
    assert not missing, f"PENDING names paths that do not exist: {missing}"


def test_the_toml_files_are_scanned() -> None:
    scanned = {rel for rel, _ in _text_files()}
    assert {"pyproject.toml", "examples/imucalib-scale-factor/pyproject.toml"} <= scanned


def test_every_cited_docs_page_exists() -> None:
    missing = [f"{rel}:{n}: {page}"
               for rel, lines in _text_files()
               if rel.startswith(("src/", "docs/", "bench/")) or rel == "README.md"
               or rel.endswith(".toml")
               for n, line in enumerate(lines, 1)
               for page in DOC_PAGE.findall(line)
               if not (ROOT / page).is_file()]
    assert not missing, "cited docs pages that do not exist:\n" + "\n".join(missing)
