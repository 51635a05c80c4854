"""The figure of ``imucalib segments --figure``: the signals with the detected intervals shaded.

Three panels over time: the gyro (°/s, per axis), the accelerometer (g, per axis) and the
detector's statistic (the accelerometer variance ς_a of
:mod:`imucalib.processing.static_detector` with its threshold, on a log scale; or the
per-sample labels of the table detector). Static intervals are shaded green, rotating ones
orange; each rotation between static intervals is marked with its integrated angle ‖θ‖ [°].

matplotlib is imported inside the function (object-oriented API with the Agg canvas: no pyplot,
no display needed).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from imucalib import units

__all__ = ["save_segments_figure"]

_MAX_POINTS = 20000


def save_segments_figure(path: str | os.PathLike[str], time_s: Any, gyro_rps: Any,
                         accel_mps2: Any | None, static: Sequence[tuple[float, float]],
                         rotating: Sequence[tuple[float, float]] = (),
                         rotation_angles_deg: Sequence[float] | None = None,
                         statistic: Any | None = None, threshold: float | None = None,
                         title: str = "") -> Path:
    """Save the segmentation figure (module docstring) as PNG.

    Parameters
    ----------
    path : str or Path
        The file to write.
    time_s : array_like, shape (n,)
        Sample times. [s]
    gyro_rps : array_like, shape (n, 3)
        Gyro output. [rad/s]
    accel_mps2 : array_like, shape (n, 3), optional
        Accelerometer output. [m/s²]
    static, rotating : sequence of (start, end)
        The intervals to shade. [s]
    rotation_angles_deg : sequence of float, optional
        ‖θ‖ of each `rotating` interval, written on it. [°]
    statistic : array_like, shape (n,), optional
        The detector's statistic (ς_a), drawn with `threshold` on a log scale.
    threshold : float, optional
        The static threshold on `statistic`.
    title : str
        The figure's title.

    Returns
    -------
    Path
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    t = np.asarray(time_s, dtype=np.float64)
    step = max(1, t.size // _MAX_POINTS)  # a long log is decimated for drawing only
    sel = slice(None, None, step)
    panels = 2 + (accel_mps2 is not None) - (statistic is None)
    fig = Figure(figsize=(11, 2.6 * panels + 0.6), layout="constrained")
    FigureCanvasAgg(fig)
    axes = list(np.atleast_1d(fig.subplots(panels, 1, sharex=True)))
    gyro = np.asarray(gyro_rps)[sel] / units.DEG_PER_S
    axes[0].plot(t[sel], gyro, lw=0.7)
    axes[0].set_ylabel("gyro [°/s]")
    axes[0].legend(["x", "y", "z"], loc="upper right", fontsize="small")
    k = 1
    if accel_mps2 is not None:
        axes[k].plot(t[sel], np.asarray(accel_mps2)[sel] / units.G0_MPS2, lw=0.7)
        axes[k].set_ylabel("accel [g]")
        k += 1
    if statistic is not None:
        axes[k].semilogy(t[sel], np.maximum(np.asarray(statistic)[sel], 1e-30), lw=0.7,
                         color="k", label="accel variance ς_a")
        if threshold is not None:
            axes[k].axhline(threshold, color="r", ls="--", lw=0.8, label="static threshold")
        axes[k].set_ylabel("ς_a [(m/s²)²]")
        axes[k].legend(loc="upper right", fontsize="small")
    for ax in axes:
        for a, b in static:
            ax.axvspan(a, b, color="tab:green", alpha=0.18, lw=0)
        for a, b in rotating:
            ax.axvspan(a, b, color="tab:orange", alpha=0.15, lw=0)
    for i, (a, b) in enumerate(rotating):
        if rotation_angles_deg is not None:
            axes[0].annotate(f"{rotation_angles_deg[i]:.1f}°", xy=(0.5 * (a + b), 1.0),
                             xycoords=("data", "axes fraction"), ha="center", va="bottom",
                             fontsize="small", color="tab:orange")
    axes[-1].set_xlabel("time [s]")
    fig.suptitle(title or "segments (green: static, orange: rotating)")
    out = Path(path)
    fig.savefig(out, dpi=100)
    return out
