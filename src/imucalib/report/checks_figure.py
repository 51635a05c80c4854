"""The verification checks of a calibration as a figure: each row's |value| against its limit.

One panel per check that has rows with a limit (P1: the held-out accelerometer and gyro
accuracy, the repeatability of each parameter over the repetitions): a horizontal bar of
|value|/limit per row, the limit at 1, passing rows in one colour and failing ones in another,
so the margin of every verified quantity is read at a glance.

matplotlib is imported inside the function (object-oriented API with the Agg canvas: no pyplot,
no global backend change).

Contents
--------
:func:`save_checks_figure`
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

__all__ = ["save_checks_figure"]


def save_checks_figure(checks: Sequence[Any], path: str | os.PathLike[str]) -> Path | None:
    """Draw every check with limited rows (module docstring); None when there is none.

    `checks` are :class:`~imucalib.analysis.verification.Check` (name, rows of name, value,
    limit, unit, passed).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    panels = [(c.name, [r for r in c.rows if math.isfinite(r.limit) and r.limit > 0
                        and math.isfinite(r.value)]) for c in checks]
    panels = [(name, rows) for name, rows in panels if rows]
    if not panels:
        return None
    heights = [max(1.2, 0.22 * len(rows) + 0.6) for _, rows in panels]
    fig = Figure(figsize=(7.0, sum(heights) + 0.4), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(panels), 1, squeeze=False, height_ratios=heights)[:, 0]
    for ax, (name, rows) in zip(axes, panels, strict=True):
        ratio = [abs(r.value) / r.limit for r in rows]
        colours = ["C2" if r.passed else "C3" for r in rows]
        ax.barh(range(len(rows)), ratio, color=colours)
        ax.axvline(1.0, color="0.3", lw=1.0, ls="--")
        ax.set_yticks(range(len(rows)), [r.name for r in rows], fontsize=6)
        ax.invert_yaxis()
        ax.set_xlim(0.0, max(1.1, 1.05 * max(ratio)))
        ax.set_title(f"{name}: |value| / limit (limit at 1)", fontsize=8)
        ax.tick_params(axis="x", labelsize=7)
    out = Path(path)
    fig.savefig(out, dpi=110)
    return out
