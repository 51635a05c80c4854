"""The process that calibrates a run's recording for the web page (docs/web.md).

``python -m imucalib.web.calibrate_worker RESULTS_DIR --recording PATH --user NAME [--db URL]``
runs the one calibration pipeline of ``imucalib calibrate`` (:func:`imucalib.calibration.calibrate`:
the procedure's analysis, its output files, the result recorded in the run that recorded the
data) with the results folder as ``--out``, then writes what the page shows:

``summary.json``
    Per unit: the parameters in their display units with GUM rounding
    (:func:`~imucalib.report.console.display_parameter`), each fit's χ²/ν, the checks and the
    decision; the records' line; the records run and its results.
``console.txt``
    The procedure's own terminal output (its ``render_console`` hook), as plain text.

With ``--certificate RUN`` it writes instead the certificate of records run ``RUN``
(``imucalib report --run RUN``, PDF and HTML, into ``RESULTS_DIR/certificate``): the
operator, the equipment and the review of each result, a DRAFT until released; again, when a
review came meanwhile (the flag file ``certificate.again``).

Its state is ``calibrate.json`` (or ``certificate.json``) in the results folder, written
atomically: ``status`` (``running``, ``done``, ``failed``), ``progress``, ``error`` (one line),
``who``, ``started_utc``, ``ended_utc``. It never prints a traceback to the page: an error is its
one line, the traceback goes to ``job.log``.
"""

from __future__ import annotations

import argparse
import io
import os
import subprocess
import sys
import time
import traceback
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from imucalib.web.run_files import read_json, write_json_atomic

__all__ = ["main", "summarise"]

#: The state file of each kind of job.
STATE_FILES = {"calibrate": "calibrate.json", "certificate": "certificate.json"}
#: The page's summary of a calibration.
SUMMARY_FILE = "summary.json"
#: The procedure's terminal output.
CONSOLE_FILE = "console.txt"
#: The certificate's folder inside the results folder.
CERTIFICATE_DIR = "certificate"
#: A flag: a review came while the certificate was being written; it is written again.
CERTIFICATE_AGAIN = "certificate.again"


def _now() -> str:
    return datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


class _State:
    """The job's state file (written at every change, ≤ 2 times a second for progress)."""

    def __init__(self, path: Path, who: str) -> None:
        self.path = path
        self.data: dict[str, Any] = dict(read_json(path) or {})
        self.data.update(status="running", progress=0.0, error=None, who=who,
                         started_utc=_now(), ended_utc=None, pid=os.getpid())
        self._last = 0.0
        self.write()

    def write(self) -> None:
        write_json_atomic(self.path, self.data)

    def progress(self, fraction: float) -> None:
        now = time.monotonic()
        if now - self._last >= 0.5:
            self._last = now
            self.data["progress"] = float(min(max(fraction, 0.0), 1.0))
            self.write()

    def end(self, error: str | None) -> None:
        self.data.update(status="failed" if error else "done", error=error,
                         ended_utc=_now(), progress=1.0 if error is None else
                         self.data.get("progress", 0.0))
        self.write()


def _check_rows(result: Any) -> list[dict[str, Any]]:
    """Return the result's checks (a P1 analysis has its own; else its decision's)."""
    checks = getattr(result, "checks", None)
    if checks is None:
        checks = result.decision.checks
    return [{"name": str(c.name), "passed": c.passed, "summary": str(c.summary)}
            for c in checks]


def summarise_unit(result: Any) -> dict[str, Any]:
    """Return one unit's tables: parameters in display units, fit quality, checks, decision."""
    from imucalib.report.console import display_parameter

    if result.error:
        return {"unit": str(result.unit), "procedure": str(result.procedure),
                "error": str(result.error), "parameters": [], "fit_quality": [],
                "checks": [], "decision": None}
    params = []
    for row in result.parameter_rows():
        value, sigma, unit = display_parameter(row.name, row.value, row.std, row.unit)
        scaled = ""
        if row.std_noise and row.std != row.std_noise:  # Birge-scaled (a misfit)
            scaled = display_parameter(row.name, row.value, row.std_noise, row.unit)[1]
        params.append({"name": row.name, "value": value, "std": sigma, "unit": unit,
                       "std_noise": scaled})
    decision = result.decision
    return {
        "unit": str(result.unit), "procedure": str(result.procedure), "error": "",
        "parameters": params,
        "fit_quality": [{"summary": q.summary(), "misfit": bool(q.misfit)}
                        for q in result.fit_quality],
        "checks": _check_rows(result),
        "decision": {"verdict": decision.verdict, "passed": decision.passed,
                     "rule": decision.rule, "failed": list(decision.failed),
                     "summary": decision.summary()},
        "notes": [str(n) for n in result.notes],
        "omitted": [str(o) for o in result.omitted],
    }


def summarise(done: Any, folder: Path, recording: Path, db: str | None) -> dict[str, Any]:
    """Return the page's summary of a :class:`~imucalib.calibration.Calibration`."""
    result = done.result
    units = [summarise_unit(u) for u in (list(result.members) or [result])]
    summary: dict[str, Any] = {
        "procedure": str(result.procedure), "units": units,
        "passed": result.passed, "record": done.record,
        "record_error": None if done.record_error is None else str(done.record_error),
        "written": [str(p.relative_to(folder)) if p.is_relative_to(folder) else p.name
                    for p in done.written],
        "records_run_id": None, "result_ids": {}}
    if done.record is not None and done.record_error is None:
        summary.update(_records_of(recording, db))
    return summary


def _records_of(recording: Path, db: str | None) -> dict[str, Any]:
    """Return the records run that recorded `recording` and its current results, by unit."""
    from imucalib.io.hashing import file_sha256
    from imucalib.records import open_records

    with open_records(db) as records:
        run = records.run_of_recording(file_sha256(recording), recording)
        if run is None:
            return {}
        ids = {}
        for rid in run.result_ids:
            entry = records.result(rid)
            if entry.current:
                ids[entry.serial] = rid
    return {"records_run_id": run.run_id, "result_ids": ids}


def _console_text(done: Any) -> str:
    from rich.console import Console

    buffer = io.StringIO()
    console = Console(file=buffer, width=120, color_system=None, force_terminal=False)
    done.procedure.render_console(console, done.result, done.written)
    return buffer.getvalue()


def _calibrate(folder: Path, recording: Path, who: str, db: str | None, reason: str = "") -> None:
    from imucalib.calibration import calibrate

    state = _State(folder / STATE_FILES["calibrate"], who)
    try:
        (folder / SUMMARY_FILE).unlink(missing_ok=True)
        done = calibrate(recording, out=folder, db=db, operator=who, progress=state.progress,
                         reason=reason)
        summary = summarise(done, folder, recording, db)
        (folder / CONSOLE_FILE).write_text(_console_text(done), encoding="utf-8")
        write_json_atomic(folder / SUMMARY_FILE, summary)
    except Exception as exc:  # the page shows one line; job.log keeps the traceback
        traceback.print_exc()
        state.end(_one_line(exc))
        raise SystemExit(2) from None
    state.end(None)


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split()) or type(exc).__name__
    from imucalib.errors import CalibrationError

    if not isinstance(exc, CalibrationError):
        text = f"{type(exc).__name__}: {text}"
    return text[:400]


def _certificate(folder: Path, run: int, who: str, db: str | None) -> None:
    """Write the certificate, again as long as a newer review asked for it meanwhile."""
    state = _State(folder / STATE_FILES["certificate"], who)
    again = folder / CERTIFICATE_AGAIN
    while True:
        again.unlink(missing_ok=True)
        _write_certificate(folder, run, db, state)
        if not again.exists():
            break
    state.end(None)


def _write_certificate(folder: Path, run: int, db: str | None, state: _State) -> None:
    out = folder / CERTIFICATE_DIR
    out.mkdir(parents=True, exist_ok=True)
    # one process writes both formats of the same report: the run is analysed once
    cmd = [sys.executable, "-m", "imucalib", "report", "--run", str(run), "--format", "pdf,html",
           "--out", str(out)]
    if db:
        cmd += ["--db", db]
    done = subprocess.run(cmd, capture_output=True, text=True, check=False)
    sys.stdout.write(done.stdout)
    sys.stdout.write(done.stderr)
    if done.returncode != 0:
        lines = [ln.strip() for ln in (done.stderr or done.stdout).splitlines() if ln.strip()]
        state.end(lines[-1][:400] if lines else f"imucalib report exited {done.returncode}")
        raise SystemExit(2)
    state.progress(1.0)


def main(argv: list[str] | None = None) -> int:
    """Run the job the arguments name (module docstring); return the exit status."""
    parser = argparse.ArgumentParser(prog="python -m imucalib.web.calibrate_worker")
    parser.add_argument("folder", type=Path)
    parser.add_argument("--recording", type=Path)
    parser.add_argument("--user", default="")
    parser.add_argument("--db", default=None)
    parser.add_argument("--certificate", type=int, default=None)
    parser.add_argument("--reason", default="")
    args = parser.parse_args(argv)
    folder: Path = args.folder
    folder.mkdir(parents=True, exist_ok=True)
    if args.certificate is not None:
        _certificate(folder, args.certificate, args.user, args.db)
    else:
        _calibrate(folder, args.recording, args.user, args.db, args.reason)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
