"""Bench: the rate transfer's reported σ against the Monte-Carlo spread on the twin (issue 30).

Does the σ the rate-transfer analysis reports hold under coloured noise? For seeds 1…N: a
rate-transfer plan of one axis (z up; the default rates ±5 … ±60 °/s, two revolutions each, or
``--rates``) run on the twin (:class:`~imucalib.station.sim.SimStation`, in process) with the
tactical grade's noise (white, flicker, rate random walk: ``noise = "grade"``; ``--white`` for
white only) and the unit's nonlinear terms set to zero (asymmetry, K2, K3, Koq), so that the
truths are (RT-9): E = E′ = 1 + M_zz, E0 = E0′ = b_z + G_zz·g, A = E2 = 0. Each run's turns are
reduced once (:func:`~imucalib.procedures.common.rate_windows.extract_rate_windows`) and fitted
two ways:

- *white*: weighted by the white σ_j = N/√T_j (RT-4), the analysis before (RT-4c);
- *coloured*: generalized least squares with the means' covariance C (RT-4c) of the fitted
  white density and the declared grade's flicker and random walk
  (:func:`~imucalib.procedures.rate_transfer.noise.turn_noise`), the analysis now (the first
  run is checked against :func:`~imucalib.procedures.rate_transfer.analysis.
  analyze_rate_transfer` bit for bit).

Per parameter: the spread of the errors (std about their mean, with its 95 % χ² interval), the
RMS reported σ (Birge-scaled on a misfit, as reported) and their ratio, for both; and the share
of misfits. Results are appended to ``--out`` (JSON lines, one per run); ``--report-only``
prints the table from them.

Run (one core, about 8 s a run)::

    OPENBLAS_NUM_THREADS=1 nice -n 5 .venv/bin/python bench/rate_transfer_montecarlo.py \\
        --n 120 --out /tmp/rt_mc.jsonl
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402
from scipy import stats  # noqa: E402

from imucalib.io.opening import open_recording  # noqa: E402
from imucalib.plan.schema import Plan  # noqa: E402
from imucalib.procedures.common.rate_windows import extract_rate_windows  # noqa: E402
from imucalib.procedures.common.reference import site_vectors  # noqa: E402
from imucalib.procedures.rate_transfer.analysis import (  # noqa: E402
    AxisTransfer,
    analyze_rate_transfer,
    transfer_of_axis,
)
from imucalib.procedures.rate_transfer.noise import turn_noise  # noqa: E402
from imucalib.procedures.rate_transfer.plan import generate_rate_transfer_plan  # noqa: E402
from imucalib.procedures.rate_transfer.roles import RATE_TRANSFER_RATE  # noqa: E402
from imucalib.station.runner import RunOptions, run_plan  # noqa: E402
from imucalib.station.sim import SimStation  # noqa: E402

UNIT = "IMU-0001"
AXIS, K = "z", 2
NAMES = ("scale_factor", "bias_line", "M", "bias_up", "asymmetry", "E2")
ZERO = {"gyro.scale_asymmetry": (0.0, 0.0, 0.0), "gyro.k2": (0.0, 0.0, 0.0),
        "gyro.k3": (0.0, 0.0, 0.0), "gyro.koq": (0.0, 0.0, 0.0)}


def make_plan(seed: int, rates: tuple[float, ...] | None, grade: str, white: bool) -> Plan:
    """One axis (z up), the unit's nonlinear terms zero, the grade's noise (or white)."""
    plan = generate_rate_transfer_plan(rates_dps=rates, axes=(AXIS,), sample_rate_hz=100.0,
                                       seed=seed, grade=grade)
    assert plan.twin is not None
    imus = tuple(i.model_copy(update={"errors": ZERO, "seed": seed,
                                      "noise": "white" if white else "grade"})
                 for i in plan.twin.imus)
    return plan.model_copy(update={"twin": plan.twin.model_copy(update={"imus": imus})})


def _row(a: AxisTransfer) -> dict[str, tuple[float, float]]:
    """(estimate, σ as reported) of each parameter of one axis' fits."""
    t = a.transfer
    assert t is not None
    asym, asym_s = t.asymmetry
    return {"scale_factor": (a.line.scale_factor, float(np.sqrt(a.line.cov[1, 1]))),
            "bias_line": (a.line.bias_rps, float(np.sqrt(a.line.cov[0, 0]))),
            "M": (float(t.params[1]) - 1.0, t.std(1)), "bias_up": (float(t.params[0]), t.std(0)),
            "asymmetry": (asym, asym_s), "E2": (float(t.params[3]), t.std(3))}


def one_run(seed: int, workdir: Path, rates: tuple[float, ...] | None, grade: str,
            white: bool, check: bool = False) -> dict[str, Any]:
    """Run one seed and return its errors and σ, white and coloured (module docstring)."""
    plan = make_plan(seed, rates, grade, white)
    assert plan.twin is not None
    path = workdir / f"rt_{seed}.h5"
    station = SimStation(plan.twin)
    t0 = time.perf_counter()
    summary = run_plan(plan, station, path, overwrite=True,
                       options=RunOptions(tick_s=5.0, truth=station.truth))
    assert summary.status == "done", summary.reason
    t1 = time.perf_counter()
    with open_recording(path) as rec:
        gyro = rec.truth["imu_models"][UNIT]["gyro"]
        g, _ = site_vectors(float(rec.metadata.get("latitude_deg", 45.0)), 0.0, None)
        _, windows, earth_up = extract_rate_windows(rec, UNIT, (RATE_TRANSFER_RATE,))
        w0 = windows[0]
        n_white = w0.gyro_se_rps * math.sqrt(w0.duration_s)
        rate_hz = plan.twin.imus[0].sample_rate_hz
        noise = turn_noise(rec, windows, n_white, rate_hz)
        old = transfer_of_axis(AXIS, windows, earth_up)
        new = transfer_of_axis(AXIS, windows, earth_up, noise.covariance[AXIS])
        if check:
            ref = analyze_rate_transfer(rec).axis(AXIS)
            assert ref.transfer is not None and new.transfer is not None
            assert np.array_equal(ref.transfer.params, new.transfer.params)
            assert np.array_equal(ref.transfer.cov, new.transfer.cov)
    path.unlink()
    m = np.asarray(gyro["scale_misalignment"], dtype=float)
    b = np.asarray(gyro["bias"], dtype=float)
    gs = np.asarray(gyro["g_sensitivity"], dtype=float)
    truth = {"scale_factor": 1.0 + m[K, K], "bias_line": b[K] + gs[K, K] * g,
             "M": m[K, K], "bias_up": b[K] + gs[K, K] * g, "asymmetry": 0.0, "E2": 0.0}
    out: dict[str, Any] = {"seed": seed, "twin_s": t1 - t0,
                           "analysis_s": time.perf_counter() - t1,
                           "misfit_white": [old.line.quality.misfit,
                                            bool(old.transfer and old.transfer.quality.misfit)],
                           "misfit_coloured": [new.line.quality.misfit,
                                               bool(new.transfer and new.transfer.quality.misfit)],
                           "chi2_coloured": [new.line.quality.reduced_chi2,
                                             new.transfer.quality.reduced_chi2
                                             if new.transfer else math.nan]}
    for label, a in (("white", old), ("coloured", new)):
        out[label] = {n: [v - truth[n], s] for n, (v, s) in _row(a).items()}
    return out


def report(rows: list[dict[str, Any]]) -> None:
    """Print spread vs RMS reported σ per parameter, white and coloured (module docstring)."""
    n = len(rows)
    lo_q, hi_q = stats.chi2.ppf([0.025, 0.975], n - 1)
    print(f"{n} runs; spread = std of the errors about their mean, 95 % interval of the spread "
          f"±[{math.sqrt((n - 1) / hi_q) - 1:+.0%}, {math.sqrt((n - 1) / lo_q) - 1:+.0%}]")
    print(f"{'parameter':14} {'spread':>10} {'mean err':>10} | {'σ white':>10} {'σ/spread':>8} |"
          f" {'σ GLS':>10} {'σ/spread':>8}")
    for name in NAMES:
        err = np.array([r["coloured"][name][0] for r in rows])
        err_w = np.array([r["white"][name][0] for r in rows])
        s_c = math.sqrt(np.mean([r["coloured"][name][1] ** 2 for r in rows]))
        s_w = math.sqrt(np.mean([r["white"][name][1] ** 2 for r in rows]))
        spread, spread_w = float(np.std(err, ddof=1)), float(np.std(err_w, ddof=1))
        print(f"{name:14} {spread:10.3g} {np.mean(err):10.3g} | {s_w:10.3g} "
              f"{s_w / spread_w:8.3f} | {s_c:10.3g} {s_c / spread:8.3f}")
    for label in ("white", "coloured"):
        mis = np.array([r[f"misfit_{label}"] for r in rows])
        print(f"misfits ({label}): line {int(mis[:, 0].sum())}/{n}, second fit "
              f"{int(mis[:, 1].sum())}/{n}")
    chi = np.array([r["chi2_coloured"] for r in rows])
    print(f"χ²/ν (GLS): line mean {np.mean(chi[:, 0]):.3f}, second fit "
          f"{np.nanmean(chi[:, 1]):.3f}; twin {np.mean([r['twin_s'] for r in rows]):.1f} s, "
          f"analysis {np.mean([r['analysis_s'] for r in rows]):.1f} s a run")


def main() -> None:
    """Run or report (module docstring)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=120)
    ap.add_argument("--first-seed", type=int, default=1)
    ap.add_argument("--rates", type=str, default="", help="magnitudes, °/s, comma-separated")
    ap.add_argument("--grade", default="tactical")
    ap.add_argument("--white", action="store_true")
    ap.add_argument("--max-minutes", type=float, default=60.0)
    ap.add_argument("--out", type=Path, default=Path("/tmp/rt_transfer_mc.jsonl"))
    ap.add_argument("--report-only", action="store_true")
    args = ap.parse_args()
    rates = tuple(float(r) for r in args.rates.split(",")) if args.rates else None
    done: list[dict[str, Any]] = []
    if args.out.exists():
        done = [json.loads(line) for line in args.out.read_text().splitlines() if line]
    if not args.report_only:
        have = {r["seed"] for r in done}
        start = time.perf_counter()
        with tempfile.TemporaryDirectory() as tmp, args.out.open("a") as fh:
            for seed in range(args.first_seed, args.first_seed + args.n):
                if seed in have:
                    continue
                if time.perf_counter() - start > 60.0 * args.max_minutes:
                    break
                r = one_run(seed, Path(tmp), rates, args.grade, args.white,
                            check=seed == args.first_seed)
                fh.write(json.dumps(r) + "\n")
                fh.flush()
                done.append(r)
    report(done)


if __name__ == "__main__":
    main()
