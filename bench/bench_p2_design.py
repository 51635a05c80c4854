"""P2's test design: optimised temperature points vs the default, and the prediction on the twin.

``optimize`` (the default): the default P2 plan (8 units, −40 … 85 °C, 7 calibration points)
against the plan :func:`~imucalib.procedures.p2.optimize.optimize_p2` chooses for every
temperature-model σ no worse than the default's, per grade: station time, points, dwell and the
worst σ ratio (docs/test-design.md, "P2: temperature points").

``twin``: a small P2 plan run on the twin (white noise, fast thermal constants, the twin of
tests/procedures/_p2_twin.py), calibrated with the models' order fixed at the predicted one;
each predicted σ (``covariance="analysis"``: independent windows, which for a white-noise unit
is what calibrate reports) against the σ calibrate reports: the parameters at T0
(``std_noise``) and every model coefficient (unscaled σ).

``spread``: the same plan on a twin with the grade's coloured noise (8 units), the models'
order fixed at 3: the c_0's errors about the truth in units of the coloured prediction and of
the σ calibrate reports (since issue 30 the coloured covariance of the window means too,
docs/p2.md "Temperature models"; the Monte Carlo of those σ over many runs is
bench/p2_sigma_montecarlo.py).

Run: ``OPENBLAS_NUM_THREADS=1 .venv/bin/python bench/bench_p2_design.py
[optimize|twin|spread] [KEEP.h5]``.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from imucalib.plan.equipment import (
    ChamberConfig,
    FixtureConfig,
    ImuConfig,
    MountConfig,
    SiteConfig,
    TableConfig,
    TwinEquipment,
)
from imucalib.procedures.p2.options import P2PlanOptions
from imucalib.procedures.p2.plan import generate_p2_plan
from imucalib.procedures.p2.predict import predict_p2_detail
from imucalib.procedures.p2.reduction import PARAM_NAMES


def optimize_table() -> None:
    """Default vs optimised P2 plan (every σ at T0 and over the range no worse)."""
    from imucalib.models.noise import NoiseModel
    from imucalib.procedures.common.grade import grade_noise
    from imucalib.procedures.p2.optimize import OptimizeSettingsP2, optimize_p2

    print("8 units, -40 … 85 °C, held out -10 and 55 °C; targets: each parameter's σ at T0 "
          "and its largest σ over the range no worse than the default plan's")
    for grade, white, sigma_t, order in (
            ("consumer", False, None, 3), ("tactical", False, None, 3),
            ("navigation", False, None, 3), ("consumer", True, 0.0, 3),
            ("tactical", True, 0.0, 3), ("tactical", False, None, 2)):
        base = P2PlanOptions(grade=grade)  # type: ignore[arg-type]
        noise = None
        if white:
            g = grade_noise(generate_p2_plan(grade=grade))
            noise = {k: NoiseModel(white_density=v.white_density) for k, v in g.items()}
        t = time.perf_counter()
        res = optimize_p2(base, settings=OptimizeSettingsP2(
            noise=noise, temperature_std_degc=sigma_t, order=order))
        dt = time.perf_counter() - t
        ref, best = res.reference, res.best
        label = (f"{grade}, {'white noise' if white else 'grade noise'}, "
                 f"σ_T {'band/√12' if sigma_t is None else sigma_t}, order {order}")
        print(f"{label}: default {ref.station_time_s / 3600:.2f} h → optimised "
              f"{best.station_time_s / 3600:.2f} h ({best.station_time_s / ref.station_time_s:.0%}"
              f"), worst ratio {best.worst_ratio:.3f} ({best.worst_name}): {best.describe()}; "
              f"{res.evaluated} plans predicted in {dt:.1f} s")


def _twin(n: int, noise: str = "white") -> TwinEquipment:
    arms = ((0.0, 0.0, 0.0), (0.0, 0.04, 0.0), (0.03, -0.06, 0.0), (0.08, 0.0, 0.02),
            (-0.1, 0.02, 0.0), (0.06, -0.06, 0.1), (0.0, 0.0, -0.02), (0.05, 0.05, 0.0))
    faces = ("+z", "+y", "-y", "+x", "-x", "+z", "-z", "+z")
    return TwinEquipment(
        seed=21,
        site=SiteConfig(latitude_deg=45.0, ambient_temperature_degc=25.0),
        table=TableConfig(kind="single-axis", grade="lab"),
        chamber=ChamberConfig(enabled=True, initial_temperature_degc=25.0,
                              max_ramp_degc_per_min=20.0, air_time_constant_s=20.0,
                              stability_noise_degc=0.0),
        fixture=FixtureConfig(kind="hexahedral", half_edge_m=0.05, mounts=tuple(
            MountConfig(face=faces[i], lever_arm_m=arms[i]) for i in range(n))),  # type: ignore[arg-type]
        imus=tuple(ImuConfig(name=f"U{i}", grade="consumer", sample_rate_hz=50.0,
                             thermal_time_constant_s=40.0, temperature_dependence="typical",
                             noise=noise) for i in range(n)))  # type: ignore[arg-type]


def twin_check(n_units: int = 4, keep: str = "") -> None:
    """Predicted σ against calibrate's on a small twin run (module docstring)."""
    from imucalib.procedures.p2.analysis import P2Options
    from imucalib.procedures.p2.batch import analyze_p2
    from imucalib.station.runner import RunOptions, run_plan
    from imucalib.station.sim import SimStation

    plan = generate_p2_plan(
        temperatures_degc=(-30.0, -10.0, 10.0, 30.0, 50.0, 70.0), held_out_degc=(0.0,),
        rate_dps=120.0, revolutions=2, static_s=8.0, settle_s=2.0, stable_for_s=60.0,
        resoak_s=5.0, ramp_degc_per_min=20.0, twin=_twin(n_units))
    order = 2
    det = predict_p2_detail(plan, order=order, covariance="analysis")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(keep) if keep else Path(tmp) / "p2.h5"
        assert plan.twin is not None
        station = SimStation(plan.twin)
        t = time.perf_counter()
        run_plan(plan, station, path, options=RunOptions(tick_s=5.0))
        print(f"twin run: {time.perf_counter() - t:.0f} s wall, "
              f"{det.prediction.station_time_s / 3600:.2f} h station (predicted)")
        batch = analyze_p2(path, options=P2Options(order=order))
        fitted = _fitted_noise(path, [r.unit for r in batch.results])
    for label, noises in (("grade noise", None), ("the run's pooled noise", fitted)):
        _ratios(plan, order, batch, noises, n_units, label)


def _fitted_noise(path: Path, units: list[str]) -> dict[str, dict[str, Any]]:
    """Per unit, the noise model pooled over all its windows (median Allan-fit terms)."""
    from imucalib.io.opening import open_recording
    from imucalib.models.noise import NoiseModel
    from imucalib.procedures.common.noise import FLICKER_FACTOR
    from imucalib.procedures.p2.observations import extract_unit_observations

    out: dict[str, dict[str, Any]] = {}
    with open_recording(path) as rec:
        for unit in units:
            obs = extract_unit_observations(rec, unit)
            fit = np.median(np.array([np.nan_to_num(w.allan_fit) for w in obs.windows
                                      if w.allan_fit is not None]), axis=0)
            out[unit] = {t: NoiseModel(white_density=np.maximum(fit[0, c], 0.0),
                                       bias_instability=np.sqrt(np.maximum(fit[1, c], 0.0)
                                                                / FLICKER_FACTOR),
                                       random_walk=np.maximum(fit[2, c], 0.0))
                         for t, c in (("gyro", slice(0, 3)), ("accel", slice(3, 6)))}
    return out


def _ratios(plan: Any, order: int, batch: Any, noises: dict[str, dict[str, Any]] | None,
            n_units: int, label: str) -> None:
    ratios: dict[str, list[float]] = {}
    for r in batch.results:
        assert r.result is not None, r.error
        noise = None if noises is None else noises[r.unit]
        pred = predict_p2_detail(plan, order=order, covariance="analysis",
                                 noise=noise).prediction.std()
        for row in r.parameter_rows():
            ratios.setdefault("c0", []).append(pred[row.name] / row.std_noise)
        for n, m in r.models.items():
            s = m.std(scaled=False)
            for j in range(1, order + 1):
                ratios.setdefault(f"c{j}", []).append(pred[f"{n}_c{j}"] / s[j])
    kinds = {"gyro bias": "gyro_bias", "gyro M": "gyro_M", "gyro G": "gyro_G",
             "accel bias": "accel_bias", "accel M": "accel_M", "accel K2": "accel_K2"}
    print(f"predicted ({label}) / calibrate-reported σ, {n_units} units × 36 parameters, "
          f"order {order}:")
    for coef, vals in ratios.items():
        arr = np.array(vals).reshape(n_units, -1) if coef == "c0" else np.array(vals).reshape(
            n_units, len(PARAM_NAMES))
        parts = []
        for label, prefix in kinds.items():
            cols = [i for i, n in enumerate(PARAM_NAMES) if n.startswith(prefix)]
            sub = arr[:, cols]
            parts.append(f"{label} {sub.min():.3f}–{sub.max():.3f}")
        print(f"  {coef}: median {np.median(arr):.3f}; " + "; ".join(parts))


def twin_spread(n_units: int = 8, keep: str = "") -> None:
    """The spread of the c_0 about the truth on a coloured-noise twin, against the prediction.

    The grade's noise (white, flicker, random walk) on the twin, cubic temperature truths, the
    models' order fixed at 3: z = (ĉ_0 − c_0,true)/σ_pred with σ_pred the coloured prediction
    (TD.P1)–(TD.P2) (σ_T = 0: the twin's chamber holds its setpoint), and the same with the σ
    calibrate reports; the RMS of z per kind of parameter over the units.
    """
    from imucalib.io.opening import open_recording
    from imucalib.models.imu import ImuModel
    from imucalib.procedures.p2.analysis import P2Options
    from imucalib.procedures.p2.batch import analyze_p2
    from imucalib.station.runner import RunOptions, run_plan
    from imucalib.station.sim import SimStation

    plan = generate_p2_plan(
        temperatures_degc=(-30.0, -10.0, 10.0, 30.0, 50.0, 70.0), held_out_degc=(0.0,),
        rate_dps=120.0, revolutions=2, static_s=8.0, settle_s=2.0, stable_for_s=60.0,
        resoak_s=5.0, ramp_degc_per_min=20.0, twin=_twin(n_units, "grade"))
    det = predict_p2_detail(plan, order=3, temperature_std_degc=0.0)
    pred = det.prediction.std()
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(keep) if keep else Path(tmp) / "p2.h5"
        assert plan.twin is not None
        station = SimStation(plan.twin)
        run_plan(plan, station, path, options=RunOptions(tick_s=5.0, truth=station.truth))
        batch = analyze_p2(path, options=P2Options(order=3))
        with open_recording(path) as rec:
            truth = {u: rec.truth["imu_models"][u] for u in rec.truth["imu_models"]}
    z_pred: dict[str, list[float]] = {}
    z_rep: dict[str, list[float]] = {}
    for r in batch.results:
        assert r.result is not None, r.error
        raw = truth[r.unit]
        values = ImuModel.from_dict(raw).parameters_at(25.0, hysteresis_state=0.0)
        k2 = np.asarray(raw["accel"]["k2"], dtype=float)
        for row in r.parameter_rows():
            true = values[row.name] if row.name in values else k2["xyz".index(row.name[-1])]
            kind = "_".join(row.name.split("_")[:2])
            z_pred.setdefault(kind, []).append((row.value - true) / pred[row.name])
            z_rep.setdefault(kind, []).append((row.value - true) / row.std_noise)
    print(f"c_0 about the truth, {n_units} units, grade noise (coloured), order 3: RMS z")
    for kind in z_pred:
        print(f"  {kind:11s} predicted σ: {np.sqrt(np.mean(np.square(z_pred[kind]))):.2f}   "
              f"reported σ: {np.sqrt(np.mean(np.square(z_rep[kind]))):.2f}   "
              f"(n = {len(z_pred[kind])})")


if __name__ == "__main__":
    what = sys.argv[1] if len(sys.argv) > 1 else "optimize"
    if what == "twin":
        twin_check(keep=sys.argv[2] if len(sys.argv) > 2 else "")
    elif what == "spread":
        twin_spread(keep=sys.argv[2] if len(sys.argv) > 2 else "")
    else:
        optimize_table()
