"""The rate transfer's default rate set against the D-optimal one (docs/rate-transfer.md).

For the line (RT-5), quadratic and cubic polynomials and the procedure's second fit (RT-7):
the D-efficiency (TD.R2) of the default rates (±5 … ±60 °/s) with equal dwell and with the
plan's dwell (2 revolutions each), the realizable D-optimal rate set (|ω| ≥ 5 °/s) and the
station time of the default plan and of the optimised one at equal generalized variance
(TD.R3); then the issue's 11 equally spaced rates. Run: ``.venv/bin/python
bench/bench_rate_design.py``.
"""

from __future__ import annotations

import numpy as np

from imucalib.procedures.rate_transfer.design import (
    MODELS,
    compare_rate_designs,
    d_efficiency,
    optimal_design,
)
from imucalib.procedures.rate_transfer.plan import generate_rate_transfer_plan
from imucalib.procedures.rate_transfer.predict import predict_rate_transfer

LABEL = {"poly1": "line (RT-5)", "poly2": "quadratic", "poly3": "cubic",
         "transfer": "1,x,|x|,x² (RT-7)"}


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
    white = predict_rate_transfer(plan.model_copy(update={"twin": plan.twin.model_copy(update={
        "imus": tuple(i.model_copy(update={"noise": "white"}) for i in plan.twin.imus)})}))
    print("\ndefault plan, tactical grade: predicted σ (TD.R4), with flicker/RW vs white only")
    ws = white.std()
    for p in pred.parameters[:7]:
        s, sw = p.predicted_std or np.nan, ws[p.name] or np.nan
        print(f"  {p.name:22} {s:10.3g} {sw:10.3g} {p.unit:6} ratio {s / sw:5.2f}")


if __name__ == "__main__":
    main()
