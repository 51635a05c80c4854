"""P2's analysis of one unit on synthetic window means with known truth (docs/p2.md)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from imucalib.errors import MissingSegmentError
from imucalib.procedures.p2.analysis import P2Options, analyze_unit
from imucalib.procedures.p2.observations import UnitObservations
from imucalib.procedures.p2.reduction import PARAM_NAMES

from ._p2_synthetic import draw_truth, unit_observations


def _z_points(result, truth):
    worst = 0.0
    for p in result.points:
        want = np.concatenate([truth.at(p.temperature_degc, p.leg), truth.lever_arm_m])
        ls = p.least_squares
        z = (ls.values - want) / np.sqrt(np.diag(ls.covariance_scaled()))
        worst = max(worst, float(np.max(np.abs(z))))
    return worst


def test_every_parameter_at_every_point_within_4_sigma_and_t0_values_from_the_models():
    for seed in range(3):
        rng = np.random.default_rng(seed)
        truth = draw_truth(rng, hysteresis=0.1, lever_arm_m=(0.05 * seed, 0.1, -0.15))
        obs = unit_observations(truth, rng, hysteresis=True)
        res = analyze_unit(obs)
        assert res.error == "" and res.result is not None
        # the point estimates are the truth at the point's temperature and leg
        assert _z_points(res, truth) < 4.5
        # c_0 of each model is the truth at T0 = 25 °C between the legs
        std = np.sqrt(np.diag(res.result.covariance))
        z0 = (res.result.values - truth.coefficients[0]) / std
        assert np.max(np.abs(z0)) < 4.5, z0.round(2)
        # both legs were run: every model has the hysteresis term, recovering h
        for i, name in enumerate(PARAM_NAMES):
            m = res.models[name]
            assert m.model.leg_coefficient is not None
            assert abs(m.model.leg_coefficient - truth.hysteresis[i]) < 4.5 * m.std()[-1]
        # the joint covariance holds each model's own σ of c_0 on its diagonal
        np.testing.assert_allclose(np.diag(res.result.covariance),
                                   [res.models[n].covariance_scaled[0, 0] for n in PARAM_NAMES],
                                   rtol=1e-6)
        assert res.passed, res.reasons
        assert max(p.agreement_sigma for p in res.points) < 4.0


@pytest.mark.slow
def test_order_choice_and_held_out_prediction_over_seeds():
    """AICc picks the true cubic for most parameters; held-out points are predicted.

    Measured over 100 seeds: AICc chose order 3 for 83 % of the 36 models, and 96 % of the
    held-out checks were consistent.
    """
    orders, consistent = [], []
    truth = draw_truth(np.random.default_rng(99))
    for seed in range(40):
        obs = unit_observations(truth, np.random.default_rng(500 + seed), gyro_se=5e-5,
                                accel_se=5e-4)
        res = analyze_unit(obs)
        orders += [m.order for m in res.models.values()]
        consistent += [c.consistent for c in res.held_out.values()]
    assert np.mean(np.array(orders) == 3) > 0.7
    assert np.mean(consistent) > 0.9


@pytest.mark.slow
def test_sigma_of_the_values_at_t0_matches_the_monte_carlo_spread():
    """At the true order, σ of every c_0 (Eq. (P2.12)) against the spread over 80 seeds."""
    truth = draw_truth(np.random.default_rng(99))
    z = []
    for seed in range(80):
        obs = unit_observations(truth, np.random.default_rng(700 + seed), gyro_se=5e-5,
                                accel_se=5e-4)
        res = analyze_unit(obs, P2Options(order=3))
        z.append((res.result.values - truth.coefficients[0])
                 / np.sqrt(np.diag(res.result.covariance)))
    z_arr = np.array(z)
    # pooled over 36 parameters × 80 seeds the spread of z is known to ±1.3 %
    assert abs(np.std(z_arr) - 1.0) < 0.06
    assert np.all(np.abs(np.std(z_arr, axis=0) - 1.0) < 0.25)  # each: ±8 % sampling error
    assert np.all(np.abs(np.mean(z_arr, axis=0)) < 0.45)


def test_a_missing_orientation_names_unit_point_and_orientation():
    rng = np.random.default_rng(1)
    truth = draw_truth(rng)
    obs = unit_observations(truth, rng)
    # point 2 loses its −z turns at −ω
    kept = tuple(w for w in obs.windows if not (w.point == 2 and w.pose == "-z"
                                                and w.table_rate_rps < 0))
    with pytest.raises(MissingSegmentError, match=r"unit U1, temperature point 2 .*-z up has no "
                                                  r"−ω turn"):
        analyze_unit(dataclasses.replace(obs, windows=kept))


def test_a_tilted_unit_and_too_few_points_are_refused():
    rng = np.random.default_rng(1)
    truth = draw_truth(rng)
    obs = unit_observations(truth, rng, temperatures=(0.0, 40.0), held_out=())
    tilted = tuple(dataclasses.replace(w, accel_mean_mps2=np.array([6.9, 6.9, 0.0]))
                   if w.point == 1 and w.kind == "static" and w.pose == "+x" else w
                   for w in obs.windows)
    with pytest.raises(MissingSegmentError, match="no body axis reads ±g"):
        analyze_unit(dataclasses.replace(obs, windows=tilted))
    one = tuple(w for w in obs.windows if w.point == 0)
    with pytest.raises(MissingSegmentError, match="at least 2"):
        analyze_unit(UnitObservations(**{**obs.__dict__, "windows": one}))


def test_options_choose_cross_validation_rate_term_and_lever_arm_mode():
    rng = np.random.default_rng(4)
    truth = draw_truth(rng, lever_arm_m=(0.0, 0.0, 0.12))
    obs = unit_observations(truth, rng)
    res = analyze_unit(obs, P2Options(criterion="cv", rate_term=True, lever_arm="cancel",
                                      max_order=2))
    m = res.models["accel_bias_x"]
    assert m.criterion == "cv" and m.order <= 2 and m.model.rate_coefficient is not None
    assert "lever arm cancel" in res.notes[0]
