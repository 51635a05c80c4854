"""The noise model behind a calibration's weights, as a table and as Allan deviation curves.

P1 fits a noise model to its long static records (``procedures/common/noise.py``: white
density N, bias instability B and random walk K per axis, from each record's Allan variance
σ²(τ) ≈ N²/τ + C_B + K²τ/3, pooled over the records about as long as the longest) and takes
each window mean's standard error from it, the model's Allan deviation at τ = the window's
length (docs/p1.md). The report shows that model: the
terms per axis in the usual datasheet units, and σ(τ) of each axis
(:func:`~imucalib.models.noise.compute_theoretical_adev`, docs/equations.md §8) with the
windows' lengths marked, where the standard errors were read.

matplotlib is imported inside the function (the Agg canvas, no pyplot).

Contents
--------
:func:`noise_model_rows`, :func:`save_noise_model_figure`
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from imucalib import units
from imucalib.models.noise import NoiseModel, compute_theoretical_adev

__all__ = ["noise_model_rows", "save_noise_model_figure"]

#: triad → (N unit, its SI value; B unit, SI value; K unit, SI value; σ(τ) unit, SI value)
_UNITS = {
    "gyro": (("°/√h", units.DEG_PER_RTH), ("°/h", units.DEG_PER_H),
             ("°/h/√h", units.DEG_PER_H_RTH), ("°/h", units.DEG_PER_H)),
    "accel": (("µg/√Hz", units.UG_PER_RTHZ), ("µg", units.UG), ("µg/√s", units.UG),
              ("µg", units.UG)),
}


def noise_model_rows(noise: Mapping[str, NoiseModel]) -> tuple[tuple[str, ...], ...]:
    """Rows (axis, N, B, K) of the noise model, in the datasheet units of `_UNITS`."""
    rows = []
    for triad, model in noise.items():
        (n_unit, n_si), (b_unit, b_si), (k_unit, k_si), _ = _UNITS[triad]
        for i, axis in enumerate("xyz"):
            rows.append((f"{triad} {axis}",
                         f"{model.white_density[i] / n_si:.3g} {n_unit}",
                         f"{model.bias_instability[i] / b_si:.3g} {b_unit}",
                         f"{model.random_walk[i] / k_si:.3g} {k_unit}"))
    return tuple(rows)


def save_noise_model_figure(noise: Mapping[str, NoiseModel], window_s: Sequence[float],
                            path: str | os.PathLike[str], *, tau_min_s: float = 0.01,
                            tau_max_s: float = 1e4, title: str = "") -> Path:
    """Save σ(τ) of each axis of the noise model, the windows' lengths marked, as PNG.

    Parameters
    ----------
    noise : mapping of str to NoiseModel
        ``"gyro"`` and/or ``"accel"``.
    window_s : sequence of float
        The lengths of the windows whose standard errors the model gave. [s]
    path : str or Path
    tau_min_s, tau_max_s : float
        The τ axis. [s]
    title : str
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    tau = np.logspace(math.log10(tau_min_s), math.log10(tau_max_s), 200)
    fig = Figure(figsize=(10, 3.6), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, len(noise), squeeze=False)[0]
    lengths = sorted({round(float(w), 3) for w in window_s if w > 0})
    for ax, (triad, model) in zip(axes, noise.items(), strict=True):
        unit, scale = _UNITS[triad][3]
        adev = compute_theoretical_adev(model, tau)
        for i, axis in enumerate("xyz"):
            ax.loglog(tau, adev[:, i] / scale, label=f"{axis} axis")
        for w in lengths:
            ax.axvline(w, color="0.35", lw=0.9, ls=":")
        ax.set_xlabel("τ [s]")
        ax.set_ylabel(f"Allan deviation [{unit}]")
        ax.set_title(f"{triad}: noise model (dotted: window lengths)", fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    if title:
        fig.suptitle(title, fontsize=10)
    out = Path(path)
    fig.savefig(out, dpi=100)
    return out
