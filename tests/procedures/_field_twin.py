"""The truth of a hand-held twin session in the field calibration's terms (docs/field.md).

The field fit sees the accelerometer in its own orthogonal frame a (x along sensor x, y in the
sensors' x–y plane). With the twin's y_a − b_a = (I + M_a)·x_b (+ K2 terms) and the RQ
decomposition I + M_a = U·Q (U upper triangular with a positive diagonal, Q a rotation:
x_a = Q·x_b), the truth in frame a is U − I for the accelerometer, (I + M_g)·Qᵀ − I for the
gyro's M and G·Qᵀ for its g-sensitivity (Eq. (FL.1) of docs/field.md).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import scipy.linalg

from imucalib.models.imu import ImuModel
from imucalib.models.triad import apply_triad


def frame_rotation(model: ImuModel) -> tuple[np.ndarray, np.ndarray]:
    """Return (U, Q) with I + M_a = U·Q, diag U > 0."""
    u, q = scipy.linalg.rq(np.eye(3) + np.asarray(model.accel.scale_misalignment))
    s = np.diag(np.sign(np.diag(u)))
    return u @ s, s @ q


def model_at(model: ImuModel, temperature_degc: float) -> ImuModel:
    """`model` with its temperature-dependent parameters fixed at their values at a temperature."""
    if model.gyro.temperature is None and model.accel.temperature is None:
        return model
    p = model.parameters_at(temperature_degc)
    ax = "xyz"

    def fixed(triad: Any, kind: str) -> Any:
        bias = np.array([p[f"{kind}_bias_{i}"] for i in ax])
        m = np.array([[p[f"{kind}_M_{i}{j}"] for j in ax] for i in ax])
        return dataclasses.replace(triad, bias=bias, scale_misalignment=m, temperature=None)

    return dataclasses.replace(model, gyro=fixed(model.gyro, "gyro"),
                               accel=fixed(model.accel, "accel"))


def static_temperature_degc(session: Any) -> float:
    """The IMU's mean true temperature over the session's static samples. [°C]"""
    still = np.zeros(session.time_s.size, dtype=bool)
    for p in session.statics:
        still |= (session.time_s >= p.start_time_s) & (session.time_s <= p.stop_time_s)
    return float(np.mean(session.temperature_degc[still]))


def session_bias_drift(session: Any, temperature_degc: float | None = None
                       ) -> tuple[np.ndarray, np.ndarray]:
    """The mean over the session's static samples of output − deterministic model (gyro, accel).

    With the grade's noise the biases wander (bias instability, random walk): the session's
    mean bias is b + this (the white part averages out), what a calibration of that session
    can see. A session whose IMU warms (a temperature-dependent truth) is taken at its statics'
    mean temperature (:func:`model_at`): the biases' drift with it is then in this mean too.
    """
    model = model_at(session.model, static_temperature_degc(session)
                     if temperature_degc is None else temperature_degc)
    still = np.zeros(session.time_s.size, dtype=bool)
    for p in session.statics:
        still |= (session.time_s >= p.start_time_s) & (session.time_s <= p.stop_time_s)
    f, w = session.true_specific_force_b_mps2[still], session.true_rate_b_rps[still]
    gyro = apply_triad(model.gyro, w, specific_force_b_mps2=f)
    accel = apply_triad(model.accel, f, rate_b_rps=w, angular_accel_b_rps2=np.zeros_like(w))
    return (np.mean(session.gyro_rps[still] - gyro, axis=0),
            np.mean(session.accel_mps2[still] - accel, axis=0))


def field_truth(model: ImuModel, *, six_position: bool = False, session: Any = None,
                temperature_degc: float | None = None) -> dict[str, float]:
    """The truth by the names of the field result's triad model (SI).

    With `session`, the biases are the session's mean biases (:func:`session_bias_drift`), and a
    temperature-dependent truth is taken at `temperature_degc` (the result's
    ``reference_temperature_degc`` when its scale factors were fitted as linear in temperature)
    or else at the statics' mean temperature.
    """
    if session is not None:
        model = model_at(model, static_temperature_degc(session)
                         if temperature_degc is None else temperature_degc)
    a, g = model.accel, model.gyro
    drift_g, drift_a = session_bias_drift(session, temperature_degc) if session is not None else (
        np.zeros(3), np.zeros(3))
    if six_position:
        ua, q = np.eye(3) + np.asarray(a.scale_misalignment), np.eye(3)
    else:
        ua, q = frame_rotation(model)
    mg = (np.eye(3) + np.asarray(g.scale_misalignment)) @ q.T - np.eye(3)
    gs = np.asarray(g.g_sensitivity) @ q.T
    out = {}
    for i, ax in enumerate("xyz"):
        out[f"accel_bias_{ax}"] = float(np.asarray(a.bias)[i] + drift_a[i])
        out[f"gyro_bias_{ax}"] = float(np.asarray(g.bias)[i] + drift_g[i])
        out[f"accel_K2_{ax}"] = float(np.broadcast_to(np.asarray(a.k2), 3)[i])
        for j, bx in enumerate("xyz"):
            out[f"accel_M_{ax}{bx}"] = float(ua[i, j] - (i == j))
            out[f"gyro_M_{ax}{bx}"] = float(mg[i, j])
            out[f"gyro_G_{ax}{bx}"] = float(gs[i, j])
    return out
