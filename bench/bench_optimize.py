"""Bench: P1's plan optimiser (issue 30): run time on one core, station times, σ tables.

Prints (docs/test-design.md, "The optimiser (P1)" and "What binds"):

1. ``--target-default``: the least station time with every parameter's σ no worse than the
   default plan's, with the procedure's 60-min static (the default margin);
2. the same with statics from 120 s (their calibrations take the grade's flicker and random
   walk as a Type B input, docs/p1.md "Noise model of the window means"; checked on the twin in
   docs/test-design.md "Truth on the twin"), with three repetitions (docs/p1.md rule 6) and
   with two;
3. the best worst σ/default within half the default's time, and what each design freedom
   buys there (the procedure's step order only; the search grid of the first optimiser);
4. the reverse table: the σ the design with short statics reaches within the default's time;
5. the station time of the default and the optimised plan, item by item, and the binding
   parameter's σ split into its white, flicker and random-walk parts.

Run: ``.venv/bin/python bench/bench_optimize.py`` (one BLAS thread: one core; 3–6 minutes).
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import dataclasses  # noqa: E402
import time  # noqa: E402
from collections import defaultdict  # noqa: E402

from imucalib.models.noise import NoiseModel  # noqa: E402
from imucalib.plan.budget import MIN_SETTLE_PHASE_S, MOVE_ALLOWANCE_S  # noqa: E402
from imucalib.plan.schema import (  # noqa: E402
    Plan,
    PositionStep,
    RateStep,
    StaticStep,
    WarmUpStep,
    step_min_duration_s,
)
from imucalib.procedures.common.grade import grade_noise  # noqa: E402
from imucalib.procedures.p1.optimize import (  # noqa: E402
    OptimizeResult,
    OptimizeSettings,
    default_targets,
    optimize_p1,
)
from imucalib.procedures.p1.predict import predict_p1  # noqa: E402
from imucalib.report.console import display_unit  # noqa: E402

HALF_H = 2.30
#: The first optimiser's grid (before the longer windows and the reversed last repetition).
FIRST_GRID = {"record_s_grid": (10.0, 20.0, 30.0, 60.0), "revolutions_grid": (2, 3, 4, 5),
              "reverse_last_grid": (False,)}


def _table(result: OptimizeResult, title: str) -> None:
    ref, best = result.reference, result.best
    print(f"\n{title}")
    print(f"  default plan   {ref.station_time_s:8,.0f} s ({ref.station_time_s / 3600:.2f} h)")
    print(f"  optimised plan {best.station_time_s:8,.0f} s ({best.station_time_s / 3600:.2f} h,"
          f" {best.station_time_s / ref.station_time_s:.1%}); worst σ/target "
          f"{best.worst_ratio:.4f} ({max(best.ratios, key=lambda n: best.ratios[n])})")
    d = best.design
    print(f"  optimised: {d.repetitions} repetitions, record {d.record_s:g} s, static "
          f"{d.static_s:g} s, {d.revolutions} rev, rates {', '.join(f'{r:g}' for r in d.rates_dps)}"
          f" °/s{', last repetition reversed' if d.reverse_last else ''}; "
          f"{result.n_evaluated} plans predicted in {result.elapsed_s:.1f} s")
    print(f"  {'parameter':<14}{'unit':<9}{'default σ':>11}{'optimised σ':>13}{'ratio':>8}")
    ref_std, best_std = ref.prediction.std(), best.prediction.std()
    for p in best.prediction.parameters:
        unit, scale = display_unit(p.name, p.unit)
        a, b = ref_std[p.name], best_std[p.name]
        assert a is not None and b is not None
        print(f"  {p.name:<14}{unit:<9}{a / scale:>11.3g}{b / scale:>13.3g}{b / a:>8.3f}")


def costs(plan: Plan) -> dict[str, float]:
    """Station time per item (the budget's model, ``plan/budget.py``). [s]"""
    out: dict[str, float] = defaultdict(float)
    for s in plan.steps:
        if isinstance(s, WarmUpStep):
            out["warm-up"] += max(s.duration_s, s.window_s)
        elif isinstance(s, StaticStep):
            out["level static record"] += s.duration_s
        elif isinstance(s, PositionStep | RateStep):
            what = {"p1.accel-position": "six positions", "p1.gyro-rate": "calibration rates",
                    "p1.held-out-position": "held-out positions",
                    "p1.held-out-rate": "held-out rates"}.get(s.role, "moves to level/start")
            out[f"{what}: settle + move"] += max(s.settle_s, MIN_SETTLE_PHASE_S) \
                + MOVE_ALLOWANCE_S
            out[f"{what}: record"] += step_min_duration_s(s) - s.settle_s
    return dict(out)


def _costs_table(ref: Plan, best: Plan) -> None:
    a, b = costs(ref), costs(best)
    print("\n5. station time item by item [s] (default | optimised)")
    for k in sorted(set(a) | set(b)):
        print(f"  {k:<40}{a.get(k, 0.0):9,.0f}{b.get(k, 0.0):9,.0f}")
    print(f"  {'total':<40}{sum(a.values()):9,.0f}{sum(b.values()):9,.0f}")


def _split(plan: Plan, name: str) -> str:
    """The σ of `name` with the white, flicker and random-walk parts of the grade's noise."""
    g = grade_noise(plan)
    tiny = 1e-6  # a white floor far below the others, so the design stays identifiable

    def part(**kw: bool) -> dict[str, NoiseModel]:
        return {k: NoiseModel(white_density=v.white_density * (1.0 if kw.get("white") else tiny),
                              bias_instability=v.bias_instability if kw.get("flicker") else 0.0,
                              random_walk=v.random_walk if kw.get("rw") else 0.0)
                for k, v in g.items()}

    unit, scale = display_unit(name, "rad/s" if name.startswith("gyro") else "m/s^2")
    parts = {"all": g, "white": part(white=True), "flicker": part(flicker=True),
             "random walk": part(rw=True), "white + flicker": part(white=True, flicker=True)}
    return ", ".join(f"{k} {float(predict_p1(plan, noise=m).std()[name] or 0.0) / scale:.3f}"
                     for k, m in parts.items()) + f" {unit}"


def main() -> None:
    """Run the searches (the full grid) and print the tables."""
    targets = default_targets()
    short = OptimizeSettings(min_static_s=120.0)
    print("P1 optimiser, tactical grade, default acceptance limits, one BLAS thread")
    t = time.perf_counter()
    least = optimize_p1(targets=targets)  # the procedure's 60-min static kept
    print(f"  least time, every σ ≤ default, 60-min static: {time.perf_counter() - t:.1f} s")
    least_short = optimize_p1(targets=targets, settings=short)
    least_two = optimize_p1(targets=targets,
                            settings=dataclasses.replace(short, min_repetitions=2))
    half = HALF_H * 3600
    within_half = optimize_p1(targets=targets,
                              settings=dataclasses.replace(short, time_budget_s=half))
    budget = least.reference.station_time_s
    within = optimize_p1(targets=targets,
                         settings=dataclasses.replace(short, time_budget_s=budget))
    _table(least, "1. every σ no worse than the default plan's, least station time, the "
                  "procedure's 60-min static")
    _table(least_short, "2a. the same with statics from 120 s (the grade's flicker, Type B), "
                        "three repetitions")
    _table(least_two, "2b. the same with two repetitions")
    _table(within_half, f"3. the best worst σ/default within {HALF_H:.2f} h (half the "
                        "default's), statics from 120 s, three repetitions")
    for label, extra in (("the procedure's step order only", {"reverse_last_grid": (False,)}),
                         ("the first optimiser's grid (its held-out points at the default's "
                          "lengths)", FIRST_GRID),
                         ("two repetitions", {"min_repetitions": 2})):
        r = optimize_p1(targets=targets, settings=dataclasses.replace(
            short, time_budget_s=half, **extra))  # type: ignore[arg-type]
        print(f"  within {HALF_H:.2f} h, {label}: worst σ/default {r.best.worst_ratio:.4f} "
              f"({max(r.best.ratios, key=lambda n: r.best.ratios[n])})")
    _table(within, f"4. reverse table, statics from 120 s: σ within the default plan's "
                   f"{budget / 3600:.2f} h")
    _costs_table(least_short.reference.plan, least_short.best.plan)
    name = max(within_half.best.ratios, key=lambda n: within_half.best.ratios[n])
    print(f"\n   {name}, the binding parameter within {HALF_H:.2f} h, by noise term:")
    for label, plan in (("default", least.reference.plan), ("2a", least_short.best.plan),
                        (f"{HALF_H:.2f} h", within_half.best.plan)):
        print(f"   {label:<8} {_split(plan, name)}")


if __name__ == "__main__":
    main()
