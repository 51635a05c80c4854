"""The noise characterisation's (Allan's) part of the report: noise tables and Allan figures.

The ``report_content`` hook of :class:`~imucalib.procedures.allan.procedure.AllanProcedure`:
each static record's fitted noise terms (value ± u, k = 1, as the datasheet table gives them)
and its Allan deviation figure per triad (docs/noise.md).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from imucalib.report.document import SECTION_TITLES, ReportContent, ReportTable, Section
from imucalib.report.sections import (
    environment_section,
    equipment_section,
    figure_of,
    object_section,
)

__all__ = ["content"]


def content(result: Any, meta: Mapping[str, Any]) -> ReportContent | None:
    """Return the noise characterisation's sections 1–5 (None without its segments)."""
    from imucalib.procedures.allan.analysis import NoiseCharacterization

    if not isinstance(result, NoiseCharacterization):  # read back: no Allan curves
        return None
    from imucalib.procedures.allan.figures import plot_allan_triad
    from imucalib.report.noise_table import format_noise_table

    tables, figures, convention = [], [], ""
    for i, seg in enumerate(result.segments):
        markdown = format_noise_table(seg.fits(), fmt="markdown")
        for block in markdown.split("\n\n"):
            lines = [ln for ln in block.splitlines()
                     if ln.startswith("|") and not set(ln) <= set("|-: ")]
            cells = [tuple(c.strip() for c in ln.strip("|").split("|")) for ln in lines]
            if cells:
                tables.append(ReportTable(f"record {i}: {seg.label}", cells[0],
                                          tuple(cells[1:])))
            elif block.strip():
                convention = block.strip()
        for sensor in ("gyro", "accel"):
            if any(c.sensor == sensor for c in seg.channels):
                fig = figure_of(lambda p, seg=seg, sensor=sensor: plot_allan_triad(
                    seg, sensor, path=p),
                    f"Allan deviation of the {sensor} axes, record {i} ({seg.label}).")
                if fig is not None:
                    figures.append(fig)
    temps = [s.temperature_degc for s in result.segments if s.temperature_degc is not None]
    site = {"IMU temperature (record means)": ", ".join(f"{t:.1f} °C" for t in temps)} \
        if temps else {}
    sections = [
        object_section({"serial": result.unit}, str(result.unit)),
        equipment_section(meta, None, result.software_version, reference=False),
        environment_section(meta, site),
        Section(SECTION_TITLES[3], ("Noise characterisation (docs/noise.md): overlapping Allan "
                                    "deviation of each static record and a fit of the noise "
                                    "terms; each value with its standard uncertainty.",)),
        Section(SECTION_TITLES[4], ("The noise tables give value ± standard uncertainty "
                                    "(k = 1), GUM 7.2.6 rounding.", *filter(None, [convention])),
                tuple(tables), tuple(figures)),
    ]
    recs = ["Use the noise terms in the navigation filter's process noise."]
    return ReportContent(tuple(sections), "A noise characterisation makes no conformity "
                         "decision.", None, tuple(recs), result.provenance)

