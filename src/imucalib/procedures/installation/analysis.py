"""The installation-error analysis of one unit (docs/installation.md, "Analysis").

The turns (role ``installation.rate``) reduced to whole-revolution means
(:func:`~imucalib.procedures.common.rate_windows.extract_rate_windows`), then M by the
chapter's closed form (IN-2) and by the general least-squares form (IN-3)
(:mod:`~imucalib.procedures.installation.misalignment`); their largest difference in units of
the closed form's σ is reported (``agreement_sigma``).

:meth:`InstallationResult.triad_parameters` gives the off-diagonal ``gyro_M_ij`` of the tested
columns from the least-squares form (the diagonal belongs to the rate transfer, whose rates
also see the nonlinearity).

Contents
--------
:class:`InstallationResult`, :func:`analyze_installation`
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imucalib.io.reader import Recording, open_recording
from imucalib.models.fit_quality import FitQuality
from imucalib.procedures.common.rate_windows import RateProcessing, extract_rate_windows
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
class InstallationResult:
    """The misalignment of one unit's gyro triad (module docstring).

    Attributes
    ----------
    unit : str
    closed_form, lsq : Misalignment
        (IN-2) and (IN-3).
    earth_rate_up_rps : float
    n_turns : int
    procedure : str
        ``"installation"``.
    """

    unit: str
    closed_form: Misalignment
    lsq: Misalignment
    earth_rate_up_rps: float
    n_turns: int
    procedure: str = "installation"

    @property
    def fit_quality(self) -> tuple[FitQuality, ...]:
        """The least-squares triad fit's χ²/ν (IN-3); none when it has no redundancy."""
        return () if self.lsq.quality is None else (self.lsq.quality,)

    @property
    def passed(self) -> bool | None:
        """No acceptance limits: None."""
        return None

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
                "earth_rate_up_rps": self.earth_rate_up_rps, "n_turns": self.n_turns,
                "closed_form": {"M": tolist(self.closed_form.matrix),
                                "M_std": tolist(self.closed_form.std)},
                "lsq": {"M": tolist(self.lsq.matrix), "M_std": tolist(self.lsq.std),
                        "chi2_per_dof": None if q is None or q.dof == 0 else q.reduced_chi2,
                        "fit": "" if q is None else q.summary()},
                "agreement_sigma": self.agreement_sigma}

    def _entries(self, off_diagonal: bool) -> list[tuple[int, int]]:
        return [(i, j) for i in range(3) for j in range(3)
                if np.isfinite(self.lsq.matrix[i, j]) and (i != j or not off_diagonal)]

    def parameter_rows(self) -> list[tuple[str, float, float, str]]:
        """(name, value, σ, unit): M_ij of both forms (``_closed`` suffix for (IN-2))."""
        rows = []
        for i, j in self._entries(False):
            name = f"gyro_M_{_AXES[i]}{_AXES[j]}"
            rows.append((name, float(self.lsq.matrix[i, j]), float(self.lsq.std[i, j]), "1"))
            rows.append((f"{name}_closed", float(self.closed_form.matrix[i, j]),
                         float(self.closed_form.std[i, j]), "1"))
        return rows

    def triad_parameters(self) -> tuple[list[str], _F64, _F64]:
        """Return the off-diagonal ``gyro_M_ij`` of the least-squares form and their covariance."""
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
    return InstallationResult(
        unit=name, closed_form=closed_form_misalignment(windows, earth_up),
        lsq=lsq_misalignment(windows, earth_up, common_bias=common_bias),
        earth_rate_up_rps=earth_up, n_turns=len(windows))
