"""Analysis of an Earth-rate bias recording: each gyro's bias by two methods, compared.

The 4-position and the up/down methods (docs/earth-rate-bias.md, equations (1)–(5)).

Static window means of every ``earth-rate-bias.position`` step
(:func:`~imucalib.procedures.common.static_windows.extract_static_windows`); for gyro axis i a
window is "horizontal" when the reference gravity on it is below 0.1 g, "up" (or "down") above
0.9 g (below −0.9 g); windows are grouped by fixture pose (tag ``pose=``). The up/down bias,
free of g-sensitivity and of the Earth rate through the scale factor, is the one handed on as the
triad's gyro bias, and the one decided on: against the unit's gyro bias limit (the recording's
``[imu.limits] gyro_bias_dph``, the plan's ``[acceptance]`` rule), *no decision* when the
specification gives none (:mod:`~imucalib.procedures.common.spec_decision`).

Contents
--------
:class:`EarthRateBiasAxis`, :class:`EarthRateBiasResult`, :func:`analyze_earth_rate_bias`
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from imucalib.errors import InsufficientExcitationError
from imucalib.io.opening import open_recording
from imucalib.io.reader import Recording
from imucalib.models.decision import Decision
from imucalib.models.fit_quality import FitQuality
from imucalib.models.procedure_result import ResultDefaults, TriadParameters
from imucalib.models.reported import ReportedParameter
from imucalib.procedures.common.spec_decision import Specification, decide_triad
from imucalib.procedures.common.static_windows import (
    StaticWindow,
    extract_static_windows,
    json_safe,
    require_recorded,
)
from imucalib.procedures.earth_rate_bias.methods import (
    AxisBias,
    AxisWindow,
    compare_methods,
    four_position_bias,
    scale_at,
    up_down_bias,
)
from imucalib.procedures.earth_rate_bias.roles import EARTH_RATE_BIAS_POSITION

__all__ = ["EarthRateBiasAxis", "EarthRateBiasResult", "analyze_earth_rate_bias"]

_AXES = "xyz"
#: rad/s → °/h
DPH_PER_RPS = 180.0 / math.pi * 3600.0


@dataclass(frozen=True)
class EarthRateBiasAxis:
    """One gyro axis: both biases, the half-difference, the latitude and the comparison.

    Attributes
    ----------
    four_position, up_down : AxisBias
        Biases by (1) and (2). [rad/s]
    half_difference : AxisBias
        (3): (1 + s)·Ω_e·sin L + G_ii·g. [rad/s]
    latitude_deg : AxisBias
        (4), in degrees.
    difference_rps, z : float
        (5).
    scale : AxisBias
        (6): the scale error s at the recorded latitude (G_ii taken as zero), dimensionless.
    """

    four_position: AxisBias
    up_down: AxisBias
    half_difference: AxisBias
    latitude_deg: AxisBias
    difference_rps: float
    z: float
    scale: AxisBias


@dataclass(frozen=True)
class EarthRateBiasResult(ResultDefaults):
    """The Earth-rate bias test's result (the result contract, docs/procedures.md).

    A :class:`~imucalib.models.procedure_result.ProcedureResult`: the gyro biases, part of the
    triad model (no ``calibration``; :meth:`triad_parameters` for ``imucalib combine``),
    decided against the unit's gyro bias limit (:attr:`decision`), no fit with redundancy.

    Attributes
    ----------
    unit : str
        The IMU.
    axes : tuple of EarthRateBiasAxis
        Per gyro axis x, y, z.
    latitude_deg : float
        The recorded latitude. [°]
    windows : list of StaticWindow
        The reduced positions.
    notes : tuple of str
        What was assumed; the axes whose methods differ by more than 3 σ.
    procedure : str
        ``"earth-rate-bias"``.
    specification : Specification
        The unit's limits and the decision rule the recording states (none: no decision).
    """

    unit: str
    axes: tuple[EarthRateBiasAxis, ...]
    latitude_deg: float
    windows: list[StaticWindow]
    notes: tuple[str, ...] = ()
    procedure: str = "earth-rate-bias"
    specification: Specification = field(default_factory=Specification)

    @property
    def decision(self) -> Decision:
        """The up/down biases against the specification's gyro bias limit.

        Its check ``specification`` under the recording's rule (docs/earth-rate-bias.md,
        "Decision"); *no decision* when the specification gives no ``gyro_bias_dph``.
        """
        return decide_triad(self.specification, self.triad_parameters(),
                            test="the Earth-rate bias test",
                            what="both methods' biases are reported with their standard "
                                 "uncertainties and compared (z) (docs/earth-rate-bias.md)")

    @property
    def fit_quality(self) -> tuple[FitQuality, ...]:
        """None: the methods are closed forms of window means, no fit with redundancy."""
        return ()

    def triad_parameters(self) -> TriadParameters:
        """Return (gyro_bias_x/y/z from the up/down method, values, diagonal covariance). [rad/s]

        The covariance as reported (no fit, nothing Birge-scaled): the σ of the rows
        ``gyro_bias_i`` of :meth:`parameter_rows`.
        """
        values = np.array([a.up_down.value_rps for a in self.axes])
        cov = np.diag([a.up_down.std_rps**2 for a in self.axes])
        return [f"gyro_bias_{i}" for i in _AXES], values, cov

    def parameter_rows(self) -> list[ReportedParameter]:
        """Return every estimate as reported, SI (5 per axis).

        Returns
        -------
        list of ReportedParameter
            Per axis: ``gyro_bias_i`` (up/down (2), the one handed on),
            ``gyro_bias_i_four_position`` (1), ``gyro_half_difference_i`` (3),
            ``latitude_from_gyro_i`` (4) [deg], ``gyro_scale_error_from_earth_rate_i`` (6) [1].
            ``std``: the σ of the closed forms, propagated from the windows' standard errors;
            ``std_noise``: the same σ (no fit, so no Birge scaling: the two are equal).
        """
        rows = []
        for i, a in zip(_AXES, self.axes, strict=True):
            for name, est, unit in ((f"gyro_bias_{i}", a.up_down, "rad/s"),
                                    (f"gyro_bias_{i}_four_position", a.four_position, "rad/s"),
                                    (f"gyro_half_difference_{i}", a.half_difference, "rad/s"),
                                    (f"latitude_from_gyro_{i}", a.latitude_deg, "deg"),
                                    (f"gyro_scale_error_from_earth_rate_{i}", a.scale, "1")):
                rows.append(ReportedParameter(name, est.value_rps, est.std_rps, unit,
                                              est.std_rps))
        return rows

    def to_dict(self) -> dict[str, Any]:
        """Return the whole result as JSON-able data (biases also in °/h)."""
        out = {
            "procedure": self.procedure, "unit": self.unit, "passed": self.passed,
            "decision": self.decision.to_dict(), "latitude_deg": self.latitude_deg,
            "axes": {i: {"four_position_rps": a.four_position.value_rps,
                         "four_position_std_rps": a.four_position.std_rps,
                         "up_down_rps": a.up_down.value_rps,
                         "up_down_std_rps": a.up_down.std_rps,
                         "four_position_dph": a.four_position.value_rps * DPH_PER_RPS,
                         "up_down_dph": a.up_down.value_rps * DPH_PER_RPS,
                         "half_difference_rps": a.half_difference.value_rps,
                         "latitude_deg": a.latitude_deg.value_rps,
                         "latitude_std_deg": a.latitude_deg.std_rps,
                         "difference_rps": a.difference_rps, "z": a.z,
                         "scale": a.scale.value_rps, "scale_std": a.scale.std_rps}
                     for i, a in zip(_AXES, self.axes, strict=True)},
            "windows": [{"step": w.step_index, "label": w.label, "pose": w.pose,
                         "gyro_mean_rps": w.mean[:3], "gyro_se_rps": w.se[:3],
                         "omega_ref_b_rps": w.omega_ref_b_rps} for w in self.windows],
            "notes": list(self.notes),
        }
        return dict(json_safe(out))  # type: ignore[call-overload]


def _axis(windows: list[StaticWindow], i: int, g: float, latitude_deg: float
          ) -> EarthRateBiasAxis:
    by_pose: dict[str, list[StaticWindow]] = {}
    for w in windows:
        by_pose.setdefault(w.pose, []).append(w)

    def aw(w: StaticWindow) -> AxisWindow:
        return AxisWindow(float(w.mean[i]), float(w.se[i]), float(w.omega_ref_b_rps[i]))

    def kind(ws: list[StaticWindow]) -> str:
        f = float(np.mean([w.force_ref_b_mps2[i] for w in ws])) / g
        return "up" if f > 0.9 else "down" if f < -0.9 else "horizontal" if abs(f) < 0.1 else ""

    kinds = {p: kind(ws) for p, ws in by_pose.items()}
    horizontal = [[aw(w) for w in ws] for p, ws in by_pose.items() if kinds[p] == "horizontal"
                  and len(ws) == 4]
    up = [aw(w) for p, ws in by_pose.items() if kinds[p] == "up" for w in ws]
    down = [aw(w) for p, ws in by_pose.items() if kinds[p] == "down" for w in ws]
    if not horizontal or not up or not down:
        raise InsufficientExcitationError(
            [f"gyro_bias_{_AXES[i]}"],
            f"gyro {_AXES[i]}: the 4-position method needs a pose with the axis horizontal at 4 "
            f"azimuths and the up/down method a pose with it up and one down; the poses give "
            f"{ {p: k or 'tilted' for p, k in kinds.items()} }")
    four = four_position_bias(horizontal)
    updown, half, lat = up_down_bias(up, down)
    diff, z = compare_methods(four, updown)
    return EarthRateBiasAxis(four, updown, half, lat, diff, z, scale_at(half, latitude_deg))


def analyze_earth_rate_bias(recording: Recording | str | os.PathLike[str], *,
                            unit: str | None = None, gravity_mps2: float | None = None,
                            noise_block_s: float = 1.0) -> EarthRateBiasResult:
    """Estimate each gyro's bias by both methods (module docstring).

    Raises
    ------
    RecordingError
        No step with role ``earth-rate-bias.position``, no table stream, no latitude.
    MissingSegmentError
        A planned position not recorded (named).
    InsufficientExcitationError
        An axis never horizontal at four azimuths, or never up and down.
    """
    if not isinstance(recording, Recording):
        with open_recording(recording) as rec:
            return analyze_earth_rate_bias(rec, unit=unit, gravity_mps2=gravity_mps2,
                                           noise_block_s=noise_block_s)
    require_recorded(recording, [EARTH_RATE_BIAS_POSITION])
    name, site, windows = extract_static_windows(recording, unit, [EARTH_RATE_BIAS_POSITION],
                                                 gravity_mps2=gravity_mps2,
                                                 noise_block_s=noise_block_s)
    axes = tuple(_axis(windows, i, site.gravity_mps2, site.latitude_deg) for i in range(3))
    notes = ["the up/down bias (2) is handed on as the gyro bias: it is free of g-sensitivity "
             "and of the Earth rate through the scale factor; the latitude (4) takes s and "
             "G_ii as zero"]
    notes += [f"gyro {_AXES[k]}: the methods differ by {a.z:.1f} σ" for k, a in enumerate(axes)
              if abs(a.z) > 3]
    return EarthRateBiasResult(unit=name, axes=axes, latitude_deg=site.latitude_deg,
                               windows=windows, notes=tuple(notes),
                               specification=Specification.of_metadata(recording.metadata))
