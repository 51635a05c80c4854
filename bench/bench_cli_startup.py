"""How long the ``imucalib`` command line takes to start and finish, against Python's own floor.

Runs, each ``--repeat`` times (default 5) in a fresh process, output discarded:

- the floors ``python -c pass`` and ``python -c "import numpy"``;
- ``imucalib --help``, ``imucalib --version``;
- ``imucalib plan show PLAN`` of a P1 plan (written first by ``imucalib plan new p1``);
- ``imucalib records list --db DB`` of an empty SQLite records database (created and migrated
  by a first, untimed run).

Printed per command: the median wall time and the median CPU time (user + system) of the
process, and the wall time as a multiple of each floor. Then the ten largest entries (cumulative
µs) of ``python -X importtime -c "import imucalib.cli"``: what every command, ``--help`` first,
pays before it runs (docs/architecture.md, "The command line").

An installed imucalib starts from cached bytecode. Where ``PYTHONDONTWRITEBYTECODE`` is set (a
container, a CI job), every start would compile imucalib's modules again; so by default the
child processes keep bytecode in a temporary ``PYTHONPYCACHEPREFIX`` (the working tree gets no
``__pycache__``), warmed by one untimed run of each command. ``--as-is`` runs them in this
environment unchanged.

Speed is measured here, never asserted by a test (tests/cli/test_startup_imports.py checks,
without timing, that the heavy libraries stay out).

Run:  .venv/bin/python bench/bench_cli_startup.py [--repeat 5] [--as-is] [--top 10]
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


def _import_profile(env: dict[str, str], top: int) -> list[tuple[int, int, str]]:
    """The `top` largest (cumulative µs, self µs, module) of ``import imucalib.cli``."""
    argv = [sys.executable, "-X", "importtime", "-c", "import imucalib.cli"]
    subprocess.run(argv, env=env, capture_output=True, check=True)  # warm the cache
    err = subprocess.run(argv, env=env, capture_output=True, text=True, check=True).stderr
    rows = []
    for line in err.splitlines():
        if not line.startswith("import time:") or "self [us]" in line:
            continue
        own, cumulative, name = line.removeprefix("import time:").split("|", 2)
        rows.append((int(cumulative), int(own), name.rstrip()))
    return sorted(rows, reverse=True)[:top]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", "-n", type=int, default=5, help="runs per command (median)")
    ap.add_argument("--as-is", action="store_true",
                    help="run the children in this environment (no bytecode cache of its own)")
    ap.add_argument("--top", type=int, default=10, help="import-profile entries shown")
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
              f"{'× numpy':>8s}")
        times = [(label, *_median(argv, env, args.repeat)) for label, argv in cases]
        bare, numpy = times[0][1], times[1][1]
        for label, wall, cpu in times:
            print(f"  {label:38s} {wall:9.3f} {cpu:8.3f} {wall / bare:7.1f} {wall / numpy:8.2f}")
        print(f"\nimport profile of `python -X importtime -c \"import imucalib.cli\"` (what "
              f"`imucalib --help` imports), top {args.top} by cumulative time:")
        print(f"  {'cumulative µs':>13s} {'self µs':>8s}  module")
        for cumulative, own, name in _import_profile(env, args.top):
            print(f"  {cumulative:13d} {own:8d}  {name}")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
