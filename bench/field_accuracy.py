"""The field calibration against the twin's truth over many hand-held sessions (docs/field.md).

For each seed a session is simulated (gentle, ``handheld_session``, or harsh,
``harsh_handheld_session``: ``imucalib.sim.HARSH``), calibrated by ``analyze_field`` (g's
Type B set to zero: the twin's g is normal gravity exactly), and every parameter with a truth
compared as z = (estimate − truth)/σ, the truth mapped into the accelerometer's frame and taken
at the result's reference temperature (the poses' mean, when the log has a temperature) or
else at the statics' mean temperature
(``tests/procedures/_field_twin.py``). The log carries the twin's temperature sensor unless
``--no-temperature``. Printed per session:
whether the gyro triad was fitted, the worst z and the session's RMS; then the totals the
docs quote (sessions with the gyro triad, RMS of all z, the largest |z|, sessions with a
|z| > 5) and the term choices (how often K2, G and the temperature term were kept).

Run:  .venv/bin/python bench/field_accuracy.py [--harsh] [--grade consumer] [--seeds 0:40]
      [--noise grade|white] [--no-temperature]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "procedures"))

from _field_twin import field_truth  # noqa: E402

from imucalib.procedures.common.static_intervals import FieldLog  # noqa: E402
from imucalib.procedures.field.analysis import FieldOptions, analyze_field  # noqa: E402
from imucalib.sim import handheld_session, harsh_handheld_session  # noqa: E402


def main() -> None:
    """Run the sessions and print the figures (module docstring)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--harsh", action="store_true", help="harsh sessions (HARSH)")
    ap.add_argument("--grade", default="consumer")
    ap.add_argument("--seeds", default="0:40", help="first:last (exclusive)")
    ap.add_argument("--noise", default="grade", choices=("grade", "white"))
    ap.add_argument("--no-temperature", action="store_true",
                    help="leave the temperature sensor out of the log")
    args = ap.parse_args()
    first, last = (int(v) for v in args.seeds.split(":"))
    make = harsh_handheld_session if args.harsh else handheld_session
    every: list[float] = []
    with_gyro = over5 = k2 = g = temp = 0
    t0 = time.perf_counter()
    for seed in range(first, last):
        s = make(args.grade, seed=seed, noise=args.noise)
        log = FieldLog("IMU", "twin", s.time_s, s.gyro_rps, s.accel_mps2,
                       temperature_degc=None if args.no_temperature else s.temperature_degc)
        r = analyze_field(log, FieldOptions(latitude_deg=s.site.latitude_deg,
                                            gravity_std_mps2=0.0))
        truth = field_truth(s.model, session=s,
                            temperature_degc=r.details["reference_temperature_degc"])
        z = {p.name: (p.value - truth[p.name]) / p.std for p in r.parameter_rows()
             if p.name in truth and p.std > 0}
        every += list(z.values())
        worst = max(z, key=lambda n: abs(z[n]))
        has_gyro = r.result.has_triad("gyro")
        with_gyro += has_gyro
        over5 += abs(z[worst]) > 5.0
        k2 += "k2" in r.model_selection[0]["chosen"]
        g += "g" in r.model_selection[1]["chosen"]
        temp += "temp" in r.model_selection[0]["chosen"]
        rms = math.sqrt(float(np.mean(np.square(list(z.values())))))
        print(f"seed {seed:3d}: gyro triad {'yes' if has_gyro else 'NO '}  worst {worst} "
              f"{z[worst]:+.2f}  RMS {rms:.2f}")
    n = last - first
    print(f"\n{args.grade}, {'harsh' if args.harsh else 'gentle'}, {args.noise} noise, seeds "
          f"{first}–{last - 1}: gyro triad in {with_gyro} of {n}; RMS of z "
          f"{math.sqrt(float(np.mean(np.square(every)))):.3f}; max |z| "
          f"{max(abs(v) for v in every):.2f}; sessions with a |z| > 5: {over5}; K2 kept in "
          f"{k2}, G in {g}, the temperature term in {temp}; "
          f"{time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
