"""P2's reduction of one temperature point: closed form and least squares (docs/p2.md)."""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.errors import InvalidInputError
from imucalib.procedures.p2.reduction import (
    LEVER_ARM_NAMES,
    PARAM_NAMES,
    PointWindows,
    closed_form,
    least_squares,
    orientation_of,
    up_vector,
)

from ._p2_synthetic import EARTH_UP, G, draw_truth
from ._p2_synthetic import point_windows as synthetic_windows


def _point(truth, rng, **kw):
    """PointWindows straight from the synthetic windows of one point (orientation = pose)."""
    from imucalib.procedures.p2.analysis import assemble_point

    windows = synthetic_windows(truth, 0, 25.0, "heating", False, rng, **kw)
    import dataclasses

    windows = [dataclasses.replace(w, orientation=w.pose) for w in windows]
    return assemble_point("U1", 0, windows, G, EARTH_UP)


def _truth_vector(truth):
    return np.concatenate([truth.at(25.0, "heating"), truth.lever_arm_m])


def test_noise_free_closed_form_and_least_squares_recover_truth_exactly():
    truth = draw_truth(np.random.default_rng(1), lever_arm_m=(0.1, -0.05, 0.15))
    pw = _point(truth, np.random.default_rng(2), noise=False)
    want = _truth_vector(truth)
    for est in (closed_form(pw), least_squares(pw)):
        assert est.names == (*PARAM_NAMES, *LEVER_ARM_NAMES)
        np.testing.assert_allclose(est.values, want, rtol=0, atol=1e-12)
    # the static-only accelerometer ("cancel") is exact too, and so is the gyro
    cancel = closed_form(pw, lever_arm="cancel")
    np.testing.assert_allclose(cancel.values, want, rtol=0, atol=1e-12)
    ls_cancel = least_squares(pw, lever_arm="cancel")
    np.testing.assert_allclose(ls_cancel.values, want, rtol=0, atol=1e-12)


def test_naive_analysis_shows_the_lever_arm_error_off_the_axis_and_none_on_it():
    rng = np.random.default_rng(5)
    truth_off = draw_truth(rng, lever_arm_m=(0.0, 0.0, 0.15))
    truth_on = draw_truth(np.random.default_rng(5), lever_arm_m=(0.0, 0.0, 0.0))
    off = _point(truth_off, np.random.default_rng(6))
    on = _point(truth_on, np.random.default_rng(6))
    i = PARAM_NAMES.index("accel_bias_z")
    naive_off, good_off = closed_form(off, lever_arm="ignore"), least_squares(off)
    # ω²·r at 60 °/s and 15 cm is 0.16 m/s²: the naive bias is off by ~(2/3)·(2/3) of it
    sigma = good_off.std[i]
    assert abs(naive_off.values[i] - good_off.values[i]) > 50 * sigma
    # (the up/down pairs see the same centripetal force: scale and misalignment keep clear)
    # the compensated analysis gives the on-axis unit's parameters within uncertainty
    good_on = least_squares(on)
    diff = (good_off.values[:24] - good_on.values[:24]) / np.hypot(good_off.std[:24],
                                                                 good_on.std[:24])
    assert np.max(np.abs(diff)) < 4.0
    naive_on = closed_form(on, lever_arm="ignore")
    assert abs(naive_on.values[i] - good_on.values[i]) < 4 * good_on.std[i]


@pytest.mark.slow
def test_sigma_matches_monte_carlo_spread_and_the_two_forms_agree():
    errs_ls, errs_cf, std_ls, std_cf, agree = [], [], [], [], []
    truth = draw_truth(np.random.default_rng(11), lever_arm_m=(0.08, -0.12, 0.05))
    want = _truth_vector(truth)
    for seed in range(300):
        pw = _point(truth, np.random.default_rng(1000 + seed))
        ls, cf = least_squares(pw), closed_form(pw)
        errs_ls.append(ls.values - want)
        errs_cf.append(cf.values - want)
        std_ls.append(ls.std)
        std_cf.append(cf.std)
        agree.append(np.max(np.abs(cf.values - ls.values) / ls.std))
    for errs, std in ((errs_ls, std_ls), (errs_cf, std_cf)):
        ratio = np.std(errs, axis=0) / np.mean(std, axis=0)
        assert np.all(np.abs(ratio - 1.0) < 0.15), ratio.round(2)
        assert np.all(np.abs(np.mean(errs, axis=0)) < 4 * np.mean(std, axis=0) / np.sqrt(300))
    assert max(agree) < 4.0


def test_fit_quality_flags_a_misfit_and_scaling_widens_sigma():
    truth = draw_truth(np.random.default_rng(3))
    pw = _point(truth, np.random.default_rng(4))
    # a 5 mg error on one static mean that the model cannot absorb
    bad = PointWindows(**{**pw.__dict__, "static_accel_mps2": pw.static_accel_mps2
                          + np.array([[0.05, 0, 0]] + [[0, 0, 0]] * 5)})
    est = least_squares(bad)
    accel = next(q for q in est.fit_quality if q.group == "accel")
    assert accel.misfit and accel.birge_ratio > 2
    assert np.all(np.diag(est.covariance_scaled())[21:] > np.diag(est.covariance)[21:])
    gyro = next(q for q in est.fit_quality if q.group == "gyro")
    assert not gyro.misfit


def test_bad_inputs_are_refused_with_the_field_named():
    truth = draw_truth(np.random.default_rng(3))
    pw = _point(truth, np.random.default_rng(4))
    with pytest.raises(InvalidInputError, match="minus_rate_rps"):
        PointWindows(**{**pw.__dict__, "minus_rate_rps": np.abs(pw.minus_rate_rps)})
    with pytest.raises(InvalidInputError, match="static_accel_mps2"):
        PointWindows(**{**pw.__dict__, "static_accel_mps2": pw.static_accel_mps2[:5]})
    with pytest.raises(InvalidInputError, match="lever_arm"):
        closed_form(pw, lever_arm="guess")  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="orientation"):
        up_vector("+w")


def test_orientation_of_reads_the_up_axis_and_refuses_a_tilted_unit():
    assert orientation_of([0.1, -9.7, 0.2], G) == "-y"
    assert orientation_of([9.81, 0.0, 0.0], G) == "+x"
    assert orientation_of([6.9, 6.9, 0.0], G) is None
