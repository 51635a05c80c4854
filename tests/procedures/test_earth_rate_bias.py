"""Earth-rate bias: closed forms on synthetic windows, σ vs Monte Carlo, twin closed loop, bad
inputs."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from imucalib.errors import (
    ConfigurationError,
    InsufficientExcitationError,
    MissingSegmentError,
    RecordingError,
)
from imucalib.procedures.earth_rate_bias.analysis import analyze_earth_rate_bias
from imucalib.procedures.earth_rate_bias.methods import (
    AxisWindow,
    four_position_bias,
    up_down_bias,
)
from imucalib.procedures.earth_rate_bias.plan import generate_earth_rate_bias_plan
from imucalib.procedures.earth_rate_bias.roles import EARTH_RATE_BIAS_POSITION
from imucalib.procedures.registry import get
from imucalib.units import EARTH_RATE_RPS

from ._p4_twin import fail_step, gyro_truth, run_twin

LAT = math.radians(45.0)
OMEGA_N, OMEGA_U = EARTH_RATE_RPS * math.cos(LAT), EARTH_RATE_RPS * math.sin(LAT)


def _four(rng, bias, sigma, scale=0.0):
    return [AxisWindow(bias + (1 + scale) * OMEGA_N * math.cos(math.radians(a))
                       + rng.normal(0, sigma), sigma, OMEGA_N * math.cos(math.radians(a)))
            for a in (0, 90, 180, 270)]


def _vertical(rng, bias, sigma, sign, scale=0.0):
    return [AxisWindow(bias + sign * (1 + scale) * OMEGA_U + rng.normal(0, sigma), sigma,
                       sign * OMEGA_U) for _ in range(4)]


def test_exact_without_noise_and_scale_cancels_in_the_bias():
    rng = np.random.default_rng(0)
    b = 5e-8
    four = four_position_bias([_four(rng, b, 0.0 + 1e-30, scale=1e-3)])
    ud, half, lat = up_down_bias(_vertical(rng, b, 1e-30, 1, 1e-3),
                                 _vertical(rng, b, 1e-30, -1, 1e-3))
    assert four.value_rps == pytest.approx(b, abs=1e-18)
    assert ud.value_rps == pytest.approx(b, abs=1e-18)
    assert half.value_rps == pytest.approx(1.001 * OMEGA_U, rel=1e-12)
    assert lat.value_rps == pytest.approx(math.degrees(math.asin(1.001 * math.sin(LAT))),
                                          rel=1e-9)


@pytest.mark.slow
def test_sigma_matches_monte_carlo_spread():
    rng = np.random.default_rng(1)
    sigma, b = 1e-8, 2e-8
    four, ud = [], []
    for _ in range(3000):
        f = four_position_bias([_four(rng, b, sigma), _four(rng, b, sigma)])
        u, _, _ = up_down_bias(_vertical(rng, b, sigma, 1), _vertical(rng, b, sigma, -1))
        four.append(f.value_rps)
        ud.append(u.value_rps)
    assert np.std(four, ddof=1) / f.std_rps == pytest.approx(1.0, abs=0.15)
    assert np.std(ud, ddof=1) / u.std_rps == pytest.approx(1.0, abs=0.15)


def _plan(seed, **kw):
    opts = dict(record_s=60.0, settle_s=5.0, warm_up_s=10.0, sample_rate_hz=20.0,
                noise="white", seed=seed)
    return generate_earth_rate_bias_plan(**(opts | kw))


@pytest.mark.parametrize("seed", [3, 17, 41])
def test_twin_closed_loop_within_4_sigma(tmp_path, seed):
    path = run_twin(_plan(seed), tmp_path / "e.h5")
    result = get("earth-rate-bias").analyze(path)
    truth = gyro_truth(path)
    bias = truth["bias"]
    for i, axis in enumerate(result.axes):
        for est in (axis.four_position, axis.up_down):
            assert abs(est.value_rps - bias[i]) < 4 * est.std_rps, (i, est, bias[i])
        # navigation grade: ±0.02 °/h at 1σ from 4 min per pose at 20 Hz
        assert axis.up_down.std_rps < 0.01 / 3600 * math.pi / 180
        assert abs(axis.latitude_deg.value_rps - 45.0) < 0.5
        assert abs(axis.z) < 4
        # (3): the half-difference also holds G_ii·g
        expected = (truth["scale_misalignment"][i, i]
                    + truth["g_sensitivity"][i, i] * 9.806 / OMEGA_U)
        assert abs(axis.scale.value_rps - expected) < 4 * axis.scale.std_rps
    names, values, cov = result.triad_parameters()
    assert names == ["gyro_bias_x", "gyro_bias_y", "gyro_bias_z"]
    assert np.all(np.abs(values - bias) < 4 * np.sqrt(np.diag(cov)))
    json.dumps(result.to_dict())
    assert len(result.parameter_rows()) == 15


def test_without_down_poses_the_up_down_method_is_unobservable(tmp_path):
    path = run_twin(_plan(5, poses=("+z", "+x", "+y")), tmp_path / "e.h5")
    with pytest.raises(InsufficientExcitationError, match="up/down"):
        analyze_earth_rate_bias(path)


def test_recording_of_another_procedure_is_refused(tmp_path):
    from imucalib.procedures.g_sensitivity.plan import generate_g_sensitivity_plan

    plan = generate_g_sensitivity_plan(record_s=3.0, settle_s=1.0, warm_up_s=1.0,
                                       sample_rate_hz=20.0, noise="white")
    path = run_twin(plan, tmp_path / "g.h5")
    with pytest.raises(RecordingError, match=r"earth-rate-bias\.position"):
        analyze_earth_rate_bias(path)


def test_plan_refuses_bad_poses():
    with pytest.raises(ConfigurationError, match="poses"):
        generate_earth_rate_bias_plan(poses=("+z", "+z"))
    with pytest.raises(ConfigurationError, match="poses"):
        generate_earth_rate_bias_plan(poses=("up",))


def test_missing_position_is_named(tmp_path):
    path = run_twin(_plan(6, poses=("+z", "-z")), tmp_path / "e.h5")
    fail_step(path, EARTH_RATE_BIAS_POSITION, nth=5)
    with pytest.raises(MissingSegmentError, match=r"-z up, azimuth 90°"):
        analyze_earth_rate_bias(path)
