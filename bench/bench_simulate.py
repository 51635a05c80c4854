"""Wall time of ``imucalib simulate`` on the built-in scenarios (the one runner on the twin).

A scenario runs as a plan through :func:`imucalib.station.runner.run_plan` on the in-process
:class:`~imucalib.station.sim.SimStation`; the twin generates its streams once per tick, so the
tick (``--tick``, and the scenario's ``chunk_s`` while nothing is decided) sets most of the cost.
Prints, per scenario, the virtual time, the wall time (best of ``--repeat``) and the ratio.

Before the single runner (issue 10) ``simulate`` had its own scheduler; on the 2-core development
machine it took 3.1 s (dual-axis-p1) and 3.3 s (static-hour) inside the process.

Per-tick cost (2026-11, same 2-core machine, other jobs running, CPU seconds of one process,
old and new code alternated, recordings bit-identical): a chamber's piece states and lagged
fluctuation constants are computed once per setpoint command instead of per IMU per tick, and a
table axis's servo constants once per command. A 2-unit P2 plan on the thermal twin (50 Hz,
tick 5 s) went from 6.3–7.1 s to 5.2–5.7 s; chamber-array (6 units, soaks of 600 s stability
checked every second) from 46–54 s to 45.5–49 s — the load's noise is as large as the gain;
its profile is now flat (synthesis, kinematics and the HDF5 writer, each a few per cent).

Run:  .venv/bin/python bench/bench_simulate.py [--tick 1.0] [--repeat 2] [NAME ...]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from imucalib.sim.scenario import load_scenario
from imucalib.station.simulate import SIMULATE_TICK_S, simulate_scenario


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*", default=["dual-axis-p1", "static-hour"])
    parser.add_argument("--tick", type=float, default=SIMULATE_TICK_S, help="tick_s [s]")
    parser.add_argument("--repeat", type=int, default=2)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.names:
            sc = load_scenario(name)
            best = float("inf")
            virtual = 0.0
            for _ in range(args.repeat):
                t0 = time.perf_counter()
                summary = simulate_scenario(sc, Path(tmp) / f"{name}.h5", overwrite=True,
                                            tick_s=args.tick)
                best = min(best, time.perf_counter() - t0)
                virtual = summary.virtual_duration_s
            print(f"{name:14s} tick {args.tick:g} s: {virtual:9,.1f} s virtual in {best:6.2f} s "
                  f"({virtual / best:,.0f}× real time), {summary.status}")


if __name__ == "__main__":
    main()
