"""Temperature models (estimation/temperature_model.py): honesty of σ, order choice, held-out
check, hysteresis, misfit, conversion to TemperatureDependence, errors.

Monte-Carlo numbers are printed (``pytest -s``) and quoted in docs/processing-estimation.md,
"Temperature models".
"""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.errors import InsufficientExcitationError, InvalidInputError
from imucalib.estimation.temperature_forms import (
    from_temperature_dependence,
    to_temperature_dependence,
)
from imucalib.estimation.temperature_model import (
    TemperaturePolynomial,
    check_held_out,
    fit_temperature_model,
    predict_temperature_model,
)
from imucalib.models.temperature import evaluate_parameter

T_DEGC = np.linspace(-40.0, 85.0, 12)
T0_DEGC = 25.0
SIGMA = 0.05  # e.g. mg
RHO = 0.6
#: A cubic whose c_3 is about 4 σ_c3 with 12 points and the AR(1) covariance below.
CUBIC = np.array([1.0, 0.02, 3e-4, 1.25e-6])
N_SEEDS = 300


def ar1_covariance(n: int, sigma: float, rho: float) -> np.ndarray:
    i = np.arange(n)
    return sigma**2 * rho ** np.abs(i[:, None] - i[None, :])


def poly(c: np.ndarray, t: np.ndarray) -> np.ndarray:
    return sum(cj * (t - T0_DEGC) ** j for j, cj in enumerate(c))


COV = ar1_covariance(T_DEGC.size, SIGMA, RHO)
CHOL = np.linalg.cholesky(COV)


def draw(truth: np.ndarray, seed: int) -> np.ndarray:
    return truth + CHOL @ np.random.default_rng(seed).standard_normal(truth.size)


@pytest.mark.slow
def test_cubic_sigma_honest_and_order_chosen() -> None:
    truth = poly(CUBIC, T_DEGC)
    z, aicc_orders, cv_orders = [], [], []
    for seed in range(N_SEEDS):
        p = draw(truth, seed)
        fixed = fit_temperature_model(T_DEGC, p, COV, order=3, reference_temperature_degc=T0_DEGC)
        z.append((np.array(fixed.model.coefficients) - CUBIC) / fixed.std())
        auto = fit_temperature_model(T_DEGC, p, COV, reference_temperature_degc=T0_DEGC)
        assert auto.criterion == "aicc" and set(auto.aicc) == {0, 1, 2, 3}
        aicc_orders.append(auto.order)
        cv_orders.append(min(auto.cv, key=lambda m: auto.cv[m]))
    zs = np.array(z)
    frac_aicc = np.mean(np.array(aicc_orders) == 3)
    frac_cv = np.mean(np.array(cv_orders) == 3)
    print(f"\ncubic: z mean {np.round(zs.mean(0), 3)}, z std {np.round(zs.std(0), 3)}; "
          f"order 3 chosen by AICc in {frac_aicc:.1%}, by CV in {frac_cv:.1%} of {N_SEEDS}")
    assert np.all(np.abs(zs.mean(0)) < 0.15)
    assert np.all(np.abs(zs.std(0) - 1.0) < 0.10)
    assert frac_aicc > 0.8
    assert frac_cv > 0.6


@pytest.mark.slow
def test_linear_truth_picks_order_one() -> None:
    truth = poly(np.array([1.0, 0.02]), T_DEGC)
    aicc, cv = [], []
    for seed in range(N_SEEDS):
        p = draw(truth, seed)
        fa = fit_temperature_model(T_DEGC, p, COV, reference_temperature_degc=T0_DEGC)
        fc = fit_temperature_model(T_DEGC, p, COV, criterion="cv")
        aicc.append(fa.order)
        cv.append(fc.order)
    frac_aicc, frac_cv = np.mean(np.array(aicc) == 1), np.mean(np.array(cv) == 1)
    print(f"\nlinear: order 1 chosen by AICc in {frac_aicc:.1%}, by CV in {frac_cv:.1%}")
    assert frac_aicc > 0.8
    # leave-one-out CV behaves like the uncorrected AIC and over-fits small K more often
    assert 0.3 < frac_cv < frac_aicc
    assert np.all(np.array(aicc) >= 1)  # the slope (~40 σ) is never missed


@pytest.mark.slow
def test_prediction_sigma_matches_monte_carlo() -> None:
    truth = poly(CUBIC, T_DEGC)
    held = np.array([-35.0, 0.0, 50.0, 80.0])
    preds, stds = [], []
    for seed in range(N_SEEDS):
        fit = fit_temperature_model(T_DEGC, draw(truth, seed), COV, order=3,
                                    reference_temperature_degc=T0_DEGC)
        pr = predict_temperature_model(fit, held)
        preds.append(pr.value)
        stds.append(pr.std)
    ratio = np.std(preds, axis=0) / np.mean(stds, axis=0)
    bias = (np.mean(preds, axis=0) - poly(CUBIC, held)) / np.mean(stds, axis=0)
    print(f"\nprediction: MC std / σ_pred at {held} °C = {np.round(ratio, 3)}")
    assert np.all(np.abs(ratio - 1.0) < 0.10)
    assert np.all(np.abs(bias) < 0.2)


def test_hysteresis_detected_with_leg_and_missed_without() -> None:
    t = np.repeat(np.linspace(-20.0, 60.0, 6), 2)
    legs = np.tile([1.0, -1.0], 6)
    h = 0.3  # 6 σ of one point
    truth = 1.0 + 0.02 * (t - T0_DEGC) + h * legs
    cov = np.diag(np.full(t.size, SIGMA**2))
    rng = np.random.default_rng(3)
    p = truth + rng.normal(0.0, SIGMA, t.size)
    with_leg = fit_temperature_model(t, p, cov, leg=legs, reference_temperature_degc=T0_DEGC)
    without = fit_temperature_model(t, p, cov, reference_temperature_degc=T0_DEGC)
    assert with_leg.model.leg_coefficient is not None
    h_z = with_leg.model.leg_coefficient / with_leg.std()[-1]
    assert abs(with_leg.model.leg_coefficient - h) < 4 * with_leg.std()[-1]
    assert h_z > 5
    th = np.array([-10.0, -10.0, 40.0, 40.0])
    lh = np.array([1.0, -1.0, 1.0, -1.0])
    ph = 1.0 + 0.02 * (th - T0_DEGC) + h * lh + rng.normal(0.0, SIGMA, 4)
    good = check_held_out(with_leg, th, ph, np.full(4, SIGMA), leg=lh)
    bad = check_held_out(without, th, ph, np.full(4, SIGMA))
    z_max = np.max(np.abs(bad.normalised_residuals))
    print(f"\nhysteresis: h/σ_h = {h_z:.1f}; held-out p with leg {good.p_value:.2g}, "
          f"without {bad.p_value:.2g}, max|z| without {z_max:.1f}")
    assert good.consistent
    assert not bad.consistent
    assert without.quality.misfit


@pytest.mark.slow
def test_misfit_flagged_and_birge_scaling_covers_better() -> None:
    t = np.linspace(-40.0, 85.0, 16)
    cov = ar1_covariance(t.size, SIGMA, RHO)
    chol = np.linalg.cholesky(cov)
    c5 = np.array([1.0, 0.02, 3e-4, 1e-6, 2e-7, 3e-9])
    truth = poly(c5, t)
    held = np.array([-30.0, -5.0, 20.0, 45.0, 70.0])
    true_held = poly(c5, held)
    flagged, cov_unscaled, cov_scaled = 0, 0, 0
    n = 200
    for seed in range(n):
        p = truth + chol @ np.random.default_rng(seed).standard_normal(t.size)
        fit = fit_temperature_model(t, p, cov, max_order=2, reference_temperature_degc=T0_DEGC)
        assert fit.order <= 2
        flagged += fit.quality.misfit
        if fit.quality.misfit:
            assert "MISFIT" in fit.note and "Birge" in fit.note
        err = np.abs(predict_temperature_model(fit, held).value - true_held)
        cov_scaled += int(np.sum(err <= 2 * predict_temperature_model(fit, held).std))
        cov_unscaled += int(np.sum(err <= 2 * predict_temperature_model(fit, held,
                                                                         scaled=False).std))
    total = n * held.size
    print(f"\nmisfit: flagged {flagged}/{n}; 2σ coverage of the prediction error: "
          f"unscaled {cov_unscaled / total:.1%}, Birge-scaled {cov_scaled / total:.1%}")
    assert flagged > 0.9 * n
    assert cov_scaled > cov_unscaled + 0.1 * total


def test_good_fit_is_not_scaled() -> None:
    fit = fit_temperature_model(T_DEGC, poly(CUBIC, T_DEGC), COV, order=3)
    assert not fit.quality.misfit
    np.testing.assert_array_equal(fit.covariance, fit.covariance_scaled)
    np.testing.assert_allclose(fit.model.coefficients[0], poly(CUBIC, np.array([fit.model.
                               reference_temperature_degc]))[0], rtol=1e-10)


def test_coefficients_reported_about_t0_in_physical_units() -> None:
    # Noise-free data: the fit returns the truth exactly whatever T0, and the dT/dt term.
    rate = 0.05 * np.tile([1.0, -1.0, 0.5], 4)
    truth = poly(CUBIC, T_DEGC) + 2.0 * rate
    fit = fit_temperature_model(T_DEGC, truth, np.full(T_DEGC.size, SIGMA**2), order=3,
                                temperature_rate_degc_ps=rate, reference_temperature_degc=25.0)
    np.testing.assert_allclose(fit.model.coefficients, CUBIC, rtol=1e-8)
    assert fit.model.rate_coefficient == pytest.approx(2.0, rel=1e-8)
    # a different T0 gives the re-expanded polynomial; default T0 is the mean temperature
    other = fit_temperature_model(T_DEGC, truth, np.full(T_DEGC.size, SIGMA**2), order=3,
                                  temperature_rate_degc_ps=rate)
    assert other.model.reference_temperature_degc == pytest.approx(np.mean(T_DEGC))
    tt = np.array([-10.0, 33.0])
    np.testing.assert_allclose(predict_temperature_model(other, tt, 0.01).value,
                               poly(CUBIC, tt) + 0.02, rtol=1e-9)


def test_conversion_to_and_from_temperature_dependence() -> None:
    rate = 0.05 * np.tile([1.0, -1.0, 0.5], 4)
    fit = fit_temperature_model(T_DEGC, poly(CUBIC, T_DEGC) + 2.0 * rate, COV, order=3,
                                temperature_rate_degc_ps=rate, reference_temperature_degc=25.0)
    dep, base = to_temperature_dependence({"bias_x": fit.model})
    tt = np.array([-20.0, 10.0, 70.0])
    rr = np.array([0.01, 0.0, -0.02])
    np.testing.assert_allclose(evaluate_parameter(base["bias_x"], "bias_x", dep, tt, rr),
                               predict_temperature_model(fit, tt, rr).value, rtol=1e-12)
    back = from_temperature_dependence(dep, "bias_x", base["bias_x"])
    assert back == fit.model
    with pytest.raises(InvalidInputError, match="hysteresis"):
        to_temperature_dependence({"b": TemperaturePolynomial(25.0, (1.0,), None, 0.1)})
    with pytest.raises(InvalidInputError, match="reference temperature"):
        to_temperature_dependence({"a": TemperaturePolynomial(25.0, (1.0,)),
                                   "b": TemperaturePolynomial(20.0, (1.0,))})


def test_held_out_consistent_for_right_model() -> None:
    truth = poly(CUBIC, T_DEGC)
    fit = fit_temperature_model(T_DEGC, draw(truth, 11), COV, order=3)
    th = np.array([-30.0, 10.0, 60.0])
    rng = np.random.default_rng(12)
    ph = poly(CUBIC, th) + rng.normal(0.0, SIGMA, 3)
    res = check_held_out(fit, th, ph, np.full(3, SIGMA))
    assert res.consistent and res.dof == 3 and res.normalised_residuals.shape == (3,)
    off = check_held_out(fit, th, ph + 10 * SIGMA, np.full(3, SIGMA))
    assert not off.consistent and off.p_value < 1e-6


# ------------------------------------------------------------------------------- errors


def test_errors() -> None:
    cov3 = np.eye(3) * SIGMA**2
    t3 = np.array([0.0, 20.0, 40.0])
    p3 = np.array([1.0, 1.1, 1.3])
    with pytest.raises(InvalidInputError, match="K ≥ 2"):
        fit_temperature_model([25.0], [1.0], [[1.0]])
    with pytest.raises(InvalidInputError, match="finite"):
        fit_temperature_model(t3, [1.0, np.nan, 1.2], cov3)
    with pytest.raises(InvalidInputError, match="finite"):
        fit_temperature_model([0.0, np.inf, 40.0], p3, cov3)
    with pytest.raises(InvalidInputError, match="shape"):
        fit_temperature_model(t3, p3, np.eye(4))
    with pytest.raises(InvalidInputError, match="shape"):
        fit_temperature_model(t3, p3[:2], cov3)
    with pytest.raises(InvalidInputError, match="positive definite"):
        fit_temperature_model(t3, p3, np.ones((3, 3)))
    with pytest.raises(InvalidInputError, match="symmetric"):
        fit_temperature_model(t3, p3, cov3 + np.triu(np.ones((3, 3)), 1) * 1e-4)
    with pytest.raises(InsufficientExcitationError, match=r"order 3 .* 3 temperature point"):
        fit_temperature_model(t3, p3, cov3, order=3)
    with pytest.raises(InsufficientExcitationError, match=r"order 2.*2 distinct"):
        fit_temperature_model([0.0, 0.0, 40.0], p3, cov3, order=2)
    # duplicated temperatures told apart by the leg are fine
    fit = fit_temperature_model([0.0, 0.0, 40.0], p3, cov3, order=1, leg=[1, -1, 1])
    assert fit.model.leg_coefficient is not None and fit.dof == 0
    # … and a duplicate that leaves the design regular is fine too
    assert fit_temperature_model([0.0, 0.0, 40.0], p3, cov3, order=1).dof == 1
    with pytest.raises(InsufficientExcitationError, match="order 0"):
        fit_temperature_model(t3, p3, cov3, leg=[1, 1, 1])
    with pytest.raises(InvalidInputError, match="leg"):
        fit_temperature_model(t3, p3, cov3, leg=[1, 0, -1])
    with pytest.raises(InvalidInputError, match="criterion"):
        fit_temperature_model(t3, p3, cov3, criterion="bic")  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="order"):
        fit_temperature_model(t3, p3, cov3, order=-1)
    good = fit_temperature_model(t3, p3, cov3, order=1)
    with pytest.raises(InvalidInputError, match="sigma"):
        check_held_out(good, [10.0], [1.0], [0.0])
    with pytest.raises(InvalidInputError, match="shape"):
        check_held_out(good, [10.0, 20.0], [1.0], [0.1, 0.1])
    legged = fit_temperature_model([0.0, 0.0, 40.0], p3, cov3, order=1, leg=[1, -1, 1])
    with pytest.raises(InvalidInputError, match="leg"):
        predict_temperature_model(legged, [10.0])


def test_auto_order_capped_by_points() -> None:
    t = np.array([0.0, 20.0, 40.0])
    fit = fit_temperature_model(t, [1.0, 1.2, 1.41], np.eye(3) * 1e-4, max_order=3)
    assert max(fit.aicc) == 2  # K − 1
    assert np.isinf(fit.aicc[2]) and np.isinf(fit.cv[2])
