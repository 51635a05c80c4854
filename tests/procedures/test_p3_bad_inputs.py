"""P3's bad inputs: each gets a typed error that names what was expected and what was found."""

from __future__ import annotations

import math

import numpy as np
import pytest
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.errors import (
    InsufficientExcitationError,
    InvalidInputError,
    MissingSegmentError,
    RecordingError,
    SaturationError,
)
from imucalib.plan.schema import CentrifugeStep, GuardConfig, Plan
from imucalib.procedures.p3.analysis import P3Options, analyze_p3, build_series, tumble_scale
from imucalib.procedures.p3.observations import P3Processing, P3Window

from ._p3_twin import p3_plan, run_p3

_SHORT = {"sample_rate_hz": 20.0, "rate_record_s": 20.0, "rest_record_s": 10.0,
          "settle_s": 15.0, "tumble_record_s": 10.0}
_K1 = {u: (1.0, 1e-5) for u in ("REF-A", "REF-B", "TEST")}


def _without(plan: Plan, drop) -> Plan:
    return plan.model_copy(update={"steps": tuple(s for i, s in enumerate(plan.steps)
                                                  if not drop(i, s))})


def test_three_rates_no_tumble_and_unnamed_units(tmp_path):
    plan = p3_plan(1, tumble=False, **_SHORT)
    # the two top rates of every configuration left out: three rates; the mounting check's
    # tags too
    top = sorted({abs(s.rate_dps) for s in plan.steps if s.role == "p3.rate"})[-2:]
    plan = _without(plan, lambda i, s: s.role == "p3.rate" and abs(s.rate_dps) in top)
    first = plan.steps[0].model_copy(update={"tags": ()})
    plan = plan.model_copy(update={"steps": (first, *plan.steps[1:])})
    path = run_p3(plan, tmp_path / "three.h5")
    with pytest.raises(RecordingError, match="give reference_a, reference_b and test"):
        analyze_p3(path)
    named = {"reference_a": "REF-A", "reference_b": "REF-B", "test": "TEST"}
    with pytest.raises(MissingSegmentError, match=r"unit REF-A: no tumble records.*give k1"):
        analyze_p3(path, options=P3Options(**named))
    with pytest.raises(InsufficientExcitationError, match=r"A1 \(REF-A, configuration 1\): 3 "
                                                          r"distinct rate\(s\).*at least 4"):
        analyze_p3(path, options=P3Options(**named, k1=_K1))


def test_a_missing_swap_is_named_and_the_cli_says_it_in_one_line(tmp_path):
    plan = p3_plan(2, **_SHORT)
    plan = _without(plan, lambda i, s: s.role == "p3.swap" or "config=2" in s.tags)
    path = run_p3(plan, tmp_path / "noswap.h5")
    with pytest.raises(MissingSegmentError, match=r"series A2: unit REF-A has no records in "
                                                  r"configuration 2 \(after the swap"):
        analyze_p3(path)
    res = CliRunner().invoke(app, ["calibrate", str(path), "--out", str(tmp_path), "-q"])
    assert res.exit_code == 2 and "configuration 2" in res.output
    assert "Traceback" not in res.output


def test_a_saturating_reference_is_refused(tmp_path):
    plan = p3_plan(3, **_SHORT)
    assert plan.twin is not None
    # reference A's accelerometer ranges to 5 g; at r_t/3 it sees 6.7 g at the top rate; the
    # station records it (no trip) so that the analysis must refuse it
    imus = tuple(i.model_copy(update={"accel_range_g": 5.0}) if i.name == "REF-A" else i
                 for i in plan.twin.imus)
    plan = plan.model_copy(update={
        "twin": plan.twin.model_copy(update={"imus": imus}),
        "guards": GuardConfig(**{**plan.guards.model_dump(), "trip_on_saturation": False})})
    path = run_p3(plan, tmp_path / "saturated.h5")
    with pytest.raises(SaturationError, match=r"unit REF-A, step \d+ \(config 1: \+\d.*"
                                              r"samples flagged saturated"):
        analyze_p3(path)


def test_a_record_shorter_than_a_revolution_is_named(tmp_path):
    plan = p3_plan(4, **_SHORT)
    i = next(i for i, s in enumerate(plan.steps) if s.role == "p3.rate" and "config=3" in s.tags)
    step = plan.steps[i]
    assert isinstance(step, CentrifugeStep)
    short = step.model_copy(update={"revolutions": None, "record_s": 0.5})  # 180° at 359 °/s
    plan = plan.model_copy(update={"steps": (*plan.steps[:i], short, *plan.steps[i + 1:])})
    path = run_p3(plan, tmp_path / "short.h5")
    with pytest.raises(MissingSegmentError, match=rf"step {i} .*at least one revolution"):
        analyze_p3(path)


def _window(role: str, config: int, mean: float, *, arm: float = math.nan,
            phase: str = "", rate: float = 0.0, unit: str = "U") -> P3Window:
    return P3Window(step_index=0, label="", role=role, unit=unit, config=config, pose="",
                    arm_deg=arm, phase=phase, rate_rps=rate, n_revolutions=0, mean=mean,
                    se=1e-5, duration_s=30.0, n_samples=3000, n_lost=0, time_s=0.0)


def test_rest_records_must_cover_every_arm_position_and_the_tumble_both_signs():
    g = 9.8
    # before: 0, 90, 180, 270; after: 90 missing → the complete phase is used
    rests = [_window("p3.rest", 1, 0.0, arm=a, phase="before") for a in (0, 90, 180, 270)]
    rests += [_window("p3.rest", 1, 0.0, arm=a, phase="after") for a in (0, 180, 270)]
    rates = [_window("p3.rate", 1, w * w / 3, rate=w) for w in (5.0, 8.0, 10.0, 12.0)]
    from imucalib.procedures.p3.analysis import AccelerometerScale, _rest_points

    arms = [0.0, 90.0, 180.0, 270.0]
    means, stds, _ = _rest_points("U", 1, rests, arms)
    assert len(means) == 1 and stds[0] == pytest.approx(1e-5 / 2)
    # neither phase complete: 90° missing before too
    broken = [w for w in rests if not (w.phase == "before" and w.arm_deg == 90)]
    with pytest.raises(MissingSegmentError, match=r"configuration 1: no complete set of rest "
                                                  r"records.*before: arm positions \[0, 180, "
                                                  r"270\] of \[0.0, 90.0, 180.0, 270.0\]"):
        _rest_points("U", 1, broken, arms)
    # three positions that do not cancel a once-per-revolution leak
    with pytest.raises(MissingSegmentError, match=r"do not cancel a tilted spin axis"):
        _rest_points("U", 1, [w for w in rests if w.arm_deg != 90], [0.0, 180.0, 270.0])
    assert len(_rest_points("U", 1, [_window("p3.rest", 1, 0.0, arm=a, phase="before")
                                     for a in (0, 120, 240)], [0.0, 120.0, 240.0])[0]) == 1
    scale = AccelerometerScale("U", 1.0, 1e-5, 0.0, 1e-5, "input")
    with pytest.raises(MissingSegmentError, match="configuration 2"):
        build_series({u: rests + rates for u in ("A", "B", "T")},
                     {"ref-a": "A", "ref-b": "B", "test": "T"},
                     {u: scale for u in ("A", "B", "T")}, 0.0)
    tumble = [_window("p3.tumble", 0, g + 1e-4), _window("p3.tumble", 0, -g + 3e-4)]
    sc = tumble_scale("U", tumble, g, 0.0)
    assert sc.k1 == pytest.approx(1.0 - 1e-5) and sc.k0 == pytest.approx(2e-4)
    with pytest.raises(MissingSegmentError, match=r"input axis up.*read \[1.0\] g"):
        tumble_scale("U", tumble[:1], g, 0.0)


def test_bad_options_are_refused():
    with pytest.raises(InvalidInputError, match="k1"):
        P3Options(k1={"A": (0.0, 1e-5)})
    with pytest.raises(InvalidInputError, match="nominal_radii_m"):
        P3Options(radii="nominal")
    with pytest.raises(InvalidInputError, match="input_axis"):
        P3Processing(input_axis="w")
    assert np.isfinite(P3Options().k2_target_g_per_g2)
