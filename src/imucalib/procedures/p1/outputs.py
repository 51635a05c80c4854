"""The output format P1 writes itself: ``residuals-png`` (:data:`P1_WRITERS`).

``imucalib.exports.outputs.write_outputs`` writes the formats every result has and asks the
result's procedure for its own (:meth:`~imucalib.procedures.common.procedure.Procedure.
output_writers`). P1's: ``….residuals.png``, each window's residual mean per axis with its
±2σ bar and the fit's χ²/ν (:mod:`imucalib.procedures.p1.residual_figure`, docs/p1.md).

Contents
--------
:data:`P1_WRITERS`
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from imucalib.errors import InvalidInputError

__all__ = ["P1_WRITERS"]


def _residuals_png(result: Any, folder: Path, stem: str) -> list[Path]:
    from imucalib.procedures.p1.analysis import P1Analysis
    from imucalib.procedures.p1.residual_figure import save_residual_figure

    if not isinstance(result, P1Analysis):
        raise InvalidInputError("output 'residuals-png' needs P1's analysis (its windows); a "
                                f"{result.procedure} result read back from its file holds "
                                "none: write it from the recording")
    return [save_residual_figure(result, folder / f"{stem}.residuals.png")]


#: P1's own output formats → writer(result, folder, stem).
P1_WRITERS: Mapping[str, Callable[[Any, Path, str], list[Path]]] = {
    "residuals-png": _residuals_png,
}
