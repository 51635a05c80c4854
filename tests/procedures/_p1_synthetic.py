"""P1 window observations made from a twin unit's model, without a recording (many seeds cheaply).

The windows of a P1 plan (docs/p1.md): the six positions (accelerometer and gyro statics) and
the rate points ±50, ±100 °/s about Y, X and Z (Z with roll at 90°), each repetition; every mean
is the truth's output (:func:`~imucalib.models.triad.apply_triad`: K2 on (I + M)·f, as the twin
simulates it) plus white noise of the grade's density over the window, and the standard errors
are that noise's. What a recording adds (flicker, the table, the reduction) is left out: these
windows test the fit and the choice of its terms, not the reduction.
"""

from __future__ import annotations

import math

import numpy as np

from imucalib import units
from imucalib.conventions import TABLE_AXIS_VECTORS
from imucalib.models import ImuModel, sample_imu_model
from imucalib.models.imu import GRADES
from imucalib.models.triad import apply_triad
from imucalib.procedures.common.reference import site_vectors
from imucalib.procedures.p1.observations import table_rotation
from imucalib.procedures.p1.plan import P1_SIX_POSITIONS_DEG
from imucalib.procedures.p1.windows import P1Observations, WindowObservation

LATITUDE_DEG = 45.0
RECORD_S = 10.0
RATES_DPS = (-100.0, -50.0, 50.0, 100.0)
REVOLUTIONS = 2
TABLE_AXES = ("pitch", "roll")
#: (table axis spinning, roll held [°], body axis turned)
RATE_GROUPS = ((0, 0.0, "Y"), (1, 0.0, "X"), (0, 90.0, "Z"))


def _window(label: str, kind: str, rep: int, tags: tuple[str, ...], gyro: np.ndarray,
            accel: np.ndarray, gyro_se: float, accel_se: float, rate_b: np.ndarray,
            force_b: np.ndarray, duration: float) -> WindowObservation:
    z3 = np.zeros(3)
    return WindowObservation(
        step_index=0, plan_step=0, kind=kind, role="calibration", repetition=rep, tags=tags,
        label=label, gyro_mean_rps=gyro, accel_mean_mps2=accel,
        gyro_se_rps=np.full(3, gyro_se), accel_se_mps2=np.full(3, accel_se),
        gyro_std_rps=z3, accel_std_mps2=z3, rate_b_rps=rate_b, force_b_mps2=force_b,
        angles_rad=np.zeros(2), table_rate_rps=0.0, axis=None, n_samples=1, n_outliers=0,
        n_revolutions=REVOLUTIONS if kind == "rate" else 0, alignment_error_s=0.0,
        duration_s=duration)


def truth(grade: str, seed: int, *, k2: bool = True) -> ImuModel:
    """A twin unit of `grade`: the grade's K2 drawn when `k2`, else none (linear)."""
    return sample_imu_model(grade, rng=seed, nonlinear=k2)


def observations(model: ImuModel, grade: str, seed: int, *, repetitions: int = 3
                 ) -> P1Observations:
    """The calibration windows of a P1 plan on `model` (module docstring)."""
    rng = np.random.default_rng(seed + 10_000)
    spec = GRADES[grade]
    vrw = spec.accel_vrw_ug_rthz * units.UG_PER_RTHZ
    arw = spec.gyro_arw_deg_rth * units.DEG_PER_RTH
    g, earth_t = site_vectors(LATITUDE_DEG, 0.0, None)
    gravity_t = np.array([0.0, 0.0, g])
    windows = []

    def measure(rate_b: np.ndarray, force_b: np.ndarray, duration: float
                ) -> tuple[np.ndarray, np.ndarray, float, float]:
        sg, sa = arw / math.sqrt(duration), vrw / math.sqrt(duration)
        gyro = apply_triad(model.gyro, rate_b, specific_force_b_mps2=force_b)
        accel = apply_triad(model.accel, force_b, rate_b_rps=np.zeros(3),
                            angular_accel_b_rps2=np.zeros(3))
        return (gyro + rng.normal(0.0, sg, 3), accel + rng.normal(0.0, sa, 3), sg, sa)

    for rep in range(1, repetitions + 1):
        for (pitch, roll), label in P1_SIX_POSITIONS_DEG:
            rot = table_rotation(TABLE_AXES, np.radians([pitch, roll]))
            rate_b, force_b = rot.inv().apply(earth_t), rot.inv().apply(gravity_t)
            gy, ac, sg, sa = measure(rate_b, force_b, RECORD_S)
            windows.append(_window(label, "static", rep, ("six-position",), gy, ac, sg, sa,
                                   rate_b, force_b, RECORD_S))
        for axis, roll_deg, body in RATE_GROUPS:
            held = np.array([0.0, math.radians(roll_deg)])
            inner = table_rotation(TABLE_AXES[axis + 1:], held[axis + 1:])
            a_b = inner.inv().apply(np.asarray(TABLE_AXIS_VECTORS[TABLE_AXES[axis]], float))
            a_t = table_rotation(TABLE_AXES, held).apply(a_b)
            for rate_dps in RATES_DPS:
                rate = math.radians(rate_dps)
                rate_b = (rate + float(earth_t @ a_t)) * a_b
                force_b = float(gravity_t @ a_t) * a_b  # whole turns: the axial part
                duration = REVOLUTIONS * 360.0 / abs(rate_dps)
                gy, ac, sg, sa = measure(rate_b, force_b, duration)
                windows.append(_window(f"{body} {rate_dps:+g}", "rate", rep, ("rate",), gy,
                                       ac, sg, sa, rate_b, force_b, duration))
    return P1Observations(sensor_id="u", windows=tuple(windows), gravity_mps2=g,
                          earth_rate_t_rps=earth_t, latitude_deg=LATITUDE_DEG,
                          heading_deg=0.0, sample_rate_hz=1000.0, cutoff_hz=None)


def truth_values(model: ImuModel) -> dict[str, float]:
    """Every parameter P1's triad model may hold, by name (K2 and G as the truth has them)."""
    out = {}
    for triad, tm in (("accel", model.accel), ("gyro", model.gyro)):
        for i, a in enumerate("xyz"):
            out[f"{triad}_bias_{a}"] = float(tm.bias[i])
            for j, b in enumerate("xyz"):
                out[f"{triad}_M_{a}{b}"] = float(tm.scale_misalignment[i, j])
                out[f"{triad}_G_{a}{b}"] = float(tm.g_sensitivity[i, j])
            out[f"{triad}_K2_{a}"] = float(tm.k2[i])
    return out
