"""Bench: are P2's reported σ of the temperature models honest under coloured noise? (issue 30)

The check: on a twin with the grade's coloured noise (white, flicker, random walk), over ≥ 100
short P2 runs, the σ the analysis reports for every temperature-model coefficient — the biases
at T0 and their slopes c_1, the scale factors, misalignments, G and K2 — against the
Monte-Carlo spread of the estimates about the truth: within ±15 % (docs/p2.md, "Temperature
models"). Beside it, the σ the analysis reported before issue 30 (the windows treated as
independent, each with its own standard error: the same estimates, ``UnitObservations.noise``
left out).

1. The plan: 5 calibration points −30 … 70 °C (the models' order fixed at 3, the twin's truth
   cubic: ``temperature_dependence = "typical"``), no held-out point, one revolution at
   120 °/s and 3-s statics, 25 Hz, 1-minute soaks in a fast chamber: about 40 minutes of
   station time, seconds of wall time. ``--units`` units on the cube (each its own truth and
   noise).
2. For seeds 1…N: the twin seed set (new truths, new noise), the plan run in-process
   (:class:`~imucalib.station.sim.SimStation`), each unit reduced
   (:func:`~imucalib.procedures.p2.observations.extract_unit_observations`) and analysed
   (:func:`~imucalib.procedures.p2.analysis.analyze_unit`, order 3) twice: as issue 30 has it
   (the coloured covariance of the window means, Eq. (TD.2)) and without the unit's noise model
   (the old independent windows). Per coefficient: the error (estimate − truth; the truth at
   T0 = 25 °C and its derivative there) and both σ (Birge-scaled, as the result reports them).
3. Per parameter group: the RMS error against the RMS reported σ, and the RMS of z = error/σ,
   with the resolution ±1/√(2n).

``--level window`` replaces the station by the twin's truth and noise generator on the plan's
windows (:func:`window_twin_unit`): the same analysis in seconds a unit instead of a minute.

Measured (docs/p2.md, "Temperature models": the table): over 150 window-level runs per grade
and 33 station-level ones, every group's RMS error / RMS σ within 0.92–1.08, the biases at T0
0.93–1.02 (with the old σ 1.5–5.1).

Intermediate results go to ``--out`` (JSON lines, one per unit and run) so a partial run is not
lost; ``--resume`` reuses them and ``--report-only`` prints the table from them.

Run (one core)::

    OPENBLAS_NUM_THREADS=1 nice -n 5 .venv/bin/python bench/p2_sigma_montecarlo.py \\
        --grade consumer --level window --n 150 --out /tmp/p2_mc_consumer.jsonl
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from imucalib.io.opening import open_recording  # noqa: E402
from imucalib.models.imu import ImuModel  # noqa: E402
from imucalib.plan.equipment import (  # noqa: E402
    ChamberConfig,
    FixtureConfig,
    ImuConfig,
    MountConfig,
    SiteConfig,
    TableConfig,
    TwinEquipment,
)
from imucalib.plan.schema import Plan  # noqa: E402
from imucalib.procedures.p2.analysis import P2Options, analyze_unit  # noqa: E402
from imucalib.procedures.p2.observations import (  # noqa: E402
    UnitObservations,
    extract_unit_observations,
    p2_units,
)
from imucalib.procedures.p2.plan import generate_p2_plan  # noqa: E402
from imucalib.procedures.p2.reduction import PARAM_NAMES  # noqa: E402
from imucalib.station.runner import RunOptions, run_plan  # noqa: E402
from imucalib.station.sim import SimStation  # noqa: E402

#: The models' order (the twin's truth is cubic).
ORDER = 3
#: T0 of the models and of the truth. [°C]
T0_DEGC = 25.0
_FACES = ("+z", "+y", "-x", "-z", "-y", "+x")


def twin(grade: str, n_units: int, seed: int, sample_rate_hz: float = 25.0) -> TwinEquipment:
    """The twin: `n_units` units of `grade` with the grade's noise and a cubic thermal truth."""
    return TwinEquipment(
        seed=seed,
        site=SiteConfig(latitude_deg=45.0, ambient_temperature_degc=25.0),
        table=TableConfig(kind="single-axis", grade="lab"),
        chamber=ChamberConfig(enabled=True, initial_temperature_degc=25.0,
                              max_ramp_degc_per_min=200.0, air_time_constant_s=5.0,
                              stability_noise_degc=0.0),
        fixture=FixtureConfig(kind="hexahedral", half_edge_m=0.05, mounts=tuple(
            MountConfig(face=_FACES[i % 6], lever_arm_m=(0.0, 0.0, 0.0))  # type: ignore[arg-type]
            for i in range(n_units))),
        imus=tuple(ImuConfig(name=f"U{i}", grade=grade,  # type: ignore[arg-type]
                             sample_rate_hz=sample_rate_hz, thermal_time_constant_s=10.0,
                             temperature_dependence="typical", noise="grade")
                   for i in range(n_units)))


def make_plan(grade: str, n_units: int, seed: int) -> Plan:
    """The short P2 plan of the module docstring with twin seed `seed`."""
    return generate_p2_plan(
        grade=grade, temperatures_degc=(-30.0, -5.0, 20.0, 45.0, 70.0), held_out_degc=(),
        rate_dps=120.0, revolutions=1, static_s=3.0, settle_s=1.0, stable_for_s=20.0,
        resoak_s=2.0, ramp_degc_per_min=100.0, twin=twin(grade, n_units, seed))


def truth_coefficients(raw: dict[str, Any]) -> dict[str, float]:
    """Each parameter's true c_0 (at T0) and c_1 (its derivative there), result names."""
    model = ImuModel.from_dict(raw)
    k2 = np.broadcast_to(np.asarray(raw["accel"]["k2"], dtype=float), (3,))
    step = 0.5

    def at(temp: float) -> dict[str, float]:
        values = model.parameters_at(temp, hysteresis_state=0.0)
        for i, a in enumerate("xyz"):
            values.setdefault(f"accel_K2_{a}", float(k2[i]))
        return values

    mid, hi, lo = at(T0_DEGC), at(T0_DEGC + step), at(T0_DEGC - step)
    out = {n: mid[n] for n in PARAM_NAMES}
    # the cubic's derivative at T0: the central difference is exact but for c_3·step²
    out.update({f"{n}_c1": (hi[n] - lo[n]) / (2.0 * step) for n in PARAM_NAMES})
    return out


def coefficients(result: Any) -> tuple[dict[str, float], dict[str, float]]:
    """Each model's c_0 and c_1 and their σ as the result reports them (Birge-scaled)."""
    values: dict[str, float] = {}
    sigma: dict[str, float] = {}
    std0 = dict(zip(result.result.param_names, np.sqrt(np.diag(result.result.covariance)),
                    strict=True))
    for n, m in result.models.items():
        s = m.std(scaled=True)
        values[n] = m.model.coefficients[0]
        sigma[n] = float(std0[n])
        values[f"{n}_c1"] = m.model.coefficients[1]
        sigma[f"{n}_c1"] = float(s[1])
    return values, sigma


def one_run(grade: str, n_units: int, seed: int, workdir: Path) -> list[dict[str, Any]]:
    """Run the plan with twin seed `seed`; per unit the errors and both σ per coefficient."""
    plan = make_plan(grade, n_units, seed)
    assert plan.twin is not None
    path = workdir / f"run-{seed}.h5"
    t0 = time.perf_counter()
    station = SimStation(plan.twin)
    summary = run_plan(plan, station, path, overwrite=True,
                       options=RunOptions(tick_s=5.0, truth=station.truth))
    if summary.status != "done":
        raise RuntimeError(f"seed {seed}: run not done: {summary.reason}")
    t_run = time.perf_counter() - t0
    rows = []
    with open_recording(path) as rec:
        raw = rec.truth["imu_models"]
        for unit in p2_units(rec):
            t1 = time.perf_counter()
            obs = extract_unit_observations(rec, unit)
            rows.append(_unit_row(obs, truth_coefficients(raw[unit]), seed, unit,
                                  t_run / n_units, t1))
    path.unlink()
    return rows


def window_twin_unit(grade: str, seed: int, unit: int, fs_hz: float = 25.0
                     ) -> tuple[UnitObservations, dict[str, float]]:
    """One unit of the window-level twin (``--level window``): its observations and truth.

    The twin's truth and noise without its station: a unit drawn as the twin draws it
    (:func:`~imucalib.models.imu.sample_imu_model`, ``temperature_dependence="typical"``), its
    noise generated over the whole sweep by the twin's generator
    (:class:`~imucalib.models.noise_generator.NoiseGenerator`: white, flicker and random walk
    continuing from the run's start), on the windows of the plan's timeline
    (:func:`~imucalib.procedures.p2.predict.plan_points`: each window's start on the run's clock
    and its length); each window's mean is the P2 model at the point's setpoint (docs/p2.md,
    Eqs. (P2.1)–(P2.3), r = 0: the gyro's b + (I + M)·u·(ω + Ω_U) + G·g·u, the
    accelerometer's b + (I + M)·g·u + K2⊙(g·u)²) plus the mean of the noise over the window.
    The first windows of each point get the Allan fit the reduction gives them
    (:func:`~imucalib.processing.statistics.window_noise_fit`), then the reduction's own
    pooled standard errors and the unit's noise model
    (:func:`~imucalib.procedures.p2.observations.unit_noise`, the grade declared).
    """
    from imucalib.models.imu import sample_imu_model
    from imucalib.models.noise_generator import NoiseGenerator
    from imucalib.procedures.common.grade import grade_noise
    from imucalib.procedures.common.reference import site_vectors
    from imucalib.procedures.p2.observations import (
        P2Processing,
        P2Window,
        pooled_standard_errors,
        unit_noise,
    )
    from imucalib.procedures.p2.predict import plan_points
    from imucalib.procedures.p2.reduction import up_vector
    from imucalib.processing.statistics import window_noise_fit

    plan = make_plan(grade, 1, seed)
    # the grade in the tactical seed: the two grades' accelerometer noise differ by a factor
    # alone, and the same draws would give them the same ratios
    rng = np.random.default_rng([seed, unit, *(() if grade == "consumer" else (1,))])
    model = sample_imu_model(grade, rng, sample_rate_hz=fs_hz, temperature_dependence="typical")
    points = plan_points(plan)
    end_s = max(w.start_s + w.duration_s for p in points for w in p.windows)
    n = math.ceil(end_s * fs_hz) + 2
    noise = np.hstack([NoiseGenerator(model.gyro_noise, 1.0 / fs_hz, rng).generate(n),
                       NoiseGenerator(model.accel_noise, 1.0 / fs_hz, rng).generate(n)])
    g, earth = site_vectors(45.0, 0.0, None)
    omega_up = float(earth[2])
    k2 = np.broadcast_to(np.asarray(model.accel.k2, dtype=float), (3,))
    fits_per_point = P2Processing().noise_windows
    windows = []
    for p in points:
        par = model.parameters_at(p.temperature_degc, hysteresis_state=0.0)
        vec = np.array([par[k] for k in PARAM_NAMES[:33]])
        bg, mg, gs = vec[:3], vec[3:12].reshape(3, 3), vec[12:21].reshape(3, 3)
        ba, ma = vec[21:24], vec[24:33].reshape(3, 3)
        for j, w in enumerate(p.windows):
            i0 = round(w.start_s * fs_hz)
            i1 = i0 + max(round(w.duration_s * fs_hz), 8)
            seg = noise[i0:i1]
            u = up_vector(w.pose)
            f = g * u
            gyro = bg + (np.eye(3) + mg) @ (u * (w.rate_rps + omega_up)) + gs @ f
            accel = ba + (np.eye(3) + ma) @ f + k2 * f**2
            fit = window_noise_fit(seg, fs_hz)[1] if j < fits_per_point else None
            mean = seg.mean(axis=0)
            windows.append(P2Window(
                step_index=len(windows), label=f"{p.index}/{j}", point=p.index, leg=p.leg,
                held_out=p.held_out, pose=w.pose, kind=w.kind, table_rate_rps=w.rate_rps,
                n_revolutions=1 if w.kind == "rate" else 0, gyro_mean_rps=gyro + mean[:3],
                accel_mean_mps2=accel + mean[3:], gyro_se_rps=np.full(3, np.nan),
                accel_se_mps2=np.full(3, np.nan), temperature_degc=p.temperature_degc,
                temperature_rate_degc_ps=0.0, duration_s=(i1 - i0 - 1) / fs_hz,
                n_samples=i1 - i0, n_lost=0, allan_fit=fit, start_s=i0 / fs_hz))
    unit_model, note = unit_noise(windows, fs_hz, (grade_noise(plan), grade))
    obs = UnitObservations(unit=f"U{unit}", windows=tuple(pooled_standard_errors(windows)),
                           gravity_mps2=g, earth_rate_up_rps=omega_up, latitude_deg=45.0,
                           sample_rate_hz=fs_hz, notes=("window-level twin", note or ""),
                           noise=unit_model)
    return obs, truth_coefficients(model.to_dict())


def one_window_run(grade: str, n_units: int, seed: int) -> list[dict[str, Any]]:
    """:func:`one_run` on the window-level twin (:func:`window_twin_unit`)."""
    rows = []
    for unit in range(n_units):
        t0 = time.perf_counter()
        obs, truth = window_twin_unit(grade, seed, unit)
        t1 = time.perf_counter()
        rows.append(_unit_row(obs, truth, seed, f"U{unit}", t1 - t0, t1))
    return rows


def _unit_row(obs: UnitObservations, truth: dict[str, float], seed: int, unit: str,
              t_run_s: float, t_start: float) -> dict[str, Any]:
    """Analyse one unit as issue 30 has it and with independent windows; its row."""
    new = analyze_unit(obs, P2Options(order=ORDER))
    old = analyze_unit(dataclasses.replace(obs, noise=None), P2Options(order=ORDER))
    v_new, s_new = coefficients(new)
    v_old, s_old = coefficients(old)
    assert obs.noise is not None
    return {"seed": seed, "unit": unit, "t_run_s": t_run_s,
            "t_analysis_s": time.perf_counter() - t_start,
            "err": {k: v_new[k] - truth[k] for k in v_new},
            "err_old": {k: v_old[k] - truth[k] for k in v_old},
            "sigma": s_new, "sigma_old": s_old,
            "misfit": [n for n, m in new.models.items() if m.quality.misfit],
            "misfit_old": [n for n, m in old.models.items() if m.quality.misfit],
            "noise_white": {t: float(m.white_density[0]) for t, m in obs.noise.items()}}


def group_of(name: str) -> str:
    """The group of a coefficient: triad, kind (bias, M_ii scale factor, misalignment, G, K2),
    and c_0 (at T0) or c_1 (slope)."""
    coef = "c1" if name.endswith("_c1") else "c0"
    base = name[:-3] if coef == "c1" else name
    triad, kind = base.split("_")[:2]
    if kind == "M":
        kind = "scale" if base[-1] == base[-2] else "misalign"
    return f"{triad} {kind} {coef}"


def report(rows: list[dict[str, Any]]) -> None:
    """The table: per group, RMS error / RMS σ and RMS z, the issue-30 σ and the old ones."""
    n = len(rows)
    names = list(rows[0]["err"])
    groups: dict[str, list[str]] = {}
    for k in names:
        groups.setdefault(group_of(k), []).append(k)
    print(f"\n{n} unit-runs ({len({r['seed'] for r in rows})} twin runs); per parameter the "
          f"RMS is known to ±{100 / math.sqrt(2 * n):.1f} % (1σ), per group of m parameters "
          "to about that / √m")
    print(f"{'group':<22}{'m':>3}{'RMS err/RMS σ':>15}{'RMS z':>8}{'worst param':>13}"
          f"{'old: RMS err/σ':>16}{'RMS z':>8}")
    worst_all: list[tuple[str, float]] = []
    for g, ks in groups.items():
        e = np.array([[r["err"][k] for k in ks] for r in rows])
        s = np.array([[r["sigma"][k] for k in ks] for r in rows])
        so = np.array([[r["sigma_old"][k] for k in ks] for r in rows])
        ratio = np.sqrt(np.mean(e**2, axis=0) / np.mean(s**2, axis=0))       # per parameter
        ratio_old = np.sqrt(np.mean(e**2, axis=0) / np.mean(so**2, axis=0))
        z = np.sqrt(np.mean((e / s) ** 2))
        zo = np.sqrt(np.mean((e / so) ** 2))
        worst = float(ratio[np.argmax(np.abs(ratio - 1.0))])
        worst_all += list(zip(ks, ratio.tolist(), strict=True))
        print(f"{g:<22}{len(ks):>3}{np.sqrt(np.mean(ratio**2)):>15.3f}{z:>8.3f}{worst:>13.3f}"
              f"{np.sqrt(np.mean(ratio_old**2)):>16.3f}{zo:>8.3f}")
    arr = np.array([w for _, w in worst_all])
    within = int(np.sum(np.abs(arr - 1.0) <= 0.15))
    worst_name, worst = max(worst_all, key=lambda x: abs(x[1] - 1.0))
    print(f"per coefficient, RMS err / RMS σ within ±15 %: {within}/{arr.size}; worst "
          f"{worst_name} × {worst:.3f}; median × {np.median(arr):.3f}")
    mis = np.mean([len(r["misfit"]) for r in rows])
    mis_old = np.mean([len(r["misfit_old"]) for r in rows])
    print(f"misfit models per unit (Birge-scaled): {mis:.2f} of 36 (old: {mis_old:.2f})")
    print(f"per unit-run: twin {np.mean([r['t_run_s'] for r in rows]):.1f} s, analysis (both) "
          f"{np.mean([r['t_analysis_s'] for r in rows]):.1f} s")


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--grade", default="consumer", choices=("consumer", "tactical"))
    ap.add_argument("--n", type=int, default=100, help="twin runs (seeds 1…N)")
    ap.add_argument("--units", type=int, default=2, help="units on the cube per run")
    ap.add_argument("--level", default="station", choices=("station", "window"),
                    help="the whole twin (station, recording, reduction) or the window-level "
                         "twin (its truth and noise generator on the plan's windows)")
    ap.add_argument("--out", type=Path, default=None, help="JSON lines of the runs")
    ap.add_argument("--resume", action="store_true", help="keep the runs already in --out")
    ap.add_argument("--report-only", action="store_true")
    ap.add_argument("--max-minutes", type=float, default=None,
                    help="stop starting runs after this wall time")
    args = ap.parse_args()
    out = args.out or Path(f"/tmp/p2_sigma_mc_{args.grade}_{args.level}.jsonl")
    t0 = time.perf_counter()
    rows: list[dict[str, Any]] = []
    if (args.resume or args.report_only) and out.exists():
        rows = [json.loads(line) for line in out.read_text().splitlines() if line.strip()]
    elif out.exists():
        out.unlink()
    if not args.report_only:
        done = {r["seed"] for r in rows}
        with tempfile.TemporaryDirectory() as tmp, out.open("a") as fh:
            for seed in range(1, args.n + 1):
                if seed in done:
                    continue
                if args.max_minutes and time.perf_counter() - t0 > 60 * args.max_minutes:
                    print(f"time limit: stopped before seed {seed}")
                    break
                new = (one_run(args.grade, args.units, seed, Path(tmp)) if args.level == "station"
                       else one_window_run(args.grade, args.units, seed))
                for r in new:
                    fh.write(json.dumps(r) + "\n")
                fh.flush()
                rows += new
                if seed <= 2 or seed % 10 == 0:
                    print(f"seed {seed}: {sum(r['t_run_s'] for r in new):.1f} s twin, "
                          f"{sum(r['t_analysis_s'] for r in new):.1f} s analysis (elapsed "
                          f"{time.perf_counter() - t0:.0f} s)", flush=True)
    if len(rows) >= 3:
        print(f"grade {args.grade}, the grade's coloured noise, order {ORDER}, "
              f"{args.units} unit(s) a run, {args.level}-level twin")
        report(rows)


if __name__ == "__main__":
    main()
