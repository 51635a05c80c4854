"""The result contract: what every procedure's result is, :class:`ProcedureResult`.

Whatever else a procedure's analysis returns, it satisfies this protocol, and the output
files, the report, the terminal, the records and ``apply``/``export``/``combine`` read a result
through it and nothing else (docs/procedures.md, "The result contract"):

- ``procedure``, ``unit``: who made it, about which IMU;
- :meth:`~ProcedureResult.parameter_rows`: every reported quantity as a
  :class:`~imucalib.models.reported.ReportedParameter` (value, reported σ — Birge-scaled on a
  misfit —, the σ before scaling, SI unit);
- :meth:`~ProcedureResult.triad_parameters`: the triad parameters it estimated (``accel_bias_x``,
  ``gyro_M_xy`` …, :mod:`imucalib.models.result`) with their covariance as reported, for
  ``imucalib combine`` and ``apply`` (empty for a procedure that estimates none);
- ``calibration``: a whole triad model ``apply`` can use
  (:class:`~imucalib.models.result.CalibrationResult`), or None;
- ``decision``: the one :class:`~imucalib.models.decision.Decision` (``passed`` is its verdict;
  *no decision* said explicitly);
- ``fit_quality``: each fit's :class:`~imucalib.models.fit_quality.FitQuality`;
- ``notes``; ``provenance`` (where it came from, when it knows); ``members`` (a batch's
  per-unit results, empty for one unit) and ``error`` (why a unit of a batch could not be
  calibrated, empty otherwise); ``omitted`` (the parts of its model a sound fit could not
  give, each with why: a *partial result*, ``imucalib calibrate`` exits 3; empty otherwise);
- :meth:`~ProcedureResult.to_dict`: the whole result, procedure-specific, as JSON-able data.

:class:`ResultDefaults` gives the members most results do not need to write.
:func:`imucalib.models.result_document.result_document` turns any of them into the one JSON
document (format version 4) whose JSON Schema ``imucalib schema result`` prints.

Contents
--------
:class:`ProcedureResult`, :class:`ResultDefaults`, :func:`calibration_rows`
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from imucalib.models.reported import ReportedParameter

if TYPE_CHECKING:
    from imucalib.models.decision import Decision
    from imucalib.models.fit_quality import FitQuality
    from imucalib.models.result import CalibrationResult, Provenance

__all__ = ["ProcedureResult", "ResultDefaults", "TriadParameters", "calibration_rows",
           "no_triad_parameters"]

#: The triad parameters of a result: names, values (k,), covariance (k, k) as reported, SI.
TriadParameters = tuple[list[str], NDArray[np.float64], NDArray[np.float64]]


@runtime_checkable
class ProcedureResult(Protocol):
    """What every procedure's analysis returns (module docstring)."""

    @property
    def procedure(self) -> str:
        """Registered name of the procedure that made it (``"p1"``, ``"tumble"``)."""
        ...

    @property
    def unit(self) -> str:
        """The IMU it is about (its stream's unit name)."""
        ...

    @property
    def decision(self) -> Decision:
        """The verdict: pass, fail or an explicit no decision."""
        ...

    @property
    def passed(self) -> bool | None:
        """``decision.passed``."""
        ...

    @property
    def fit_quality(self) -> tuple[FitQuality, ...]:
        """Each fit's χ²/ν and misfit verdict; empty when no fit has redundancy."""
        ...

    @property
    def notes(self) -> tuple[str, ...]:
        """What the reader must know."""
        ...

    @property
    def calibration(self) -> CalibrationResult | None:
        """The whole triad model it yields, or None."""
        ...

    @property
    def provenance(self) -> Provenance | None:
        """Where it came from (its calibration's, or the file's it was read from), or None."""
        ...

    @property
    def members(self) -> tuple[ProcedureResult, ...]:
        """A batch's per-unit results; empty for the result of one unit."""
        ...

    @property
    def error(self) -> str:
        """Why this unit of a batch could not be calibrated; empty when it was."""
        ...

    @property
    def omitted(self) -> tuple[str, ...]:
        """The parts of the model left out, each with why (a partial result); empty if none."""
        ...

    def parameter_rows(self) -> list[ReportedParameter]:
        """Every reported quantity, SI."""
        ...

    def triad_parameters(self) -> TriadParameters:
        """Return the triad parameters estimated, with their covariance as reported (or none)."""
        ...

    def to_dict(self) -> dict[str, Any]:
        """Return the whole result as JSON-able data."""
        ...


def no_triad_parameters() -> TriadParameters:
    """Return the empty triad parameters of a result that estimates none."""
    return [], np.zeros(0), np.zeros((0, 0))


def calibration_rows(cal: CalibrationResult) -> list[ReportedParameter]:
    """Return a calibration's parameters as reported rows (σ Birge-scaled per misfit group)."""
    scaled = cal.covariance_scaled  # σ = √diag, as CalibrationResult.std(scaled=True)
    return [ReportedParameter(n, float(v), math.sqrt(float(scaled[i, i])),
                              str(cal.units.get(n, "")), math.sqrt(float(cal.covariance[i, i])))
            for i, (n, v) in enumerate(zip(cal.param_names, cal.values, strict=True))]


class ResultDefaults:
    """Defaults of :class:`ProcedureResult` members for a result of one unit.

    ``passed`` from ``decision``; no ``members``, no ``error``; no ``calibration``; no triad
    parameters; :meth:`parameter_rows` from ``calibration`` when a subclass gives one. A
    subclass overrides what it has (a dataclass field of the same name wins).
    """

    @property
    def passed(self) -> bool | None:
        """``decision.passed``."""
        decision: Decision = self.decision  # type: ignore[attr-defined]
        return decision.passed

    @property
    def members(self) -> tuple[ProcedureResult, ...]:
        """No members: the result of one unit."""
        return ()

    @property
    def error(self) -> str:
        """No error: the unit was calibrated."""
        return ""

    @property
    def omitted(self) -> tuple[str, ...]:
        """Nothing left out: the whole model."""
        return ()

    @property
    def calibration(self) -> CalibrationResult | None:
        """No whole triad model."""
        return None

    @property
    def provenance(self) -> Provenance | None:
        """The calibration's provenance, or None."""
        cal = self.calibration
        return None if cal is None else cal.provenance

    def triad_parameters(self) -> TriadParameters:
        """No triad parameters."""
        return no_triad_parameters()

    def parameter_rows(self) -> list[ReportedParameter]:
        """Return the calibration's parameters (σ Birge-scaled per misfit group), if any."""
        cal = self.calibration
        return [] if cal is None else calibration_rows(cal)
