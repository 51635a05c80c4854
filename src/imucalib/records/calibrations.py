"""Record a procedure's result, and the run behind it, in the records database.

What ``imucalib calibrate`` and the demo call after a calibration (docs/records.md).

Contents
--------
:func:`record_calibration`
"""

from __future__ import annotations

from pathlib import Path

from imucalib.models.procedure_result import ProcedureResult

__all__ = ["record_calibration"]


def record_calibration(result: ProcedureResult, recording: Path | None, *, db: str | None,
                       operator: str = "") -> str:
    """Record a procedure result (and the run behind it) and return one line saying where.

    Each unit's result with reported parameters is recorded as its result document (the result
    contract; a batch, P2, records each unit that was calibrated); a result without parameters
    is only noted.
    """
    units = list(result.members) or [result]
    recordable = [u for u in units if not u.error and u.parameter_rows()]
    if not recordable:
        return f"not recorded: a {result.procedure} result has no calibrated parameters"
    from imucalib.records.api import open_records

    records = open_records(db)
    try:
        plan_name, plan_hash = "", ""
        if recording is not None and recording.suffix.lower() in (".h5", ".hdf5"):
            from imucalib.io.context import RecordingContext
            from imucalib.io.opening import open_recording

            with open_recording(recording) as rec:
                context = RecordingContext.of(rec.metadata)
            plan_name, plan_hash = context.plan_name, context.plan_hash
        run_id = records.record_run(plan_name=plan_name, plan_hash=plan_hash,
                                    procedure=str(result.procedure), recording=recording,
                                    operator=operator)
        ids = [records.record_result(run_id, unit, passed=unit.passed, serial=str(unit.unit))
               for unit in recordable]
        return (f"recorded run {run_id}, result(s) {', '.join(map(str, ids))} in "
                f"{records.url}")
    finally:
        records.close()
