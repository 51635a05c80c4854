"""The datasheet-style noise table of per-axis Allan fits (report and exports show it).

Contents
--------
:data:`TABLE_ROWS`, :func:`format_noise_table`. Units and conventions: docs/noise.md.
"""

from __future__ import annotations

import csv
import io as _io
import math
from collections.abc import Mapping

from imucalib.analysis.noise_fit import NoiseFit, NoiseTerm
from imucalib.errors import InvalidInputError
from imucalib.report.numbers import format_pm

__all__ = ["TABLE_ROWS", "format_noise_table"]


#: Rows of the datasheet table per sensor: (parameter, term, unit, note prefix, source).
TABLE_ROWS: dict[str, tuple[tuple[str, str, str, str, str], ...]] = {
    "gyro": (
        ("Angle random walk", "white", "°/√h", "ARW", "fit"),
        ("Noise density (one-sided)", "white", "(°/s)/√Hz", "one-sided", "fit"),
        ("Bias instability (0.664 applied)", "bias_instability", "°/h", "", "fit"),
        ("Allan minimum (no factor)", "bias_instability_allan_minimum", "°/h", "", "reading"),
        ("Rate random walk", "random_walk", "°/h/√h", "RRW", "fit"),
        ("Rate ramp", "rate_ramp", "°/h²", "", "fit"),
        ("Quantization", "quantization", "″", "", "fit"),
    ),
    "accel": (
        ("Velocity random walk", "white", "m/s/√h", "VRW", "fit"),
        ("Noise density (one-sided)", "white", "µg/√Hz", "one-sided", "fit"),
        ("Bias instability (0.664 applied)", "bias_instability", "µg", "", "fit"),
        ("Allan minimum (no factor)", "bias_instability_allan_minimum", "µg", "", "reading"),
        ("Acceleration random walk", "random_walk", "µg/√h", "", "fit"),
        ("Acceleration ramp", "rate_ramp", "µg/h", "", "fit"),
        ("Quantization", "quantization", "m/s", "", "fit"),
    ),
}


def _cell(term: NoiseTerm | None, unit: str, note: str, sigma_scale: float = 1.0) -> str:
    if term is None:
        return "—"
    for u in term.display:
        if u.unit == unit and u.note.startswith(note):
            if not term.detected:
                bound = u.upper if u.upper is not None else 2 * u.std
                return f"< {bound:.3g} (n.d.)" if math.isfinite(bound) else "n.d."
            if math.isfinite(u.std):
                return format_pm(u.value, u.std * sigma_scale)
            return f"{u.value:.4g}"
    raise InvalidInputError(f"no unit {unit!r} ({note}) for term {term.name!r}")


def _quality_cell(fit: NoiseFit) -> str:
    q = fit.quality
    if q.dof == 0:
        return "—"
    text = f"{q.reduced_chi2:.2g}"
    return f"{text} misfit: σ×{q.sigma_scale:.2g}" if q.misfit else text


def format_noise_table(fits: Mapping[str, NoiseFit], *, fmt: str = "text") -> str:
    """Datasheet-style table of per-axis fits, e.g. ``{"gyro_x": fit, …, "accel_z": fit}``.

    One row per parameter of :data:`TABLE_ROWS` (the units users see on datasheets: ARW in
    °/√h, one-sided density in (°/s)/√Hz or µg/√Hz, bias instability in °/h or µg with the
    0.664 factor, the raw Allan minimum beside it, …), one column per channel with value ± standard
    uncertainty, rounded by GUM 7.2.6 (:func:`~imucalib.report.numbers.format_pm`,
    docs/reporting.md); ``< X (n.d.)`` marks a term that was not detected, X its upper bound
    (the fit's 2σ limit; for the Allan minimum the lowest usable 97.7 % confidence limit,
    docs/noise.md; 2u for a term without one), ``—`` one not fitted or without a usable point.
    Sensors are grouped; the last line states the convention.

    Raises
    ------
    InvalidInputError
        No fits, or `fmt` not ``"text"``, ``"csv"``, ``"markdown"``.
    """
    if fmt not in ("text", "csv", "markdown"):
        raise InvalidInputError(f"`fmt` must be 'text', 'csv' or 'markdown'; got {fmt!r}")
    if not fits:
        raise InvalidInputError("`fits` is empty")
    rows: list[list[str]] = []
    for sensor in ("gyro", "accel"):
        chans = [name for name, f in fits.items() if f.sensor == sensor]
        if not chans:
            continue
        rows.append(["parameter", "unit", *chans])
        for label, term_name, unit, note, source in TABLE_ROWS[sensor]:
            cells = []
            for ch in chans:
                f = fits[ch]
                if source == "reading":
                    cells.append(_cell(f.reading(term_name), unit, note))
                else:  # a misfit's σ scaled by the Birge ratio (docs/processing-estimation.md)
                    term = next((t for t in f.terms if t.name == term_name), None)
                    cells.append(_cell(term, unit, note, f.quality.sigma_scale))
            rows.append([label, unit, *cells])
        rows.append(["Fit χ²/ν", "", *(_quality_cell(fits[ch]) for ch in chans)])
    foot = ("Densities: N two-sided (IEEE 952; = Kalibr sigma_c); the noise-density row is the "
            "one-sided datasheet value sqrt(2)*N. Uncertainties are 1-sigma; '< X (n.d.)': not "
            "detected, below the upper bound X (docs/noise.md). A fit chi2/nu above its 99 % "
            "quantile is a misfit: that channel's fitted sigma are scaled by the Birge ratio "
            "sqrt(chi2/nu) (docs/processing-estimation.md).")
    if fmt == "csv":
        buf = _io.StringIO()
        writer = csv.writer(buf, lineterminator="\n")
        writer.writerows(rows)
        return buf.getvalue()
    if fmt == "markdown":
        out: list[str] = []
        for row in rows:
            if row[0] == "parameter" and out:
                out.append("")
            out.append("| " + " | ".join(row) + " |")
            if row[0] == "parameter":
                out.append("|" + "---|" * len(row))
        return "\n".join([*out, "", foot]) + "\n"
    widths = [max(len(r[i]) for r in rows if i < len(r)) for i in range(max(map(len, rows)))]
    text = ["  ".join(c.ljust(widths[i]) for i, c in enumerate(r)).rstrip() for r in rows]
    return "\n".join([*text, foot]) + "\n"
