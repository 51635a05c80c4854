"""The tumble's analysis: from a recording to each accelerometer's coefficients (docs/tumble.md).

1. Every tumble record reduced (:mod:`~imucalib.procedures.tumble.observations`): the mean of
   each accelerometer, its standard error, the body-frame specific force (T.10).
2. Per head axis o, each accelerometer i in the plane it turns (the two body axes ⟂ o), with
   p the third body axis (the pendulous axis PA = +p_b): the gravity angle θ_k = atan2(f_p, f_i)
   of each position (T.11), so that a_i = g cos θ, a_p = g sin θ; every position of the
   sequence (tag ``positions=N``) must be there, else :class:`~imucalib.errors.MissingSegmentError`
   names the angles missing.
3. The Fourier fit (least squares at the measured angles, or the DFT at the commanded ones),
   the inversion to K0, K1, δ, K2 − Kpp, Kip, K3, Koq with full covariance and the χ² acted on
   (:mod:`~imucalib.procedures.tumble.fourier`); the coefficients asked for must be resolvable
   (:class:`~imucalib.errors.InsufficientExcitationError` names the others).
4. The drift check: each sequence's closing 0° record against its first (z-score in the notes).
5. The triad's parameters (T.12): b_i = K1·K0, M_ii = K1 − 1, M_ip = K1·δ,
   K2_i = (K2 − Kpp)/K1 (the twin's h(u) with u = K1·a_i), combined over the head axes that
   test the same accelerometer by GLS.

The result satisfies the result contract (:class:`~imucalib.models.procedure_result.
ProcedureResult`, docs/procedures.md): part of a triad model (no ``calibration``), and a
decision on the triad's parameters against the unit's specification (the recording's
``[imu.limits]``: accelerometer bias, scale factor, misalignment; the plan's ``[acceptance]``
rule), *no decision* when the specification gives none of those limits
(:mod:`~imucalib.procedures.common.spec_decision`).

Contents
--------
:class:`TumbleOptions`, :class:`AccelerometerTumble`, :class:`TumbleResult`,
:func:`analyze_tumble`, :func:`tumble_sequences`, :func:`head_angle_covariance`.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imucalib import units
from imucalib.conventions import AXES
from imucalib.errors import InvalidInputError, MissingSegmentError, RecordingError
from imucalib.estimation.linear import LsqSolution, solve_weighted_lsq
from imucalib.io.opening import open_recording
from imucalib.io.reader import Recording
from imucalib.io.streams import DEVICE_IMU
from imucalib.models.decision import Decision
from imucalib.models.earth import Site
from imucalib.models.fit_quality import FitQuality
from imucalib.models.procedure_result import ResultDefaults, TriadParameters
from imucalib.models.reported import ReportedParameter
from imucalib.procedures.common.spec_decision import Specification, decide_triad
from imucalib.procedures.tumble.fourier import (
    COEFFICIENTS,
    SIGNATURE_HARMONICS,
    TumbleFit,
    equally_spaced,
    fit_fourier,
    fourier_dft,
    identifiable_subset,
    invert_coefficients,
    resolvable_coefficients,
)
from imucalib.procedures.tumble.observations import (
    TumbleProcessing,
    TumbleWindow,
    extract_tumble_windows,
)
from imucalib.procedures.tumble.roles import TUMBLE_DRIFT, TUMBLE_POSITION

__all__ = ["AccelerometerTumble", "TumbleOptions", "TumbleResult", "analyze_tumble",
           "head_angle_covariance", "tumble_sequences"]

_F64 = NDArray[np.float64]
#: SI unit of each coefficient.
COEFFICIENT_UNITS: dict[str, str] = {
    "K0": "m/s^2", "K1": "1", "delta": "rad", "K2": "1/(m/s^2)", "Kip": "1/(m/s^2)",
    "K3": "1/(m/s^2)^2", "Koq": "1/(m/s^2)"}
#: Drift between a sequence's first and closing 0° records flagged above this many σ.
DRIFT_Z = 3.0
#: The FitQuality group of the GLS that combines the head axes (:attr:`TumbleResult.triad_fit`).
COMBINATION_GROUP = "accel triad (head axes combined)"


@dataclass(frozen=True)
class TumbleOptions:
    """Options of :func:`analyze_tumble`.

    Attributes
    ----------
    unit : str, optional
        The IMU stream (the only one when omitted).
    coefficients : sequence of str, optional
        The coefficients to estimate (:data:`~imucalib.procedures.tumble.fourier.COEFFICIENTS`);
        default: all that the positions resolve.
    method : {"lsq", "dft"}
        The Fourier stage: least squares at the measured angles, or the DFT at the commanded
        (equally spaced) ones.
    gravity_mps2 : float, optional
        Local gravity; default normal gravity at the recorded latitude.
    gravity_rel_std : float, optional
        Its relative standard uncertainty (Type B on K1); default 2e-5 for normal gravity, 0 for
        a given value.
    angle_std_arcsec : float
        Type B: the RMS over a revolution of the head's angle error (a dividing head's or
        encoder's once- and twice-per-revolution error: 1″ for a high-grade table), modelled as
        ε(φ) = Σ_{n=1,2} a_n cos nφ + b_n sin nφ with a_n, b_n of σ_θ/√2 each and added to the
        means' covariance, Eq. (T.13). [″]
    processing : TumbleProcessing
    """

    unit: str | None = None
    coefficients: Sequence[str] | None = None
    method: str = "lsq"
    gravity_mps2: float | None = None
    gravity_rel_std: float | None = None
    angle_std_arcsec: float = 1.0
    processing: TumbleProcessing = field(default_factory=TumbleProcessing)

    def __post_init__(self) -> None:
        if not (math.isfinite(self.angle_std_arcsec) and self.angle_std_arcsec >= 0):
            raise InvalidInputError(f"`angle_std_arcsec` must be ≥ 0; got "
                                    f"{self.angle_std_arcsec!r}")
        if self.method not in ("lsq", "dft"):
            raise InvalidInputError(f"`method` must be 'lsq' or 'dft'; got {self.method!r}")
        if self.coefficients is not None:
            bad = [c for c in self.coefficients if c not in COEFFICIENTS]
            if bad:
                raise InvalidInputError(f"`coefficients` must be names of {list(COEFFICIENTS)}; "
                                        f"got {bad}")


@dataclass(frozen=True)
class AccelerometerTumble:
    """One accelerometer tumbled about one head axis.

    Attributes
    ----------
    sensor : str
        The accelerometer (input axis IA = +sensor_b).
    head_axis : str
        The body axis along the head axis (its OA).
    pendulous_axis : str
        The third body axis (PA = +pendulous_b; δ tilts IA towards it).
    fit : TumbleFit
        Coefficients, covariance, Fourier stage, χ².
    drift : tuple of (str, float, float)
        Per sequence (pass): closing 0° minus first 0° mean, and its σ. [m/s²]
    """

    sensor: str
    head_axis: str
    pendulous_axis: str
    fit: TumbleFit
    drift: tuple[tuple[str, float, float], ...] = ()

    @property
    def key(self) -> str:
        """``<sensor>_head_<head axis>``, the suffix of its parameter names."""
        return f"{self.sensor}_head_{self.head_axis}"

    def triad(self, *, scaled: bool = True) -> tuple[list[str], _F64, _F64]:
        """(T.12): names, values and covariance of b_i, M_ii, M_ip (and K2_i when fitted).

        The covariance is J·C_q·Jᵀ, C_q Birge-scaled when the fit is a misfit, or with
        ``scaled=False`` the noise-only one.
        """
        fit = self.fit
        q = fit.q_values
        Cq = fit.q_covariance * fit.quality.sigma_scale**2 if scaled else fit.q_covariance
        idx = {n: k for k, n in enumerate(fit.names)}
        i, p = self.sensor, self.pendulous_axis
        names = [f"accel_bias_{i}", f"accel_M_{i}{i}"]
        rows = [np.eye(q.size)[idx["K0"]], np.eye(q.size)[idx["K1"]]]
        values = [q[idx["K0"]], q[idx["K1"]] - 1.0]
        if "delta" in idx:
            names.append(f"accel_M_{i}{p}")
            rows.append(np.eye(q.size)[idx["delta"]])
            values.append(q[idx["delta"]])
        if "K2" in idx:
            k1, k2 = q[idx["K1"]], q[idx["K2"]]
            names.append(f"accel_K2_{i}")
            row = np.zeros(q.size)
            row[idx["K2"]] = 1.0 / k1**2
            row[idx["K1"]] = -2.0 * k2 / k1**3
            rows.append(row)
            values.append(k2 / k1**2)
        J = np.array(rows)
        return names, np.array(values), J @ Cq @ J.T


@dataclass(frozen=True)
class TumbleResult(ResultDefaults):
    """The tumble's result for one IMU (docs/tumble.md).

    It satisfies :class:`~imucalib.models.procedure_result.ProcedureResult`: no
    ``calibration`` (it estimates the accelerometers' part of a triad model,
    :meth:`triad_parameters`), ``decision`` against the unit's specification
    (:attr:`decision`).

    Attributes
    ----------
    unit : str
    gravity_mps2, gravity_rel_std : float
        The local gravity used and its relative Type B σ.
    accelerometers : tuple of AccelerometerTumble
        One per (head axis, accelerometer in its plane).
    method : str
    windows : tuple of TumbleWindow
    triad_fit : FitQuality or None
        χ² of the combination of the head axes' triad parameters (T.12).
    notes : tuple of str
    specification : Specification
        The unit's limits and the decision rule the recording states (none: no decision).
    """

    unit: str
    gravity_mps2: float
    gravity_rel_std: float
    accelerometers: tuple[AccelerometerTumble, ...]
    method: str
    windows: tuple[TumbleWindow, ...]
    triad_fit: FitQuality | None = None
    notes: tuple[str, ...] = ()
    procedure: str = "tumble"
    specification: Specification = field(default_factory=Specification)

    @property
    def decision(self) -> Decision:
        """The triad's b_i, M_ii, M_ip against the specification's accelerometer limits.

        Its check ``specification`` under the recording's rule (docs/tumble.md, "Decision");
        *no decision* when the specification gives no accelerometer bias, scale-factor or
        misalignment limit (K2 has none). Each misfit in its notes.
        """
        return decide_triad(self.specification, self.triad_parameters(), test="the tumble",
                            what="it estimates the accelerometers' coefficients "
                                 "(docs/tumble.md)",
                            notes=tuple(q.summary() for q in self.fit_quality if q.misfit))

    @property
    def fit_quality(self) -> tuple[FitQuality, ...]:
        """Each accelerometer's Fourier fit and the triad fit: χ²/ν and misfit verdicts."""
        own = tuple(a.fit.quality for a in self.accelerometers)
        return own if self.triad_fit is None else (*own, self.triad_fit)

    def get(self, sensor: str, head_axis: str) -> AccelerometerTumble:
        """Return the fit of accelerometer `sensor` about head axis `head_axis`.

        Raises
        ------
        InvalidInputError
            No such pair in this result.
        """
        for a in self.accelerometers:
            if a.sensor == sensor and a.head_axis == head_axis:
                return a
        raise InvalidInputError(f"no accelerometer {sensor} tumbled about head axis {head_axis}; "
                                f"have {[a.key for a in self.accelerometers]}")

    def _k1_std(self, a: AccelerometerTumble) -> float:
        k1 = a.fit.value("K1")
        return math.hypot(a.fit.std("K1"), k1 * self.gravity_rel_std)

    def parameter_rows(self) -> list[ReportedParameter]:
        """Every fit's coefficients, then the triad's parameters (T.12), SI.

        ``std`` is the σ reported: a coefficient's from its fit's covariance, Birge-scaled when
        the fit is a misfit (:class:`~imucalib.procedures.tumble.fourier.TumbleFit`), K1's
        with the gravity's relative Type B σ added (K1·σ_g/g in quadrature); a triad
        parameter's from :meth:`triad_parameters`. ``std_noise`` is the same σ before any
        Birge scaling: a coefficient's from ``fit.covariance_noise`` (K1's with the gravity's
        Type B term, which is no fit's); a triad parameter's the same combination of the head
        axes (the weights of the reported GLS mean) applied to each fit's noise-only
        covariance, not scaled by :attr:`triad_fit`, the gravity's Type B σ on M_ii added.
        Where no fit is a misfit the two are equal.
        """
        rows = []
        for a in self.accelerometers:
            for name in a.fit.names:
                if name == "K1":
                    std = self._k1_std(a)
                    noise = math.hypot(a.fit.std_noise("K1"),
                                       a.fit.value("K1") * self.gravity_rel_std)
                else:
                    std, noise = a.fit.std(name), a.fit.std_noise(name)
                rows.append(ReportedParameter(f"{name}_{a.key}", a.fit.value(name), std,
                                              COEFFICIENT_UNITS[name], noise))
        names, values, cov = self.triad_parameters()
        noise_std = np.sqrt(np.diag(self._triad_covariance_noise()))
        for n, v, s, sn in zip(names, values, np.sqrt(np.diag(cov)), noise_std, strict=True):
            rows.append(ReportedParameter(n, float(v), float(s), "m/s^2" if "_bias_" in n else
                                          ("1/(m/s^2)" if "_K2_" in n else "1"), float(sn)))
        return rows

    def triad_parameters(self) -> TriadParameters:
        """Return the triad's b_i, M_ii, M_ip, K2_i with covariance, (T.12), head axes combined.

        Each (head axis, accelerometer) gives its own; a parameter given by two head axes is
        their GLS mean (independent records), its covariance scaled by the Birge ratio² of
        :attr:`triad_fit` when the head axes disagree beyond their σ (a misfit). The gravity's
        Type B σ is added to M_ii. The covariance is the one reported (:meth:`parameter_rows`
        ``std``).
        """
        names, values, cov = _combine([a.triad() for a in self.accelerometers])
        if self.triad_fit is not None:
            cov = cov * self.triad_fit.sigma_scale**2
        return names, values, self._add_gravity(names, values, cov)

    def _add_gravity(self, names: Sequence[str], values: _F64, cov: _F64) -> _F64:
        """Add the gravity's relative Type B σ to each M_ii of `cov` (in place; returned)."""
        for k, n in enumerate(names):
            if n.startswith("accel_M_") and n[-1] == n[-2]:
                cov[k, k] += ((1.0 + values[k]) * self.gravity_rel_std) ** 2
        return cov

    def _triad_covariance_noise(self) -> _F64:
        """Return the covariance of :meth:`triad_parameters` before Birge scaling.

        The reported GLS mean x̂ = W·t (W = (AᵀC⁻¹A)⁻¹AᵀC⁻¹, C the head axes' covariances as
        scaled) with C replaced by the noise-only ones: W·C_noise·Wᵀ, plus the gravity's Type B
        σ; exactly the reported covariance when no fit is a misfit.
        """
        scaled = [a.triad() for a in self.accelerometers]
        if all(not a.fit.quality.misfit for a in self.accelerometers):
            names, values, cov = _combine(scaled)
        else:
            noise = [a.triad(scaled=False) for a in self.accelerometers]
            names, values, _ = _combine(scaled)
            cov = _combination_weights(scaled, names)
            cov = cov @ _block_diag([p[2] for p in noise]) @ cov.T
        return self._add_gravity(names, values, cov)

    def to_dict(self) -> dict[str, Any]:
        """Return the whole result as JSON-able data."""
        names, values, cov = self.triad_parameters()
        return {
            "procedure": self.procedure, "unit": self.unit, "passed": self.passed,
            "decision": self.decision.to_dict(),
            "method": self.method, "gravity_mps2": self.gravity_mps2,
            "gravity_rel_std": self.gravity_rel_std,
            "parameters": [r._asdict() for r in self.parameter_rows()],
            "triad": {"names": names, "values": values.tolist(), "covariance": cov.tolist(),
                      "fit": None if self.triad_fit is None else {
                          "chi2": self.triad_fit.chi2, "dof": self.triad_fit.dof,
                          "misfit": self.triad_fit.misfit,
                          "summary": self.triad_fit.summary()}},
            "accelerometers": [{
                "sensor": a.sensor, "head_axis": a.head_axis, "pendulous_axis": a.pendulous_axis,
                "coefficients": list(a.fit.names), "values": a.fit.values.tolist(),
                "covariance": a.fit.covariance.tolist(),
                "covariance_noise": a.fit.covariance_noise.tolist(),
                "fourier": {"method": a.fit.fourier.method, "names": list(a.fit.fourier.names),
                            "values": a.fit.fourier.values.tolist(),
                            "std": np.sqrt(np.diag(a.fit.fourier.covariance)).tolist()},
                "harmonic_residuals": a.fit.harmonic_residuals,
                "fit": {"chi2": a.fit.quality.chi2, "dof": a.fit.quality.dof,
                        "misfit": a.fit.quality.misfit, "summary": a.fit.quality.summary()},
                "drift": [{"pass": d[0], "value_mps2": d[1], "std_mps2": d[2]}
                          for d in a.drift]} for a in self.accelerometers],
            "records": [{"step": w.step_index, "label": w.label, "role": w.role,
                         "axis": w.axis, "angle_deg": w.angle_deg, "pass": w.direction,
                         "mean_mps2": w.mean.tolist(), "se_mps2": w.se.tolist(),
                         "duration_s": w.duration_s} for w in self.windows],
            "notes": list(self.notes),
        }


def _triad_order(name: str) -> tuple[int, str]:
    kind = name.split("_")[1]
    return ({"bias": 0, "M": 1, "K2": 2}.get(kind, 3), name)


def _combination_design(parts: Sequence[tuple[list[str], _F64, _F64]], names: Sequence[str]
                        ) -> _F64:
    """Return A of the combination: row k (the parts' k-th parameter) picks its name."""
    size = sum(len(p[0]) for p in parts)
    A = np.zeros((size, len(names)))
    A[np.arange(size), [list(names).index(n) for p in parts for n in p[0]]] = 1.0
    return A


def _combination_weights(parts: Sequence[tuple[list[str], _F64, _F64]], names: Sequence[str]
                         ) -> _F64:
    """W = (AᵀC⁻¹A)⁻¹AᵀC⁻¹ of the GLS mean x̂ = W·t of :func:`_combine_fit` (C of `parts`)."""
    A = _combination_design(parts, names)
    CiA = np.linalg.solve(_block_diag([p[2] for p in parts]), A)
    return np.asarray(np.linalg.solve(A.T @ CiA, CiA.T), dtype=np.float64)


def _combine_fit(parts: Sequence[tuple[list[str], _F64, _F64]]
                 ) -> tuple[list[str], LsqSolution | None]:
    """GLS of the parameters several head axes give (the one solver): names and the solution.

    The parts are independent: their covariance is block-diagonal, and the solution's χ² is
    Σ_parts rᵀC⁻¹r of the parts against the combined values (ν = rows − parameters).
    """
    names = sorted({n for p in parts for n in p[0]}, key=_triad_order)
    if not names:
        return [], None
    t = np.concatenate([p[1] for p in parts])
    A = _combination_design(parts, names)
    return names, solve_weighted_lsq(A, t, covariance=_block_diag([p[2] for p in parts]),
                                     param_names=names, group=COMBINATION_GROUP,
                                     context="combination of the head axes")


def _combine(parts: Sequence[tuple[list[str], _F64, _F64]]
             ) -> tuple[list[str], _F64, _F64]:
    """GLS of the parameters several head axes give: names, values, covariance (noise only)."""
    names, sol = _combine_fit(parts)
    if sol is None:
        return [], np.zeros(0), np.zeros((0, 0))
    return names, np.array(sol.estimate), np.array(sol.covariance_noise)


def _block_diag(blocks: Sequence[_F64]) -> _F64:
    n = sum(b.shape[0] for b in blocks)
    out = np.zeros((n, n))
    k = 0
    for b in blocks:
        out[k:k + b.shape[0], k:k + b.shape[0]] = b
        k += b.shape[0]
    return out


def tumble_sequences(windows: Sequence[TumbleWindow]) -> dict[str, list[TumbleWindow]]:
    """Return the position records (not the drift checks) by head axis, checked complete.

    Raises
    ------
    MissingSegmentError
        A head axis whose sequence (tag ``positions=N``) lacks angles (named), per pass.
    """
    out: dict[str, list[TumbleWindow]] = {}
    for w in windows:
        if w.role == TUMBLE_POSITION:
            out.setdefault(w.axis, []).append(w)
    if not out:
        raise MissingSegmentError("no tumble position record (role tumble.position) completed")
    for axis, ws in out.items():
        n = max(w.n_positions for w in ws)
        if n <= 0:
            continue
        want = [360.0 * k / n for k in range(n)]
        for direction in sorted({w.direction for w in ws}):
            got = {round(w.angle_deg, 6) for w in ws if w.direction == direction}
            missing = [a for a in want if round(a, 6) not in got]
            if missing:
                raise MissingSegmentError(
                    f"head axis {axis}{f' ({direction})' if direction else ''}: the "
                    f"{n}-position sequence lacks the position(s) at "
                    f"{', '.join(f'{a:g}°' for a in missing)} (not recorded, or the record "
                    "failed); every position is needed for the Fourier reduction")
    return out


def _drift(ws_all: Sequence[TumbleWindow], axis: str, k: int) -> list[tuple[str, float, float]]:
    out = []
    for d in (w for w in ws_all if w.role == TUMBLE_DRIFT and w.axis == axis):
        first = [w for w in ws_all if w.role == TUMBLE_POSITION and w.axis == axis
                 and w.direction == d.direction and round(w.angle_deg, 6) == round(d.angle_deg,
                                                                                   6)]
        if first:
            f = first[0]
            out.append((d.direction or "all", float(d.mean[k] - f.mean[k]),
                        float(math.hypot(d.se[k], f.se[k]))))
    return out


def head_angle_covariance(head_angle_rad: _F64, slope_mps2: _F64, angle_std_rad: float
                          ) -> _F64:
    """Return the means' covariance from the head's angle error, Eq. (T.13).

    ε(φ) = Σ_{n=1,2} a_n cos nφ + b_n sin nφ, a_n, b_n ~ N(0, σ_θ²/2) (RMS σ_θ over a
    revolution); mean k moves by s_k·ε(φ_k), s_k = ∂y/∂θ = −g sin θ_k (its sign cancels):
    C_kl = s_k s_l (σ_θ²/2) Σ_n cos n(φ_k − φ_l).

    Parameters
    ----------
    head_angle_rad : ndarray, shape (M,)
        The head (table) angle φ_k of each mean. [rad]
    slope_mps2 : ndarray, shape (M,)
        s_k. [m/s² per rad]
    angle_std_rad : float
        σ_θ. [rad]
    """
    d = head_angle_rad[:, None] - head_angle_rad[None, :]
    kernel = 0.5 * angle_std_rad**2 * (np.cos(d) + np.cos(2 * d))
    return np.asarray(slope_mps2[:, None] * kernel * slope_mps2[None, :], dtype=np.float64)


def _fit_one(ws: list[TumbleWindow], i: int, p: int, g: float, opt: TumbleOptions
             ) -> TumbleFit:
    """Fit (steps 2–3 of the module docstring) accelerometer i (PA = p) of one head axis."""
    y = np.array([w.mean[i] for w in ws])
    theta = np.array([math.atan2(w.force_b[p], w.force_b[i]) for w in ws])  # (T.11)
    C = head_angle_covariance(np.array([w.table_angles_rad[0] for w in ws]),
                              g * np.sin(theta), opt.angle_std_arcsec * units.ARCSEC)
    C += np.diag(np.array([w.se[i] for w in ws]) ** 2)
    distinct = sorted({round(w.angle_deg, 6) for w in ws})
    n_spaced = len(distinct) if equally_spaced(np.radians(distinct), tol_rad=1e-6) else None
    if opt.coefficients is not None:
        wanted = list(opt.coefficients)
    elif n_spaced is not None:
        wanted = list(resolvable_coefficients(n_spaced))
    else:
        wanted = list(identifiable_subset(theta, g))
    if opt.method == "dft":
        nominal = np.array([math.atan2(w.force_nominal_b[p], w.force_nominal_b[i]) for w in ws])
        keys = np.round(np.degrees(np.mod(nominal, 2 * math.pi)), 6)
        uniq = sorted(set(keys.tolist()))
        # the passes' mean at each angle: an averaging operator on the means
        avg = np.array([(keys == u) / np.sum(keys == u) for u in uniq])
        first = [int(np.argmax(keys == u)) for u in uniq]
        fourier = fourier_dft(nominal[first], avg @ y, avg @ C @ avg.T, tol_rad=1e-6)
    else:
        top = (n_spaced // 2 if n_spaced is not None
               else max(SIGNATURE_HARMONICS[c][0] for c in wanted))
        fourier = fit_fourier(theta, y, C, top, n_positions=n_spaced)
    return invert_coefficients(fourier, g, wanted, n_positions=n_spaced,
                               group=f"accel {AXES[i]}")


def analyze_tumble(recording: Recording | str | os.PathLike[str], *,
                   options: TumbleOptions | None = None,
                   progress: Callable[[float], None] | None = None) -> TumbleResult:
    """Analyse a tumble recording (module docstring).

    Raises
    ------
    RecordingError
        Not a tumble recording, no latitude, no such unit.
    MissingSegmentError
        A position of a sequence missing, a record with dropouts.
    InsufficientExcitationError
        Coefficients asked for that the positions cannot resolve (named).
    InvalidInputError
        The DFT form asked for positions that are not equally spaced.
    """
    opt = options or TumbleOptions()
    if isinstance(recording, Recording):
        return _analyze(recording, opt, progress)
    with open_recording(Path(recording)) as rec:
        return _analyze(rec, opt, progress)


def _analyze(rec: Recording, opt: TumbleOptions,
             progress: Callable[[float], None] | None) -> TumbleResult:
    lat = float(rec.metadata.get("latitude_deg", math.nan))
    if not math.isfinite(lat):
        raise RecordingError(f"{rec.path} does not record the latitude (latitude_deg): the "
                             "local gravity needs it (or give gravity_mps2)")
    site = Site(latitude_deg=lat, heading_deg=float(rec.metadata.get("heading_deg", 0.0)),
                gravity_mps2=opt.gravity_mps2)
    g = site.local_gravity_mps2
    g_rel = (opt.gravity_rel_std if opt.gravity_rel_std is not None
             else (0.0 if opt.gravity_mps2 is not None else 2e-5))
    units_ = [s.unit for s in rec.streams if s.device == DEVICE_IMU]
    unit = opt.unit or (units_[0] if len(units_) == 1 else None)
    if unit is None:
        raise RecordingError(f"{rec.path} has IMU streams {units_}: say which unit to analyse")
    windows = extract_tumble_windows(rec, unit, g, site.earth_rate_t_rps,
                                     processing=opt.processing, progress=progress)
    sequences = tumble_sequences(windows)
    accels = []
    notes = [f"local gravity {g:.7g} m/s² ({'given' if opt.gravity_mps2 else 'normal'} gravity, "
             f"relative σ {g_rel:.1g}); Kpp = Koo = 0 assumed: K0 holds Kpp·g², K2 is K2 − Kpp"]
    for head in sorted(sequences, key=AXES.index):
        o = AXES.index(head)
        for i in (k for k in range(3) if k != o):
            p = 3 - o - i
            fit = _fit_one(sequences[head], i, p, g, opt)
            drift = _drift(windows, head, i)
            accels.append(AccelerometerTumble(sensor=AXES[i], head_axis=head,
                                              pendulous_axis=AXES[p], fit=fit,
                                              drift=tuple(drift)))
            if fit.quality.misfit:
                notes.append(fit.quality.summary() + f" (head axis {head})")
            for direction, d, s in drift:
                if abs(d) > DRIFT_Z * s:
                    notes.append(f"accel {AXES[i]}, head axis {head} ({direction}): the closing "
                                 f"0° record differs from the first by {d:.3g} m/s² "
                                 f"({d / s:+.1f}σ): the output drifted during the sequence")
    triad_fit = _combination_quality(accels)
    if triad_fit is not None and triad_fit.dof > 0:
        notes.append(triad_fit.summary())
    if progress is not None:
        progress(1.0)
    return TumbleResult(unit=unit, gravity_mps2=g, gravity_rel_std=g_rel,
                        accelerometers=tuple(accels), method=opt.method, windows=tuple(windows),
                        triad_fit=triad_fit, notes=tuple(notes),
                        specification=Specification.of_metadata(rec.metadata))


def _combination_quality(accels: Sequence[AccelerometerTumble]) -> FitQuality | None:
    """χ² of the GLS that combines the head axes' triad parameters (their agreement)."""
    _, sol = _combine_fit([a.triad() for a in accels])
    return None if sol is None else sol.fit_quality
