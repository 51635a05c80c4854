"""The field calibration's result and its triad model.

The field fits estimate the accelerometer in the correction form (F.1) of
:mod:`imucalib.estimation.gravity_norm` (or the triad form of the six-position fit) and the
gyro's M in the accelerometer's frame; :func:`triad_from_field` maps them into the triad model
y = b + (I + M)·x of :mod:`imucalib.models.result` (docs/field.md, Eq. (FL.1)):

    I + M_a = (T·(I + diag s))⁻¹,   b_a = b                                              (FL.1)

x being the specific force in the accelerometer's orthogonal frame a (x along sensor x, y in the
sensors' x–y plane): I + M_a is upper triangular, its three lower entries exactly zero (with
zero variance). The covariance is carried through the Jacobian of (FL.1) (numerical, central
differences), with the gyro block and the gyro–accelerometer cross-covariance of the rotation
fit as they are.

A field calibration has no acceptance limits: its result (:class:`FieldResult`, a
:class:`~imucalib.models.procedure_result.ProcedureResult`) makes *no decision*
(:data:`NO_DECISION_REASON`), its notes and each fit's χ²/ν saying what the reader must know.

Contents
--------
:class:`FieldResult`, :func:`triad_from_field`, :func:`accel_matrix`,
:func:`field_decision`, :data:`NO_DECISION_REASON`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imucalib.models.decision import Decision, no_decision
from imucalib.models.fit_quality import FitQuality
from imucalib.models.procedure_result import ResultDefaults, TriadParameters, calibration_rows
from imucalib.models.reported import ReportedParameter
from imucalib.models.result import (
    CalibrationResult,
    Provenance,
    triad_parameter_names,
    triad_parameter_unit,
)
from imucalib.procedures.common.static_windows import json_safe

__all__ = ["NO_DECISION_REASON", "FieldResult", "accel_matrix", "field_decision",
           "triad_from_field"]

_F64 = NDArray[np.float64]

#: Why a field calibration decides nothing (docs/field.md).
NO_DECISION_REASON = ("a field calibration has no acceptance limits: its poses and turns are "
                      "made by hand against no reference standard, so it judges no "
                      "specification limit; it reports the triad model and each fit's χ²/ν "
                      "(docs/field.md)")
#: The group of the static gyro fit (FL.2) in :attr:`FieldResult.quality`.
_STATIC_GYRO_GROUP = "gyro (static poses)"


def field_decision(quality: tuple[FitQuality, ...] = ()) -> Decision:
    """Return a field calibration's *no decision*, each misfit fit's summary in its notes."""
    return no_decision(NO_DECISION_REASON, notes=tuple(q.summary() for q in quality if q.misfit))


def accel_matrix(theta: NDArray[np.float64]) -> _F64:
    """Return I + M_a of (FL.1) for θ = (b, s, α) of (F.1)."""
    t = np.array([[1.0, -theta[6], theta[7]], [0.0, 1.0, -theta[8]], [0.0, 0.0, 1.0]])
    return np.asarray(np.linalg.inv(t @ np.diag(1.0 + theta[3:6])), dtype=np.float64)


def _accel_triad(theta: _F64) -> _F64:
    """(b, M row-major[, K2[, K3]]) of (FL.1) from θ of (F.1), (F.1′) or (F.1⁗).

    K2 = k2 and K3 = k3 to first order.
    """
    return np.concatenate([theta[:3], (accel_matrix(theta) - np.eye(3)).ravel(), theta[9:]])


def _jacobian(fun: Any, x: _F64, rel: float = 1e-6) -> _F64:
    cols = []
    for i in range(x.size):
        h = rel * max(1.0, abs(x[i]))
        up, dn = x.copy(), x.copy()
        up[i] += h
        dn[i] -= h
        cols.append((fun(up) - fun(dn)) / (2 * h))
    return np.column_stack(cols)


def triad_from_field(accel_form: str, accel_values: _F64, accel_cov: _F64,
                     gyro_static: _F64, gyro_static_cov: _F64,
                     gyro_m: _F64 | None, gyro_m_cov: _F64 | None,
                     gyro_accel_cov: _F64 | None) -> tuple[list[str], _F64, _F64]:
    """Return (names, values, covariance) of the triad model (FL.1) (module docstring).

    Parameters
    ----------
    accel_form : {"gravity-norm", "six-position"}
        θ of (F.1) (9 values) or (F.1′) (12), or (b, M row-major) of (F.10) (12 values).
    accel_values, accel_cov
        The accelerometer estimate and its covariance (Birge-scaling not applied).
    gyro_static, gyro_static_cov
        Gyro bias (3) [rad/s], and G (9, row-major) [rad/s per m/s²] when fitted, with their
        covariance.
    gyro_m, gyro_m_cov, gyro_accel_cov
        The gyro M (9, row-major), its covariance and its cross-covariance with the accel
        values (9 × len(accel_values)); None when no rotation was fitted (the gyro triad is
        then left out: a bias alone is not a triad).
    """
    if accel_form == "gravity-norm":
        jac = _jacobian(_accel_triad, accel_values)
        a_vals = _accel_triad(accel_values)
    else:
        jac = np.eye(accel_values.size)
        a_vals = accel_values.copy()
    # 12 values of (b, M), then K2 (F.1′) and K3 (F.1⁗) when fitted (K3 only with K2)
    names = list(triad_parameter_names("accel", "triad", k2=a_vals.size >= 15,
                                       k3=a_vals.size == 18))
    values = [a_vals]
    blocks = [jac @ accel_cov @ jac.T]
    if gyro_m is None or gyro_m_cov is None:
        cov = blocks[0]
        return names, np.concatenate(values), 0.5 * (cov + cov.T)
    with_g = gyro_static.size == 12
    names += list(triad_parameter_names("gyro", "triad", g_sensitivity=with_g))
    values.append(np.concatenate([gyro_static[:3], gyro_m, gyro_static[3:]]))
    k = a_vals.size
    n = k + 12 + (9 if with_g else 0)
    static_idx = [k, k + 1, k + 2, *range(k + 12, n)]
    cov = np.zeros((n, n))
    cov[:k, :k] = blocks[0]
    cov[np.ix_(static_idx, static_idx)] = gyro_static_cov
    cov[k + 3:k + 12, k + 3:k + 12] = gyro_m_cov
    if gyro_accel_cov is not None:
        cross = gyro_accel_cov @ jac.T                       # (9, 12 or 15)
        cov[k + 3:k + 12, :k] = cross
        cov[:k, k + 3:k + 12] = cross.T
    return names, np.concatenate(values), 0.5 * (cov + cov.T)


@dataclass(frozen=True)
class FieldResult(ResultDefaults):
    """A field calibration (the result contract of docs/procedures.md).

    A :class:`~imucalib.models.procedure_result.ProcedureResult`: ``calibration`` is
    :attr:`result`; ``decision`` *no decision* (:func:`field_decision`), so ``passed`` is None.

    Attributes
    ----------
    unit, source : str
        The IMU and the log analysed.
    result : CalibrationResult
        The triad model (accelerometer; gyro when rotations were fitted), model ``"triad"``:
        what ``imucalib apply`` reads.
    accel_form : {"gravity-norm", "six-position"}
    gyro_form : str
        ``"rotations"`` (gravity-referenced and/or known-angle turns), or ``"bias only"``.
    gyro_static_names : tuple of str
        ``gyro_bias_x`` … and, when fitted, ``gyro_G_xx`` … (from the static poses).
    gyro_static_values, gyro_static_cov : ndarray
        Their values and covariance, Birge-scaled where the static fit (FL.2) is a misfit
        (also in `result` when the gyro triad is).
    gravity_mps2, gravity_std_mps2 : float
        Local g used and its standard uncertainty. [m/s²]
    threshold_factor : float
        The detector's k (chosen or given).
    poses : list of dict
        Per static pose: times, means, σ, the fit's residual.
    rotations : list of dict
        Per rotation: times, kind, angle, residual.
    coverage : dict
        Missing directions and the poses needed per parameter for the targets.
    quality : tuple of FitQuality
        χ²/ν of each fit (accel, gyro bias, gyro rotations).
    notes : tuple of str
    details : dict
        The accelerometer's fitted values and covariance as fitted, the latitude, the settings.
    extra_rows : list of ReportedParameter
        Estimates outside the triad model (the accelerometer's bias rates, (F.1″)), σ
        Birge-scaled as the accelerometer fit's.
    omitted : tuple of str
        The parts a sound fit could not give, each with why (a *partial result*: docs/field.md,
        "A partial result"; ``imucalib calibrate`` exits 3).
    model_selection : tuple of dict
        Per fitted group, the optional terms chosen and every candidate's χ², ν and criterion
        (:meth:`~imucalib.estimation.term_selection.TermChoice.to_dict`; docs/field.md,
        "Model terms").
    procedure : str
    decision : Decision
        *No decision* (:func:`field_decision`): a field calibration has no acceptance limits.
    """

    unit: str
    source: str
    result: CalibrationResult
    accel_form: str
    gyro_form: str
    gyro_static_names: tuple[str, ...]
    gyro_static_values: _F64
    gyro_static_cov: _F64
    gravity_mps2: float
    gravity_std_mps2: float
    threshold_factor: float
    poses: list[dict[str, Any]]
    rotations: list[dict[str, Any]]
    coverage: dict[str, Any]
    quality: tuple[FitQuality, ...]
    notes: tuple[str, ...] = ()
    details: dict[str, Any] = field(default_factory=dict)
    extra_rows: list[ReportedParameter] = field(default_factory=list)
    model_selection: tuple[dict[str, Any], ...] = ()
    omitted: tuple[str, ...] = ()
    procedure: str = "field"
    decision: Decision = field(default_factory=field_decision)

    @property
    def fit_quality(self) -> tuple[FitQuality, ...]:
        """The accelerometer and gyro fits' χ²/ν and misfit verdicts (:attr:`quality`)."""
        return tuple(self.quality)

    @property
    def calibration(self) -> CalibrationResult:
        """The triad model (:attr:`result`)."""
        return self.result

    def parameter_rows(self) -> list[ReportedParameter]:
        """Every parameter: name, value, σ (Birge-scaled on a misfit), SI unit, σ before scaling.

        The calibration's parameters (σ scaled per triad as its fit, docs/field.md step 6), then,
        when no rotation was fitted, the static gyro bias (and G) of (FL.2), then the
        :attr:`extra_rows`. The gyro bias and G come from the static fit (FL.2), whose Birge
        ratio their covariance holds already (:attr:`gyro_static_cov`): their ``std_noise`` is
        that σ divided by it (docs/processing-estimation.md, Eq. (3)).
        """
        static = set(self.gyro_static_names)
        scale = next((q.sigma_scale for q in self.quality if q.group == _STATIC_GYRO_GROUP),
                     1.0)
        rows = [r._replace(std_noise=r.std_noise / scale) if r.name in static else r
                for r in calibration_rows(self.result)]
        if not self.result.has_triad("gyro"):
            sb = np.sqrt(np.diag(self.gyro_static_cov))
            rows += [ReportedParameter(n, float(v), float(s), triad_parameter_unit(n),
                                       float(s) / scale) for n, v, s in
                     zip(self.gyro_static_names, self.gyro_static_values, sb, strict=True)]
        return rows + list(self.extra_rows)

    def triad_parameters(self) -> TriadParameters:
        """(names, values, covariance Birge-scaled) for :func:`~imucalib.estimation.combine`."""
        cal = self.result
        return list(cal.param_names), cal.values.copy(), cal.covariance_scaled.copy()

    def to_dict(self) -> dict[str, Any]:
        """Return the whole result as JSON-able data."""
        rows = self.parameter_rows()
        out = {
            "procedure": self.procedure, "unit": self.unit, "source": self.source,
            "passed": self.passed, "accel_form": self.accel_form, "gyro_form": self.gyro_form,
            "parameters": {r.name: {"value": r.value, "std": r.std, "unit": r.unit}
                           for r in rows},
            "fit_quality": [{"group": q.group, "chi2": q.chi2, "dof": q.dof,
                             "reduced_chi2": q.reduced_chi2, "misfit": q.misfit,
                             "sigma_scale": q.sigma_scale} for q in self.quality],
            "gravity_mps2": self.gravity_mps2, "gravity_std_mps2": self.gravity_std_mps2,
            "threshold_factor": self.threshold_factor,
            "poses": self.poses, "rotations": self.rotations, "coverage": self.coverage,
            "result": self.result.to_dict(), "notes": list(self.notes),
            "model_selection": list(self.model_selection), "omitted": list(self.omitted),
            "details": self.details,
        }
        return dict(json_safe(out))  # type: ignore[call-overload]


def calibration_result(unit: str, source: str, names: list[str], values: _F64, cov: _F64,
                       quality: tuple[FitQuality, ...], notes: tuple[str, ...],
                       provenance: Provenance) -> CalibrationResult:
    """Build the CalibrationResult; each triad's FitQuality renamed to its group."""
    groups: list[FitQuality] = []
    for q in quality:
        g = q.group.split(" ")[0]
        if any(n.startswith(g + "_") for n in names) and g not in [x.group for x in groups]:
            groups.append(replace(q, group=g))
    return CalibrationResult(
        sensor_id=unit, procedure="field", model="triad", param_names=tuple(names),
        values=values, covariance=cov, units={n: triad_parameter_unit(n) for n in names},
        provenance=provenance, notes=notes, fit_quality=tuple(groups))

