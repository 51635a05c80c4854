"""``imucalib combine RESULT…`` and ``imucalib schema result``: result files as a whole.

``combine`` fuses the triad parameters several tests estimated (the tumble's accelerometer
parameters, the rate transfer's gyro biases and scale factors, the installation test's gyro
misalignments, the g-sensitivity test's G …) into one triad model of the unit by generalised
least squares (:func:`~imucalib.estimation.combine.combine_triad_parameters`, docs/procedures.md,
"Combining tests"), and writes it as a result file that ``apply``, ``export``, ``report`` and
the records take. ``schema result`` prints the JSON Schema of the result file (format version
4, :func:`~imucalib.models.result_document.result_schema`).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer

from imucalib.cli._app import app, console, fail
from imucalib.errors import CalibrationError, InvalidInputError

__all__ = ["combine", "schema_app"]

schema_app = typer.Typer(help="JSON Schemas of imucalib's files.", no_args_is_help=True)
app.add_typer(schema_app, name="schema")


@app.command()
def combine(
    results: Annotated[list[Path], typer.Argument(
        metavar="RESULT...", help="Result files (.result.json) of tests of one unit, each "
                                  "giving part of its triad model.")],
    out: Annotated[Path, typer.Option("--out", "-o", help="The combined result file to "
                                                          "write (.result.json).")],
    unit: Annotated[str | None, typer.Option(
        help="The unit's serial, when the results name it differently.")] = None,
) -> None:
    """Fuse several tests' triad parameters into one triad model (a result file).

    Each triad that appears must be complete (its 3 biases and 9 scale/misalignment terms;
    G, K2 and K3 optional, all or none): a parameter two tests give gets their weighted mean, and
    their χ² says whether they agree (a misfit scales the σ by the Birge ratio).
    """
    from imucalib.estimation.combine import TriadPart, combine_triad_parameters
    from imucalib.models.decision import no_decision
    from imucalib.models.result import Provenance
    from imucalib.models.result_document import (
        load_result,
        result_document,
        stored_from_calibration,
    )

    try:
        loaded = [load_result(p) for p in results]
        serials = sorted({r.unit for r in loaded})
        if unit is None and len(serials) > 1:
            raise InvalidInputError(f"the results are of different units {serials}; give "
                                    "--unit SERIAL when they are one unit under several names")
        parts = []
        for path, r in zip(results, loaded, strict=True):
            names, values, cov = r.triad_parameters()
            if not names:
                raise InvalidInputError(f"{path} ({r.procedure}) estimates no triad parameter; "
                                        "combine takes tests that do")
            parts.append(TriadPart(r.procedure, tuple(names), values, cov))
        sources = [str(p) for p in results]
        cal = combine_triad_parameters(
            parts, sensor_id=unit or serials[0],
            provenance=Provenance(details={"parts": [r.procedure for r in loaded],
                                           "files": sources}))
        stored = stored_from_calibration(
            cal, decision=no_decision("a combination of tests makes no conformity decision; "
                                      "each test's own result holds its decision"),
            details={"parts": [{"procedure": r.procedure, "file": s, "verdict":
                                r.decision.verdict} for r, s in zip(loaded, sources,
                                                                     strict=True)]})
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(result_document(stored), indent=1, allow_nan=False) + "\n",
                       encoding="utf-8")
    except CalibrationError as exc:
        raise fail(exc) from exc
    except OSError as exc:
        raise fail(InvalidInputError(f"cannot write {out}: {exc.strerror or exc}")) from exc
    for q in cal.fit_quality[:1]:
        console.print(q.summary(), style="yellow" if q.misfit else None, highlight=False)
    console.print(f"combined {len(parts)} result(s) ({', '.join(r.procedure for r in loaded)}) "
                  f"into {len(cal.param_names)} triad parameters of {cal.sensor_id}; wrote {out}",
                  highlight=False, soft_wrap=True)


@schema_app.command("result")
def schema_result(
    out: Annotated[Path | None, typer.Option("--out", "-o", help="Write it here instead of "
                                                                 "printing it.")] = None,
) -> None:
    """Print the JSON Schema (draft 2020-12) of the result file, format version 4."""
    from imucalib.models.result_document import result_schema

    text = json.dumps(result_schema(), indent=1)
    if out is None:
        typer.echo(text)
        return
    try:
        out.write_text(text + "\n", encoding="utf-8")
    except OSError as exc:
        raise fail(InvalidInputError(f"cannot write {out}: {exc.strerror or exc}")) from exc
    console.print(f"wrote {out}", highlight=False)
