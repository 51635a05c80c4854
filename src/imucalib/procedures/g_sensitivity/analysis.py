"""Analysis of a g-sensitivity recording: the 12 drift coefficients of the gyro triad.

Static window means of every ``g-sensitivity.position`` step
(:func:`~imucalib.procedures.common.static_windows.extract_static_windows`), then the drift
model fitted by :func:`~imucalib.procedures.common.drift_model.fit_windows`
(docs/g-sensitivity.md, equations (1)–(4)); the options, the fit and the parameter names are
those of :mod:`~imucalib.procedures.common.drift_model` (shared with the random-drift test,
re-exported here). The gyro scale-misalignment acting on the Earth rate
is taken as known (:attr:`GSensitivityOptions.scale_misalignment`, nominal zero) with a Type B
standard uncertainty per element (:attr:`GSensitivityOptions.scale_misalignment_std`, 1e-3 by
default, a rate test's worst case), propagated through the full covariance (2).

The decision: D0 and G against the unit's specification (the recording's ``[imu.limits]``
``gyro_bias_dph`` and ``gyro_g_sensitivity_dph_per_g``, the plan's ``[acceptance]`` rule), *no
decision* when it gives neither (:mod:`~imucalib.procedures.common.spec_decision`).

Contents
--------
:class:`GSensitivityOptions`, :class:`GSensitivityResult`, :func:`analyze_g_sensitivity`
"""

from __future__ import annotations

import math
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
from imucalib.procedures.common.drift_model import (
    DriftFit,
    GSensitivityOptions,
    drift_parameter_names,
    fit_windows,
)
from imucalib.procedures.common.spec_decision import Specification, decide_triad
from imucalib.procedures.common.static_windows import (
    StaticWindow,
    extract_static_windows,
    json_safe,
    require_recorded,
)
from imucalib.procedures.g_sensitivity.roles import G_SENSITIVITY_POSITION

__all__ = ["GSensitivityOptions", "GSensitivityResult", "analyze_g_sensitivity",
           "drift_parameter_names", "fit_windows"]

_F64 = NDArray[np.float64]


@dataclass(frozen=True)
class GSensitivityResult(ResultDefaults):
    """The g-sensitivity test's result (the result contract, docs/procedures.md).

    A :class:`~imucalib.models.procedure_result.ProcedureResult`: part of the gyro triad model
    (no ``calibration``; :meth:`triad_parameters` for ``imucalib combine``), decided against
    the unit's gyro bias and g-sensitivity limits (:attr:`decision`).

    Attributes
    ----------
    unit : str
        The IMU.
    fit : DriftFit
        Coefficients (3, 4): D0 [rad/s] and D1..D3 [rad/s per m/s²] per gyro axis, covariance
        (Birge-scaled per axis on a misfit).
    windows : list of StaticWindow
        The reduced positions.
    gravity_mps2, latitude_deg : float
        The site used. [m/s²], [°]
    notes : tuple of str
        What was assumed; each misfit's summary.
    procedure : str
        ``"g-sensitivity"``.
    specification : Specification
        The unit's limits and the decision rule the recording states (none: no decision).
    """

    unit: str
    fit: DriftFit
    windows: list[StaticWindow]
    gravity_mps2: float
    latitude_deg: float
    notes: tuple[str, ...] = ()
    procedure: str = "g-sensitivity"
    specification: Specification = field(default_factory=Specification)

    @property
    def decision(self) -> Decision:
        """D0 and G against the specification's gyro bias and g-sensitivity limits.

        Its check ``specification`` under the recording's rule (docs/g-sensitivity.md,
        "Decision"); *no decision* when the specification gives neither ``gyro_bias_dph`` nor
        ``gyro_g_sensitivity_dph_per_g``. Each misfit in its notes.
        """
        return decide_triad(self.specification, self.triad_parameters(),
                            test="the g-sensitivity test",
                            what="D0 and G are reported with their standard uncertainties "
                                 "(docs/g-sensitivity.md)",
                            notes=tuple(f.summary() for f in self.fit.fits if f.misfit))

    @property
    def fit_quality(self) -> tuple[FitQuality, ...]:
        """Each gyro axis' drift fit (4): χ²/ν and misfit verdict."""
        return tuple(self.fit.fits)

    @property
    def bias_rps(self) -> _F64:
        """D0 per axis. [rad/s]"""
        return np.asarray(self.fit.coefficients[:, 0], dtype=np.float64)

    @property
    def g_sensitivity(self) -> _F64:
        """G (3, 3): row gyro axis, column specific-force axis. [rad/s per m/s²]"""
        return np.asarray(self.fit.coefficients[:, 1:], dtype=np.float64)

    def triad_parameters(self) -> TriadParameters:
        """Return (names, values, covariance) in the names of :mod:`imucalib.models.result`.

        The covariance as reported: Birge-scaled per gyro axis whose fit is a misfit (4), the
        σ of :meth:`parameter_rows`.
        """
        return drift_parameter_names(), self.fit.coefficients.ravel().copy(), \
            self.fit.covariance.copy()

    def parameter_rows(self) -> list[ReportedParameter]:
        """Return the 12 coefficients as reported, SI.

        Returns
        -------
        list of ReportedParameter
            Row-major as :meth:`triad_parameters`. ``std``: the σ reported, √ of the diagonal
            of the covariance (3)–(4), scaled by the axis fit's Birge ratio √(χ²/ν) where it
            is a misfit; ``std_noise``: the same σ before that scaling (``std`` divided by
            the axis fit's ``sigma_scale``), the window noise and σ_M's Type B term (2)
            propagated. Equal where the axis fit is no misfit.
        """
        names, values, cov = self.triad_parameters()
        rows = []
        for k, (n, v) in enumerate(zip(names, values, strict=True)):
            std = float(math.sqrt(cov[k, k]))
            rows.append(ReportedParameter(
                n, float(v), std, "rad/s" if "bias" in n else "(rad/s)/(m/s^2)",
                std / self.fit.fits[k // 4].sigma_scale))
        return rows

    def to_dict(self) -> dict[str, Any]:
        """Return the whole result as JSON-able data."""
        names, values, cov = self.triad_parameters()
        out = {
            "procedure": self.procedure, "unit": self.unit, "passed": self.passed,
            "decision": self.decision.to_dict(),
            "parameters": {n: {"value": float(v), "std": float(math.sqrt(cov[k, k]))}
                           for k, (n, v) in enumerate(zip(names, values, strict=True))},
            "covariance": cov,
            "fit_quality": [{"group": f.group, "chi2": f.chi2, "dof": f.dof,
                             "reduced_chi2": f.reduced_chi2, "misfit": f.misfit,
                             "sigma_scale": f.sigma_scale} for f in self.fit.fits],
            "gravity_mps2": self.gravity_mps2, "latitude_deg": self.latitude_deg,
            "windows": [{"step": w.step_index, "label": w.label,
                         "angles_rad": w.angles_rad, "gyro_mean_rps": w.mean[:3],
                         "gyro_se_rps": w.se[:3], "force_ref_b_mps2": w.force_ref_b_mps2,
                         "omega_ref_b_rps": w.omega_ref_b_rps,
                         "residual_rps": self.fit.residuals[k]}
                        for k, w in enumerate(self.windows)],
            "notes": list(self.notes),
        }
        return dict(json_safe(out))  # type: ignore[call-overload]


def analyze_g_sensitivity(recording: Recording | str | os.PathLike[str], *,
                          unit: str | None = None, options: GSensitivityOptions | None = None
                          ) -> GSensitivityResult:
    """Estimate the gyro triad's D0 and g-sensitivity from a recording (module docstring).

    Raises
    ------
    RecordingError
        No step with role ``g-sensitivity.position``, no table stream, no latitude.
    MissingSegmentError
        A planned position not recorded (named), a window too short.
    InsufficientExcitationError
        Positions that do not span the gravity directions.
    """
    opt = options or GSensitivityOptions()
    if not isinstance(recording, Recording):
        with open_recording(recording) as rec:
            return analyze_g_sensitivity(rec, unit=unit, options=opt)
    rec = recording
    require_recorded(rec, [G_SENSITIVITY_POSITION])
    name, site, windows = extract_static_windows(rec, unit, [G_SENSITIVITY_POSITION],
                                                 gravity_mps2=opt.gravity_mps2,
                                                 noise_block_s=opt.noise_block_s)
    fit = fit_windows(windows, opt)
    notes = [f"Earth rate at latitude {site.latitude_deg:g}° subtracted through the gyro "
             f"scale-misalignment taken as "
             f"{'nominal (zero)' if opt.scale_misalignment is None else 'given'}, each element "
             f"with a Type B standard uncertainty of {opt.scale_misalignment_std:g}"]
    notes += [f.summary() for f in fit.fits if f.misfit]
    return GSensitivityResult(unit=name, fit=fit, windows=windows,
                              gravity_mps2=site.gravity_mps2, latitude_deg=site.latitude_deg,
                              notes=tuple(notes),
                              specification=Specification.of_metadata(rec.metadata))
