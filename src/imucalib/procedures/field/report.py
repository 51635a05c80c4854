"""The field calibration's part of the report: the generic sections with its own traceability.

The ``report_content`` hook of :class:`~imucalib.procedures.field.procedure.FieldProcedure`: the
generic content of :mod:`imucalib.report.content_generic` (every parameter with U = 2u, each
fit's χ²/ν, the notes), whose traceability statement is the field calibration's: by hand, with
no rotation table, its references are gravity, whole turns and the Earth rate (docs/field.md).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from imucalib.report.content_generic import content as generic_content
from imucalib.report.document import ReportContent

__all__ = ["TRACEABILITY", "content"]

#: The traceability statement of a field calibration (section 2 of its report).
TRACEABILITY = ("Traceability: a field calibration by hand uses no rotation table. Its references "
                "are local gravity (normal gravity at the stated latitude and height with a Type "
                "B for the local anomaly, or the value given), the known angle of whole turns "
                "flat on a surface, and the Earth rate as a defined constant (15.041 °/h); the "
                "orientations of the poses are not references (docs/field.md).")


def content(result: Any, meta: Mapping[str, Any], *, description: str) -> ReportContent:
    """Return a field calibration's sections 1–5 (module docstring).

    Raises
    ------
    InvalidInputError
        A result without parameter rows.
    """
    return generic_content(result, meta, description=description,
                           documentation="docs/field.md", traceability=TRACEABILITY)
