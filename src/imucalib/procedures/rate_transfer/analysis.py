"""The rate-transfer analysis of one unit (docs/rate-transfer.md, "Analysis").

For each body axis tested (the turns tagged ``axis=<k>``, the unit with that axis up): the
input rates x_j = ω_table,j + Ω_U (RT-1), the gyro k means y_j (RT-2)–(RT-4)
(:mod:`~imucalib.procedures.common.rate_windows`) and their covariance C under the fitted white
noise and the declared grade's flicker and random walk (RT-4c,
:mod:`~imucalib.procedures.rate_transfer.noise`), the straight line and the nonlinearity
(RT-5)–(RT-6), and the second fit with the asymmetry and the quadratic term (RT-7)–(RT-8), both
by generalized least squares with C (:mod:`~imucalib.procedures.rate_transfer.fit`).

In the triad model's terms (docs/rate-transfer.md, (RT-9)): E′ = 1 + M_kk, A = (1 + M_kk)·a_k/2
(so the asymmetry is a_k), E2 = K2_k·(1 + M_kk)², and E0′ = b_k + G_kk·g (the bias with axis k up
holds the g-sensitivity along it). :meth:`RateTransferResult.triad_parameters` gives
``gyro_M_kk`` (the quadratic term E2 stays in the report: the triad model has no gyro K2).

The result satisfies the result contract (:class:`~imucalib.models.procedure_result.
ProcedureResult`, docs/procedures.md): part of a triad model (no ``calibration``), and a
decision on ``gyro_M_kk`` against the unit's gyro scale-factor limit (the recording's
``[imu.limits] gyro_scale_ppm``, the plan's ``[acceptance]`` rule), *no decision* when the
specification gives none (:mod:`~imucalib.procedures.common.spec_decision`).

Contents
--------
:class:`AxisTransfer`, :class:`RateTransferResult`, :func:`analyze_rate_transfer`,
:func:`transfer_of_axis`
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imucalib.errors import InsufficientExcitationError
from imucalib.io.opening import open_recording
from imucalib.io.reader import Recording
from imucalib.models.decision import Decision
from imucalib.models.fit_quality import FitQuality
from imucalib.models.procedure_result import ResultDefaults, TriadParameters
from imucalib.models.reported import ReportedParameter
from imucalib.procedures.common.rate_windows import (
    RateProcessing,
    RateWindow,
    extract_rate_windows,
)
from imucalib.procedures.common.spec_decision import Specification, decide_triad
from imucalib.procedures.rate_transfer.fit import (
    LineFit,
    TransferFit,
    fit_line,
    fit_rate_transfer,
)
from imucalib.procedures.rate_transfer.noise import turn_noise
from imucalib.procedures.rate_transfer.roles import RATE_TRANSFER_RATE

__all__ = ["AxisTransfer", "RateTransferResult", "analyze_rate_transfer", "transfer_of_axis"]

_F64 = NDArray[np.float64]
_INDEX = {"x": 0, "y": 1, "z": 2}


@dataclass(frozen=True)
class AxisTransfer:
    """The rate transfer of one gyro axis.

    Attributes
    ----------
    axis : {"x", "y", "z"}
    input_rps, output_rps, se_rps : ndarray
        x_j (RT-1), y_j and σ_j = √C_jj of each turn. [rad/s]
    line : LineFit
        (RT-5)–(RT-6).
    transfer : TransferFit or None
        (RT-7)–(RT-8); None when the rates cannot separate its terms.
    covariance_rps2 : ndarray (n, n) or None
        C of the means (RT-4c), both fits' GLS weight; None: diag σ_j² (RT-4). [(rad/s)²]
    """

    axis: str
    input_rps: _F64
    output_rps: _F64
    se_rps: _F64
    line: LineFit
    transfer: TransferFit | None
    covariance_rps2: _F64 | None = None

    @property
    def nonlinearity(self) -> tuple[float, float, float]:
        """The nonlinearity (RT-6), its σ as reported and its σ before Birge scaling. [1]

        The σ before scaling is (RT-6a) (:func:`~imucalib.procedures.rate_transfer.fit.
        nonlinearity_noise_std`). The one reported is it × the Birge factor of the second fit
        (RT-7) (``sigma_scale``: its Birge ratio when it is a misfit, else 1): that fit models
        the nonlinear shape, so its misfit says the means scatter beyond their σ. Not the line's
        (RT-5): the line's misfit is the nonlinearity being measured, and would scale its σ up
        to the nonlinearity itself. Without a second fit (rates of one sign, < 3 magnitudes),
        the line's factor, conservatively.
        """
        noise = self.line.nonlinearity_noise_std_ppm * 1e-6
        q = self.line.quality if self.transfer is None else self.transfer.quality
        return self.line.nonlinearity_ppm * 1e-6, noise * q.sigma_scale, noise

    def to_dict(self) -> dict[str, Any]:
        """JSON-able summary."""
        out: dict[str, Any] = {
            "axis": self.axis,
            "input_rps": self.input_rps.tolist(), "output_rps": self.output_rps.tolist(),
            "se_rps": self.se_rps.tolist(),
            "scale_factor": self.line.scale_factor,
            "scale_factor_std": float(np.sqrt(self.line.cov[1, 1])),
            "bias_rps": self.line.bias_rps, "bias_std_rps": float(np.sqrt(self.line.cov[0, 0])),
            "nonlinearity_ppm_fs": self.line.nonlinearity_ppm,
            "nonlinearity_std_ppm_fs": self.nonlinearity[1] * 1e6,
            "nonlinearity_noise_std_ppm_fs": self.nonlinearity[2] * 1e6,
            "line_residuals_rps": self.line.residuals_rps.tolist(),
            "line_chi2_per_dof": self.line.quality.reduced_chi2,
            "line_birge_ratio": self.line.quality.birge_ratio,
            "line_fit": self.line.quality.summary(),
        }
        t = self.transfer
        if t is not None:
            asym, asym_s = t.asymmetry
            k_plus, k_minus = t.slopes
            out.update({
                "second_fit": {
                    "bias_rps": float(t.params[0]), "bias_std_rps": t.std(0),
                    "scale_factor": float(t.params[1]), "scale_factor_std": t.std(1),
                    "abs_term": float(t.params[2]), "abs_term_std": t.std(2),
                    "e2_s_per_rad": float(t.params[3]), "e2_std_s_per_rad": t.std(3),
                    "k_plus": k_plus, "k_minus": k_minus,
                    "asymmetry_ppm": asym * 1e6, "asymmetry_std_ppm": asym_s * 1e6,
                    "residuals_rps": t.residuals_rps.tolist(),
                    "chi2_per_dof": t.quality.reduced_chi2,
                    "birge_ratio": t.quality.birge_ratio, "fit": t.quality.summary()}})
        return out


def transfer_of_axis(axis: str, windows: Sequence[RateWindow], earth_rate_up_rps: float,
                     covariance_rps2: _F64 | None = None) -> AxisTransfer:
    """Fit the turns of one axis (module docstring).

    `covariance_rps2` is C of the axis' turns' means (RT-4c), in the order of its turns in
    `windows` [(rad/s)²]; omitted, diag σ_j² of the windows' white σ (RT-4).

    Raises
    ------
    InsufficientExcitationError
        Fewer than two distinct rates for the axis.
    """
    k = _INDEX[axis]
    mine = [w for w in windows if w.axis == axis]
    x = np.array([w.table_rate_rps + earth_rate_up_rps for w in mine])
    if np.unique(np.round(x, 9)).size < 2:
        raise InsufficientExcitationError([f"gyro_M_{axis}{axis}"], (
            f"axis {axis}: {len(mine)} turn(s) at {np.unique(np.round(x, 9)).size} distinct "
            "rate(s); the scale factor needs at least two rates"))
    y = np.array([w.gyro_mean_rps[k] for w in mine])
    se = (np.array([w.gyro_se_rps[k] for w in mine]) if covariance_rps2 is None
          else np.sqrt(np.diag(covariance_rps2)))
    line = fit_line(x, y, se, group=f"gyro {axis}", covariance=covariance_rps2)
    try:
        transfer: TransferFit | None = fit_rate_transfer(x, y, se, group=f"gyro {axis}",
                                                         covariance=covariance_rps2)
    except InsufficientExcitationError:
        transfer = None
    return AxisTransfer(axis=axis, input_rps=x, output_rps=y, se_rps=se, line=line,
                        transfer=transfer, covariance_rps2=covariance_rps2)


@dataclass(frozen=True)
class RateTransferResult(ResultDefaults):
    """The rate transfer of one unit (module docstring).

    It satisfies :class:`~imucalib.models.procedure_result.ProcedureResult`: no
    ``calibration`` (``gyro_M_kk`` only, :meth:`triad_parameters`), ``decision`` against the
    unit's gyro scale-factor limit (:attr:`decision`).

    Attributes
    ----------
    unit : str
    axes : tuple of AxisTransfer
    earth_rate_up_rps : float
        Ω_U added to the table rates. [rad/s]
    n_turns : int
    procedure : str
        ``"rate-transfer"``.
    notes : tuple of str
    specification : Specification
        The unit's limits and the decision rule the recording states (none: no decision).
    """

    unit: str
    axes: tuple[AxisTransfer, ...]
    earth_rate_up_rps: float
    n_turns: int
    procedure: str = "rate-transfer"
    notes: tuple[str, ...] = field(default=())
    specification: Specification = field(default_factory=Specification)

    @property
    def fit_quality(self) -> tuple[FitQuality, ...]:
        """Each axis' line fit (RT-5) and second fit (RT-7): χ²/ν and misfit verdict."""
        return tuple(q for a in self.axes
                     for q in (a.line.quality, *(() if a.transfer is None
                                                 else (a.transfer.quality,))))

    @property
    def decision(self) -> Decision:
        """Each ``gyro_M_kk`` against the specification's gyro scale-factor limit.

        Its check ``specification`` under the recording's rule (docs/rate-transfer.md,
        "Decision"); *no decision* when the specification gives no ``gyro_scale_ppm`` (the
        nonlinearity, asymmetry and quadratic term have no specification limit). Each misfit in
        its notes.
        """
        return decide_triad(self.specification, self.triad_parameters(),
                            test="the rate transfer",
                            what="it measures each gyro's scale factor, bias, nonlinearity, "
                                 "asymmetry and quadratic term (docs/rate-transfer.md)",
                            notes=tuple(q.summary() for q in self.fit_quality if q.misfit))

    def axis(self, name: str) -> AxisTransfer:
        """Return the result of body axis `name`."""
        for a in self.axes:
            if a.axis == name:
                return a
        raise KeyError(f"axis {name!r} was not tested; tested: {[a.axis for a in self.axes]}")

    def to_dict(self) -> dict[str, Any]:
        """JSON-able, everything."""
        return {"procedure": self.procedure, "unit": self.unit, "passed": self.passed,
                "decision": self.decision.to_dict(),
                "earth_rate_up_rps": self.earth_rate_up_rps, "n_turns": self.n_turns,
                "axes": [a.to_dict() for a in self.axes], "notes": list(self.notes)}

    def parameter_rows(self) -> list[ReportedParameter]:
        """Every estimate, SI, per axis: the line (RT-5)–(RT-6), then the second fit (RT-7).

        ``std`` is the σ reported: a fit's, Birge-scaled when that fit is a misfit (the line's
        for the scale factor and ``gyro_bias_line``, the second fit's for ``gyro_M_kk``,
        ``gyro_bias_up``, the asymmetry (RT-8) and E2); the nonlinearity's (RT-6a) scaled by
        the second fit's factor (:attr:`AxisTransfer.nonlinearity`). ``std_noise`` is the same
        σ before that scaling: ``std`` / the fit's ``sigma_scale`` (the nonlinearity's (RT-6a)
        itself). An axis without a second fit gives ``gyro_M_kk`` from the line, as
        :meth:`triad_parameters` does.
        """
        rows: list[ReportedParameter] = []

        def row(name: str, value: float, std: float, unit: str, scale: float
                ) -> ReportedParameter:
            return ReportedParameter(name, float(value), float(std), unit, float(std) / scale)

        for a in self.axes:
            k, line = a.axis, a.line
            ls = line.quality.sigma_scale
            nl, nl_std, nl_noise = a.nonlinearity
            rows += [row(f"gyro_scale_factor_{k}", line.scale_factor,
                         float(np.sqrt(line.cov[1, 1])), "1", ls),
                     row(f"gyro_bias_line_{k}", line.bias_rps, float(np.sqrt(line.cov[0, 0])),
                         "rad/s", ls),
                     ReportedParameter(f"gyro_nonlinearity_{k}", nl, nl_std, "1", nl_noise)]
            t = a.transfer
            if t is None:
                rows.append(row(f"gyro_M_{k}{k}", line.scale_factor - 1.0,
                                float(np.sqrt(line.cov[1, 1])), "1", ls))
                continue
            ts = t.quality.sigma_scale
            asym, asym_s = t.asymmetry
            rows += [row(f"gyro_M_{k}{k}", float(t.params[1]) - 1.0, t.std(1), "1", ts),
                     row(f"gyro_bias_up_{k}", float(t.params[0]), t.std(0), "rad/s", ts),
                     row(f"gyro_asymmetry_{k}", asym, asym_s, "1", ts),
                     row(f"gyro_E2_{k}", float(t.params[3]), t.std(3), "s/rad", ts)]
        return rows

    def triad_parameters(self) -> TriadParameters:
        """``gyro_M_kk`` = E′ − 1 with its variance as reported, for the combined model (RT-9).

        An axis whose rates cannot separate the second fit gives ``gyro_M_kk`` from the line.
        The variance is the reported σ² of the same row of :meth:`parameter_rows`.
        """
        names: list[str] = []
        blocks: list[tuple[_F64, _F64]] = []
        for a in self.axes:
            k, t = a.axis, a.transfer
            if t is None:
                names.append(f"gyro_M_{k}{k}")
                blocks.append((np.array([a.line.scale_factor - 1.0]),
                               a.line.cov[1:2, 1:2].copy()))
                continue
            # the triad model has no gyro K2 (models/result.py): the quadratic term stays in the
            # CSV and the report; the scale factor from the fit that models it
            names.append(f"gyro_M_{k}{k}")
            blocks.append((np.array([float(t.params[1]) - 1.0]), t.cov[1:2, 1:2].copy()))
        n = len(names)
        values = np.concatenate([b[0] for b in blocks]) if blocks else np.zeros(0)
        cov = np.zeros((n, n))
        i = 0
        for v, c in blocks:
            cov[i:i + v.size, i:i + v.size] = c
            i += v.size
        return names, values, cov


def analyze_rate_transfer(recording: Recording | str | os.PathLike[str], *,
                          unit: str | None = None,
                          processing: RateProcessing | None = None) -> RateTransferResult:
    """Analyse a rate-transfer recording (module docstring).

    Raises
    ------
    RecordingError
        Not a rate-transfer recording, no such unit, no table or latitude.
    MissingSegmentError, SaturationError, InvalidInputError
        A turn that cannot be used (:func:`~imucalib.procedures.common.rate_windows.
        extract_rate_windows`).
    InsufficientExcitationError
        An axis with fewer than two distinct rates.
    """
    if not isinstance(recording, Recording):
        with open_recording(recording) as rec:
            return analyze_rate_transfer(rec, unit=unit, processing=processing)
    name, windows, earth_up = extract_rate_windows(recording, unit, (RATE_TRANSFER_RATE,),
                                                   processing=processing)
    w0 = windows[0]
    white = np.asarray(w0.gyro_se_rps * np.sqrt(max(w0.duration_s, 1e-3)), dtype=np.float64)
    noise = turn_noise(recording, windows, white, _sample_rate_hz(recording, name))
    axes = tuple(transfer_of_axis(a, windows, earth_up, noise.covariance[a])
                 for a in sorted({w.axis for w in windows}))
    return RateTransferResult(
        unit=name, axes=axes, earth_rate_up_rps=earth_up, n_turns=len(windows),
        specification=Specification.of_metadata(recording.metadata),
        notes=("means over whole table revolutions (encoder angle); white noise density from "
               "the pooled scatter of 1 s block means (RT-4); input = table rate + vertical "
               "Earth rate; both fits by generalized least squares with the means' covariance "
               "(RT-4c) (docs/rate-transfer.md)", noise.note))


def _sample_rate_hz(rec: Recording, unit: str) -> float:
    """Return the unit's mean sample rate over its stream. [Hz]"""
    from imucalib.io.streams import DEVICE_IMU

    for s in rec.streams:
        if s.device == DEVICE_IMU and s.unit == unit and s.n_samples > 1:
            span = s.t_last_s - s.t_first_s
            if span > 0:
                return (s.n_samples - 1) / span
    return 100.0
