"""Tests of imucalib.estimation.noise_covariance: Allan identity, closed forms, Monte Carlo."""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.errors import InvalidInputError
from imucalib.estimation import compute_window_mean_covariance
from imucalib.models.noise import NoiseModel, compute_theoretical_adev
from imucalib.models.noise_generator import simulate_noise

MODELS = {
    "white": (NoiseModel(white_density=1.0), 1e-12),
    "random_walk": (NoiseModel(random_walk=0.1), 1e-12),
    "markov": (NoiseModel(markov_sigma=1.0, markov_time_constant_s=3.0), 1e-9),
    "flicker": (NoiseModel(bias_instability=1.0), 0.03),  # GM bank vs IEEE form, τ ≥ 2/f0
    "mix": (NoiseModel(white_density=1.0, bias_instability=0.34, random_walk=0.087), 0.03),
}


@pytest.mark.parametrize("name", sorted(MODELS))
@pytest.mark.parametrize("T", [2.0, 20.0, 300.0])
def test_adjacent_windows_give_the_allan_variance(name: str, T: float) -> None:
    model, rtol = MODELS[name]
    C = compute_window_mean_covariance(model, [5.0, 5.0 + T], T)
    avar = 0.5 * (C[:, 0, 0] + C[:, 1, 1] - 2 * C[:, 0, 1])
    np.testing.assert_allclose(avar, compute_theoretical_adev(model, [T])[0] ** 2, rtol=rtol)


def test_closed_forms_for_white_and_random_walk() -> None:
    C = compute_window_mean_covariance(NoiseModel(white_density=0.2, random_walk=0.05),
                                       [1.0, 4.0, 10.0], [2.0, 3.0, 5.0], reference_time_s=0.0)
    k2 = 0.05**2
    # walk from 0: Var(mean over [a, b]) = K²(a + (b − a)/3) for b − a = T; Cov of disjoint
    # windows [a1, b1] before [a2, b2]: K²·(mean time of window 1)
    assert C[0, 0, 0] == pytest.approx(0.04 / 2.0 + k2 * (1.0 + 2.0 / 3.0))
    assert C[0, 0, 2] == pytest.approx(k2 * 2.0)  # centre of [1, 3]
    assert C[0, 1, 2] == pytest.approx(k2 * 5.5)  # centre of [4, 7]
    np.testing.assert_array_equal(C[0], C[0].T)
    assert np.all(np.linalg.eigvalsh(C[0]) > 0)


@pytest.mark.slow
def test_monte_carlo_covariance_of_the_generator() -> None:
    # K = 4 windows with gaps in one continuous record of white + flicker + random walk
    fs = 20.0
    model = NoiseModel(white_density=[1.0, 0.5, 0.2], bias_instability=[0.3, 0.5, 0.2],
                       random_walk=[0.05, 0.02, 0.1])
    starts = np.array([0.0, 15.0, 40.0, 100.0])
    dur = np.array([10.0, 10.0, 30.0, 20.0])
    n = int(120.0 * fs)
    idx = [slice(int(s * fs), int((s + d) * fs)) for s, d in zip(starts, dur, strict=True)]
    rng = np.random.default_rng(5)
    runs = 300  # each call of the generator costs one 32768-sample block
    means = np.empty((runs, 4, 3))
    for r in range(runs):
        x = simulate_noise(model, n, 1 / fs, rng)
        means[r] = [x[i].mean(axis=0) for i in idx]
    C = compute_window_mean_covariance(model, starts, dur, reference_time_s=0.0)
    for ax in range(3):
        emp = np.cov(means[:, :, ax].T)
        # an empirical (co)variance has sd ≈ √((1 + ρ²)/runs)·scale ≤ 8.2 % of scale: 4 sd
        scale = np.sqrt(np.outer(np.diag(C[ax]), np.diag(C[ax])))
        assert np.all(np.abs(emp - C[ax]) < 0.33 * scale), (ax, emp / C[ax])
        # the variances together: mean ratio within 4 sd of its ≈ 8 %/√4 spread
        assert np.mean(np.diag(emp) / np.diag(C[ax])) == pytest.approx(1.0, abs=0.16)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"window_start_s": [[0.0]]}, r"`window_start_s` must have shape \(K,\) with K ≥ 1"),
        ({"window_duration_s": [1.0, 2.0, 3.0]},
         r"`window_duration_s` must be a scalar or have shape \(2,\); got \(3,\)"),
        ({"window_duration_s": 0.0}, r"`window_duration_s` must be > 0; got min 0"),
        ({"reference_time_s": 5.0}, r"`reference_time_s` must be ≤ every window start \(0 s\); "
                                    r"got 5 s"),
    ],
)
def test_bad_inputs_raise_with_messages(kwargs: dict, match: str) -> None:
    args = {"window_start_s": [0.0, 10.0], "window_duration_s": 5.0}
    args.update(kwargs)
    with pytest.raises(InvalidInputError, match=match):
        compute_window_mean_covariance(NoiseModel(white_density=1.0), args.pop("window_start_s"),
                                       args.pop("window_duration_s"), **args)
