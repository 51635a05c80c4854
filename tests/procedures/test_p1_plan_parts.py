"""P1's plan options that the optimiser uses: held-out lengths and the last repetition reversed.

docs/test-design.md, "The optimiser (P1)": an optimised plan keeps the default plan's
verification (held-out records and revolutions of their own) and may run its last repetition
in reverse order, so that the six positions close the run. The default plan is unchanged.
"""

from __future__ import annotations

from collections import Counter

import pytest

from imucalib.errors import ConfigurationError
from imucalib.plan.budget import estimate_plan_recording
from imucalib.plan.schema import PositionStep, RateStep
from imucalib.procedures.p1.optimize import P1Design
from imucalib.procedures.p1.options import P1PlanOptions
from imucalib.procedures.p1.plan import generate_p1_plan
from imucalib.procedures.p1.predict import predict_p1
from imucalib.procedures.p1.roles import (
    P1_ACCEL_POSITION,
    P1_GYRO_BIAS,
    P1_GYRO_RATE,
    P1_HELD_OUT_POSITION,
    P1_HELD_OUT_RATE,
)


def test_the_default_plan_is_unchanged_by_the_new_options():
    plan = generate_p1_plan()
    assert generate_p1_plan(held_out_record_s=10.0, held_out_revolutions=3,
                            reverse_last=False) == plan
    assert estimate_plan_recording(plan).duration_s == pytest.approx(16548.6, abs=0.1)
    assert len(plan.steps) == 110


def test_held_out_lengths_apply_to_the_verification_steps_only():
    plan = generate_p1_plan(record_s=60.0, revolutions=8, held_out_record_s=10.0,
                            held_out_revolutions=3)
    by_role = Counter()
    for s in plan.steps:
        if isinstance(s, PositionStep) and s.role == P1_HELD_OUT_POSITION:
            assert s.record_s == 10.0
        elif isinstance(s, PositionStep) and s.role == P1_ACCEL_POSITION:
            assert s.record_s == 60.0
        elif isinstance(s, RateStep) and s.rate_dps != 0.0:
            assert s.revolutions == (3 if s.role == P1_HELD_OUT_RATE else 8), s.label
        elif isinstance(s, RateStep):
            assert s.record_s == 60.0  # the zero-rate calibration point
        by_role[s.role] += 1
    assert by_role[P1_HELD_OUT_POSITION] == 12 and by_role[P1_HELD_OUT_RATE] == 18


def test_the_last_repetition_reversed_keeps_every_step():
    forward = generate_p1_plan(repetitions=3, static_s=300.0)
    reverse = generate_p1_plan(repetitions=3, static_s=300.0, reverse_last=True)
    assert Counter(s.model_dump_json() for s in reverse.steps) == \
        Counter(s.model_dump_json() for s in forward.steps)
    assert estimate_plan_recording(reverse).duration_s == \
        estimate_plan_recording(forward).duration_s
    # the first repetitions as the procedure orders them, the last one's parts reversed
    n_first = sum("rep3" not in s.tags for s in forward.steps)
    assert reverse.steps[:n_first] == forward.steps[:n_first]
    last = [s for s in reverse.steps if "rep3" in s.tags]
    roles = [s.role for s in last if s.role]
    assert roles[:4] == [P1_HELD_OUT_POSITION] * 4
    assert roles[-6:] == [P1_ACCEL_POSITION] * 6
    i_static = roles.index(P1_GYRO_BIAS)
    assert P1_GYRO_RATE in roles[:i_static] and P1_GYRO_RATE not in roles[i_static:]
    # the static record still follows the move to level
    i = next(k for k, s in enumerate(last) if s.role == P1_GYRO_BIAS)
    assert isinstance(last[i - 1], PositionStep) and last[i - 1].angles_deg == (0.0, 0.0)


def test_the_six_positions_closing_the_run_lower_the_accelerometer_biases_sigma():
    """Under flicker the biases rest on the span of their windows (docs/test-design.md)."""
    kw = {"repetitions": 3, "static_s": 300.0, "record_s": 60.0, "revolutions": 5}
    forward = predict_p1(generate_p1_plan(**kw)).std()
    reverse = predict_p1(generate_p1_plan(reverse_last=True, **kw)).std()
    for a in "xyz":
        f, r = forward[f"accel_bias_{a}"], reverse[f"accel_bias_{a}"]
        assert f is not None and r is not None and r < 0.99 * f


def test_an_optimised_design_keeps_the_base_plans_verification():
    base = P1PlanOptions()
    opts = P1Design(3, (-100.0, -50.0, 0.0, 50.0, 100.0), 8, 60.0, 200.0, True).options(base)
    assert (opts.held_out_record_s, opts.held_out_revolutions) == (10.0, 3)
    assert (opts.record_s, opts.revolutions, opts.reverse_last) == (60.0, 8, True)
    given = P1PlanOptions(held_out_record_s=20.0, held_out_revolutions=2)
    opts = P1Design(3, (-100.0, -50.0, 0.0, 50.0, 100.0), 8, 60.0, 200.0).options(given)
    assert (opts.held_out_record_s, opts.held_out_revolutions) == (20.0, 2)


@pytest.mark.parametrize(("kw", "message"), [
    ({"held_out_record_s": 0.0}, r"`held_out_record_s` must be > 0 s; got 0"),
    ({"held_out_revolutions": 0}, r"`held_out_revolutions` must be ≥ 1; got 0"),
])
def test_bad_held_out_lengths_are_refused(kw, message):
    with pytest.raises(ConfigurationError, match=message):
        generate_p1_plan(**kw)
