"""A parameter of one unit across its calibrations, with 2σ bars (``imucalib records drift``).

matplotlib is imported inside the function (object-oriented API with the Agg canvas: no pyplot,
no global backend change).

Contents
--------
:func:`save_drift_figure`
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from datetime import datetime
from pathlib import Path

__all__ = ["save_drift_figure"]


def save_drift_figure(path: str | os.PathLike[str], when: Sequence[datetime],
                      values: Sequence[float], stds: Sequence[float], *, title: str,
                      unit: str) -> Path:
    """Draw each calibration's value with ±2σ bars against its date; return the PNG's path.

    Raises
    ------
    OSError
        The file cannot be written.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7.0, 3.5), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    from matplotlib.dates import date2num

    ax.errorbar(date2num(list(when)), list(values), yerr=[2.0 * s for s in stds], fmt="o-",
                capsize=3)
    ax.set_title(f"{title} ({len(values)} calibrations, bars ±2σ)")
    ax.set_ylabel(f"value [{unit}]" if unit else "value")
    ax.xaxis_date()
    ax.set_xlabel("calibrated (UTC)")
    fig.autofmt_xdate()
    out = Path(path)
    fig.savefig(out, dpi=110)
    return out
