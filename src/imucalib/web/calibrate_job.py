"""A run's calibration and certificate jobs, seen from the server (docs/web.md).

The analysis is heavy, so it never runs in the server: :func:`start_job` starts
:mod:`imucalib.web.calibrate_worker` in a process of its own session (a Ctrl-C at the server's
terminal does not reach it; it ends by itself), and the server only reads its files in the run's
results folder ``RUNS/<run id>/results/`` (:class:`ResultsFolder`). One job of a kind runs at
a time per run (:class:`JobBusyError` otherwise; a certificate asked for while one is being
written is written once more by the running job); a job whose process ended without writing
its end is shown failed.

Contents
--------
:class:`ResultsFolder`, :class:`JobState`, :func:`start_job`, :func:`download_path`,
:class:`JobBusyError`, :class:`DownloadError`
"""

from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from imucalib.errors import CalibrationError
from imucalib.web.calibrate_worker import (
    CERTIFICATE_AGAIN,
    CERTIFICATE_DIR,
    CONSOLE_FILE,
    STATE_FILES,
    SUMMARY_FILE,
)
from imucalib.web.run_files import RUN_ID_PATTERN, pid_alive, read_json, write_json_atomic

__all__ = ["DownloadError", "JobBusyError", "JobState", "ResultsFolder", "download_path",
           "start_job"]

#: The results folder's own files: never offered as downloads.
INTERNAL = frozenset({*STATE_FILES.values(), SUMMARY_FILE, CONSOLE_FILE, CERTIFICATE_AGAIN,
                      "job.log"})
#: The folders a download may come from, relative to the results folder.
DOWNLOAD_DIRS = ("", CERTIFICATE_DIR)


class JobBusyError(CalibrationError):
    """A job of that kind is already running for the run."""


class DownloadError(CalibrationError):
    """A download that names no file of the run's results (or one outside them)."""


@dataclass(frozen=True)
class JobState:
    """A job's state as the page shows it.

    Attributes
    ----------
    kind : str
        ``calibrate`` or ``certificate``.
    status : str
        ``none`` (never started), ``running``, ``done`` or ``failed``.
    progress : float
        The fraction done (0–1).
    error : str or None
        Why it failed (one line).
    who, started_utc, ended_utc : str
    reason : str
        Why a run already calibrated was calibrated again ("" for a first calibration).
    """

    kind: str
    status: str
    progress: float = 0.0
    error: str | None = None
    who: str = ""
    started_utc: str = ""
    ended_utc: str = ""
    reason: str = ""

    @property
    def running(self) -> bool:
        """Whether the job is at work."""
        return self.status == "running"


@dataclass(frozen=True)
class ResultsFolder:
    """The results folder of one run: ``RUNS/<run id>/results``."""

    folder: Path

    @classmethod
    def of(cls, runs_dir: Path, run_id: str) -> ResultsFolder:
        """Return the results folder of run `run_id` (DownloadError for a malformed id)."""
        if not RUN_ID_PATTERN.match(run_id):
            raise DownloadError(f"{run_id!r} is not a run id")
        return cls(Path(runs_dir) / run_id / "results")

    def state(self, kind: str) -> JobState:
        """Return the state of the job of `kind` (a dead process's "running" is "failed")."""
        data = read_json(self.folder / STATE_FILES[kind])
        if not isinstance(data, dict):
            return JobState(kind, "none")
        status = str(data.get("status") or "none")
        error = data.get("error")
        if status == "running" and not pid_alive(_int(data.get("pid")), str(self.folder)):
            status = "failed"
            error = error or (f"the {kind} process ended without finishing "
                              "(its log: job.log in the run's results folder)")
        return JobState(kind, status, float(data.get("progress") or 0.0),
                        str(error) if error else None, str(data.get("who") or ""),
                        str(data.get("started_utc") or ""), str(data.get("ended_utc") or ""),
                        str(data.get("reason") or ""))

    def ask_certificate_again(self) -> None:
        """Ask the running certificate job to write the certificate once more."""
        (self.folder / CERTIFICATE_AGAIN).touch()

    def certificate_asked(self) -> bool:
        """Return whether a certificate was asked for and not written (and forget the ask)."""
        flag = self.folder / CERTIFICATE_AGAIN
        if not flag.exists():
            return False
        flag.unlink(missing_ok=True)
        return True

    def summary(self) -> dict[str, Any] | None:
        """Return the calibration's summary (None until one is written)."""
        data = read_json(self.folder / SUMMARY_FILE)
        return data if isinstance(data, dict) else None

    def console_text(self) -> str:
        """Return the procedure's terminal output ("" when none)."""
        try:
            return (self.folder / CONSOLE_FILE).read_text(encoding="utf-8")
        except OSError:
            return ""

    def downloads(self) -> list[tuple[str, int]]:
        """Return (name relative to the folder, size) of every file offered, sorted."""
        out = []
        for sub in DOWNLOAD_DIRS:
            where = self.folder / sub if sub else self.folder
            if not where.is_dir():
                continue
            for path in sorted(where.iterdir()):
                if path.is_file() and not path.is_symlink() and path.name not in INTERNAL \
                        and not path.name.startswith("."):
                    name = f"{sub}/{path.name}" if sub else path.name
                    out.append((name, path.stat().st_size))
        return out


def _int(value: Any) -> int | None:
    try:
        return int(value)
    except (TypeError, ValueError):
        return None


def download_path(results: ResultsFolder, name: str) -> Path:
    """Return the file `name` of the run's results, only if it is one of :meth:`downloads`.

    The name is looked up in the listing, never joined onto a path: ``..``, an absolute path,
    a link or a file outside the results folder is refused.

    Raises
    ------
    DownloadError
        No such file among the run's results.
    """
    offered = {n for n, _size in results.downloads()}
    if name not in offered:
        raise DownloadError(f"no file {name!r} among this run's results")
    path = results.folder / name
    if not path.resolve().is_relative_to(results.folder.resolve()):
        raise DownloadError(f"no file {name!r} among this run's results")
    return path


def start_job(results: ResultsFolder, kind: str, *, who: str, db: str | None,
              recording: str = "", records_run: int | None = None,
              python: str | None = None, reason: str = "") -> None:
    """Start the job of `kind` for the run (its process; the server does not wait for it).

    Parameters
    ----------
    results : ResultsFolder
    kind : str
        ``calibrate`` (the run's `recording`) or ``certificate`` (records run `records_run`).
    who : str
        Who calibrates (recorded as the analysis' operator) or asked for the certificate.
    db : str or None
        The records database (None: the default one).
    reason : str
        Why a run already calibrated is calibrated again: the new result's amendment reason in
        the records (``imucalib calibrate --reason``), shown on the results page.

    Raises
    ------
    JobBusyError
        A job of that kind is running for the run.
    CalibrationError
        No recording to calibrate, or no records run for a certificate.
    """
    if results.state(kind).running:
        if kind == "certificate":   # a newer review: the running job writes it once more
            results.ask_certificate_again()
            if results.state(kind).running:
                return
            results.certificate_asked()            # it ended meanwhile: start anew
        else:
            raise JobBusyError(f"a {kind} job is already running for this run")
    cmd = [python or sys.executable, "-m", "imucalib.web.calibrate_worker",
           str(results.folder), "--user", who]
    if kind == "calibrate":
        if not recording or not Path(recording).is_file():
            raise CalibrationError(f"the run's recording {recording or '(none)'} is not there: "
                                   "nothing to calibrate")
        cmd += ["--recording", recording]
        if reason.strip():
            cmd += ["--reason", reason.strip()]
    else:
        if records_run is None:
            raise CalibrationError("the run has no calibration in the records yet: calibrate "
                                   "it first")
        cmd += ["--certificate", str(records_run)]
    if db:
        cmd += ["--db", db]
    results.folder.mkdir(parents=True, exist_ok=True)
    state_file = results.folder / STATE_FILES[kind]
    with (results.folder / "job.log").open("ab") as log:
        proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=log,
                                stderr=subprocess.STDOUT, start_new_session=True,
                                env={**os.environ, "PYTHONUNBUFFERED": "1"})
    write_json_atomic(state_file, {"status": "running", "progress": 0.0, "error": None,
                                   "who": who, "pid": proc.pid, "started_utc": "",
                                   "ended_utc": None, "reason": reason.strip() or None})
    _REAPERS.append(proc)
    _reap()


#: Started processes, polled so that an ended one leaves no zombie behind.
_REAPERS: list[subprocess.Popen[bytes]] = []


def _reap() -> None:
    for proc in list(_REAPERS):
        if proc.poll() is not None:
            _REAPERS.remove(proc)
