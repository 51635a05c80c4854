"""P1's plan optimiser (docs/test-design.md, "The optimiser (P1)"), on the coarse grid."""

from __future__ import annotations

import dataclasses
import math

import pytest

from imucalib import units
from imucalib.errors import ConfigurationError
from imucalib.procedures.p1.optimize import (
    OptimizeSettings,
    default_targets,
    optimize_p1,
    parse_targets,
    spec_targets,
)
from imucalib.procedures.p1.plan import generate_p1_plan

DEFAULT_H = 4.6


@pytest.fixture(scope="module")
def targets():
    return default_targets()


#: Statics from 120 s, the shortest the analysis accepts: predicted well, but their calibrations
#: under-report the biases' σ (docs/test-design.md, "Truth on the twin"); the search's
#: mechanics are tested on them, the default keeps the procedure's 60 min.
SHORT_STATIC_S = 120.0


@pytest.fixture(scope="module")
def least_time(targets):
    return optimize_p1(targets=targets,
                       settings=OptimizeSettings.coarse(min_static_s=SHORT_STATIC_S))


def test_default_targets_met_in_far_less_time_with_short_statics(least_time, targets):
    best, ref = least_time.best, least_time.reference
    assert ref.station_time_s == pytest.approx(DEFAULT_H * 3600, rel=0.01)
    sigma = best.prediction.std()
    assert all(sigma[n] <= s * (1 + 1e-6) for n, s in targets.items())
    # the issue asks for half (2.3 h); the coarse grid reaches 55 % (2.52 h), the full grid
    # 52 %: the biases' flicker floor needs the windows spread over the session, which the
    # warm-up shortens (docs/test-design.md, "What binds")
    assert best.station_time_s <= 0.56 * ref.station_time_s
    assert best.design.repetitions >= 2 and min(best.lack_of_fit_dof.values()) >= 6
    # the default plan's verification, whatever the calibration windows' lengths
    held = [s for s in best.plan.steps if "verification" in s.tags]
    assert len(held) == best.design.repetitions * (4 + 3 * 2)
    assert {getattr(s, "record_s", None) for s in held if s.kind == "position"} == {10.0}
    assert {getattr(s, "revolutions", None) for s in held if s.kind == "rate"} == {3}


def test_with_the_procedures_60_min_static_no_shorter_plan_meets_the_default(targets):
    """The default margin: the optimiser keeps the static the noise model needs, and then
    the default plan is already the shortest meeting its own σ (docs/test-design.md)."""
    assert OptimizeSettings().min_static_s == 3600.0
    result = optimize_p1(targets=targets, settings=OptimizeSettings.coarse())
    assert result.best.design.static_s >= 3600.0
    assert result.best.station_time_s == pytest.approx(result.reference.station_time_s,
                                                       rel=0.01)
    assert result.best.worst_ratio <= 1.0 + 1e-6


def test_within_the_default_time_every_sigma_is_better(targets):
    budget = DEFAULT_H * 3600
    result = optimize_p1(targets=targets,
                         settings=OptimizeSettings.coarse(time_budget_s=budget,
                                                          min_static_s=SHORT_STATIC_S))
    assert result.best.station_time_s <= budget
    assert result.best.worst_ratio < 1.0


@pytest.mark.parametrize("criterion", ["D", "A"])
def test_d_and_a_criteria_within_a_budget(targets, criterion):
    settings = OptimizeSettings.coarse(criterion=criterion, time_budget_s=3.0 * 3600,
                                       min_static_s=SHORT_STATIC_S,
                                       max_repetitions=3, revolutions_grid=(3,),
                                       rate_magnitudes_dps=(50.0, 100.0))
    result = optimize_p1(targets=targets, settings=settings)
    assert result.best.station_time_s <= 3.0 * 3600
    assert math.isfinite(result.best.criterion_value)


def test_impossible_target_in_a_tiny_budget_is_refused(targets):
    tiny = dict.fromkeys(targets, 1e-12)
    with pytest.raises(ConfigurationError, match=r"no P1 plan fits within 0\.50 h: the shortest"):
        optimize_p1(targets=tiny, settings=OptimizeSettings.coarse(time_budget_s=1800.0))


def test_unreachable_target_names_the_best_reached(targets):
    settings = OptimizeSettings.coarse(max_repetitions=3, record_s_grid=(10.0,),
                                       revolutions_grid=(3,), rate_magnitudes_dps=(50.0, 100.0))
    with pytest.raises(ConfigurationError, match="meets the targets; the best reaches a worst "
                                                 "σ/target of"):
        optimize_p1(targets={"gyro_bias_z": 1e-9}, settings=settings)


def test_criterion_needs_a_budget():
    with pytest.raises(ConfigurationError, match="criterion D needs a time budget"):
        OptimizeSettings(criterion="D").check()


def test_parse_targets_prefix_and_errors(targets):
    got = parse_targets("gyro_bias=5e-6, accel_M_xx=1e-5", list(targets))
    assert got == {"gyro_bias_x": 5e-6, "gyro_bias_y": 5e-6, "gyro_bias_z": 5e-6,
                   "accel_M_xx": 1e-5}
    with pytest.raises(ConfigurationError, match="names no P1 parameter"):
        parse_targets("gyro_nope=1", list(targets))
    with pytest.raises(ConfigurationError, match="write NAME=σ"):
        parse_targets("gyro_bias=-1", list(targets))


def test_spec_targets_are_limit_over_k(targets):
    plan = generate_p1_plan()
    got = spec_targets(plan, list(targets), k=4.0)
    assert got["gyro_bias_z"] == pytest.approx(20.0 * units.DEG_PER_H / 4.0)
    assert got["accel_M_xy"] == pytest.approx(2000e-6 / 4.0)
    assert "gyro_G_xy" in got
    with pytest.raises(ConfigurationError, match="k must be > 0"):
        spec_targets(plan, list(targets), k=0.0)


def test_settings_are_checked():
    with pytest.raises(ConfigurationError, match="≥ 10 s"):
        dataclasses.replace(OptimizeSettings(), record_s_grid=(5.0,)).check()
