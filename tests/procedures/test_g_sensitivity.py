"""g-sensitivity: closed form vs LSQ, σ vs Monte Carlo, twin closed loop, bad inputs."""

from __future__ import annotations

import json

import numpy as np
import pytest

from imucalib.errors import (
    InsufficientExcitationError,
    MissingSegmentError,
    RecordingError,
)
from imucalib.procedures.common.reference import site_vectors, static_inputs_b
from imucalib.procedures.g_sensitivity.analysis import analyze_g_sensitivity
from imucalib.procedures.g_sensitivity.fit import fit_drift_model, six_position_closed_form
from imucalib.procedures.g_sensitivity.plan import (
    G_SENSITIVITY_POSITIONS_DEG,
    generate_g_sensitivity_plan,
)
from imucalib.procedures.g_sensitivity.roles import G_SENSITIVITY_POSITION
from imucalib.procedures.registry import get

from ._p4_twin import fail_step, gyro_truth, run_twin

G_TRUE = ((2e-5, 1e-5, -1e-5), (0.0, 3e-5, 2e-5), (-1e-5, 0.0, 1e-5))  # rad/s per m/s²
G, EARTH = site_vectors(45.0, 0.0, None)


def _inputs(positions):
    rows = [static_inputs_b(("pitch", "roll"), np.radians(p), G, EARTH) for p in positions]
    return np.array([r[0] for r in rows]), np.array([r[1] for r in rows])


def _synthetic(rng, positions, sigma, bias, g_sens):
    w, f = _inputs(positions)
    y = w + bias + f @ g_sens.T + rng.normal(0.0, sigma, (len(positions), 3))
    return w, f, y


def test_closed_form_equals_lsq_on_the_six_positions():
    rng = np.random.default_rng(0)
    bias, gs = np.array([1e-5, -2e-5, 3e-6]), np.array(G_TRUE)
    w, f, y = _synthetic(rng, G_SENSITIVITY_POSITIONS_DEG[:6], 1e-6, bias, gs)
    fit = fit_drift_model(w, f, y, np.full((6, 3), 1e-6))
    np.testing.assert_allclose(fit.coefficients, six_position_closed_form(y, w, G),
                               rtol=1e-9, atol=1e-15)


@pytest.mark.slow
def test_sigma_matches_monte_carlo_spread():
    rng = np.random.default_rng(1)
    bias, gs, sigma = np.array([1e-5, -2e-5, 3e-6]), np.array(G_TRUE), 2e-6
    est = []
    for _ in range(1000):
        w, f, y = _synthetic(rng, G_SENSITIVITY_POSITIONS_DEG, sigma, bias, gs)
        fit = fit_drift_model(w, f, y, np.full((14, 3), sigma))
        est.append(fit.coefficients.ravel())
    spread = np.std(est, axis=0, ddof=1)
    ratio = spread / fit.std.ravel()
    assert np.all(np.abs(ratio - 1) < 0.15), ratio
    truth = np.column_stack([bias, gs]).ravel()
    assert np.all(np.abs(np.mean(est, axis=0) - truth) < 4 * spread / np.sqrt(1000))


def test_type_b_scale_uncertainty_widens_sigma():
    rng = np.random.default_rng(2)
    w, f, y = _synthetic(rng, G_SENSITIVITY_POSITIONS_DEG, 1e-8, np.zeros(3), np.zeros((3, 3)))
    plain = fit_drift_model(w, f, y, np.full((14, 3), 1e-8))
    typeb = fit_drift_model(w, f, y, np.full((14, 3), 1e-8), scale_misalignment_std=1e-2)
    # the vertical Earth rate turns with gravity: δm·Ω_e·sin L/g aliases into G (5e-8 here)
    assert np.all(typeb.std[:, 1:] > 20 * plain.std[:, 1:])
    expected = 1e-2 * np.linalg.norm(EARTH) * np.sin(np.radians(45.0)) / G
    np.testing.assert_allclose(np.diag(typeb.std[:, 1:]), expected, rtol=0.2)


def _plan(seed, **kw):
    opts = dict(grade="tactical", record_s=30.0, settle_s=5.0, warm_up_s=10.0,
                sample_rate_hz=20.0, noise="white", errors={"gyro.g_sensitivity": G_TRUE},
                seed=seed)
    return generate_g_sensitivity_plan(**(opts | kw))


@pytest.mark.parametrize("seed", [3, 11, 29])
def test_twin_closed_loop_within_4_sigma(tmp_path, seed):
    plan = _plan(seed)
    path = run_twin(plan, tmp_path / "g.h5")
    result = get("g-sensitivity").analyze(path)
    truth = gyro_truth(path)
    expected = np.column_stack([truth["bias"], truth["g_sensitivity"]])
    z = (result.fit.coefficients - expected) / result.fit.std
    assert np.all(np.abs(z) < 4), z
    np.testing.assert_allclose(result.g_sensitivity, G_TRUE, atol=2e-6)
    names, values, cov = result.triad_parameters()
    assert names[:4] == ["gyro_bias_x", "gyro_G_xx", "gyro_G_xy", "gyro_G_xz"]
    assert values.shape == (12,) and cov.shape == (12, 12)
    assert len(result.parameter_rows()) == 12
    json.dumps(result.to_dict())
    assert all(not f.misfit for f in result.fit.fits)


def test_missing_position_is_named(tmp_path):
    plan = _plan(5)
    path = run_twin(plan, tmp_path / "g.h5")
    fail_step(path, G_SENSITIVITY_POSITION)
    with pytest.raises(MissingSegmentError, match="position 0"):
        analyze_g_sensitivity(path)


def test_recording_without_roles_is_refused(tmp_path):
    from imucalib.procedures.allan.plan import generate_allan_plan

    plan = generate_allan_plan(record_s=600.0, warm_up_s=1.0, sample_rate_hz=20.0)
    path = run_twin(plan, tmp_path / "a.h5")
    with pytest.raises(RecordingError, match=r"g-sensitivity\.position"):
        analyze_g_sensitivity(path)


def test_too_few_positions_is_unobservable():
    w, f = _inputs(G_SENSITIVITY_POSITIONS_DEG[:3])
    with pytest.raises(InsufficientExcitationError):
        fit_drift_model(w, f, w, np.full((3, 3), 1e-6))
