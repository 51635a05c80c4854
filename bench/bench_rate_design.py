"""The rate transfer's default rate set against the D-optimal one (docs/rate-transfer.md).

For the line (RT-5), quadratic and cubic polynomials and the procedure's second fit (RT-7):
the D-efficiency (TD.R2) of the default rates (±5 … ±60 °/s) with equal dwell and with the
plan's dwell (2 revolutions each), the realizable D-optimal rate set (|ω| ≥ 5 °/s) and the
station time of the default plan and of the optimised one at equal generalized variance
(TD.R3); then the issue's 11 equally spaced rates; the predicted σ of the default plan with
the grade's coloured noise against white (TD.R4); then the optimiser
(:func:`~imucalib.procedures.rate_transfer.optimize.optimize_rate_transfer`, ``imucalib plan
optimize rate-transfer``) for one axis: the default targets (every σ no worse than the default
plan's) and the scale-factor terms' targets alone (M_kk, asymmetry, E2), under the tactical
grade's white + flicker + random-walk noise and under white noise, with the eff_D (TD.R2) of the
rate set it chose. Run: ``.venv/bin/python bench/bench_rate_design.py`` (about a minute).
"""

from __future__ import annotations

import numpy as np

from imucalib.plan.schema import Plan, RateStep
from imucalib.procedures.rate_transfer.design import (
    MODELS,
    compare_rate_designs,
    d_efficiency,
    optimal_design,
)
from imucalib.procedures.rate_transfer.optimize import optimize_rate_transfer
from imucalib.procedures.rate_transfer.plan import generate_rate_transfer_plan
from imucalib.procedures.rate_transfer.predict import predict_rate_transfer

LABEL = {"poly1": "line (RT-5)", "poly2": "quadratic", "poly3": "cubic",
         "transfer": "1,x,|x|,x² (RT-7)"}


def _eff(plan: Plan, model: str) -> float:
    """eff_D (TD.R2) of a plan's first axis as written (its rates and dwell)."""
    turns = [s for s in plan.steps if isinstance(s, RateStep) and "axis=x" in s.tags]
    rates = np.array([s.rate_dps for s in turns])
    dwell = np.array([(s.revolutions or 0) * 360.0 / abs(s.rate_dps) for s in turns])
    return d_efficiency(model, rates / np.max(np.abs(rates)), dwell)


def white_twin(plan: Plan) -> Plan:
    """`plan` with its twin IMU's noise white only (the prediction then white too)."""
    assert plan.twin is not None
    return plan.model_copy(update={"twin": plan.twin.model_copy(update={
        "imus": tuple(i.model_copy(update={"noise": "white"}) for i in plan.twin.imus)})})


def optimiser_table() -> None:
    """The optimiser for one axis (x): targets met, design, time, eff_D of its rate set."""
    print("\noptimiser, axis x (σ by (TD.R4): the analysis's GLS under the noise named):")
    print(f"{'noise':10} {'targets':22} {'station s':>16} {'saved':>6} {'eff(RT-7)':>10} "
          f"{'eff line':>9} {'worst':>6}  design")
    for noise in ("grade", "white"):
        base = generate_rate_transfer_plan(axes=("x",))
        if noise == "white":
            base = white_twin(base)
        ref = predict_rate_transfer(base).std()
        for label, names in (("every σ (default)", None),
                             ("M, asymmetry, E2", ("gyro_M_xx", "gyro_asymmetry_x",
                                                   "gyro_E2_x")),
                             ("M (scale factor)", ("gyro_M_xx",))):
            targets = None if names is None else {n: float(ref[n] or 0.0) for n in names}
            o = optimize_rate_transfer(base, targets=targets)
            b, r = o.best, o.reference
            print(f"{noise:10} {label:22} {r.station_time_s:7.0f}→{b.station_time_s:<7.0f}"
                  f" {100 * (1 - b.station_time_s / r.station_time_s):5.0f}%"
                  f" {_eff(r.plan, 'transfer'):4.2f}→{_eff(b.plan, 'transfer'):<4.2f}"
                  f" {_eff(r.plan, 'poly1'):4.2f}→{_eff(b.plan, 'poly1'):<4.2f}"
                  f" {b.worst_ratio:6.3f}  {b.design.describe()} [{b.worst_name}]")


def main() -> None:
    plan = generate_rate_transfer_plan()  # x, y, z; ±5 … ±60 °/s; 2 revolutions
    print("default plan: ±5, 12.5, 18, 27, 36, 45, 60 °/s, 2 revolutions, axes x, y, z")
    print(f"{'model':20} {'eff eq.dwell':>12} {'eff plan':>9} {'optimised |ω| °/s (revs)':>34}"
          f" {'eff opt':>8} {'record s':>14} {'station s':>16} {'saved':>6}")
    for model in MODELS:
        c = compare_rate_designs(plan, model)
        opt = ", ".join(f"{abs(r):.4g}({n})" for r, n in
                        zip(c.optimal_rates_dps, c.optimal_revolutions, strict=True) if r > 0)
        print(f"{LABEL[model]:20} {c.efficiency_equal_dwell:12.3f} {c.efficiency_plan_dwell:9.3f}"
              f" {opt:>34} {c.optimal_efficiency:8.3f}"
              f" {c.default_record_s:6.0f}→{c.optimal_record_s:<6.0f}"
              f" {c.default_station_s:7.0f}→{c.optimal_station_s:<7.0f}"
              f" {100 * c.time_saved_fraction:5.0f}%")
    print("\nunrestricted D-optimal designs on u = ω/ω_max ∈ [−1, 1] (weights = time fractions):")
    for model in MODELS:
        u, w = optimal_design(model)
        print(f"  {LABEL[model]:20} " + ", ".join(f"{a:+.4f}:{b:.3f}" for a, b in zip(u, w,
                                                                                   strict=True)))
    eleven = np.linspace(-1.0, 1.0, 11)
    print("\nissue: 11 equally spaced rates on [−1, 1], equal dwell, eff = (det M/det M*)^(1/m),"
          " m = number of parameters:")
    for model in MODELS:
        print(f"  {LABEL[model]:20} {d_efficiency(model, eleven):.4f}")
    if plan.twin is None:  # pragma: no cover - the generator writes a twin
        return
    pred = predict_rate_transfer(plan)
    white = predict_rate_transfer(white_twin(plan))
    print("\ndefault plan, tactical grade: predicted σ (TD.R4), with flicker/RW vs white only")
    ws = white.std()
    for p in pred.parameters[:7]:
        s, sw = p.predicted_std or np.nan, ws[p.name] or np.nan
        print(f"  {p.name:22} {s:10.3g} {sw:10.3g} {p.unit:6} ratio {s / sw:5.2f}")
    optimiser_table()


if __name__ == "__main__":
    main()
