"""The main job of ``make demo``: procedure P1 end to end on the digital twin.

Run as ``python -m imucalib.demo --out DIR``. It

1. generates the default P1 plan (six positions, a 60-minute level static record, rate points
   about pitch, roll and Z, held-out positions and rates, three repetitions) for a tactical-grade
   IMU and writes it to ``DIR/p1-plan.toml``;
2. runs it on the twin through the station runner, with every guard active, into a Recording;
3. calibrates: estimates every parameter with its uncertainty (full triad model), checks the
   residuals, the held-out accuracy and the repeatability, and decides pass/fail;
4. compares the estimates with the twin's truth (which only the demo and the tests read);
5. records the calibration in the records database (docs/records.md: ``--db URL``, default
   ``$IMUCALIB_DB``, else records.db in the user's data directory; ``--no-record`` skips it);

and prints where the files and the record are. ``--quick`` shortens the static record and runs
one repetition.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from rich.console import Console
from rich.table import Table

from imucalib.errors import CalibrationError

if TYPE_CHECKING:
    from imucalib.models.result import CalibrationResult

__all__ = ["main"]


def _truth_table(result: CalibrationResult, truth: dict[str, Any]) -> Table:
    from imucalib.models.imu import ImuModel

    model = ImuModel.from_dict(truth["imu_models"][result.sensor_id])
    true = {}
    for triad, tm in (("accel", model.accel), ("gyro", model.gyro)):
        for i, a in enumerate("xyz"):
            true[f"{triad}_bias_{a}"] = tm.bias[i]
            true[f"{triad}_K2_{a}"] = np.broadcast_to(np.asarray(tm.k2, dtype=float), 3)[i]
            true[f"{triad}_K3_{a}"] = np.broadcast_to(np.asarray(tm.k3, dtype=float), 3)[i]
            for j, b in enumerate("xyz"):
                true[f"{triad}_M_{a}{b}"] = tm.scale_misalignment[i, j]
                true[f"{triad}_G_{a}{b}"] = tm.g_sensitivity[i, j] if triad == "gyro" else 0.0
    z = np.array([(result.value(n) - true[n]) / result.sigma(n) for n in result.param_names])
    table = Table("parameters", "within 2σ", "within 3σ", "within 4σ", "largest |error|/σ",
                  title="estimates against the twin's truth")
    table.add_row(str(z.size), str(int(np.sum(np.abs(z) <= 2))), str(int(np.sum(np.abs(z) <= 3))),
                  str(int(np.sum(np.abs(z) <= 4))), f"{np.abs(z).max():.2f}")
    return table


def main(argv: list[str] | None = None) -> int:
    """Run the demo; return the process exit code."""
    parser = argparse.ArgumentParser(prog="python -m imucalib.demo", description=__doc__)
    parser.add_argument("--out", type=Path, default=Path("out"), help="output folder")
    parser.add_argument("--seed", type=int, default=1, help="seed of the twin")
    parser.add_argument("--quick", action="store_true", help="one repetition, 10 min static")
    parser.add_argument("--db", default=None, help="records database URL or SQLite file")
    parser.add_argument("--no-record", action="store_true", help="do not record the result")
    args = parser.parse_args(argv)
    console = Console()
    from imucalib.calibration import calibrate
    from imucalib.io.opening import open_recording
    from imucalib.models.result import CalibrationResult
    from imucalib.plan import describe_plan, write_plan
    from imucalib.procedures import registry
    from imucalib.station.runner import RunOptions, run_plan
    from imucalib.station.sim import SimStation

    try:
        args.out.mkdir(parents=True, exist_ok=True)
        p1 = registry.get("p1")
        plan = p1.generate_plan(grade="tactical", sample_rate_hz=200.0, seed=args.seed,
                                repetitions=1 if args.quick else 3,
                                static_s=600.0 if args.quick else 3600.0,
                                warm_up_s=300.0 if args.quick else None)
        plan_path = write_plan(plan, args.out / "p1-plan.toml")
        total = sum(r.min_duration_s for r in describe_plan(plan))
        console.rule("[bold]1. The plan")
        console.print(f"{plan_path}: {len(plan.steps)} steps, at least {total / 3600:.2f} h of "
                      "station time", highlight=False)
        console.rule("[bold]2. Run it on the digital twin")
        assert plan.twin is not None
        station = SimStation(plan.twin)
        path = args.out / "p1-run.h5"
        wall = time.perf_counter()
        summary = run_plan(plan, station, path, overwrite=True,
                           options=RunOptions(tick_s=2.0, truth=station.truth))
        console.print(f"{summary.status}: {summary.steps_done} steps, "
                      f"{summary.end_s / 3600:.2f} h of station time in "
                      f"{time.perf_counter() - wall:.1f} s → {path}", highlight=False)
        if summary.status != "done":
            raise CalibrationError(f"the run did not complete: {summary.reason}")
        console.rule("[bold]3. Calibrate and verify")
        done = calibrate(path, procedure="p1", options={"model": "triad"}, out=args.out,
                         record=not args.no_record, db=args.db, operator="demo")
        analysis, written = done.result, done.written
        p1.render_console(console, analysis, written)
        console.rule("[bold]4. Against the truth")
        with open_recording(path) as rec:
            truth = rec.truth
        # the calibration as written for apply (its result file) against the twin's truth
        saved = next(p for p in written if p.name.endswith(".result.json"))
        console.print(_truth_table(CalibrationResult.load(saved), truth))
        if not args.no_record:
            console.rule("[bold]5. Record")
            if done.record_error is not None:
                raise done.record_error
            console.print(done.record, highlight=False, soft_wrap=True)
    except CalibrationError as exc:
        Console(stderr=True).print(f"[bold red]error:[/] {exc}", highlight=False)
        return 2
    pdf = next((p for p in written if p.suffix == ".pdf"), None)
    console.print(f"\nFiles are in {args.out.resolve()}: the plan, the recording, the result "
                  "(.result.json) and the full report (.report.json)"
                  + (f"\nCalibration report (PDF): {pdf.resolve()}" if pdf else ""),
                  highlight=False, soft_wrap=True)
    return 0 if analysis.passed else 1


if __name__ == "__main__":
    sys.exit(main())
