"""Record a procedure's result, and the run behind it, in the records database.

What ``imucalib calibrate`` and the demo call after a calibration (docs/records.md).

Contents
--------
:func:`record_calibration`
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

__all__ = ["record_calibration"]


def record_calibration(result: Any, recording: Path | None, *, db: str | None,
                       operator: str = "") -> str:
    """Record a procedure result (and the run behind it) and return one line saying where.

    A result holding a :class:`~imucalib.models.result.CalibrationResult` (``.result``), or
    one with ``parameter_rows()``, is recorded; a batch (P2) records each unit; a noise
    characterisation has no parameters with uncertainties to record and is only noted.
    """
    units = list(getattr(result, "results", None) or [result])
    recordable = [u for u in units if getattr(u, "result", None) is not None
                  or callable(getattr(u, "parameter_rows", None))]
    if not recordable:
        return f"not recorded: a {result.procedure} result has no calibrated parameters"
    from imucalib.records.api import open_records

    records = open_records(db)
    try:
        plan_name, plan_hash = "", ""
        if recording is not None and recording.suffix.lower() in (".h5", ".hdf5"):
            from imucalib.io.context import RecordingContext
            from imucalib.io.reader import open_recording

            with open_recording(recording) as rec:
                context = RecordingContext.of(rec.metadata)
            plan_name, plan_hash = context.plan_name, context.plan_hash
        run_id = records.record_run(plan_name=plan_name, plan_hash=plan_hash,
                                    procedure=str(result.procedure), recording=recording,
                                    operator=operator)
        ids = []
        for unit in recordable:
            cal = getattr(unit, "result", None)
            ids.append(records.record_result(run_id, cal if cal is not None else unit,
                                             passed=getattr(unit, "passed", None),
                                             serial=str(getattr(unit, "unit", "")) or None))
        return (f"recorded run {run_id}, result(s) {', '.join(map(str, ids))} in "
                f"{records.url}")
    finally:
        records.close()


