"""Same results before and after a change: every estimate of the bench's recordings, compared.

The analysis-speed work promises the same estimates and σ (docs/performance.md, "Same
results"). This script makes that check repeatable:

    # once, with the code before the change (a worktree of the old commit on PYTHONPATH):
    git worktree add /tmp/before <old-commit>
    PYTHONPATH=/tmp/before/src .venv/bin/python bench/results_equality.py dump /tmp/before.json
    # with the code after it:
    .venv/bin/python bench/results_equality.py dump /tmp/after.json
    .venv/bin/python bench/results_equality.py compare /tmp/before.json /tmp/after.json

``dump`` analyses every ``run.gzip.h5`` under ``--dir`` (default ``/tmp/bench``, the recordings
``bench/bench_analysis.py --keep /tmp/bench`` made) with the generic call
``procedure_of(path).analyze(path, unit=None, options={})`` and writes each parameter's value, σ
and noise-only σ (a P2 lot's units too) as JSON. ``compare`` prints, per recording, the largest
difference relative to max(|value|, σ) and which parameter it is, and exits 1 when one exceeds
``--tolerance`` (default 1e-9) or a parameter is missing on one side.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

_FIELDS = ("value", "std", "std_noise")


def _rows(result: Any, prefix: str, out: dict[str, dict[str, float]]) -> None:
    for row in result.parameter_rows():
        out[prefix + row.name] = {k: float(getattr(row, k)) for k in _FIELDS}
    for member in getattr(result, "members", ()) or ():
        _rows(member, f"{prefix}{getattr(member, 'unit', '?')}:", out)


def dump(folder: Path, out: Path) -> int:
    """Analyse every bench recording under `folder`; write their parameters to `out`."""
    from imucalib.calibration import procedure_of

    files = sorted(folder.glob("*/run.gzip.h5"))
    if not files:
        print(f"no */run.gzip.h5 under {folder}: run bench/bench_analysis.py --keep {folder} "
              "first", file=sys.stderr)
        return 2
    found: dict[str, dict[str, dict[str, float]]] = {}
    for path in files:
        rows: dict[str, dict[str, float]] = {}
        _rows(procedure_of(path).analyze(path, unit=None, options={}), "", rows)
        found[path.parent.name] = rows
        print(f"{path.parent.name}: {len(rows)} parameters", file=sys.stderr)
    out.write_text(json.dumps(found, indent=1))
    return 0


def compare(before: Path, after: Path, tolerance: float) -> int:
    """Print the largest relative difference per recording; 1 when one exceeds `tolerance`."""
    a, b = json.loads(before.read_text()), json.loads(after.read_text())
    status = 0
    for name in sorted(set(a) | set(b)):
        if name not in a or name not in b or set(a[name]) != set(b[name]):
            odd = sorted(set(a.get(name, {})) ^ set(b.get(name, {})))[:5]
            print(f"{name}: the parameters differ ({odd})")
            status = 1
            continue
        worst, where = 0.0, ""
        for param, old in a[name].items():
            new = b[name][param]
            scale = max(abs(old["value"]), abs(old["std"]) if math.isfinite(old["std"]) else 0.0,
                        1e-300)
            for field in _FIELDS:
                x, y = old[field], new[field]
                if math.isnan(x) and math.isnan(y):
                    continue
                rel = abs(x - y) / scale if math.isfinite(x - y) else math.inf
                if rel > worst:
                    worst, where = rel, f"{param} {field}: {x!r} → {y!r}"
        flag = "  EXCEEDS" if worst > tolerance else ""
        print(f"{name}: {worst:.2e}{flag}" + (f" ({where})" if where else ""))
        status = max(status, int(worst > tolerance))
    return status


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="command", required=True)
    d = sub.add_parser("dump", help="analyse the bench's recordings, write their parameters")
    d.add_argument("out", type=Path)
    d.add_argument("--dir", type=Path, default=Path("/tmp/bench"))
    c = sub.add_parser("compare", help="compare two dumps")
    c.add_argument("before", type=Path)
    c.add_argument("after", type=Path)
    c.add_argument("--tolerance", type=float, default=1e-9)
    args = ap.parse_args(argv)
    if args.command == "dump":
        return dump(args.dir, args.out)
    return compare(args.before, args.after, args.tolerance)


if __name__ == "__main__":
    sys.exit(main())
