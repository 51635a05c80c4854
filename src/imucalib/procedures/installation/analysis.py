"""The installation-error analysis of one unit (docs/installation.md, "Analysis").

The turns (role ``installation.rate``) reduced to whole-revolution means
(:func:`~imucalib.procedures.common.rate_windows.extract_rate_windows`), then M by the
chapter's closed form (IN-2) and by the general least-squares form (IN-3)
(:mod:`~imucalib.procedures.installation.misalignment`); their largest difference in units of
the closed form's σ is reported (``agreement_sigma``).

:meth:`InstallationResult.triad_parameters` gives the off-diagonal ``gyro_M_ij`` of the tested
columns from the least-squares form (the diagonal belongs to the rate transfer, whose rates
also see the nonlinearity).

The result satisfies the result contract (:class:`~imucalib.models.procedure_result.
ProcedureResult`, docs/procedures.md): part of a triad model (no ``calibration``), and a
decision on the off-diagonal ``gyro_M_ij`` against the unit's gyro misalignment limit (the
recording's ``[imu.limits] gyro_misalignment_urad``, the plan's ``[acceptance]`` rule), *no
decision* when the specification gives none (:mod:`~imucalib.procedures.common.spec_decision`).

Contents
--------
:class:`InstallationResult`, :func:`analyze_installation`
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imucalib.io.opening import open_recording
from imucalib.io.reader import Recording
from imucalib.models.decision import Decision
from imucalib.models.fit_quality import FitQuality
from imucalib.models.procedure_result import ResultDefaults, TriadParameters
from imucalib.models.reported import ReportedParameter
from imucalib.procedures.common.rate_windows import RateProcessing, extract_rate_windows
from imucalib.procedures.common.spec_decision import Specification, decide_triad
from imucalib.procedures.installation.misalignment import (
    Misalignment,
    closed_form_misalignment,
    lsq_misalignment,
)
from imucalib.procedures.installation.roles import INSTALLATION_RATE

__all__ = ["InstallationResult", "analyze_installation"]

_F64 = NDArray[np.float64]
_AXES = "xyz"


@dataclass(frozen=True)
class InstallationResult(ResultDefaults):
    """The misalignment of one unit's gyro triad (module docstring).

    It satisfies :class:`~imucalib.models.procedure_result.ProcedureResult`: no
    ``calibration`` (the off-diagonal ``gyro_M_ij`` only, :meth:`triad_parameters`),
    ``decision`` against the unit's gyro misalignment limit (:attr:`decision`).

    Attributes
    ----------
    unit : str
    closed_form, lsq : Misalignment
        (IN-2) and (IN-3).
    earth_rate_up_rps : float
    n_turns : int
    procedure : str
        ``"installation"``.
    notes : tuple of str
        What the reader must know (the least-squares fit's misfit).
    specification : Specification
        The unit's limits and the decision rule the recording states (none: no decision).
    """

    unit: str
    closed_form: Misalignment
    lsq: Misalignment
    earth_rate_up_rps: float
    n_turns: int
    procedure: str = "installation"
    notes: tuple[str, ...] = ()
    specification: Specification = field(default_factory=Specification)

    @property
    def fit_quality(self) -> tuple[FitQuality, ...]:
        """The least-squares triad fit's χ²/ν (IN-3); none when it has no redundancy."""
        return () if self.lsq.quality is None else (self.lsq.quality,)

    @property
    def decision(self) -> Decision:
        """The off-diagonal ``gyro_M_ij`` (least squares) against the misalignment limit.

        Its check ``specification`` under the recording's rule (docs/installation.md,
        "Decision"); *no decision* when the specification gives no ``gyro_misalignment_urad``.
        A misfit in its notes.
        """
        return decide_triad(self.specification, self.triad_parameters(),
                            test="the installation test",
                            what="it measures the gyro triad's misalignment "
                                 "(docs/installation.md)",
                            notes=tuple(q.summary() for q in self.fit_quality if q.misfit))

    @property
    def agreement_sigma(self) -> float:
        """Return max |M_lsq − M_closed| / σ_closed over the estimated entries."""
        d = np.abs(self.lsq.matrix - self.closed_form.matrix) / self.closed_form.std
        return float(np.nanmax(d))

    def to_dict(self) -> dict[str, Any]:
        """JSON-able, everything."""
        q = self.lsq.quality

        def tolist(a: _F64) -> list[Any]:
            return [[None if not np.isfinite(v) else float(v) for v in row] for row in a]

        return {"procedure": self.procedure, "unit": self.unit, "passed": self.passed,
                "decision": self.decision.to_dict(),
                "earth_rate_up_rps": self.earth_rate_up_rps, "n_turns": self.n_turns,
                "closed_form": {"M": tolist(self.closed_form.matrix),
                                "M_std": tolist(self.closed_form.std)},
                "lsq": {"M": tolist(self.lsq.matrix), "M_std": tolist(self.lsq.std),
                        "chi2_per_dof": None if q is None or q.dof == 0 else q.reduced_chi2,
                        "fit": "" if q is None else q.summary()},
                "agreement_sigma": self.agreement_sigma, "notes": list(self.notes)}

    def _entries(self, off_diagonal: bool) -> list[tuple[int, int]]:
        return [(i, j) for i in range(3) for j in range(3)
                if np.isfinite(self.lsq.matrix[i, j]) and (i != j or not off_diagonal)]

    def parameter_rows(self) -> list[ReportedParameter]:
        """M_ij of both forms, SI (``_closed`` suffix for (IN-2)).

        ``std`` is the σ reported: the least-squares form's Birge-scaled when its pooled fit
        is a misfit (IN-4), the closed form's from the means' σ (no fit, no scaling).
        ``std_noise`` is the same σ before that scaling: the least-squares σ / its
        ``sigma_scale``; the closed form's σ itself.
        """
        q = self.lsq.quality
        scale = 1.0 if q is None else q.sigma_scale
        rows = []
        for i, j in self._entries(False):
            name = f"gyro_M_{_AXES[i]}{_AXES[j]}"
            std = float(self.lsq.std[i, j])
            closed = float(self.closed_form.std[i, j])
            rows.append(ReportedParameter(name, float(self.lsq.matrix[i, j]), std, "1",
                                          std / scale))
            rows.append(ReportedParameter(f"{name}_closed", float(self.closed_form.matrix[i, j]),
                                          closed, "1", closed))
        return rows

    def triad_parameters(self) -> TriadParameters:
        """Return the off-diagonal ``gyro_M_ij`` of the least-squares form and their covariance.

        The covariance is the one reported (Birge-scaled on a misfit, (IN-4)), whose diagonal
        is the σ² of the same rows of :meth:`parameter_rows`.
        """
        entries = self._entries(True)
        idx = [3 * i + j for i, j in entries]
        names = [f"gyro_M_{_AXES[i]}{_AXES[j]}" for i, j in entries]
        values = np.array([self.lsq.matrix[i, j] for i, j in entries])
        return names, values, self.lsq.cov[np.ix_(idx, idx)]


def analyze_installation(recording: Recording | str | os.PathLike[str], *,
                         unit: str | None = None, processing: RateProcessing | None = None,
                         common_bias: bool = False) -> InstallationResult:
    """Analyse an installation-error recording (module docstring).

    Raises
    ------
    RecordingError
        Not an installation recording, no such unit, no table or latitude.
    MissingSegmentError
        A turn cut short, or a +ω turn without its −ω pair.
    SaturationError, InvalidInputError
        Unusable samples.
    InsufficientExcitationError
        An axis turned at one rate only.
    """
    if not isinstance(recording, Recording):
        with open_recording(recording) as rec:
            return analyze_installation(rec, unit=unit, processing=processing,
                                        common_bias=common_bias)
    name, windows, earth_up = extract_rate_windows(recording, unit, (INSTALLATION_RATE,),
                                                   processing=processing)
    closed = closed_form_misalignment(windows, earth_up)
    lsq = lsq_misalignment(windows, earth_up, common_bias=common_bias)
    misfit = () if lsq.quality is None or not lsq.quality.misfit else (lsq.quality.summary(),)
    return InstallationResult(
        unit=name, closed_form=closed, lsq=lsq,
        earth_rate_up_rps=earth_up, n_turns=len(windows), notes=misfit,
        specification=Specification.of_metadata(recording.metadata))
