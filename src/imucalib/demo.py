"""The main job of ``make demo``: the P1 procedure end to end on the digital twin.

Run as ``python -m imucalib.demo --out DIR``. It simulates the dual-axis P1 scenario (six
positions, a level static record, ±rate points about pitch and roll) into ``DIR/p1.h5`` and
summarises the recording.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from rich.console import Console

from imucalib.errors import CalibrationError

__all__ = ["main"]


def main(argv: list[str] | None = None) -> int:
    """Run the demo; return the process exit code."""
    parser = argparse.ArgumentParser(prog="python -m imucalib.demo", description=__doc__)
    parser.add_argument("--out", type=Path, default=Path("out"), help="output folder")
    parser.add_argument("--seed", type=int, default=None, help="override the scenario's seed")
    args = parser.parse_args(argv)
    console = Console()
    from imucalib.io.inspect import summarize_recording
    from imucalib.sim.runner import simulate_scenario
    from imucalib.sim.scenario import load_scenario

    try:
        args.out.mkdir(parents=True, exist_ok=True)
        scenario = load_scenario("dual-axis-p1")
        if args.seed is not None:
            scenario = scenario.model_copy(update={"seed": args.seed})
        path = args.out / "p1.h5"
        console.rule("[bold]1. Run P1 on the digital twin")
        summary = simulate_scenario(scenario, path, overwrite=True)
        console.print(summary.describe(), highlight=False)
        console.rule("[bold]2. The recording")
        summarize_recording(path).render(console)
    except CalibrationError as exc:
        Console(stderr=True).print(f"[bold red]error:[/] {exc}", highlight=False)
        return 2
    console.print(f"\nFiles are in {args.out.resolve()}", highlight=False)
    return 0


if __name__ == "__main__":
    sys.exit(main())
