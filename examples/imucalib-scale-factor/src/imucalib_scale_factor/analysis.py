"""The scale-factor analysis: the z gyro's straight line y = K1·ω + b over the turns.

For each turn (the steps with role :data:`~imucalib_scale_factor.plan.ROLE_RATE`) imucalib's
rate-window reader (:func:`~imucalib.procedures.common.rate_windows.extract_rate_windows`) gives
the gyro means over whole table revolutions, the table rate from the encoder angle over the same
span, and each mean's standard error from the unit's pooled white noise. The input rate about
the vertical is the table rate plus the vertical Earth rate Ω_U = Ω_e·sin L (docs/rate-transfer.md
of imucalib, (RT-1)); the horizontal Earth rate cancels over whole revolutions. Then

    y_j = K1·ω_j + b + e_j,   e_j ~ N(0, σ_j²)                                           (SF-1)

is solved by weighted least squares (:func:`imucalib.estimation.solve_weighted_lsq`), and the
fit's χ²/ν is assessed (:func:`imucalib.models.fit_quality.assess_fit`): on a misfit (χ² above
its 99 % quantile) the standard uncertainties are scaled by the Birge ratio √(χ²/ν).

The result (:class:`ScaleFactorResult`) satisfies imucalib's result contract
(:class:`imucalib.models.procedure_result.ProcedureResult`), which imucalib's result file,
outputs, report and records read: ``procedure``, ``unit``, ``decision`` (*no decision*: the test
sets no limits) and ``passed``, ``fit_quality``, ``notes``, ``parameter_rows()`` (each σ as
reported and before the Birge scaling) and ``to_dict()``; the rest (``calibration``,
``members``, ``error``, ``triad_parameters()``: none) comes from imucalib's
:class:`~imucalib.models.procedure_result.ResultDefaults`.

Contents
--------
:class:`ScaleFactorResult`, :func:`fit_scale_factor`, :func:`analyze_scale_factor`
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib import __version__ as imucalib_version
from imucalib.estimation import solve_weighted_lsq
from imucalib.io.hashing import file_sha256
from imucalib.io.opening import open_recording
from imucalib.io.reader import Recording
from imucalib.models.decision import Decision, no_decision
from imucalib.models.fit_quality import FitQuality, assess_fit
from imucalib.models.procedure_result import ResultDefaults
from imucalib.models.reported import ReportedParameter
from imucalib.models.result import Provenance
from imucalib.procedures.common.rate_windows import RateProcessing, extract_rate_windows
from imucalib_scale_factor import __version__
from imucalib_scale_factor.plan import NAME, ROLE_RATE

__all__ = ["ScaleFactorResult", "analyze_scale_factor", "fit_scale_factor"]

_F64 = NDArray[np.float64]
#: The parameter names of the CSV, the report and the records (the triad naming of imucalib).
K1_NAME, BIAS_NAME = "gyro_K1_z", "gyro_bias_z"
#: The provenance of a result made without a recording (frozen: one instance is shared).
_NO_PROVENANCE = Provenance()


@dataclass(frozen=True)
class ScaleFactorResult(ResultDefaults):
    """The z gyro's scale factor and bias of one unit (module docstring).

    A :class:`~imucalib.models.procedure_result.ProcedureResult`; ``passed``, ``calibration``
    (None), ``members``, ``error`` and ``triad_parameters()`` (none: K1 and b stay this test's
    own quantities) from :class:`~imucalib.models.procedure_result.ResultDefaults`.

    Attributes
    ----------
    unit : str
        The IMU analysed (its stream name).
    k1, k1_std : float
        The scale factor K1 of (SF-1) and its standard uncertainty (Birge-scaled on a misfit). [1]
    bias_rps, bias_std_rps : float
        The bias b and its standard uncertainty. [rad/s]
    correlation : float
        The correlation of K1 and b.
    input_rps, output_rps, se_rps : ndarray
        ω_j, y_j and σ_j of each turn. [rad/s]
    residuals_rps : ndarray
        y_j − (K1·ω_j + b). [rad/s]
    quality : tuple of FitQuality
        The fit's χ²/ν (one entry; imucalib's report prints its summary).
    earth_rate_up_rps : float
        Ω_U added to the table rates. [rad/s]
    provenance : Provenance
        The recording, its SHA-256, the plan hash and the software.
    notes : tuple of str
        How the numbers were made, for the report.
    procedure : str
        ``"scale-factor"``.
    """

    unit: str
    k1: float
    k1_std: float
    bias_rps: float
    bias_std_rps: float
    correlation: float
    input_rps: _F64
    output_rps: _F64
    se_rps: _F64
    residuals_rps: _F64
    quality: tuple[FitQuality, ...]
    earth_rate_up_rps: float = 0.0
    # a class-level default (not a default_factory): only so does the field override the
    # ``provenance`` property of ResultDefaults
    provenance: Provenance = _NO_PROVENANCE
    notes: tuple[str, ...] = ()
    procedure: str = NAME

    @property
    def fit_quality(self) -> tuple[FitQuality, ...]:
        """The line fit's χ²/ν and misfit verdict (the ProcedureResult contract)."""
        return tuple(self.quality)

    @property
    def decision(self) -> Decision:
        """*No decision*: the test sets no acceptance limits (``passed`` is None)."""
        return no_decision("the scale-factor test has no acceptance limits: K1 and the bias "
                           "are reported with their standard uncertainties",
                           notes=tuple(q.summary() for q in self.quality if q.misfit))

    def to_dict(self) -> dict[str, Any]:
        """Return everything as JSON-able data (the report JSON, the records' document)."""
        q = self.quality[0]
        p = self.provenance
        return {
            "procedure": self.procedure, "unit": self.unit, "passed": self.passed,
            "decision": self.decision.to_dict(), "k1": self.k1, "k1_std": self.k1_std,
            "bias_rps": self.bias_rps, "bias_std_rps": self.bias_std_rps,
            "correlation": self.correlation,
            "chi2_per_dof": q.reduced_chi2, "dof": q.dof, "misfit": q.misfit,
            "birge_ratio": q.birge_ratio, "fit": q.summary(),
            "earth_rate_up_rps": self.earth_rate_up_rps,
            "input_rps": self.input_rps.tolist(), "output_rps": self.output_rps.tolist(),
            "se_rps": self.se_rps.tolist(), "residuals_rps": self.residuals_rps.tolist(),
            "provenance": {"recording": p.recording, "recording_sha256": p.recording_sha256,
                           "plan_hash": p.plan_hash, "software_version": p.software_version,
                           "created_utc": p.created_utc, "details": dict(p.details)},
            "notes": list(self.notes),
        }

    def parameter_rows(self) -> list[ReportedParameter]:
        """Return K1 and the bias as reported, SI.

        Returns
        -------
        list of ReportedParameter
            ``gyro_K1_z`` [1] and ``gyro_bias_z`` [rad/s]. ``std``: the standard uncertainty
            reported (:attr:`k1_std`, :attr:`bias_std_rps`: scaled by the Birge ratio
            √(χ²/ν) on a misfit); ``std_noise``: the same before that scaling (``std`` divided
            by the fit's ``sigma_scale``), the σ_j propagated. Equal when the fit is no misfit.
        """
        scale = self.quality[0].sigma_scale if self.quality else 1.0
        return [ReportedParameter(K1_NAME, self.k1, self.k1_std, "1", self.k1_std / scale),
                ReportedParameter(BIAS_NAME, self.bias_rps, self.bias_std_rps, "rad/s",
                                  self.bias_std_rps / scale)]


def fit_scale_factor(input_rps: ArrayLike, output_rps: ArrayLike, se_rps: ArrayLike
                     ) -> tuple[_F64, _F64, _F64, FitQuality]:
    """Fit (SF-1) y = K1·ω + b weighted by 1/σ²; Birge-scale the covariance on a misfit.

    Parameters
    ----------
    input_rps, output_rps, se_rps : array_like, shape (n,)
        ω_j, y_j and σ_j, n ≥ 2 with at least two distinct rates. [rad/s]

    Returns
    -------
    estimate : ndarray, shape (2,)
        (K1 [1], b [rad/s]).
    covariance : ndarray, shape (2, 2)
        Their covariance, scaled by χ²/ν when the fit is a misfit.
    residuals : ndarray, shape (n,)
        y − (K1·ω + b). [rad/s]
    quality : FitQuality
        χ²/ν and the misfit verdict.

    Raises
    ------
    InvalidInputError
        Shapes that disagree, a σ ≤ 0, a value that is not finite.
    InsufficientExcitationError
        Fewer than two distinct rates (K1 and b cannot be separated).

    Examples
    --------
    >>> import numpy as np
    >>> est, cov, res, q = fit_scale_factor([1.0, -1.0, 2.0, -2.0], [1.1, -0.9, 2.1, -1.9],
    ...                                     [0.01] * 4)
    >>> np.round(est, 9).tolist(), q.dof
    ([1.0, 0.1], 2)
    """
    x = np.asarray(input_rps, dtype=np.float64)
    design = np.column_stack([x, np.ones_like(x)])
    sol = solve_weighted_lsq(design, output_rps, param_names=(K1_NAME, BIAS_NAME), sigma=se_rps)
    quality = assess_fit("gyro z", float(sol.chi2), int(sol.dof))
    cov = np.asarray(sol.covariance, dtype=np.float64) * quality.sigma_scale ** 2
    return (np.asarray(sol.estimate, dtype=np.float64), cov,
            np.asarray(sol.residuals, dtype=np.float64), quality)


def analyze_scale_factor(recording: Recording | str | os.PathLike[str], *,
                         unit: str | None = None, processing: RateProcessing | None = None
                         ) -> ScaleFactorResult:
    """Analyse a scale-factor recording (module docstring).

    Parameters
    ----------
    recording : Recording or path
        An open Recording, or the path of one made from the scale-factor plan.
    unit : str, optional
        The IMU stream (default: the only one).
    processing : RateProcessing, optional
        Options of the turn reduction (dropouts allowed, noise block length).

    Returns
    -------
    ScaleFactorResult

    Raises
    ------
    RecordingError
        No such unit, no single-axis table stream, no latitude, no turn.
    MissingSegmentError, SaturationError, InvalidInputError
        A turn that cannot be used.
    InsufficientExcitationError
        Fewer than two distinct rates.
    """
    if not isinstance(recording, Recording):
        with open_recording(recording) as rec:
            return analyze_scale_factor(rec, unit=unit, processing=processing)
    name, windows, earth_up = extract_rate_windows(recording, unit, (ROLE_RATE,),
                                                   processing=processing)
    x = np.array([w.table_rate_rps + earth_up for w in windows])
    y = np.array([w.gyro_mean_rps[2] for w in windows])
    se = np.array([w.gyro_se_rps[2] for w in windows])
    est, cov, residuals, quality = fit_scale_factor(x, y, se)
    std = np.sqrt(np.diag(cov))
    path = Path(recording.path)
    provenance = Provenance(
        plan_hash=str(recording.metadata.get("plan_hash", "") or ""),
        recording=path.name, recording_sha256=file_sha256(path) if path.is_file() else "",
        software_version=imucalib_version,
        created_utc=datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
        details={"plugin": f"imucalib-scale-factor {__version__}", "n_turns": len(windows)})
    return ScaleFactorResult(
        unit=name, k1=float(est[0]), k1_std=float(std[0]), bias_rps=float(est[1]),
        bias_std_rps=float(std[1]), correlation=float(cov[0, 1] / (std[0] * std[1])),
        input_rps=x, output_rps=y, se_rps=se, residuals_rps=residuals, quality=(quality,),
        earth_rate_up_rps=earth_up, provenance=provenance,
        notes=("z gyro means over whole table revolutions (encoder angle); σ from the unit's "
               "pooled white noise of 1 s block means; input = table rate + vertical Earth "
               "rate (imucalib docs/rate-transfer.md)",))
