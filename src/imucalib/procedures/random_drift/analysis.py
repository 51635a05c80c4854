"""Analysis of a random-drift recording: the scatter of repeated drift-model fits.

Static window means of every ``random-drift.position`` step
(:func:`~imucalib.procedures.common.static_windows.extract_static_windows`), grouped by
repetition (tag ``rep=<k>``); per repetition the gyro drift model D0 + D1·f_x + D2·f_y + D3·f_z
(docs/g-sensitivity.md, Eqs. (1)–(4); :mod:`~imucalib.procedures.common.drift_model`) and the
accelerometer bias (the same design: each accelerometer's output minus the reference force
against [1, f_x, f_y, f_z], weighted by the windows' standard errors); then over the repetitions
the scatter of every coefficient, the gyro random drift 2.7·√Σσ² and the accelerometer zero
stability (docs/random-drift.md, Eqs. (1)–(5)).

The decision: the means over the repetitions (D0, G, the accelerometer bias: what
:meth:`RandomDriftResult.triad_parameters` hands on) against the unit's specification (the
recording's ``[imu.limits]`` ``gyro_bias_dph``, ``gyro_g_sensitivity_dph_per_g``,
``accel_bias_ug``, the plan's ``[acceptance]`` rule); the scatters, the random drift and the zero
stability have no specification limit. *No decision* when it gives none of those
(:mod:`~imucalib.procedures.common.spec_decision`).

Contents
--------
:class:`RandomDriftResult`, :func:`analyze_random_drift`
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imucalib.errors import InsufficientExcitationError, RecordingError
from imucalib.estimation.linear import solve_weighted_lsq
from imucalib.io.opening import open_recording
from imucalib.io.reader import Recording
from imucalib.models.decision import Decision
from imucalib.models.fit_quality import FitQuality
from imucalib.models.procedure_result import ResultDefaults, TriadParameters
from imucalib.models.reported import ReportedParameter
from imucalib.procedures.common.drift_model import (
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
from imucalib.procedures.random_drift.plan import MIN_REPETITIONS
from imucalib.procedures.random_drift.roles import RANDOM_DRIFT_POSITION
from imucalib.procedures.random_drift.scatter import (
    Scatter,
    allan_at_interval,
    random_drift,
    scatter,
)

__all__ = ["RandomDriftResult", "analyze_random_drift", "fit_accel_bias"]

_F64 = NDArray[np.float64]
_AXES = "xyz"
_COEFFS = ("D0", "D1", "D2", "D3")


def fit_accel_bias(windows: list[StaticWindow]) -> tuple[_F64, _F64]:
    """Return each accelerometer's bias and its σ from one repetition's windows. [m/s²]

    Weighted least squares of ā_ik − f_ik on [1, f_xk, f_yk, f_zk] (the intercept is the bias;
    the slopes absorb scale and misalignment), by
    :func:`~imucalib.estimation.linear.solve_weighted_lsq`. The σ is the white-noise σ within
    the repetition (docs/random-drift.md: reported beside the scatter s), not Birge-scaled.

    Raises
    ------
    InsufficientExcitationError
        Windows whose forces do not span [1, f_x, f_y, f_z] (named).
    """
    f = np.array([w.force_ref_b_mps2 for w in windows])
    a = np.column_stack([np.ones(len(windows)), f])
    bias, std = np.zeros(3), np.zeros(3)
    for i, ax in enumerate(_AXES):
        fit = solve_weighted_lsq(
            a, np.array([w.mean[3 + i] - w.force_ref_b_mps2[i] for w in windows]),
            sigma=np.array([w.se[3 + i] for w in windows]), group=f"accel {ax}",
            param_names=(f"accel_bias_{ax}", *(f"accel_slope_{ax}{j}" for j in _AXES)),
            context=f"accelerometer {ax} bias design")
        bias[i] = fit.estimate[0]
        std[i] = fit.std[0]
    return bias, std


@dataclass(frozen=True)
class RandomDriftResult(ResultDefaults):
    """The random-drift test's result (the result contract, docs/procedures.md).

    A :class:`~imucalib.models.procedure_result.ProcedureResult`: a characterisation of the
    scatter between repetitions; :meth:`triad_parameters` gives the mean coefficients for
    ``imucalib combine`` (no ``calibration``), decided against the unit's limits
    (:attr:`decision`).

    Attributes
    ----------
    unit : str
        The IMU.
    repetitions : list of int
        The repetition numbers, in time order.
    times_s : ndarray, shape (R,)
        Middle of each repetition (station time). [s]
    drift : ndarray, shape (R, 3, 4)
        D0 [rad/s] and D1..D3 [rad/s per m/s²] of each repetition and gyro axis.
    drift_std : ndarray, shape (R, 3, 4)
        Their σ within a repetition: the drift fit's (docs/g-sensitivity.md, Eqs. (3)–(4)),
        Birge-scaled where that repetition's fit of that axis is a misfit;
        :attr:`drift_std_noise` is the σ before that scaling.
    accel_bias, accel_bias_std : ndarray, shape (R, 3)
        Each repetition's accelerometer biases and their white-noise σ (not Birge-scaled,
        :func:`fit_accel_bias`). [m/s²]
    drift_scatter : list of list of Scatter
        [axis][k]: (1), (2) of D0..D3 over the repetitions.
    accel_zero_stability : list of Scatter
        Per accelerometer: (1), (2) of the bias over the repetitions.
    random_drift_rps : ndarray, shape (3, 2)
        (3) and (4) per gyro axis. [rad/s]
    allan_d0_rps, allan_accel_mps2 : ndarray, shape (3,)
        (5) of D0 and of the accelerometer bias at the repetition interval.
    interval_s : float
        Mean spacing of the repetitions. [s]
    gravity_mps2 : float
        g used. [m/s²]
    notes : tuple of str
        What was assumed.
    procedure : str
        ``"random-drift"``.
    drift_fits : tuple of FitQuality
        Each repetition's drift fit per gyro axis (R × 3, repetition-major).
    specification : Specification
        The unit's limits and the decision rule the recording states (none: no decision).
    """

    unit: str
    repetitions: list[int]
    times_s: _F64
    drift: _F64
    drift_std: _F64
    accel_bias: _F64
    accel_bias_std: _F64
    drift_scatter: list[list[Scatter]]
    accel_zero_stability: list[Scatter]
    random_drift_rps: _F64
    allan_d0_rps: _F64
    allan_accel_mps2: _F64
    interval_s: float
    gravity_mps2: float
    notes: tuple[str, ...] = ()
    procedure: str = "random-drift"
    drift_fits: tuple[FitQuality, ...] = ()
    specification: Specification = field(default_factory=Specification)

    @property
    def decision(self) -> Decision:
        """The mean D0, G and accelerometer bias against the specification's limits.

        Its check ``specification`` under the recording's rule (docs/random-drift.md,
        "Decision"); *no decision* when the specification gives none of ``gyro_bias_dph``,
        ``gyro_g_sensitivity_dph_per_g``, ``accel_bias_ug`` (the scatter, the random drift and
        the zero stability have no specification limit). Each misfit in its notes.
        """
        return decide_triad(self.specification, self.triad_parameters(),
                            test="the random-drift test",
                            what="the scatter over the repetitions, the random drift and the "
                                 "zero stability are reported with their standard "
                                 "uncertainties (docs/random-drift.md)",
                            notes=tuple(q.summary() for q in self.drift_fits if q.misfit))

    @property
    def fit_quality(self) -> tuple[FitQuality, ...]:
        """Each repetition's drift fit per gyro axis: χ²/ν and misfit verdict."""
        return self.drift_fits

    @property
    def drift_std_noise(self) -> _F64:
        """:attr:`drift_std` before the Birge scaling of a misfit, shape (R, 3, 4)."""
        scale = np.ones(self.drift_std.shape[:2])
        if len(self.drift_fits) == scale.size:
            scale = np.array([q.sigma_scale for q in self.drift_fits]).reshape(scale.shape)
        return np.asarray(self.drift_std / scale[:, :, None], dtype=np.float64)

    def triad_parameters(self) -> TriadParameters:
        """Return the mean over the repetitions of D0, G and the accelerometer bias.

        The covariance as reported: diagonal, σ² = s²/R from the scatter s of (1) (no fit,
        nothing Birge-scaled).
        """
        r = len(self.repetitions)
        names = [*drift_parameter_names(), *(f"accel_bias_{i}" for i in _AXES)]
        values = np.concatenate([self.drift.mean(axis=0).ravel(), self.accel_bias.mean(axis=0)])
        var = np.concatenate([self.drift.var(axis=0, ddof=1).ravel(),
                              self.accel_bias.var(axis=0, ddof=1)]) / r
        return names, values, np.diag(var)

    def parameter_rows(self) -> list[ReportedParameter]:
        """Return the scatters, random drifts and zero stabilities as reported, SI.

        Returns
        -------
        list of ReportedParameter
            Per gyro axis ``gyro_sigma_D0_i`` … ``gyro_sigma_D3_i`` (the scatter s of (1)) and
            ``gyro_random_drift_i`` ((3)), then ``accel_zero_stability_i`` ((1) of the
            accelerometer bias). ``std``: the standard uncertainty of s, u(s) of (1), or of the
            random drift, (4): from the scatter and the number of repetitions, no fit, so no
            Birge scaling; ``std_noise``: the same (the two are equal). The means over the
            repetitions are :meth:`triad_parameters` (in the result file's covariance block).
        """
        rows = []
        for i, ax in enumerate(_AXES):
            for k, c in enumerate(_COEFFS):
                sc = self.drift_scatter[i][k]
                rows.append(ReportedParameter(f"gyro_sigma_{c}_{ax}", sc.std, sc.std_uncertainty,
                                              "rad/s" if k == 0 else "(rad/s)/(m/s^2)",
                                              sc.std_uncertainty))
            rd, u = float(self.random_drift_rps[i, 0]), float(self.random_drift_rps[i, 1])
            rows.append(ReportedParameter(f"gyro_random_drift_{ax}", rd, u, "rad/s", u))
        for i, ax in enumerate(_AXES):
            sc = self.accel_zero_stability[i]
            rows.append(ReportedParameter(f"accel_zero_stability_{ax}", sc.std,
                                          sc.std_uncertainty, "m/s^2", sc.std_uncertainty))
        return rows

    def to_dict(self) -> dict[str, Any]:
        """Return the whole result as JSON-able data."""
        names, values, cov = self.triad_parameters()
        out = {
            "procedure": self.procedure, "unit": self.unit, "passed": self.passed,
            "decision": self.decision.to_dict(),
            "repetitions": self.repetitions, "times_s": self.times_s,
            "interval_s": self.interval_s, "gravity_mps2": self.gravity_mps2,
            "drift": self.drift, "drift_std": self.drift_std,
            "drift_std_noise": self.drift_std_noise,
            "accel_bias_mps2": self.accel_bias, "accel_bias_std_mps2": self.accel_bias_std,
            "drift_scatter": {ax: {c: vars(self.drift_scatter[i][k])
                                   for k, c in enumerate(_COEFFS)}
                              for i, ax in enumerate(_AXES)},
            "accel_zero_stability": {ax: vars(self.accel_zero_stability[i])
                                     for i, ax in enumerate(_AXES)},
            "random_drift_rps": {ax: {"value": self.random_drift_rps[i, 0],
                                      "std": self.random_drift_rps[i, 1]}
                                 for i, ax in enumerate(_AXES)},
            "allan_d0_rps": self.allan_d0_rps, "allan_accel_mps2": self.allan_accel_mps2,
            "parameters": {n: {"value": float(v), "std": float(math.sqrt(cov[k, k]))}
                           for k, (n, v) in enumerate(zip(names, values, strict=True))},
            "notes": list(self.notes),
        }
        return dict(json_safe(out))  # type: ignore[call-overload]


def _group(windows: list[StaticWindow]) -> dict[int, list[StaticWindow]]:
    groups: dict[int, list[StaticWindow]] = {}
    for w in windows:
        tag = w.tag_value("rep")
        try:
            rep = int(tag) if tag is not None else -1
        except ValueError:
            rep = -1
        if rep < 0:
            raise RecordingError(f"step {w.step_index} ({w.label}): a random-drift position "
                                 f"needs the tag rep=<k>; got {tag!r}")
        groups.setdefault(rep, []).append(w)
    return dict(sorted(groups.items()))


def analyze_random_drift(recording: Recording | str | os.PathLike[str], *,
                         unit: str | None = None, options: GSensitivityOptions | None = None
                         ) -> RandomDriftResult:
    """Estimate the scatter of the repeated drift models (module docstring).

    Raises
    ------
    RecordingError
        No step with role ``random-drift.position``, a position without ``rep=``.
    MissingSegmentError
        A planned position not recorded (named).
    InsufficientExcitationError
        Fewer than 3 repetitions, or a repetition whose positions do not span the gravity
        directions.
    """
    opt = options or GSensitivityOptions()
    if not isinstance(recording, Recording):
        with open_recording(recording) as rec:
            return analyze_random_drift(rec, unit=unit, options=opt)
    require_recorded(recording, [RANDOM_DRIFT_POSITION])
    name, site, windows = extract_static_windows(recording, unit, [RANDOM_DRIFT_POSITION],
                                                 gravity_mps2=opt.gravity_mps2,
                                                 noise_block_s=opt.noise_block_s)
    groups = _group(windows)
    if len(groups) < MIN_REPETITIONS:
        raise InsufficientExcitationError(
            [f"gyro_sigma_{c}_{a}" for a in _AXES for c in _COEFFS],
            f"random drift needs at least {MIN_REPETITIONS} repetitions of the positions; the "
            f"recording has {len(groups)} ({sorted(groups)})")
    fits = [fit_windows(ws, opt) for ws in groups.values()]
    accel = [fit_accel_bias(ws) for ws in groups.values()]
    drift = np.array([f.coefficients for f in fits])
    drift_std = np.array([f.std for f in fits])
    acc = np.array([a[0] for a in accel])
    times = np.array([np.mean([w.time_s for w in ws]) for ws in groups.values()])
    sc = [[scatter(drift[:, i, k], f"gyro {c} {a}") for k, c in enumerate(_COEFFS)]
          for i, a in enumerate(_AXES)]
    rd = np.array([random_drift(sc[i][0].std, [s.std for s in sc[i][1:]], site.gravity_mps2,
                                len(groups)) for i in range(3)])
    notes = ["random drift (3) takes D1..D3 as their drift at 1 g; the Earth rate is "
             "2π/86164.1 s (the sidereal day; the MIMU chapter's 23 h 59 min 57.33 s, "
             "docs/procedures.md, is a misprint)"]
    return RandomDriftResult(
        unit=name, repetitions=list(groups), times_s=times, drift=drift, drift_std=drift_std,
        accel_bias=acc, accel_bias_std=np.array([a[1] for a in accel]), drift_scatter=sc,
        accel_zero_stability=[scatter(acc[:, i], f"accel bias {a}")
                              for i, a in enumerate(_AXES)],
        random_drift_rps=rd,
        allan_d0_rps=np.array([allan_at_interval(drift[:, i, 0]) for i in range(3)]),
        allan_accel_mps2=np.array([allan_at_interval(acc[:, i]) for i in range(3)]),
        interval_s=float(np.mean(np.diff(times))), gravity_mps2=site.gravity_mps2,
        notes=tuple(notes),
        drift_fits=tuple(q for f in fits for q in f.fits),
        specification=Specification.of_metadata(recording.metadata))
