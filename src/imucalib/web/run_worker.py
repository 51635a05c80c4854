"""The worker process of a supervised run: ``python -m imucalib.web.run_worker RUN_FOLDER``.

It runs the plan of ``RUN_FOLDER/run.json`` with the runner of ``imucalib run``
(:func:`~imucalib.station.runner.run_plan`, or :func:`~imucalib.station.runner.resume_run` with
``--resume``), on the station ``imucalib run --station`` would build, with the CLI's run
metadata and records: there is no second way of running a plan (docs/web-runs.md). What differs
is who watches and who answers:

- :class:`~imucalib.web.run_reporter.RunReporter` is the runner's ``on_status``: it writes the
  run's state and events for the supervisor and takes its commands;
- its ``on_recording_log`` is the runner's ``on_log``: every line the runner writes to the
  Recording's event log is a line of the page's log too;
- :class:`WebOperator` is the runner's operator: an operator check opens a prompt and waits for
  the answer the supervisor passes on (a refusal is the runner's safe stop, as at the terminal);
- an abort (a command, SIGTERM or SIGINT) raises
  :class:`~imucalib.web.run_reporter.RunAborted` at the next tick: the runner's Ctrl-C path.

The worker runs in a session of its own, so a Ctrl-C at the server's terminal does not reach it,
and it keeps running when the server stops. Exit status: 0 finished, 1 stopped, 2 failed.
"""

from __future__ import annotations

import argparse
import logging
import signal
import sys
import time
import traceback
from datetime import UTC, datetime
from pathlib import Path
from types import FrameType
from typing import Any

from imucalib.errors import CalibrationError, ConfigurationError
from imucalib.station.operator import OperatorAnswer
from imucalib.web.run_files import RunFiles
from imucalib.web.run_reporter import COMMAND_POLL_S, RunAborted, RunReporter
from imucalib.web.run_tap import SignalTap, tap_station

__all__ = ["WebOperator", "main"]


class WebOperator:
    """The runner's operator in a supervised run: asks through the run's prompt, waits."""

    def __init__(self, reporter: RunReporter) -> None:
        self.reporter = reporter

    def confirm(self, item: str) -> OperatorAnswer:
        """Open a prompt for `item`; block until it is answered (or the run is aborted)."""
        rep = self.reporter
        rep.open_prompt(item)
        while rep.answer is None:
            rep.check_abort()
            time.sleep(COMMAND_POLL_S)
            rep.poll_commands(force=True)
        answer = rep.answer
        confirmed, who = bool(answer.get("confirmed")), str(answer.get("who") or "?")
        rep.close_prompt(confirmed, who)
        note = str(answer.get("note") or "")
        return OperatorAnswer(confirmed, who, note=(note + " (web)").strip())


class _LogToReporter(logging.Handler):
    """The library's warnings (a failed safe stop, a failed close) into the run's log."""

    def __init__(self, reporter: RunReporter) -> None:
        super().__init__(logging.WARNING)
        self.reporter = reporter

    def emit(self, record: logging.LogRecord) -> None:
        try:
            self.reporter.log(record.getMessage(), record.levelname.lower())
        except Exception:  # a log line must never stop the run
            self.handleError(record)


def _check_serials(serials: list[str], station: Any) -> None:
    names = [src.name for src in station.imus]
    if serials and sorted(serials) != sorted(names):
        raise ConfigurationError(f"the unit serials given {serials} are not the station's units "
                                 f"{names}")


def _run(files: RunFiles, cfg: dict[str, Any], resume: bool) -> int:
    from imucalib.drivers.station_spec import make_station
    from imucalib.plan import load_plan, plan_hash
    from imucalib.records.run_entry import check_due, run_environment, run_metadata
    from imucalib.station.runner import RunOptions, find_resume_point, resume_run, run_plan

    recording = Path(cfg["recording"])
    old = files.read_state() or {}
    tap = SignalTap()
    first = 0
    if resume:
        point = find_resume_point(recording)
        plan, first = point.plan, point.first_step
    else:
        plan = load_plan(files.plan)
    who = str(cfg.get("resumed_by") if resume else cfg["operator"])
    rep = RunReporter(files, plan, who, tap, first_step=first, pace=cfg.get("pace"),
                      prompt_seq=int(old.get("prompt_seq", 0)),
                      resumed=int(old.get("resumed", 0)) + (1 if resume else 0))
    logging.getLogger("imucalib").addHandler(_LogToReporter(rep))

    def on_signal(signum: int, frame: FrameType | None) -> None:
        rep.request_abort(f"signal {signal.Signals(signum).name}")

    signal.signal(signal.SIGTERM, on_signal)
    signal.signal(signal.SIGINT, on_signal)
    rep.set_status("starting")
    spec = str(cfg["station"])
    tick = cfg.get("tick_s") or (2.0 if spec == "sim" else 0.5)
    options = RunOptions(tick_s=float(tick), operator=WebOperator(rep), on_status=rep.on_status,
                         on_log=rep.on_recording_log)
    db = cfg.get("db")
    record = bool(cfg.get("record", True))
    try:
        if resume:
            rep.log(f"resuming at step {first} ({plan.step_label(first)}) for {who}"
                    if first < len(plan.steps) else f"resuming (closing) for {who}")

            def factory(p: Any, start_time_s: float) -> Any:
                st, _ = make_station(spec, p, start_time_s)
                _check_serials(list(cfg.get("serials") or []), st)
                return tap_station(st, tap)

            rep.set_status("running")
            summary = resume_run(recording, factory, options=options)
        else:
            station_name = "sim" if spec == "sim" else Path(spec).stem
            override = cfg.get("override_due") or None
            equipment, overdue = check_due(db, station_name, override, create=record)
            if overdue:
                rep.log(f"equipment overdue for calibration used "
                        f"({', '.join(str(e.equipment_id) for e in overdue)}), overridden by "
                        f"{cfg['operator']}: {override}", "warning")
            bare, station_toml = make_station(spec, plan)
            _check_serials(list(cfg.get("serials") or []), bare)
            options.station_toml = station_toml
            options.truth = getattr(bare, "truth", None)
            recording.parent.mkdir(parents=True, exist_ok=True)
            started = datetime.now(UTC)
            rep.log(f"plan {plan.name!r} started by {who} on {spec}")
            rep.set_status("running")
            summary = run_plan(plan, tap_station(bare, tap), recording, options=options,
                               extra_metadata=run_metadata(who, equipment, overdue, override))
            ended = datetime.now(UTC)
            if record:
                try:
                    from imucalib.records import open_records

                    with open_records(db) as records:
                        rep.extra["records_run_id"] = records.record_run(
                            plan_name=plan.name, plan_hash=plan_hash(plan),
                            procedure=plan.procedure, recording=summary.path, operator=who,
                            station=station_name if equipment else None,
                            equipment=[e.equipment_id for e in equipment],
                            environment=run_environment(summary.status, overdue, override),
                            started_utc=started, ended_utc=ended)
                except CalibrationError as exc:
                    rep.log(f"the run was not recorded in the records database: {exc}", "error")
    except RunAborted as exc:
        _finish(rep, "stopped", f"{exc}; the recording was closed and can be resumed")
        return 1
    except CalibrationError as exc:
        _finish(rep, "failed", f"{type(exc).__name__}: {exc}")
        return 2
    except Exception as exc:
        rep.log(traceback.format_exc(limit=8), "error")
        _finish(rep, "failed", f"{type(exc).__name__}: {exc}")
        return 2
    rep.extra["summary"] = {"status": summary.status, "steps_done": summary.steps_done,
                            "steps_invalid": summary.steps_invalid, "trips": list(summary.trips),
                            "reason": summary.reason, "storage_note": summary.storage_note}
    for trip in summary.trips:
        rep.log(f"trip: {trip}", "warning")
    if summary.status == "done":
        _finish(rep, "finished", None)
        return 0
    _finish(rep, "stopped", f"{summary.reason}; the recording was closed and can be resumed")
    return 1


def _finish(rep: RunReporter, status: str, error: str | None) -> None:
    for i, state in enumerate(rep.steps):
        if state == "running":
            rep.set_step(i, "done" if status == "finished" else "failed")
    rep.log(f"run {status}" + (f": {error}" if error else ""),
            "info" if status == "finished" else "warning")
    rep.set_status(status, error)
    rep.event("end", status=status, error=error)
    rep.close()


def main(argv: list[str] | None = None) -> int:
    """Run (or ``--resume``) the run of a folder; return the exit status (module docstring)."""
    parser = argparse.ArgumentParser(prog="python -m imucalib.web.run_worker")
    parser.add_argument("folder", type=Path)
    parser.add_argument("--resume", action="store_true")
    args = parser.parse_args(argv)
    files = RunFiles(args.folder.resolve())
    cfg = files.read_config()
    if cfg is None:
        print(f"{files.config} is missing or unreadable", file=sys.stderr)
        return 2
    return _run(files, cfg, args.resume)


if __name__ == "__main__":
    sys.exit(main())
