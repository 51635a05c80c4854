"""P1 accelerometer chain (docs/p1.md) from samples to parameters: outliers → low-pass → window
statistics → weighted least squares, on one continuous record with white + flicker noise."""

from __future__ import annotations

import numpy as np
import pytest

from imucalib import units
from imucalib.estimation import (
    SIX_POSITION_UP_B,
    build_triad_design,
    compute_crlb,
    compute_window_mean_covariance,
    solve_weighted_lsq,
)
from imucalib.models.noise import NoiseModel
from imucalib.models.noise_generator import simulate_noise
from imucalib.models.triad import TriadModel, apply_triad
from imucalib.processing import (
    compute_window_statistics,
    lowpass_zero_phase,
    reject_outliers_3sigma,
)

FS = 100.0
SETTLE_S, RECORD_S = 30.0, 10.0  # docs/p1.md, calibration step 1
PER_S = SETTLE_S + RECORD_S
G = units.G0_MPS2
NOISE = NoiseModel(white_density=50.0 * units.UG_PER_RTHZ, bias_instability=20.0 * units.UG)
TRUTH = TriadModel(kind="accel", bias=[1.2e-3 * G, -0.8e-3 * G, 0.5e-3 * G],
                   scale_misalignment=[[300e-6, 0.4e-3, -0.2e-3], [-0.3e-3, -150e-6, 0.1e-3],
                                       [0.2e-3, 0.5e-3, 250e-6]])
DESIGN = build_triad_design(G * SIX_POSITION_UP_B)
TRUE_X = np.concatenate([TRUTH.bias, TRUTH.scale_misalignment.ravel()])


def _position_means(rng: np.random.Generator, se_method: str):
    """Six position means (y − x, flattened like DESIGN) and their standard errors."""
    per = int(PER_S * FS)
    noise = simulate_noise(NOISE, 6 * per, 1 / FS, rng)  # one continuous record
    means, ses = [], []
    for k, up in enumerate(SIX_POSITION_UP_B):
        y = apply_triad(TRUTH, np.tile(G * up, (per, 1))) + noise[k * per:(k + 1) * per]
        y[rng.integers(0, per, 3)] += 50 * units.MG  # a few glitches
        y = reject_outliers_3sigma(y).values
        y = lowpass_zero_phase(y, FS, bandwidth_hz=40.0).values
        st = compute_window_statistics(y[int(SETTLE_S * FS):], FS, noise_model=NOISE,
                                       se_method=se_method)
        means.append(st.mean - G * up)
        ses.append(st.standard_error)
    return np.concatenate(means), np.concatenate(ses)


def _full_covariance() -> np.ndarray:
    """18 × 18 covariance of the position means: axes independent, positions correlated."""
    starts = np.arange(6) * PER_S + SETTLE_S
    C = compute_window_mean_covariance(NOISE, starts, RECORD_S, reference_time_s=0.0)
    full = np.zeros((18, 18))
    for i in range(3):
        full[i::3, i::3] = C[i]
    return full


@pytest.mark.slow
def test_p1_chain_uncertainty_matches_monte_carlo() -> None:
    rng = np.random.default_rng(12)
    cov = _full_covariance()
    err = {"gls": [], "allan": [], "white": []}
    for _ in range(60):
        z, se = _position_means(rng, "noise-model")
        gls = solve_weighted_lsq(DESIGN.H, z, param_names=DESIGN.param_names, covariance=cov)
        diag = solve_weighted_lsq(DESIGN.H, z, param_names=DESIGN.param_names, sigma=se)
        err["gls"].append((gls.estimate - TRUE_X) / gls.std)
        err["allan"].append((diag.estimate - TRUE_X) / diag.std)
        z_w, se_w = _position_means(rng, "white")
        white = solve_weighted_lsq(DESIGN.H, z_w, param_names=DESIGN.param_names, sigma=se_w)
        err["white"].append((white.estimate - TRUE_X) / white.std)
    e = {k: np.array(v) for k, v in err.items()}
    # full coloured-noise covariance (flicker state included): every parameter is calibrated
    assert 0.8 < e["gls"][:, :3].std() < 1.25, e["gls"][:, :3].std()
    assert 0.8 < e["gls"][:, 3:].std() < 1.25, e["gls"][:, 3:].std()
    # diagonal Allan SE: scale and misalignment close (adjacent-window scatter), bias not
    # (the flicker state common to all positions is not in σ_A)
    assert 0.8 < e["allan"][:, 3:].std() < 1.4
    assert e["allan"][:, :3].std() > 2.0
    # the white formula is overconfident everywhere
    assert e["white"][:, 3:].std() > 2.0
    # the GLS covariance is the CRLB of the design with that noise covariance
    bound = compute_crlb(DESIGN.H, cov, param_names=DESIGN.param_names)
    np.testing.assert_allclose(gls.std, bound.std, rtol=1e-9)
