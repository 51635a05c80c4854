"""P2 in batch: every unit of one or many array recordings, on local cores or a Dask cluster.

One job per run of units of one recording: it opens the file once and, unit by unit, reduces
that unit's windows one step at a time (:func:`analyze_units_file`), so a job's memory is that
of one step of one unit, whatever the number of units, and the jobs share nothing but the file.
A unit that cannot be calibrated returns a result holding its typed error
(:func:`~imucalib.procedures.p2.analysis.failed_unit`); the others go on.

Where the jobs run:

- ``workers=1``: in this process, all units of a recording in one job;
- ``workers=N``: this process and N − 1 local ones (forked on Linux, each with one thread of
  every numerical library; :func:`~imucalib.procedures.common.workers.share_with_workers`),
  the units in N runs per recording, the processes taking the largest runs first;
- ``scheduler="tcp://host:8786"``: an existing Dask cluster (``dask.distributed.Client``, the
  ``dask`` extra); the workers must see the recordings at the same paths (a shared file
  system). A :class:`dask.distributed.Client` may be passed instead of an address.

The results do not depend on where they ran (each unit's result is a pure function of the
file).

Contents
--------
:class:`P2BatchResult`, :data:`BATCH_DECISION_RULE`, :func:`analyze_p2`,
:func:`analyze_unit_file`, :func:`analyze_units_file`, :func:`summary_rows`, :func:`batch_json`,
:func:`held_out_units`.
"""

from __future__ import annotations

import ctypes
import dataclasses
import functools
import json
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from imucalib.errors import (
    CalibrationError,
    ConfigurationError,
    InvalidInputError,
    MissingSegmentError,
)
from imucalib.io.hashing import file_sha256
from imucalib.io.opening import open_recording, reopening
from imucalib.io.reader import Recording, StepRecord, StreamData
from imucalib.models.decision import Check, Decision
from imucalib.models.fit_quality import FitQuality
from imucalib.models.procedure_result import ResultDefaults
from imucalib.procedures.common.workers import share_with_workers
from imucalib.procedures.p2.analysis import P2Options, analyze_unit, failed_unit
from imucalib.procedures.p2.observations import extract_unit_observations, p2_units
from imucalib.procedures.p2.reduction import PARAM_NAMES
from imucalib.procedures.p2.result import P2UnitResult
from imucalib.procedures.p2.roles import P2_SOAK

__all__ = ["BATCH_DECISION_RULE", "P2BatchResult", "analyze_p2", "analyze_unit_file",
           "analyze_units_file", "batch_json", "held_out_units", "summary_rows"]

#: The decision rule of a batch (docs/p2.md, "The decision").
BATCH_DECISION_RULE = "a P2 array or lot passes when every unit passes P2's acceptance"


@dataclass(frozen=True)
class P2BatchResult(ResultDefaults):
    """Every unit's P2 result, of one recording (an array) or many (a production lot).

    A :class:`~imucalib.models.procedure_result.ProcedureResult` (docs/procedures.md, "The
    result contract"): ``unit`` is ``"array"`` (or ``"lot"``), ``members`` are the units'
    results (each written on its own), ``decision`` passes when every unit passes (docs/p2.md,
    "The decision"); a batch has no parameters, triad model or provenance of its own.
    """

    recordings: tuple[str, ...]
    results: tuple[P2UnitResult, ...]
    procedure: str = "p2"

    @property
    def unit(self) -> str:
        """``"array"`` for one recording, ``"lot"`` for several."""
        return "array" if len(self.recordings) == 1 else "lot"

    @property
    def members(self) -> tuple[P2UnitResult, ...]:
        """Every unit's result, in the order of the recordings and their units."""
        return tuple(self.results)

    @property
    def decision(self) -> Decision:
        """Pass when every unit passes; ``failed`` names the units that did not.

        One check per unit (``unit <name>``: its verdict, why it failed, how many of its
        temperature models are NOT consistent at the held-out points); a note counts the units
        with such models (not part of P2's rule, docs/p2.md "The decision").
        """
        failed = tuple(r.unit for r in self.results if not r.passed)
        checks = tuple(Check(f"unit {r.unit}", r.passed, _unit_summary(r))
                       for r in self.results)
        held = held_out_units(self)
        notes = ((f"{len(held)} of {len(self.results)} unit(s) have temperature models NOT "
                  f"consistent at the held-out points ({', '.join(held)}): not part of P2's "
                  "rule (docs/p2.md, \"The decision\"); each unit's decision names them",)
                 if held else ())
        return Decision(passed=not failed, rule=BATCH_DECISION_RULE, failed=failed,
                        checks=checks, notes=notes)

    @property
    def notes(self) -> tuple[str, ...]:
        """Why each unit that could not be calibrated failed (``<unit>: <error>``)."""
        return tuple(f"{r.unit}: {r.error}" for r in self.results if r.error)

    @property
    def fit_quality(self) -> tuple[FitQuality, ...]:
        """Every unit's fits, unit by unit."""
        return tuple(q for r in self.results for q in r.fit_quality)

    def to_dict(self) -> dict[str, Any]:
        """Return the summary and every unit's result, JSON-able."""
        return {"procedure": "p2", "recordings": list(self.recordings), "passed": self.passed,
                "summary": summary_rows(self), "units": [r.to_dict() for r in self.results]}


def _unit_summary(r: P2UnitResult) -> str:
    """One unit's verdict in a few words: why it failed, its inconsistent held-out models."""
    text = {True: "PASS", False: "FAIL", None: "NO DECISION"}[r.passed]
    if r.reasons:
        text += ": " + "; ".join(r.reasons)
    if r.held_out_inconsistent:
        text += (f" ({len(r.held_out_inconsistent)} of {len(r.held_out)} temperature models NOT "
                 "consistent at the held-out points, not part of the rule)")
    return text


def held_out_units(batch: P2BatchResult) -> tuple[str, ...]:
    """Return the units with a temperature model NOT consistent at the held-out points."""
    return tuple(r.unit for r in batch.results if r.held_out_inconsistent)


def summary_rows(batch: P2BatchResult) -> list[dict[str, Any]]:
    """One row per unit: pass/fail, the compensated errors, the worst parameters, the error.

    ``held_out_inconsistent`` names the parameters whose temperature model is NOT consistent at
    the held-out points (not part of P2's rule; docs/p2.md, "The decision").

    The worst parameters are those whose value at T0 lies furthest from nominal in units of the
    lot's spread (|x − median| / (1.4826·MAD)), the three largest; empty for fewer than three
    calibrated units.
    """
    done = [r for r in batch.results if r.result is not None]
    spread: dict[str, tuple[float, float]] = {}
    if len(done) >= 3:
        for name in PARAM_NAMES:
            x = np.array([r.result.value(name) for r in done if r.result is not None])
            med = float(np.median(x))
            mad = float(np.median(np.abs(x - med))) * 1.4826
            spread[name] = (med, mad)
    rows = []
    for r in batch.results:
        worst: list[str] = []
        if r.result is not None and spread:
            scores = {n: abs(r.result.value(n) - m) / s for n, (m, s) in spread.items() if s > 0}
            worst = [f"{n} ({v:.1f} MAD)" for n, v in sorted(scores.items(),
                                                              key=lambda kv: -kv[1])[:3]]
        rows.append({"unit": r.unit, "passed": r.passed,
                     "accel_error_mps2": r.compensated_error.get("accel_mps2"),
                     "gyro_error_rps": r.compensated_error.get("gyro_rps"),
                     "worst_parameters": worst, "error": r.error,
                     "held_out_inconsistent": list(r.held_out_inconsistent)})
    return rows


def _plan_limits(rec: Recording) -> tuple[float | None, float | None]:
    """Return the held-out accuracy of the recording's plan (accelerometer [g], gyro [°/s])."""
    from imucalib.io.context import RecordingContext

    spec = RecordingContext.of(rec.metadata).imu_spec
    return spec.get("accel_accuracy_g"), spec.get("gyro_accuracy_dps")

def _soak_failures(steps: Sequence[StepRecord], unit: str) -> dict[int, str]:
    """Return the temperature points whose soak did not complete (never reached)."""
    out: dict[int, str] = {}
    for step in steps:
        if step.role != P2_SOAK or not step.concerns(unit) or step.status == "done":
            continue
        point = step.tag_value("point")
        target = step.commanded.get("temperature_degc") if isinstance(step.commanded,
                                                                      dict) else None
        key = int(point) if point is not None and point.isdigit() else -1
        out.setdefault(key, (
            f"unit {unit}, temperature point {key}"
            + (f" ({float(target):+g} °C)" if isinstance(target, int | float) else "")
            + f", step {step.index} ({step.label}): the temperature was never reached (soak "
            f"{step.status}{': ' + step.note if step.note else ''})"))
    return out


def analyze_unit_file(path: str | os.PathLike[str], unit: str, options: P2Options | None = None,
                      recording_sha256: str = "") -> P2UnitResult:
    """Analyse one unit of a P2 recording; a unit that cannot be calibrated returns its error.

    Pure in the file: the same (file, unit, options) give the same result wherever it runs.
    """
    return analyze_units_file(path, [unit], options, recording_sha256)[0]


def analyze_units_file(path: str | os.PathLike[str], units: Sequence[str],
                       options: P2Options | None = None, recording_sha256: str = ""
                       ) -> list[P2UnitResult]:
    """Analyse some units of a P2 recording, one after the other, opening the file once.

    Each unit as :func:`analyze_unit_file` would (the same results); the file is opened and
    checked, and its steps table read, once for all of them.
    """
    opt = options or P2Options()
    try:
        rec_cm = open_recording(path)
    except CalibrationError as exc:
        return [failed_unit(unit, exc) for unit in units]
    out = []
    with rec_cm as rec:
        if opt.accel_accuracy_g is None or opt.gyro_accuracy_dps is None:
            acc, gyr = _plan_limits(rec)
            opt = dataclasses.replace(
                opt, accel_accuracy_g=opt.accel_accuracy_g if opt.accel_accuracy_g
                is not None else acc,
                gyro_accuracy_dps=opt.gyro_accuracy_dps if opt.gyro_accuracy_dps
                is not None else gyr)
        steps = rec.steps
        table_windows: dict[int, StreamData] = {}  # the turns' table rows, read once for all
        for unit in units:
            try:
                soaks = _soak_failures(steps, unit)
                if soaks:
                    raise MissingSegmentError(soaks[min(soaks)])
                obs = extract_unit_observations(rec, unit, processing=opt.processing,
                                                steps=steps, table_windows=table_windows)
                out.append(analyze_unit(obs, opt, source=str(path),
                                        recording_sha256=recording_sha256))
            except CalibrationError as exc:
                out.append(failed_unit(unit, exc))
            except (np.linalg.LinAlgError, ValueError) as exc:  # a defect no check named
                out.append(failed_unit(unit, InvalidInputError(f"unit {unit}: {exc}")))
            _return_freed_memory()
    return out


def _return_freed_memory() -> None:
    """Hand the heap a unit freed back to the system (glibc only; elsewhere nothing).

    A unit's windows are many mid-sized arrays; glibc keeps what they freed in its heap, so
    the resident size grew by about 10 MiB a unit without this (bench/bench_p2.py) — memory
    that is free but looks taken. ``malloc_trim(0)`` returns it.
    """
    global _TRIM  # looked up once per process
    if _TRIM is None:
        try:
            _TRIM = ctypes.CDLL("libc.so.6").malloc_trim
        except (OSError, AttributeError):
            _TRIM = False
    if _TRIM:
        _TRIM(0)


_TRIM: Any = None


def _analyze_jobs(options: P2Options, jobs: list[tuple[str, list[str], str]]
                  ) -> list[list[P2UnitResult]]:
    """Run jobs of :func:`analyze_p2` (path, units, SHA-256) one after the other (a worker's)."""
    return [analyze_units_file(p, units, options, sha) for p, units, sha in jobs]


def _chunks(items: list[int], n: int) -> list[list[int]]:
    """Split `items` into at most `n` runs of consecutive items of near-equal length."""
    n = max(1, min(n, len(items)))
    size, extra = divmod(len(items), n)
    out, start = [], 0
    for k in range(n):
        stop = start + size + (1 if k < extra else 0)
        out.append(items[start:stop])
        start = stop
    return [c for c in out if c]


def _tasks(paths: Sequence[Path], units: Sequence[str] | None) -> list[tuple[str, str, str]]:
    tasks = []
    for path in paths:
        with open_recording(path) as rec:
            have = p2_units(rec)
        chosen = list(units) if units else have
        missing = [x for x in chosen if x not in have]
        if missing:
            raise InvalidInputError(f"{path} has no IMU stream(s) {missing}; it has {have}")
        sha = file_sha256(path)
        tasks += [(str(path), x, sha) for x in chosen]
    return tasks


def analyze_p2(paths: str | os.PathLike[str] | Sequence[str | os.PathLike[str]], *,
               units: Sequence[str] | None = None, options: P2Options | None = None,
               workers: int = 1, scheduler: Any = None,
               progress: Callable[[float], None] | None = None) -> P2BatchResult:
    """Calibrate every unit of one or many P2 recordings (module docstring).

    Parameters
    ----------
    paths : path or sequence of paths
        The recordings (a lot: several arrays).
    units : sequence of str, optional
        Only these units (each recording must have them); default every IMU stream.
    options : P2Options, optional
    workers : int
        Local processes (1: in this process).
    scheduler : str or dask.distributed.Client, optional
        A Dask scheduler address or client; then `workers` is ignored.
    progress : callable, optional
        Called with the fraction of units done.

    Raises
    ------
    InvalidInputError
        No recording, a unit not in a recording, `workers` < 1.
    ConfigurationError
        A scheduler given without the ``dask`` extra installed.
    """
    items = [paths] if isinstance(paths, str | os.PathLike) else list(paths)
    files = [Path(p) for p in items]
    if not files:
        raise InvalidInputError("give at least one recording")
    if workers < 1:
        raise InvalidInputError(f"--workers must be ≥ 1; got {workers}")
    opt = options or P2Options()
    # _tasks opens each file to list its units; opening it again here skips the checks
    with reopening():
        tasks = _tasks(files, units)
        results: dict[int, P2UnitResult] = {}
        # a job: a run of consecutive units of one recording (one open of the file per run)
        by_file: dict[tuple[str, str], list[int]] = {}
        for i, (p, _, sha) in enumerate(tasks):
            by_file.setdefault((p, sha), []).append(i)
        parallel = scheduler is not None or workers > 1
        # local: one run of units per process and recording (a run's fixed cost, opening the file
        # and reading its steps and table rows, about 60 ms, paid once per process)
        n_runs = (workers if scheduler is None else 8) if parallel else 1
        jobs = [(p, sha, run) for (p, sha), idx in by_file.items() for run in _chunks(idx, n_runs)]

        def done(run: list[int], res: list[P2UnitResult]) -> None:
            for i, r in zip(run, res, strict=True):
                results[i] = r
            if progress is not None:
                progress(len(results) / len(tasks))

        def names(run: list[int]) -> list[str]:
            return [tasks[i][1] for i in run]

        if scheduler is not None:
            try:
                from dask.distributed import Client
                from dask.distributed import as_completed as dask_completed
            except ImportError as exc:
                raise ConfigurationError("--scheduler needs the dask extra: pip install "
                                         "'imucalib[dask]'") from exc
            client = scheduler if isinstance(scheduler, Client) else Client(str(scheduler))
            try:
                futures = {client.submit(analyze_units_file, p, names(run), opt, sha,
                                         pure=False): run for p, sha, run in jobs}
                for fut in dask_completed(list(futures)):
                    done(futures[fut], fut.result())
            finally:
                if client is not scheduler:
                    client.close()
        elif not parallel or len(tasks) == 1:
            for p, sha, run in jobs:
                done(run, analyze_units_file(p, names(run), opt, sha))
        else:  # this process and workers − 1 others share the jobs (largest first)
            shared = [(p, names(run), sha) for p, sha, run in jobs]
            n_done = [0]

            def tick(n: int) -> None:
                n_done[0] += n
                if progress is not None:
                    progress(n_done[0] / len(jobs))

            per_job = share_with_workers(shared, [len(run) for _, _, run in jobs], workers,
                                         there=functools.partial(_analyze_jobs, opt),
                                         done=tick, n_jobs=len(jobs))
            for (_, _, run), res in zip(jobs, per_job, strict=True):
                for i, r in zip(run, res, strict=True):
                    results[i] = r
        return P2BatchResult(recordings=tuple(str(f) for f in files),
                             results=tuple(results[i] for i in range(len(tasks))))


def batch_json(batch: P2BatchResult) -> str:
    """Return the batch's JSON (summary and every unit)."""
    return json.dumps(batch.to_dict(), indent=1, allow_nan=True)
