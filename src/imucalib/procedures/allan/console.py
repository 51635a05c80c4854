"""The noise characterisation (Allan) on the terminal: each record's noise-term table.

The ``render_console`` hook of :class:`~imucalib.procedures.allan.procedure.AllanProcedure`, for
``imucalib calibrate`` and ``imucalib allan`` (docs/noise.md).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from rich.console import Console

from imucalib.report.console import print_written

__all__ = ["render_noise_characterization"]


def render_noise_characterization(console: Console, result: Any, written: Sequence[Path]
                                  ) -> None:
    """Print each record's noise-term table and the files written."""
    from imucalib.report.noise_table import format_noise_table

    for seg in result.segments:
        temp = "" if seg.temperature_degc is None else f", {seg.temperature_degc:.1f} °C"
        console.print(f"[bold]{seg.label}[/]: {seg.n_samples:,} samples at "
                      f"{seg.sample_rate_hz:g} Hz{temp}", highlight=False)
        console.print(format_noise_table(seg.fits(), fmt="text"), highlight=False,
                      soft_wrap=True)
    print_written(console, written)
