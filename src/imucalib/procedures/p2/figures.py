"""P2's figures: each parameter against temperature per unit, and the spread across a lot.

:func:`save_temperature_figure` draws, for one unit, one panel per parameter (gyro and
accelerometer bias, scale and misalignment terms): the per-point least-squares estimates with
2σ bars (calibration points filled, held-out points open; heating and cooling legs in their
own colours), the fitted temperature model (docs/p2.md, "Temperature models") and its 2σ
prediction band, with the model's order and χ²/ν in the panel title. Biases are in °/h and mg,
scale and misalignment terms in ppm, the gyro g-sensitivity in (°/h)/g, the accelerometer K2
in µg/g².

:func:`save_lot_figure` draws, for a batch, each parameter's value at T0 across the units (one
point per unit with its 2σ bar), so an outlying unit stands out.

matplotlib is imported inside the functions (the Agg canvas, no pyplot).

Contents
--------
:func:`save_temperature_figure`, :func:`save_lot_figure`
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from imucalib import units
from imucalib.estimation.temperature_model import predict_temperature_model
from imucalib.procedures.p2.reduction import PARAM_NAMES

__all__ = ["save_lot_figure", "save_temperature_figure"]

_LEG_COLOURS = {"heating": "C3", "cooling": "C0"}


def _display(name: str) -> tuple[float, str]:
    """Return the factor dividing SI values for display and the display unit."""
    if name.startswith("gyro_bias"):
        return units.DEG_PER_H, "°/h"
    if name.startswith("accel_bias"):
        return 1e-3 * units.G0_MPS2, "mg"
    if name.startswith("gyro_G"):  # rad/s per m/s² → (°/h)/g
        return units.DEG_PER_H / units.G0_MPS2, "(°/h)/g"
    if name.startswith("accel_K2"):  # per m/s² → µg/g²
        return 1e-6 / units.G0_MPS2, "µg/g²"
    return 1e-6, "ppm"


def _figure(n: int, ncols: int, width: float, height: float) -> tuple[Any, list[Any]]:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    nrows = -(-n // ncols)
    # fixed margins: a constrained layout of 36 panels costs seconds per figure
    fig = Figure(figsize=(width, height * nrows))
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrows, ncols, squeeze=False).ravel().tolist()
    fig.subplots_adjust(left=0.04, right=0.99, bottom=0.05, top=0.94, wspace=0.35,
                        hspace=0.55)
    for ax in axes[n:]:
        ax.set_visible(False)
    return fig, axes[:n]


def save_temperature_figure(unit_result: Any, path: str | os.PathLike[str]) -> Path:
    """Save one unit's parameters-versus-temperature figure (module docstring) as PNG.

    Parameters
    ----------
    unit_result : P2UnitResult
        A calibrated unit (``points`` and ``models``).
    path : str or Path
        The file to write.
    """
    from imucalib.report.figure_cache import png_once

    out = Path(path)
    out.write_bytes(png_once(unit_result, "p2-temperature",
                             lambda p: _draw_temperature(unit_result, p)))
    return out


def _draw_temperature(unit_result: Any, out: Path) -> None:
    points = unit_result.points
    fig, axes = _figure(len(PARAM_NAMES), 6, 16.0, 2.2)
    legs = sorted({p.leg for p in points})
    t_lo = min(p.temperature_degc for p in points)
    t_hi = max(p.temperature_degc for p in points)
    grid = np.linspace(t_lo - 5.0, t_hi + 5.0, 121)
    for i, (ax, name) in enumerate(zip(axes, PARAM_NAMES, strict=True)):
        factor, unit = _display(name)
        fit = unit_result.models.get(name)
        for leg in legs:
            colour = _LEG_COLOURS.get(leg, "C2")
            mine = [p for p in points if p.leg == leg]
            for held in (False, True):
                sel = [p for p in mine if p.held_out == held]
                if not sel:
                    continue
                t = np.array([p.temperature_degc for p in sel])
                v = np.array([p.least_squares.values[i] for p in sel]) / factor
                s = np.array([np.sqrt(p.least_squares.covariance_scaled()[i, i])
                              for p in sel]) / factor
                ax.errorbar(t, v, yerr=2 * s, fmt="o", ms=3, capsize=2, color=colour,
                            mfc="none" if held else colour,
                            label=f"{leg}{' held out' if held else ''}")
            if fit is not None:
                leg_arg = None
                if fit.model.leg_coefficient is not None:
                    leg_arg = np.full(grid.size, 1.0 if leg == "heating" else -1.0)
                pred = predict_temperature_model(fit, grid, leg=leg_arg)
                ax.plot(grid, pred.value / factor, color=colour, lw=1)
                ax.fill_between(grid, (pred.value - 2 * pred.std) / factor,
                                (pred.value + 2 * pred.std) / factor, color=colour,
                                alpha=0.15, lw=0)
        title = name.replace("_", " ")
        if fit is not None:
            title += f"  (order {fit.order}, χ²/ν {fit.quality.reduced_chi2:.2g})"
        ax.set_title(title, fontsize=7)
        ax.set_ylabel(unit, fontsize=7)
        ax.tick_params(labelsize=6)
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=6, loc="best")
    fig.suptitle(f"P2 unit {unit_result.unit}: parameters against internal temperature [°C] "
                 "(2σ bars; models with 2σ bands)", fontsize=10)
    fig.savefig(out, dpi=90)


def save_lot_figure(batch: Any, path: str | os.PathLike[str]) -> Path:
    """Save the lot's spread of every parameter at T0 across units (module docstring) as PNG."""
    from imucalib.report.figure_cache import png_once

    out = Path(path)
    out.write_bytes(png_once(batch, "p2-lot", lambda p: _draw_lot(batch, p)))
    return out


def _draw_lot(batch: Any, out: Path) -> None:
    done = [r for r in batch.results if r.result is not None]
    fig, axes = _figure(len(PARAM_NAMES), 6, 16.0, 2.0)
    names = [r.unit for r in done]
    x = np.arange(len(done))
    for ax, name in zip(axes, PARAM_NAMES, strict=True):
        factor, unit = _display(name)
        v = np.array([r.result.value(name) for r in done]) / factor
        s = np.array([r.result.std()[name] for r in done]) / factor
        colours = ["C2" if r.passed else "C3" for r in done]
        for xi, vi, si, ci in zip(x, v, s, colours, strict=True):
            ax.errorbar([xi], [vi], yerr=[2 * si], fmt="o", ms=3, capsize=2, color=ci)
        if v.size:
            ax.axhline(float(np.median(v)), color="0.5", lw=0.8)
        ax.set_title(name.replace("_", " "), fontsize=7)
        ax.set_ylabel(unit, fontsize=7)
        ax.set_xticks(x)
        ax.set_xticklabels(names, rotation=90, fontsize=5)
        ax.tick_params(labelsize=6)
        ax.grid(True, axis="y", alpha=0.3)
    fig.suptitle(f"P2 lot: every parameter at T0 across {len(done)} unit(s) (green pass, red "
                 "fail; 2σ bars; grey: the median)", fontsize=10)
    fig.savefig(out, dpi=90)
