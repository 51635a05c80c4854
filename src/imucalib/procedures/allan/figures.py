"""Allan-deviation figures for the report: one log-log figure per sensor triad.

Contents
--------
:func:`plot_allan_triad`
    Three panels (x, y, z) of one record: the measured overlapping ADEV with its confidence band,
    the fitted total, each fitted term's line (its asymptote, labelled with its value) and the
    Allan minimum. Returns a matplotlib ``Figure``; saves PNG/PDF/SVG when given a path.
:func:`save_allan_figures`
    Both triads of every record of a
    :class:`~imucalib.procedures.allan.analysis.NoiseCharacterization`.

matplotlib is imported inside the functions (object-oriented API with the Agg canvas: no
pyplot, no global backend change), never when imucalib is imported. Deviations are shown in °/h
(gyro) and µg (accelerometer) against τ in seconds.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from imucalib import units
from imucalib.analysis.noise_fit import NoiseFit, NoiseTerm
from imucalib.errors import InvalidInputError
from imucalib.report.noise_table import TABLE_ROWS
from imucalib.report.numbers import format_pm

if TYPE_CHECKING:
    from imucalib.procedures.allan.analysis import NoiseCharacterization, SegmentNoise

__all__ = ["plot_allan_triad", "save_allan_figures"]

_SCALE = {"gyro": (units.DEG_PER_H, "°/h"), "accel": (units.UG, "µg")}
_SYMBOL = {"quantization": "Q", "white": "N", "bias_instability": "B", "random_walk": "K",
           "rate_ramp": "R", "markov_sigma": "σ_M"}
_COLOURS = {"quantization": "tab:purple", "white": "tab:blue", "bias_instability": "tab:green",
            "random_walk": "tab:orange", "rate_ramp": "tab:red", "markov_sigma": "tab:brown"}


def _term_text(fit: NoiseFit, term: NoiseTerm) -> str:
    rows = [r for r in TABLE_ROWS[fit.sensor] if r[1] == term.name and r[4] == "fit"]
    shown = term.display[0]
    if rows:
        _, _, unit, note, _ = rows[0]
        shown = next((u for u in term.display if u.unit == unit and u.note.startswith(note)),
                     shown)
    value = f"{shown.value:.3g}"
    if math.isfinite(shown.std) and term.detected:
        value = format_pm(shown.value, shown.std)  # GUM 7.2.6, docs/reporting.md
    return f"{_SYMBOL.get(term.name, term.name)} = {value} {shown.unit}"


def _panel(ax: Any, channel_name: str, fit: NoiseFit, oadev: Any, scale: float,
           unit: str) -> None:
    tau = oadev.taus_s
    ax.fill_between(tau, oadev.ci_low / scale, oadev.ci_high / scale, color="0.8",
                    label=f"{oadev.confidence:.0%} interval (EDF)")
    ax.loglog(tau, oadev.deviation / scale, "o", ms=3.5, color="k", label="OADEV")
    grid = np.geomspace(tau[0], tau[-1], 200)
    model = fit.model_avar(grid)
    ax.loglog(grid, np.sqrt(model["total"]) / scale, "-", color="tab:gray", lw=1.5,
              label=f"fit (χ²/dof = {fit.chi2:.0f}/{fit.dof})")
    floor = float(np.min(oadev.ci_low)) / scale / 10
    for term in fit.terms:
        if term.name not in model or not term.detected:
            continue
        line = np.sqrt(model[term.name]) / scale
        keep = line >= floor
        ax.loglog(grid[keep], line[keep], "--", lw=1.0, color=_COLOURS.get(term.name, "k"),
                  label=_term_text(fit, term))
    k = int(np.argmin(oadev.deviation))
    ax.loglog(tau[k], oadev.deviation[k] / scale, "v", ms=8, mfc="none", color="tab:red",
              label=f"σ_min = {oadev.deviation[k] / scale:.3g} {unit} (no 0.664)")
    ax.set_title(channel_name)
    ax.set_xlabel("τ [s]")
    ax.set_ylabel(f"Allan deviation [{unit}]")
    ax.grid(True, which="both", lw=0.3, alpha=0.6)
    ax.set_ylim(bottom=max(floor * 5, float(np.min(oadev.ci_low)) / scale / 3))
    ax.legend(fontsize=6.5, loc="best")


def plot_allan_triad(segment: SegmentNoise, sensor: str, *,
                     path: str | os.PathLike[str] | None = None,
                     title: str | None = None, dpi: int = 150) -> Any:
    """Figure of one triad of one record (module docstring).

    Parameters
    ----------
    segment : SegmentNoise
        A record of :func:`imucalib.procedures.allan.analysis.analyze_allan_recording`.
    sensor : {"gyro", "accel"}
        Which triad.
    path : path, optional
        Save the figure there; the suffix chooses the format (``.png``, ``.pdf``, ``.svg``).
    title : str, optional
        Figure title (default: sensor, record label and sample rate).
    dpi : int
        Resolution of raster output.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    InvalidInputError
        Unknown sensor, a record without that triad, or an unsupported file suffix.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    if sensor not in _SCALE:
        raise InvalidInputError(f"`sensor` must be 'gyro' or 'accel'; got {sensor!r}")
    chans = [c for c in segment.channels if c.sensor == sensor]
    if not chans:
        raise InvalidInputError(f"record {segment.label!r} has no {sensor} channel")
    if path is not None and Path(path).suffix.lower() not in (".png", ".pdf", ".svg"):
        raise InvalidInputError(f"figure file must end in .png, .pdf or .svg; got {path}")
    scale, unit = _SCALE[sensor]
    fig = Figure(figsize=(4.2 * len(chans), 4.0), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, len(chans), squeeze=False)[0]
    for ax, ch in zip(axes, chans, strict=True):
        _panel(ax, ch.axis_name, ch.fit, ch.oadev, scale, unit)
    temp = "" if segment.temperature_degc is None else f", {segment.temperature_degc:.1f} °C"
    fig.suptitle(title or f"{sensor} — {segment.label} ({segment.n_samples} samples at "
                          f"{segment.sample_rate_hz:g} Hz{temp}); densities two-sided")
    if path is not None:
        fig.savefig(path, dpi=dpi)
    return fig


def save_allan_figures(result: NoiseCharacterization, out_dir: str | os.PathLike[str], *,
                       fmt: str = "png") -> list[Path]:
    """Save :func:`plot_allan_triad` for every record and triad; return the files written.

    Files are named ``allan_<record index>_<sensor>.<fmt>``.
    """
    if fmt not in ("png", "pdf", "svg"):
        raise InvalidInputError(f"`fmt` must be 'png', 'pdf' or 'svg'; got {fmt!r}")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for i, seg in enumerate(result.segments):
        for sensor in ("gyro", "accel"):
            if any(c.sensor == sensor for c in seg.channels):
                path = out / f"allan_{i}_{sensor}.{fmt}"
                plot_allan_triad(seg, sensor, path=path)
                written.append(path)
    return written
