"""Count a fuzz campaign's outcomes by door (not a test module).

Usage: python tests/fuzz/tally.py TALLY.jsonl

TALLY.jsonl is what ``IMUCALIB_FUZZ_TALLY`` collected (one JSON line per case,
:func:`tests.fuzz._harness.tally`). Prints a Markdown table: for each door the cases, exit 0
(and 1, a failed decision; 3, a partial result of ``calibrate``), exit 2 with one ``error:``
line, exit 2 with an ``error:`` line and one line per offending field (a plan's or a
scenario's refusal), exit 2 by the command-line parser (``Usage:`` and one ``Error:``
line), and what must stay at zero: tracebacks, internal errors, hangs, deaths by a signal and
any other exit (a row without the ``error`` flag, from
before it was recorded, counts as an ``error:`` line: the suite asserts it).
"""

from __future__ import annotations

import json
import sys
from collections import Counter, defaultdict
from pathlib import Path

COLUMNS = ("cases", "exit 0/1/3", "exit 2, one line", "exit 2, field lines", "exit 2, usage",
           "tracebacks", "internal errors", "hangs", "signals", "other")


def count(path: Path) -> dict[str, Counter[str]]:
    """The counts of each column of :data:`COLUMNS` per door."""
    table: dict[str, Counter[str]] = defaultdict(Counter)
    for line in path.read_text(encoding="utf-8").splitlines():
        if not line.strip():
            continue
        row = json.loads(line)
        c = table[str(row.get("door") or row.get("what"))]
        c["cases"] += 1
        code = row.get("code")
        bad = False
        for key, column in (("traceback", "tracebacks"), ("internal", "internal errors"),
                            ("hang", "hangs")):
            if row.get(key):
                c[column] += 1
                bad = True
        if row.get("signal"):
            c["signals"] += 1
            bad = True
        if bad:
            continue
        if code in (0, 1, 3):
            c["exit 0/1/3"] += 1
        elif code == 2 and row.get("one_line"):
            c["exit 2, one line"] += 1
        elif code == 2 and row.get("usage"):
            c["exit 2, usage"] += 1
        elif code == 2 and row.get("error", True):  # an error: line and one line per field
            c["exit 2, field lines"] += 1
        else:
            c["other"] += 1
    return table


def markdown(table: dict[str, Counter[str]]) -> str:
    """The counts as a Markdown table, a total row last."""
    total: Counter[str] = Counter()
    lines = ["| door | " + " | ".join(COLUMNS) + " |",
             "|---|" + "---:|" * len(COLUMNS)]
    for door in sorted(table):
        total.update(table[door])
        lines.append(f"| {door} | " + " | ".join(str(table[door][c]) for c in COLUMNS) + " |")
    lines.append("| **total** | " + " | ".join(f"**{total[c]}**" for c in COLUMNS) + " |")
    return "\n".join(lines)


if __name__ == "__main__":
    print(markdown(count(Path(sys.argv[1]))))
