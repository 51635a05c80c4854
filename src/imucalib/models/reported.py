"""One reported parameter of a result: :class:`ReportedParameter`.

Every procedure's result lists what it reports as rows of this one shape (the result contract,
docs/procedures.md): the value, ``std`` = the standard uncertainty the tool reports (scaled by
the Birge ratio √(χ²/ν) where the fit that gave it is a misfit, docs/processing-estimation.md),
``std_noise`` = the same σ before that scaling (noise propagation and Type B terms), and the SI
unit. Where a fit is no misfit the two are equal.

Contents
--------
:class:`ReportedParameter`, :func:`scaled_rows`
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import NamedTuple

__all__ = ["ReportedParameter", "scaled_rows"]


class ReportedParameter(NamedTuple):
    """One parameter as reported: name, value, σ (reported), unit, σ before Birge scaling."""

    name: str
    value: float
    std: float
    unit: str
    std_noise: float


def scaled_rows(rows: Iterable[tuple[str, float, float, str]], scale: float
                ) -> list[ReportedParameter]:
    """Return `rows` (name, value, noise-only σ, unit) with σ scaled by `scale` (≥ 1).

    For a fit whose every parameter shares one Birge factor (:attr:`FitQuality.sigma_scale`
    of :mod:`imucalib.models.fit_quality`): ``std`` = `scale`·σ, ``std_noise`` = σ.
    """
    return [ReportedParameter(str(n), float(v), float(s) * scale, str(u), float(s))
            for n, v, s, u in rows]
