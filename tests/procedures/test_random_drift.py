"""Random drift: the scatter statistics, twin runs (white and grade noise), bad inputs."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from imucalib.errors import (
    ConfigurationError,
    InsufficientExcitationError,
    MissingSegmentError,
)
from imucalib.procedures.random_drift.analysis import analyze_random_drift
from imucalib.procedures.random_drift.plan import generate_random_drift_plan
from imucalib.procedures.random_drift.roles import RANDOM_DRIFT_POSITION
from imucalib.procedures.random_drift.scatter import allan_at_interval, random_drift, scatter
from imucalib.procedures.registry import get

from ._p4_twin import fail_step, run_twin


@pytest.mark.slow
def test_scatter_uncertainty_and_interval_against_monte_carlo():
    rng = np.random.default_rng(0)
    draws = rng.normal(0.0, 2.0, (5000, 7))
    stats = [scatter(d) for d in draws]
    s = np.array([x.std for x in stats])
    # u(s) = s/√(2(R − 1)) against the spread of s (the exact value differs by 2.5 % at R = 7)
    assert np.std(s) / np.mean([x.std_uncertainty for x in stats]) == pytest.approx(1, abs=0.15)
    covered = np.mean([x.low <= 2.0 <= x.high for x in stats])
    assert covered == pytest.approx(0.95, abs=0.01)


def test_random_drift_and_allan_closed_forms():
    value, u = random_drift(3.0, [1.0, 0.0, 2.0], 2.0, 5)
    assert value == pytest.approx(2.7 * math.sqrt(9 + 4 + 16))
    assert u == pytest.approx(value / math.sqrt(8))
    assert allan_at_interval([0.0, 1.0, 0.0, 1.0]) == pytest.approx(math.sqrt(0.5))
    with pytest.raises(InsufficientExcitationError, match="at least 3"):
        scatter([1.0, 2.0], "gyro D0 x")


def _plan(seed, noise="white", **kw):
    opts = dict(repetitions=6, span_s=3000.0, record_s=30.0, settle_s=5.0, warm_up_s=10.0,
                sample_rate_hz=20.0, noise=noise, seed=seed)
    return generate_random_drift_plan(**(opts | kw))


@pytest.mark.slow
def test_twin_white_noise_scatter_matches_the_per_repetition_sigma(tmp_path):
    ratios = []
    for seed in (3, 8, 21):
        path = run_twin(_plan(seed), tmp_path / f"r{seed}.h5")
        result = get("random-drift").analyze(path)
        s = np.array([[x.std for x in row] for row in result.drift_scatter])
        ratios.append((s / result.drift_std.mean(axis=0)) ** 2)
        acc = np.array([x.std for x in result.accel_zero_stability])
        ratios.append((acc / result.accel_bias_std.mean(axis=0)) ** 2)
    # white noise: s²/σ² ~ χ²_ν/ν with ν = 5 per coefficient, 45 coefficients over three seeds
    pooled = float(np.mean(np.concatenate([r.ravel() for r in ratios])))
    assert 0.65 < pooled < 1.4, pooled


def test_twin_grade_noise_scatter_against_the_noise_model(tmp_path):
    path = run_twin(_plan(4, noise="grade"), tmp_path / "g.h5")
    result = analyze_random_drift(path)
    from imucalib.io.opening import open_recording

    with open_recording(path) as rec:
        noise = rec.truth["imu_models"][result.unit]["gyro_noise"]
    b, k = np.array(noise["bias_instability"]), np.array(noise["random_walk"])
    white = result.drift_std[:, :, 0].mean(axis=0)
    # D0 between repetitions T apart: white σ plus the Allan variance of the noise at T
    predicted = np.sqrt(white**2 + (0.664 * b) ** 2 + k**2 * result.interval_s / 3)
    s = np.array([row[0].std for row in result.drift_scatter])
    ratio = math.sqrt(np.mean(s**2) / np.mean(predicted**2))
    assert 0.4 < ratio < 2.5, (s, predicted)
    assert len(result.repetitions) == 6
    assert np.all(result.random_drift_rps[:, 0] > 2.7 * s)
    json.dumps(result.to_dict())
    names, _, cov = result.triad_parameters()
    assert names[0] == "gyro_bias_x" and names[-1] == "accel_bias_z" and cov.shape == (15, 15)
    assert len(result.parameter_rows()) == 18


def test_too_few_repetitions_is_refused(tmp_path):
    plan = _plan(5, repetitions=3, span_s=600.0)
    steps = [s for s in plan.steps if "rep=3" not in s.tags]
    plan = plan.model_copy(update={"steps": tuple(steps)})
    path = run_twin(plan, tmp_path / "r.h5")
    with pytest.raises(InsufficientExcitationError, match="at least 3 repetitions"):
        analyze_random_drift(path)


def test_plan_refuses_two_repetitions():
    with pytest.raises(ConfigurationError, match="repetitions"):
        generate_random_drift_plan(repetitions=2)


def test_missing_position_is_named(tmp_path):
    path = run_twin(_plan(7, repetitions=3, span_s=600.0), tmp_path / "r.h5")
    fail_step(path, RANDOM_DRIFT_POSITION, nth=8)
    with pytest.raises(MissingSegmentError, match=r"rep 2, position 2"):
        analyze_random_drift(path)
