"""The rate transfer's σ under coloured noise (docs/rate-transfer.md, (RT-4c); issue 30).

The turns' means share the gyro's flicker and random walk: weighting them by their white σ
(RT-4) alone understated the biases' σ 3–5× (bench/rate_transfer_montecarlo.py). The analysis
now fits by GLS with the means' covariance C (RT-4c). Checked here:

- a constructed case: means drawn from the C of the default plan's turns under the tactical
  grade's noise; the GLS σ match the spread of 1000 draws, the old white-weighted σ of the
  biases do not (the test that fails with the old σ);
- on the twin, one run with the grade's noise: the analysis's C is that of the prediction
  (the same model, (TD.2)), the σ it reports agree with ``plan show --predict``, the note says
  the flicker and random walk are the grade's Type B; with white noise nothing changes;
- a modest coverage check on the twin (slow): the biases' z-scores over 40 seeds.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from imucalib.estimation.noise_covariance import compute_window_mean_covariance
from imucalib.io.opening import open_recording
from imucalib.procedures import registry
from imucalib.procedures.common.grade import grade_noise
from imucalib.procedures.common.rate_windows import extract_rate_windows
from imucalib.procedures.common.reference import site_vectors
from imucalib.procedures.rate_transfer.fit import fit_line, fit_rate_transfer
from imucalib.procedures.rate_transfer.plan import generate_rate_transfer_plan
from imucalib.procedures.rate_transfer.predict import predict_rate_transfer
from imucalib.procedures.rate_transfer.roles import RATE_TRANSFER_RATE

from .._rate_twin import gyro_truth, run, with_unit

ZERO = {"gyro.scale_asymmetry": (0.0, 0.0, 0.0), "gyro.k2": (0.0, 0.0, 0.0),
        "gyro.k3": (0.0, 0.0, 0.0), "gyro.koq": (0.0, 0.0, 0.0)}


def _default_turns() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """x [rad/s], starts and spans [s] of the default plan's turns about z, back to back."""
    rates = np.radians([r for m in (5.0, 12.5, 18.0, 27.0, 36.0, 45.0, 60.0) for r in (m, -m)])
    span = 2 * 2 * np.pi / np.abs(rates)
    starts = np.concatenate([[15.0], 15.0 + np.cumsum(span[:-1] + 16.0)])
    return rates + 5.16e-5, starts, span


def test_gls_sigma_matches_the_spread_and_the_white_sigma_does_not() -> None:
    x, starts, span = _default_turns()
    noise = grade_noise(generate_rate_transfer_plan(axes=("z",)))["gyro"]
    cov = compute_window_mean_covariance(noise, starts, span, reference_time_s=0.0)[2]
    white_se = float(np.ravel(noise.white_density)[2]) / np.sqrt(span)
    chol = np.linalg.cholesky(cov)
    rng = np.random.default_rng(7)
    truth = 1e-5 + (1.0 - 2e-4) * x
    est_gls, est_white = [], []
    for i in range(1000):
        y = truth + chol @ rng.standard_normal(x.size)
        line = fit_line(x, y, white_se, covariance=cov)
        second = fit_rate_transfer(x, y, white_se, covariance=cov)
        if i == 0:
            noise_only = np.r_[np.sqrt(np.diag(line.cov)), np.sqrt(np.diag(second.cov))]
            first_misfit = line.quality.misfit or second.quality.misfit
        est_gls.append([line.bias_rps, line.scale_factor, *second.params])
        old_line, old_second = fit_line(x, y, white_se), fit_rate_transfer(x, y, white_se)
        est_white.append([old_line.bias_rps, old_line.scale_factor, *old_second.params])
    spread = np.std(est_gls, axis=0, ddof=1)
    # the fits' σ with a known C do not depend on y (but for a misfit's Birge factor): the
    # noise-only (AᵀC⁻¹A)⁻¹, which the fits report when χ² is in range
    a1 = np.column_stack([np.ones_like(x), x])
    a2 = np.column_stack([np.ones_like(x), x, np.abs(x), x * x])
    ci = np.linalg.inv(cov)
    sigma = np.r_[np.sqrt(np.diag(np.linalg.inv(a1.T @ ci @ a1))),
                  np.sqrt(np.diag(np.linalg.inv(a2.T @ ci @ a2)))]
    assert not first_misfit  # (seed 7) so the fits report their noise-only σ, (AᵀC⁻¹A)⁻¹
    assert np.allclose(noise_only, sigma, rtol=1e-9)
    ratio = noise_only / spread  # 1000 draws: the spread is known to ±4.5 % (2σ)
    assert np.all(np.abs(ratio - 1.0) < 0.08), ratio
    # the old fit: white weights, white σ (RT-4) — the biases' σ far below their spread
    spread_w = np.std(est_white, axis=0, ddof=1)
    w = np.diag(1.0 / white_se**2)
    old_sigma = np.r_[np.sqrt(np.diag(np.linalg.inv(a1.T @ w @ a1))),
                      np.sqrt(np.diag(np.linalg.inv(a2.T @ w @ a2)))]
    old_ratio = old_sigma / spread_w
    assert old_ratio[0] < 0.35 and old_ratio[2] < 0.5, old_ratio  # bias line, bias E0′
    # GLS is the efficient estimator: never a wider spread than the white-weighted one
    assert np.all(spread <= spread_w * 1.03), spread / spread_w


@pytest.fixture(scope="module")
def coloured_run(tmp_path_factory: pytest.TempPathFactory):  # type: ignore[no-untyped-def]
    plan = generate_rate_transfer_plan(rates_dps=(10.0, 30.0, 60.0), axes=("z",), seed=5,
                                       sample_rate_hz=100.0)
    plan = with_unit(plan, noise="grade", errors=ZERO, seed=5)
    return plan, run(plan, tmp_path_factory.mktemp("rt") / "rt.h5")


def test_analysis_reports_the_coloured_sigma_of_the_prediction(coloured_run) -> None:  # type: ignore[no-untyped-def]
    plan, path = coloured_run
    result = registry.get("rate-transfer").analyze(path)
    a = result.axis("z")
    assert a.covariance_rps2 is not None
    c = a.covariance_rps2
    off = c[~np.eye(c.shape[0], dtype=bool)]
    assert np.min(off) > 0.0  # flicker and random walk correlate every pair of turns
    note = result.notes[-1]
    assert "grade tactical" in note and "Type B" in note and "flicker" in note
    # the analysis's σ against the prediction of the same plan (N fitted vs the grade's N)
    predicted = predict_rate_transfer(plan).std()
    rows = {r.name: r for r in result.parameter_rows()}
    for name in ("gyro_bias_line_z", "gyro_bias_up_z", "gyro_M_zz", "gyro_scale_factor_z",
                 "gyro_asymmetry_z", "gyro_E2_z"):
        ratio = rows[name].std_noise / (predicted[name] or np.nan)
        assert 0.9 < ratio < 1.1, (name, ratio)
    # and well above what the white σ (RT-4) gave: the biases rest on the flicker
    with open_recording(path) as rec:
        _, windows, _ = extract_rate_windows(rec, None, (RATE_TRANSFER_RATE,))
    white_se = np.array([w.gyro_se_rps[2] for w in windows])
    old = fit_line(a.input_rps, a.output_rps, white_se)
    assert rows["gyro_bias_line_z"].std_noise > 2.0 * np.sqrt(old.cov[0, 0])


def test_white_twin_keeps_the_white_weights(tmp_path: Path) -> None:
    plan = with_unit(generate_rate_transfer_plan(rates_dps=(10.0, 30.0, 60.0), axes=("z",),
                                                 seed=6), errors=ZERO, seed=6)
    result = registry.get("rate-transfer").analyze(run(plan, tmp_path / "w.h5"))
    a = result.axis("z")
    assert a.covariance_rps2 is not None
    c = a.covariance_rps2
    assert np.array_equal(c, np.diag(np.diag(c)))
    assert "white only" in result.notes[-1]
    old = fit_line(a.input_rps, a.output_rps, a.se_rps)
    assert np.allclose(old.cov, a.line.cov, rtol=1e-9, atol=0.0)


@pytest.mark.slow
def test_bias_z_scores_cover_on_the_twin(tmp_path: Path) -> None:
    """40 seeds, one axis, the grade's noise: RMS z of both biases within 1 ± 0.3."""
    z_new, z_old = [], []
    for seed in range(100, 140):
        plan = generate_rate_transfer_plan(rates_dps=(10.0, 30.0, 60.0), axes=("z",),
                                           seed=seed, sample_rate_hz=100.0)
        path = run(with_unit(plan, noise="grade", errors=ZERO, seed=seed),
                   tmp_path / f"{seed}.h5")
        truth = gyro_truth(path)
        g, _ = site_vectors(float(truth["latitude_deg"]), 0.0, None)
        b = float(truth["bias"][2] + truth["g_sensitivity"][2, 2] * g)
        a = registry.get("rate-transfer").analyze(path).axis("z")
        assert a.transfer is not None
        z_new += [(a.line.bias_rps - b) / np.sqrt(a.line.cov[0, 0]),
                  (a.transfer.params[0] - b) / a.transfer.std(0)]
        with open_recording(path) as rec:
            _, windows, _ = extract_rate_windows(rec, None, (RATE_TRANSFER_RATE,))
        old = fit_line(a.input_rps, a.output_rps, np.array([w.gyro_se_rps[2] for w in windows]))
        z_old.append((old.bias_rps - b) / np.sqrt(old.cov[0, 0]))
        path.unlink()
    rms = float(np.sqrt(np.mean(np.square(z_new))))
    assert 0.7 < rms < 1.3, rms
    assert float(np.sqrt(np.mean(np.square(z_old)))) > 2.0
