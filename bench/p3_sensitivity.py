"""P3 sensitivity campaign: how the K2 error grows with the imperfections of a real centrifuge.

Twin runs of the default P3 plan (r_t = 1 m, five rates up to 20 g, 10 µm of rotor-centre
shift at the top rate with the 2 kg test load), navigation-grade units, each setting over
several seeds, analysed as `imucalib calibrate` does (each series' effective radius) and with
the patent's nominal radii (r_t/3, r_t):

- reference misplacement: the mounting holes of the references at r_t/3 ± δ (A's hole δ
  further out, B's δ further in; the swap puts each reference in the other's hole), or both
  further out;
- spin-axis tilt θ_s (gravity leaks into the radial input once per revolution);
- arm-position error: one of the four rest positions off by ε, with a 0.05° tilt (the rest
  average then keeps part of the leak);
- the references' noise: white only, or the grade's (bias instability and random walk).

Printed: a Markdown table per setting: the shift of the K2_T error from the baseline's, seed by
seed (the same seeds in every setting, so the noise common to both cancels; its mean ± the
spread over the seeds), the RMS K2_T error, the mean reported σ (all g/g²), the shift of c′ in
nm/(rad/s)², and the worst |z| of the five estimates. docs/p3.md,
"Sensitivity", holds the table of one run.

Run:  .venv/bin/python bench/p3_sensitivity.py [--seeds 4]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from imucalib import units
from imucalib.io.opening import open_recording
from imucalib.plan.schema import Plan
from imucalib.procedures.p3.analysis import P3Options, analyze_p3
from imucalib.procedures.p3.plan import UNIT_NAMES, generate_p3_plan
from imucalib.procedures.p3.roundrobin import PARAMETERS
from imucalib.station.runner import RunOptions, run_plan
from imucalib.station.sim import SimStation

R_T = 1.0


def make_plan(seed: int, *, noise: str = "white", delta_m: float = 0.0, out_m: float = 0.0,
              tilt_deg: float = 0.0, arm_error_deg: float = 0.0) -> Plan:
    """The default P3 plan with one imperfection of the twin (module docstring)."""
    arms = (0.0, 90.0 + arm_error_deg, 180.0, 270.0)
    plan = generate_p3_plan(seed=seed, arm_positions_deg=arms)
    assert plan.twin is not None
    twin = plan.twin.model_copy(update={
        "imus": tuple(i.model_copy(update={"noise": noise}) for i in plan.twin.imus),
        "centrifuge": plan.twin.centrifuge.model_copy(update={"spin_axis_tilt_deg": tilt_deg}),
        "fixture": plan.twin.fixture.model_copy(update={"arm_radii_m": (
            R_T / 3 + delta_m + out_m, -(R_T / 3 - delta_m + out_m), R_T)})})
    return plan.model_copy(update={"twin": twin})


def truth(path: Path, plan: Plan) -> dict[str, float]:
    """K2 of each x accelerometer as (P3.1) defines it, c and c′ (tests/procedures/_p3_twin)."""
    assert plan.twin is not None
    fuge = plan.twin.centrifuge
    load = max(s.centrifuge_load_kg or 0.0 for s in plan.steps if s.role == "p3.load")
    with open_recording(path) as rec:
        models = rec.truth["imu_models"]
    out = {}
    for role, key in (("ref-a", "K2_A"), ("ref-b", "K2_B"), ("test", "K2_T")):
        accel = models[UNIT_NAMES[role]]["accel"]
        out[key] = float(accel["k2"][0]) * (1.0 + float(np.asarray(
            accel["scale_misalignment"])[0, 0]))
    out["c"] = fuge.unbalance_c0_m_per_rps_sq
    out["c_loaded"] = fuge.unbalance_c0_m_per_rps_sq + fuge.unbalance_c_m_per_rps_sq_per_kg * load
    return out


def one(plan: Plan, folder: Path) -> dict[str, list[float]]:
    """Run a plan and analyse it both ways; return errors, σ and z."""
    path = folder / "run.h5"
    path.unlink(missing_ok=True)
    assert plan.twin is not None
    station = SimStation(plan.twin)
    summary = run_plan(plan, station, path, options=RunOptions(tick_s=5.0, truth=station.truth))
    assert summary.status == "done", summary.reason
    tr = truth(path, plan)
    out: dict[str, list[float]] = {}
    for how, options in (("fitted", P3Options()),
                         ("nominal", P3Options(radii="nominal",
                                               nominal_radii_m=(R_T / 3, R_T)))):
        est = analyze_p3(path, options=options).estimate
        out[how] = [(est.value("K2_T") - tr["K2_T"]) * units.G0_MPS2,
                    est.std("K2_T") * units.G0_MPS2,
                    (est.value("c_loaded") - tr["c_loaded"]) * 1e9,
                    max(abs((est.value(p) - tr[p]) / est.std(p)) for p in PARAMETERS)]
    path.unlink()
    return out


SETTINGS: list[tuple[str, dict[str, Any]]] = [
    ("baseline (white noise)", {}),
    ("references' holes ±1 mm", {"delta_m": 1e-3}),
    ("references' holes ±5 mm", {"delta_m": 5e-3}),
    ("references' holes ±20 mm", {"delta_m": 20e-3}),
    ("both references 20 mm further out", {"out_m": 20e-3}),
    ("spin-axis tilt 0.01°", {"tilt_deg": 0.01}),
    ("spin-axis tilt 0.05°", {"tilt_deg": 0.05}),
    ("spin-axis tilt 0.2°", {"tilt_deg": 0.2}),
    ("tilt 0.05°, one arm position 0.1° off", {"tilt_deg": 0.05, "arm_error_deg": 0.1}),
    ("tilt 0.05°, one arm position 0.5° off", {"tilt_deg": 0.05, "arm_error_deg": 0.5}),
    ("tilt 0.05°, one arm position 2° off", {"tilt_deg": 0.05, "arm_error_deg": 2.0}),
    ("grade noise (bias instability, random walk)", {"noise": "grade"}),
]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=4)
    parser.add_argument("--only", default="", help="settings whose name contains this "
                                                   "(the baseline always runs)")
    args = parser.parse_args()
    print("| setting | radii | K2_T shift from baseline [g/g²] | K2_T RMS error | mean σ | "
          "c′ shift [nm/(rad/s)²] | worst |z| |")
    print("|---|---|---|---|---|---|---|")
    t0 = time.time()
    base: dict[str, np.ndarray] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, opts in SETTINGS:
            if opts and args.only not in name:
                continue
            rows: dict[str, list[list[float]]] = {"fitted": [], "nominal": []}
            for seed in range(args.seeds):
                res = one(make_plan(100 + seed, **opts), Path(tmp))
                for how in rows:
                    rows[how].append(res[how])
            for how, r in rows.items():
                a = np.array(r)
                if not opts:
                    base[how] = a
                # the same seeds in every setting: the shift from the baseline, seed by seed,
                # is the setting's effect with the noise common to both taken out
                shift = a[:, 0] - base[how][:, 0]
                c_shift = a[:, 2] - base[how][:, 2]
                print(f"| {name} | {how} | {shift.mean():+.2g} ± {shift.std():.1g} | "
                      f"{np.sqrt(np.mean(a[:, 0] ** 2)):.2g} | {a[:, 1].mean():.2g} | "
                      f"{c_shift.mean():+.2g} | {a[:, 3].max():.2g} |", flush=True)
    print(f"\n{args.seeds} seeds per setting (the same in each), {time.time() - t0:.0f} s")


if __name__ == "__main__":
    main()
