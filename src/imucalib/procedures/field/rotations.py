"""Step 5 of the field calibration: the gyro triad from the rotations between the poses.

docs/field.md, "Rotations that disagree, and a partial result": the rotations the detector
found become observations of :func:`~imucalib.estimation.gyro_rotations.fit_gyro_rotations`
(gravity-referenced, or known-angle turns flat on a desk); clipped ones are left out before
the fit, full turns are counted with the gravity-rotation-corrected gyro, and a rotation that
stands out from the others is left out when the refit converges or lowers χ² enough, each
named in its row (``left_out``).

Contents
--------
:func:`fit_gyro`, :func:`gyro_covariance`.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imucalib.errors import CalibrationError, InsufficientExcitationError
from imucalib.procedures.common.static_intervals import FieldLog, StaticPose
from imucalib.units import EARTH_RATE_RPS

__all__ = ["fit_gyro", "gyro_covariance"]

_F64 = NDArray[np.float64]
#: A rotation is a full turn when its angle is within this fraction of a whole turn …
_FULL_TURN_TOL = 0.10
#: … and gravity is back within this of where it was. [°]
_TURN_GRAVITY_DEG = 5.0


def _recount_turns(observations: list[Any], rows: list[dict[str, Any]], theta: _F64,
                   density: _F64) -> None:
    """Count each full turn's whole turns with the gyro the gravity-referenced rotations fit.

    A turn's known angle n·2π is read off the gyro's own integral, which is off by the scale
    error: a log whose gyro scale is 1.5× the import options' shows a 360° turn as 540°, and
    the turns would then teach the fit a wrong scale. With three gravity-referenced rotations
    or more, they are fitted first (:func:`_robust_rotation_fit`); each turn's angle is then
    that of the corrected integral ‖(I + M)⁻¹·∫(y − b)dt‖, and a turn whose corrected angle is
    not within 10 % of a whole number of turns becomes a gravity-referenced rotation. Changes
    the observations and rows in place; nothing when the gravity rotations cannot be fitted.
    """
    grav = [k for k, o in enumerate(observations) if o.kind == "gravity"]
    turns = [k for k, o in enumerate(observations) if o.kind == "turn"]
    if len(grav) < 3 or not turns:
        return
    try:
        fit, _ = _robust_rotation_fit([observations[k] for k in grav], list(grav),
                                      [dict(r) for r in rows], theta, density, None)
    except CalibrationError:
        return
    inv = np.linalg.inv(np.eye(3) + np.asarray(fit.values).reshape(3, 3))
    for k in turns:
        o = observations[k]
        w = o.gyro_rps - o.bias_rps
        theta_raw = np.sum(0.5 * (w[1:] + w[:-1]) * np.diff(o.time_s)[:, None], axis=0)
        n = float(np.linalg.norm(inv @ theta_raw)) / (2 * math.pi)
        whole = round(n)
        if whole >= 1 and abs(n - whole) <= _FULL_TURN_TOL:
            observations[k] = dataclasses.replace(o, angle_rad=2 * math.pi * whole)
        else:
            observations[k] = dataclasses.replace(o, kind="gravity", angle_rad=None)
            rows[k]["kind"] = "gravity"


def _clipped_rotations(log: FieldLog, rows: list[dict[str, Any]]) -> dict[int, str]:
    """Rotations during which a gyro axis sat at its largest |value| for 3 samples or more.

    A rate beyond the gyro's range clips: the output holds the full-scale code while the hand
    turns on, and the integrated angle falls short. The full scale is not known from a log, so
    an axis's largest |value| in the log held by three consecutive samples of a rotation is
    taken as clipping (a genuine peak of a smooth hand turn is one sample).
    """
    top = np.max(np.abs(log.gyro_rps), axis=0)
    out: dict[int, str] = {}
    for k, row in enumerate(rows):
        sel = (log.time_s >= row["start_time_s"]) & (log.time_s <= row["end_time_s"])
        at_top = np.abs(log.gyro_rps[sel]) >= top * (1.0 - 1e-9)
        for axis in range(3):
            runs = np.diff(np.flatnonzero(np.diff(np.concatenate(
                [[0], at_top[:, axis].astype(np.int8), [0]]))))[::2]
            if runs.size and int(runs.max()) >= 3:
                out[k] = (f"the gyro's {'xyz'[axis]} axis clipped at "
                          f"{math.degrees(float(top[axis])):.4g} °/s for {int(runs.max())} "
                          "samples (a turn faster than its range)")
                break
    return out


#: A rotation is left out when it disagrees with the others beyond this (its largest residual
#: against its own σ) and leaving it out lowers χ² by more than the 99.9 % quantile of χ²_3.
_DISAGREE_SIGMA = 5.0
_DROP_CHI2 = 16.27
#: … and when it disagrees more than this many times the rotations' median disagreement: a
#: model that misfits every rotation (a scale asymmetry it lacks) must show in χ²/ν, not be
#: hidden by leaving rotations out.
_DISAGREE_MEDIANS = 4.0


def _robust_rotation_fit(observations: list[Any], used: list[int], rows: list[dict[str, Any]],
                         theta: _F64, density: _F64, accel_cov: _F64 | None
                         ) -> tuple[Any, list[int]]:
    """Step 5's fit, rotations that disagree with the others left out one at a time.

    A fit that does not converge, or one whose χ² is a misfit, is tried again without the
    rotation that disagrees most with the model (:func:`~imucalib.estimation.gyro_rotations.
    rotation_disagreement`, at the fit's M or the nominal scale) when it stands out from the
    others (beyond :data:`_DISAGREE_SIGMA` and :data:`_DISAGREE_MEDIANS` times their median):
    kept out when the refit converges where the fit did not, or lowers χ² by more than
    :data:`_DROP_CHI2`. At most a
    fifth of the rotations (at least one) go; each is named in its row (``left_out``).

    Raises
    ------
    ConvergenceError
        No fit converges even so; the message names the rotations that disagree.
    """
    from imucalib.errors import ConvergenceError
    from imucalib.estimation.gyro_rotations import fit_gyro_rotations, rotation_disagreement

    def fit(obs: list[Any]) -> Any:
        return fit_gyro_rotations(obs, theta, gyro_noise_density_rps_rthz=density,
                                  accel_covariance=accel_cov)

    try:
        best: Any = fit(observations)
        error: ConvergenceError | None = None
    except ConvergenceError as exc:
        best, error = None, exc
    budget = max(1, len(observations) // 5)
    while (best is None or best.quality.misfit) and budget > 0 and len(observations) > 4:
        far = rotation_disagreement(observations, theta, gyro_noise_density_rps_rthz=density,
                                    m=None if best is None else best.values)
        k = int(np.argmax(far))
        if far[k] < max(_DISAGREE_SIGMA, _DISAGREE_MEDIANS * float(np.median(far))):
            break  # none stands out: a model misfit of every rotation is left to χ²/ν
        rest = observations[:k] + observations[k + 1:]
        try:
            trial = fit(rest)
        except ConvergenceError:
            break
        if best is not None and best.quality.chi2 - trial.quality.chi2 <= _DROP_CHI2:
            break
        row = rows[used[k]]
        row["left_out"] = (f"it disagrees with the other rotations by {far[k]:.3g}σ (a bump, "
                           "a pose that was not still, or a detection that split a motion)")
        observations, used, best, budget = rest, used[:k] + used[k + 1:], trial, budget - 1
    if best is None:
        assert error is not None
        far = rotation_disagreement(observations, theta, gyro_noise_density_rps_rthz=density)
        worst = [f"{rows[used[k]]['start_time_s']:.1f}–{rows[used[k]]['end_time_s']:.1f} s "
                 f"({far[k]:.3g}σ)" for k in np.argsort(far)[::-1][:3]]
        raise ConvergenceError(f"{error}; the rotations that disagree most at the nominal "
                               f"scale: {', '.join(worst)} (a gyro scale far from the import "
                               "options' or the datasheet's? check --gyro-scale and the units)")
    return best, used


def gyro_covariance(fit: Any) -> _F64:
    """Return the rotation fit's covariance before Birge scaling, the accelerometer's part in."""
    extra = fit.covariance_accel if fit.covariance_accel is not None else 0.0
    return np.asarray(fit.covariance_noise + extra, dtype=np.float64)


def fit_gyro(log: FieldLog, detection: Any, poses: list[StaticPose], y: _F64, up: _F64,
             gyro_form: str, window_s: float, accel_values: _F64, accel_cov: _F64, form: str,
             six: Any, g_sens: _F64 | None, lat: float | None) -> dict[str, Any] | None:
    """Step 5; None when `gyro_form` is "none" or the log holds no rotation.

    `gyro_form` and `window_s` are those of
    :class:`~imucalib.procedures.field.analysis.FieldOptions`; `accel_cov` the accelerometer's
    noise-only covariance (its Birge ratio scales its rows afterwards).

    The gyro samples of each rotation are first freed of the g-sensitivity G·f̂(t) (f̂ the
    corrected accelerometer samples) when G was fitted; each rotation's bias is the mean of
    its two poses' static means (less their G·f), so that a wandering bias is followed. The
    integration starts and ends `window_s` inside the static intervals (at most their length):
    a high detector threshold takes the fading ends of a motion (a hand's tremor) for rest, and
    an angle cut there is a misfit of up to 10⁻³ rad (found on the twin at k = 20); the extra
    still samples add only their noise and the bias error, which the fit's covariance carries.

    The Earth's rate turns with the body during a motion, so the two poses' means do not
    remove it (a 4 s turn of 150° leaves ~2·10⁻⁴ rad, several σ of a consumer gyro at 400 Hz
    on the twin): its vertical part Ω·sin L is removed sample by sample along the corrected
    accelerometer's direction (and from the static means), the horizontal part Ω·cos L,
    whose direction needs the heading, is a Type B on the bias of each motion (σ = Ω·cos L/√2
    per axis; Ω itself when the latitude is unknown) (FL.3).
    """
    from imucalib.estimation.gravity_norm import correct_accel
    from imucalib.estimation.gyro_rotations import RotationObservation

    if gyro_form == "none" or not detection.rotations:
        if gyro_form in ("gravity", "turns"):
            raise InsufficientExcitationError(
                ["gyro_M"], f"{log.source}: no rotation between the static poses was found "
                            f"(gyro_form {gyro_form!r} needs them)")
        return None
    by_stop = {seg.stop_index - 1: k for k, seg in enumerate(detection.static)}
    by_start = {seg.start_index: k for k, seg in enumerate(detection.static)}
    if form == "six-position":
        def correct(y: _F64) -> _F64:
            return np.asarray(np.linalg.solve(np.eye(3) + six.scale_misalignment,
                                              (np.atleast_2d(y) - six.bias).T).T)
        # on a fixture the poses' up directions and the turns' axes are the fixture's axes
        # by construction (a face flat on the desk turns about its own normal): the nominal
        # directions, exact, as Ferraris et al. take them
        from imucalib.estimation.six_position import nominal_directions

        theta = np.zeros(9)
        means = list(float(np.median(np.linalg.norm(y, axis=1))) * nominal_directions(y))
    else:
        def correct(y: _F64) -> _F64:
            return correct_accel(accel_values, y)
        theta = accel_values
        means = list(y)           # the poses' means, at t̄ when the bias drift was fitted
    density = poses[0].gyro_se * math.sqrt(poses[0].duration_s + log.period_s)
    omega_up = 0.0 if lat is None else EARTH_RATE_RPS * math.sin(math.radians(lat))
    omega_h = EARTH_RATE_RPS * (1.0 if lat is None else math.cos(math.radians(lat)))

    def vertical(f: _F64) -> _F64:
        fa = correct(f)
        return np.asarray(omega_up * fa / np.linalg.norm(fa, axis=1, keepdims=True))

    observations, rows = [], []
    for rot in detection.rotations:
        kb, ka = by_stop.get(rot.start_index), by_start.get(rot.stop_index - 1)
        if kb is None or ka is None:
            continue
        # integrate from `window_s` inside the static intervals: a detector threshold that
        # takes the fading ends of a motion for rest would otherwise cut them off the angle
        margin = max(1, round(window_s / log.period_s))
        sl = slice(max(detection.static[kb].start_index, rot.start_index - margin),
                   min(detection.static[ka].stop_index, rot.stop_index + margin))
        gyro = log.gyro_rps[sl]
        before, after = poses[kb], poses[ka]
        ub, ua = up[kb], up[ka]
        static_b = before.gyro_mean - vertical(before.accel_mean)[0]
        static_a = after.gyro_mean - vertical(after.accel_mean)[0]
        gyro = gyro - vertical(log.accel_mps2[sl])
        if g_sens is not None:
            gyro = gyro - correct(log.accel_mps2[sl]) @ g_sens.T
            static_b = static_b - g_sens @ correct(before.accel_mean)[0]
            static_a = static_a - g_sens @ correct(after.accel_mean)[0]
        turns = rot.angle_norm_rad / (2 * math.pi)
        same_up = math.degrees(math.acos(min(1.0, float(ub @ ua)))) <= _TURN_GRAVITY_DEG
        is_turn = same_up and round(turns) >= 1 and abs(turns - round(turns)) <= _FULL_TURN_TOL
        kind = "turn" if is_turn else "gravity"
        if gyro_form == "turns" and kind != "turn":
            continue
        if gyro_form == "gravity":
            kind = "gravity"
        observations.append(RotationObservation(
            kind=kind, time_s=log.time_s[sl], gyro_rps=gyro,
            bias_rps=0.5 * (static_b + static_a),
            bias_std_rps=np.sqrt(0.25 * (before.gyro_se**2 + after.gyro_se**2)
                                 + omega_h**2 / 2.0),
            accel_before_mps2=means[kb], accel_before_std=before.accel_se,
            accel_after_mps2=means[ka], accel_after_std=after.accel_se,
            angle_rad=2 * math.pi * round(turns) if kind == "turn" else None))
        rows.append({"start_time_s": rot.start_time_s, "end_time_s": rot.end_time_s,
                     "kind": kind, "angle_deg": math.degrees(rot.angle_norm_rad),
                     "pose_before": kb, "pose_after": ka})
    if gyro_form == "turns" and not observations:
        raise InsufficientExcitationError(
            ["gyro_M"], f"{log.source}: no full turn flat on the desk was found (a rotation of "
                        "n·360° within 10 %, the gravity direction back within 5°)")
    if gyro_form == "auto":
        _recount_turns(observations, rows, theta, density)
    clipped = _clipped_rotations(log, rows)
    for k in sorted(clipped, reverse=True):
        rows[k]["left_out"] = clipped[k]
    used = [k for k in range(len(rows)) if k not in clipped]
    fit, used = _robust_rotation_fit(
        [observations[k] for k in used], used, rows, theta, density,
        None if form == "six-position" else accel_cov)
    for k, r in zip(used, fit.residuals, strict=True):
        rows[k]["residual"] = r
    observations = [observations[k] for k in used]
    kinds = {o.kind for o in observations}
    label = ("gravity-referenced and known-angle turns" if kinds == {"gravity", "turn"}
             else "known-angle turns" if kinds == {"turn"} else "gravity-referenced")
    return {"fit": fit, "form": label, "rows": rows}
