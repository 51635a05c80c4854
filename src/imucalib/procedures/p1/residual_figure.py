"""P1's residual figure (output ``residuals-png``): each window's residual mean, ±2σ bars.

One panel per fitted triad: the accelerometer's residuals per static position [µg], the gyro's
per window (positions and rate points) [°/h], each axis in its own colour, with error bars of
twice the window mean's standard error (the noise the fit was weighted with), and the fit's
χ²/ν in the title (a misfit says so; docs/processing-estimation.md, "Goodness of fit"). A
misfit shows as residuals far outside their bars, and their pattern says which positions or
rates the model does not describe.

matplotlib is imported inside the function (object-oriented API with the Agg canvas: no pyplot,
no global backend change).

Contents
--------
:func:`save_residual_figure`
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from imucalib import units

__all__ = ["save_residual_figure"]

_TRIADS = (("accel", "µg", units.UG), ("gyro", "°/h", units.DEG_PER_H))


def _panel(ax: Any, labels: Sequence[str], mean: np.ndarray, se: np.ndarray, unit: str,
           title: str) -> None:
    x = np.arange(len(labels))
    for j, (axis, colour) in enumerate(zip("xyz", ("C0", "C1", "C2"), strict=True)):
        ax.errorbar(x + (j - 1) * 0.2, mean[:, j], yerr=2.0 * se[:, j], fmt="o", ms=3,
                    color=colour, capsize=2, label=f"{axis} axis")
    ax.axhline(0.0, color="0.5", lw=0.8)
    ax.set_xticks(x)
    ax.set_xticklabels(labels, rotation=90, fontsize=6)
    ax.set_ylabel(f"residual [{unit}]")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7, loc="best")
    ax.grid(True, axis="y", alpha=0.3)


def save_residual_figure(analysis: Any, path: str | os.PathLike[str]) -> Path:
    """Save the residual figure of a calibration analysis (module docstring) as PNG.

    Parameters
    ----------
    analysis : P1Analysis or compatible
        Holds ``result`` (a :class:`~imucalib.models.result.CalibrationResult` whose
        ``residuals`` are keyed ``"<triad>: <window label>"``) and, when it has them,
        ``observations`` (the windows, for the standard-error bars; none without).
    path : str or Path
        The file to write.

    Returns
    -------
    Path
    """
    from imucalib.report.figure_cache import png_once

    out = Path(path)
    out.write_bytes(png_once(analysis, "residuals", lambda p: _draw(analysis, p)))
    return out


def _draw(analysis: Any, out: Path) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    result = analysis.result
    observations = getattr(analysis, "observations", None)
    windows = {w.label: w for w in getattr(observations, "windows", ())}
    quality = {q.group: q for q in result.fit_quality}
    fig = Figure(figsize=(11, 7.5), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(2, 1)
    for ax, (triad, unit, scale) in zip(axes, _TRIADS, strict=True):
        keys = [k for k in result.residuals if k.startswith(f"{triad}: ")]
        labels = [k[len(triad) + 2:] for k in keys]
        if not keys:
            ax.set_axis_off()
            continue
        mean = np.array([result.residuals[k].mean for k in keys]) / scale
        se = np.array([(windows[lab].accel_se_mps2 if triad == "accel"
                        else windows[lab].gyro_se_rps) if lab in windows else np.zeros(3)
                       for lab in labels]) / scale
        q = quality.get(triad)
        title = f"{result.sensor_id} {triad} residuals (bars: ±2 standard errors)"
        if q is not None and q.dof > 0:
            title += f"; χ²/ν = {q.reduced_chi2:.3g}" + (" — MODEL MISFIT" if q.misfit else "")
        _panel(ax, labels, mean, se, unit, title)
    fig.savefig(out, dpi=110)
