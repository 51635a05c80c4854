"""The outputs P2 writes itself: the temperature figure of a unit, the summary of a batch.

``imucalib.exports.outputs.write_outputs`` writes the formats every result has and asks the
result's procedure for its own (:meth:`~imucalib.procedures.common.procedure.Procedure.
output_writers`, ``batch_outputs``). P2's (docs/p2.md, docs/exports.md):

- ``temperature-png`` (``….temperature.png``): every parameter of one unit against temperature,
  with its model and 2σ band;
- after every unit's own files, the batch's ``<name>.<array|lot>.p2.summary.json`` and
  ``.summary.csv`` (one row per unit: pass/fail, the compensated errors, the parameters
  furthest from the lot, the error) and, for two or more calibrated units, ``.lot.png`` (every
  parameter's spread across the units).

Contents
--------
:data:`P2_WRITERS`, :func:`write_batch_summary`
"""

from __future__ import annotations

import csv
import json
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from imucalib.errors import InvalidInputError

__all__ = ["P2_WRITERS", "write_batch_summary"]


def _temperature_png(result: Any, folder: Path, stem: str) -> list[Path]:
    from imucalib.procedures.p2.figures import save_temperature_figure
    from imucalib.procedures.p2.result import P2UnitResult

    if not isinstance(result, P2UnitResult) or not result.models:
        raise InvalidInputError("output 'temperature-png' needs a P2 unit's temperature "
                                f"models; a {result.procedure} result "
                                + ("read back from its file " if not isinstance(
                                    result, P2UnitResult) else "") + "holds none")
    return [save_temperature_figure(result, folder / f"{stem}.temperature.png")]


#: P2's own output formats → writer(result, folder, stem).
P2_WRITERS: Mapping[str, Callable[[Any, Path, str], list[Path]]] = {
    "temperature-png": _temperature_png,
}


def write_batch_summary(batch: Any, folder: Path, stem: str) -> list[Path]:
    """Write a batch's summary JSON and CSV and, for two or more calibrated units, the lot figure.

    Parameters
    ----------
    batch : P2BatchResult
    folder : Path
    stem : str
        ``<name>.<array|lot>.p2``.

    Returns
    -------
    list of Path
    """
    from imucalib.procedures.p2.batch import summary_rows

    rows = summary_rows(batch)
    summary = folder / f"{stem}.summary.json"
    summary.write_text(json.dumps({"procedure": batch.procedure, "passed": batch.passed,
                                   "recordings": list(batch.recordings), "units": rows},
                                  indent=1, allow_nan=True) + "\n", encoding="utf-8")
    table = folder / f"{stem}.summary.csv"
    with open(table, "w", encoding="utf-8", newline="") as fh:
        writer = csv.writer(fh, lineterminator="\n")
        writer.writerow(["unit", "passed", "accel_error_mps2", "gyro_error_rps",
                         "worst_parameters", "error", "held_out_inconsistent"])
        for row in rows:
            writer.writerow([row["unit"], row["passed"], row["accel_error_mps2"],
                             row["gyro_error_rps"], "; ".join(row["worst_parameters"]),
                             row["error"], "; ".join(row["held_out_inconsistent"])])
    written = [summary, table]
    if sum(r.result is not None for r in batch.results) >= 2:
        from imucalib.procedures.p2.figures import save_lot_figure

        written.append(save_lot_figure(batch, folder / f"{stem}.lot.png"))
    return written
