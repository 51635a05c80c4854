"""How long the ``imucalib`` command line takes to start and finish, against Python's own floor.

Runs, each ``--repeat`` times (default 5) in a fresh process, output discarded:

- the floors ``python -c pass`` and ``python -c "import numpy"``;
- ``imucalib --help``, ``imucalib --version``;
- ``imucalib plan show PLAN`` of a P1 plan (written first by ``imucalib plan new p1``);
- ``imucalib records list --db DB`` of an empty SQLite records database (created and migrated
  by a first, untimed run).

Printed per command: the median wall time and the median CPU time (user + system) of the
process, the wall time as a multiple of each floor, and the total of its imports (``python -X
importtime``: the cumulative µs of its top-level imports, one more run). Then the largest entries
(cumulative µs) of the import profile of ``imucalib --help`` and of ``imucalib records list``:
what each pays before it runs (docs/architecture.md, "The command line").

Wall and CPU times follow the machine's load (on a shared machine, compare runs made under the
same load, or the medians of several runs). ``--instructions`` adds a number that does not: the
instructions each command executes, counted by valgrind (``cachegrind``, where valgrind is
installed; about 50 times slower, once per command, with ``PYTHONHASHSEED=0``).

An installed imucalib starts from cached bytecode. Where ``PYTHONDONTWRITEBYTECODE`` is set (a
container, a CI job), every start would compile imucalib's modules again; so by default the
child processes keep bytecode in a temporary ``PYTHONPYCACHEPREFIX`` (the working tree gets no
``__pycache__``), warmed by one untimed run of each command. ``--as-is`` runs them in this
environment unchanged.

Speed is measured here, never asserted by a test (tests/cli/test_startup_imports.py and
tests/cli/test_commands_on_demand.py check, without timing, that the heavy libraries and the
other commands' modules stay out).

Run:  .venv/bin/python bench/bench_cli_startup.py [--repeat 5] [--as-is] [--top 10]
      [--instructions]
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def _imucalib() -> list[str]:
    """The console script beside this interpreter (what a user runs), else ``-m imucalib.cli``."""
    script = Path(sys.executable).with_name("imucalib")
    return [str(script)] if script.is_file() else [sys.executable, "-m", "imucalib.cli"]


def _once(argv: list[str], env: dict[str, str]) -> tuple[float, float]:
    """Run `argv` once; return its wall time and CPU time (user + system) [s]."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(argv, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                          text=True, check=False)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(argv)} failed ({done.returncode}):\n{done.stderr}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def _median(argv: list[str], env: dict[str, str], repeat: int) -> tuple[float, float]:
    _once(argv, env)  # untimed: bytecode cache, database migration, file cache
    runs = [_once(argv, env) for _ in range(repeat)]
    return (statistics.median(w for w, _ in runs), statistics.median(c for _, c in runs))


def _import_rows(argv: list[str], env: dict[str, str]) -> list[tuple[int, int, int, str]]:
    """(cumulative µs, self µs, depth, module) of every import of one ``-X importtime`` run."""
    done = subprocess.run([argv[0], "-X", "importtime", *argv[1:]], env=env, capture_output=True,
                          text=True, check=False)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(argv)} failed ({done.returncode}):\n{done.stderr}")
    rows = []
    for line in done.stderr.splitlines():
        if not line.startswith("import time:") or "self [us]" in line:
            continue
        own, cumulative, name = line.removeprefix("import time:").split("|", 2)
        depth = (len(name) - len(name.lstrip(" ")) - 1) // 2
        rows.append((int(cumulative), int(own), depth, name.rstrip()))
    return rows


def _imports_us(rows: list[tuple[int, int, int, str]]) -> int:
    """The total import time of a run: the cumulative µs of its top-level imports."""
    return sum(cumulative for cumulative, _, depth, _ in rows if depth == 0)


def _instructions(argv: list[str], env: dict[str, str]) -> int | None:
    """The instructions `argv` executes (valgrind's cachegrind), or None without valgrind."""
    valgrind = shutil.which("valgrind")
    if valgrind is None:
        return None
    done = subprocess.run([valgrind, "--tool=cachegrind", "--cache-sim=no",
                           "--cachegrind-out-file=/dev/null", *argv],
                          env={**env, "PYTHONHASHSEED": "0"}, stdout=subprocess.DEVNULL,
                          stderr=subprocess.PIPE, text=True, check=False)
    refs = [line for line in done.stderr.splitlines() if "I   refs:" in line]
    return int(refs[-1].rsplit(":", 1)[1].replace(",", "")) if refs else None


def _python_argv(argv: list[str], cli: list[str]) -> list[str]:
    """`argv` started by this interpreter (``-X importtime`` goes before the script)."""
    if argv[0] == sys.executable:
        return argv
    return [sys.executable, "-m", "imucalib.cli", *argv[len(cli):]]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", "-n", type=int, default=5, help="runs per command (median)")
    ap.add_argument("--as-is", action="store_true",
                    help="run the children in this environment (no bytecode cache of its own)")
    ap.add_argument("--top", type=int, default=10, help="import-profile entries shown")
    ap.add_argument("--instructions", action="store_true",
                    help="also count each command's instructions with valgrind (slow)")
    args = ap.parse_args()

    work = Path(tempfile.mkdtemp(prefix="imucalib-bench-cli-"))
    try:
        env = dict(os.environ)
        if args.as_is:
            mode = ("as is (bytecode " + ("not written" if env.get("PYTHONDONTWRITEBYTECODE")
                                          else "cached as usual") + ")")
        else:
            env.pop("PYTHONDONTWRITEBYTECODE", None)
            env["PYTHONPYCACHEPREFIX"] = str(work / "pycache")
            mode = "bytecode cached (in a temporary PYTHONPYCACHEPREFIX)"
        cli = _imucalib()
        plan, db = work / "p1.toml", work / "records.db"
        subprocess.run([*cli, "plan", "new", "p1", "--out", str(plan)], env=env, check=True,
                       stdout=subprocess.DEVNULL)
        cases = [
            ("python -c pass", [sys.executable, "-c", "pass"]),
            ('python -c "import numpy"', [sys.executable, "-c", "import numpy"]),
            ("imucalib --help", [*cli, "--help"]),
            ("imucalib --version", [*cli, "--version"]),
            ("imucalib plan show P1.toml", [*cli, "plan", "show", str(plan)]),
            ("imucalib records list --db EMPTY.db", [*cli, "records", "list", "--db", str(db)]),
        ]
        load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
        print(f"imucalib command-line start-up: median of {args.repeat} fresh processes; {mode}; "
              f"{os.cpu_count()} CPUs, load average {load:.2f}")
        print(f"  {'command':38s} {'wall [s]':>9s} {'cpu [s]':>8s} {'× pass':>7s} "
              f"{'× numpy':>8s} {'imports [ms]':>13s}"
              + (f" {'instructions':>14s}" if args.instructions else ""))
        times = [(label, *_median(argv, env, args.repeat)) for label, argv in cases]
        bare, numpy = times[0][1], times[1][1]
        profiles = {label: _import_rows(_python_argv(argv, cli), env) for label, argv in cases}
        for label, wall, cpu in times:
            line = (f"  {label:38s} {wall:9.3f} {cpu:8.3f} {wall / bare:7.1f} "
                    f"{wall / numpy:8.2f} {_imports_us(profiles[label]) / 1e3:13.1f}")
            if args.instructions:
                argv = dict(cases)[label]
                count = _instructions(argv, env)
                line += f" {count:14,d}" if count is not None else f" {'(no valgrind)':>14s}"
            print(line)
        for label in ("imucalib --help", "imucalib records list --db EMPTY.db"):
            print(f"\nimport profile of `{label}`, top {args.top} by cumulative time:")
            print(f"  {'cumulative µs':>13s} {'self µs':>8s}  module")
            for cumulative, own, _, name in sorted(profiles[label], reverse=True)[:args.top]:
                print(f"  {cumulative:13d} {own:8d}  {name}")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
