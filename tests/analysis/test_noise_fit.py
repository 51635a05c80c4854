"""Noise-term fits on twin data with known coefficients, against their Monte-Carlo spread.

Twin data come from imucalib.models.noise_generator (two-sided coefficients). Criteria per
coefficient over R runs: the reported standard uncertainty u must match the Monte-Carlo standard
deviation s (ratio s/mean(u) within the band below, which allows for the sampling error of s, about
1/√(2(R−1))), the normalised errors z = (estimate − truth)/u must be centred and covered
(|z| < 2 in most runs), the bias |mean(z)| small.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from imucalib import units
from imucalib.analysis import (
    FLICKER_FACTOR,
    NoiseFit,
    compute_edf_greenhall,
    compute_oadev,
    convert_noise_term,
    fit_noise_terms,
)
from imucalib.analysis._avar_covariance import covariance_basis
from imucalib.errors import InvalidInputError
from imucalib.models.noise import NoiseModel
from imucalib.models.noise_generator import NoiseGenerator

# name: (sample rate [Hz], samples, truth, flicker corner [Hz], sensor)
CONFIGS = {
    "gyro-QNBK-100Hz": (100.0, 1 << 16, {"quantization": 3e-5, "white": 1e-3,
                                         "bias_instability": 1e-3, "random_walk": 3e-4},
                        10.0, "gyro"),
    "accel-NBR-200Hz": (200.0, 1 << 16, {"white": 5e-4, "bias_instability": 3e-4,
                                         "rate_ramp": 2e-5}, 20.0, "accel"),
    "gyro-NK-1kHz": (1000.0, 1 << 17, {"white": 1e-3, "random_walk": 2e-3}, 1.0, "gyro"),
    "gyro-QN-50Hz": (50.0, 1 << 15, {"quantization": 5e-4, "white": 1e-3}, 1.0, "gyro"),
}


def model_of(truth: dict[str, float], f0: float) -> NoiseModel:
    return NoiseModel(white_density=truth.get("white", 0.0),
                      bias_instability=truth.get("bias_instability", 0.0),
                      random_walk=truth.get("random_walk", 0.0),
                      quantization=truth.get("quantization", 0.0),
                      rate_ramp=truth.get("rate_ramp", 0.0), bias_instability_corner_hz=f0)


def monte_carlo(name: str, runs: int, seed: int) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    rate, n, truth, f0, sensor = CONFIGS[name]
    model = model_of(truth, f0)
    terms = tuple(truth)
    est = {k: [] for k in terms}
    unc = {k: [] for k in terms}
    for r in range(runs):
        y = NoiseGenerator(model, 1 / rate, rng=seed + r).generate(n)[:, 1]
        fit = fit_noise_terms(compute_oadev(y, rate, identify_noise=False), sensor=sensor,
                              terms=terms)
        for k in terms:
            est[k].append(fit.term(k).value_si)
            unc[k].append(fit.term(k).std_si)
    return {k: (np.array(est[k]), np.array(unc[k])) for k in terms}


def check(name: str, runs: int, seed: int, ratio_band: tuple[float, float], cover2: float,
          bias: float) -> None:
    truth = CONFIGS[name][2]
    for k, (v, u) in monte_carlo(name, runs, seed).items():
        z = (v - truth[k]) / u
        ratio = v.std(ddof=1) / u.mean()
        msg = f"{name} {k}: MC sd/u = {ratio:.2f}, mean z = {z.mean():+.2f}, " \
              f"|z|<2 in {np.mean(np.abs(z) < 2):.0%}"
        assert ratio_band[0] <= ratio <= ratio_band[1], msg
        assert np.mean(np.abs(z) < 2) >= cover2, msg
        assert abs(z.mean()) <= bias, msg


@pytest.mark.parametrize("name", list(CONFIGS))
def test_fit_recovers_known_terms_within_uncertainty(name: str) -> None:
    # 24 runs: s is known to ±15 %, mean z to ±0.2 (1σ)
    check(name, runs=24, seed=100, ratio_band=(0.6, 1.6), cover2=0.8, bias=0.65)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["gyro-QNBK-100Hz", "accel-NBR-200Hz"])
def test_fit_uncertainty_matches_monte_carlo_spread(name: str) -> None:
    # 150 runs: s to ±6 %; observed ratios 0.82–1.15 (the ramp with flicker is the 1.15)
    check(name, runs=150, seed=10_000, ratio_band=(0.78, 1.3), cover2=0.88, bias=0.35)


def test_covariance_diagonal_reproduces_greenhall_edf() -> None:
    n_phase = 100_001
    ms = tuple(2**k for k in range(15))
    basis = covariance_basis(ms, n_phase, 0.01)
    tau = np.array(ms) * 0.01
    for comp, alpha, avar in (("N", 0, 1 / tau), ("K", -2, tau / 3),
                              ("B", -1, np.full(tau.size, FLICKER_FACTOR**2)),
                              ("Q", 2, 3 / tau**2)):
        edf_model = 2 * avar**2 / np.diag(basis.covariance({comp: 1.0}))
        edf_g = np.array([compute_edf_greenhall(alpha, 2, m, n_phase, overlapping=True,
                                                modified=False) for m in ms])
        m = np.array(ms)  # Greenhall's algorithm is asymptotic in m (continuous-time sx)
        np.testing.assert_allclose(edf_model[m >= 64], edf_g[m >= 64], rtol=0.01, err_msg=comp)
        if comp == "N":  # small m: NIST SP 1065 Table 5, white FM (overlapping ADEV)
            n = n_phase
            edf_t5 = (3 * (n - 1) / (2 * m) - 2 * (n - 2) / n) * 4 * m**2 / (4 * m**2 + 5)
            np.testing.assert_allclose(edf_model[m <= 1024], edf_t5[m <= 1024], rtol=0.01)
    # white rate at m = 1 exactly: successive differences, ρ(1) = −1/2 → edf = 2n/3
    edf1 = 2 / np.diag(basis.covariance({"N": 1.0}))[0] * (1 / 0.01) ** 2
    assert edf1 == pytest.approx(2 * (n_phase - 2) / 3, rel=1e-3)


def test_covariance_matches_monte_carlo() -> None:
    rng = np.random.default_rng(1)
    n, dt, nw, k, q = 1 << 12, 0.01, 0.02, 0.01, 1e-4
    av = []
    for _ in range(800):
        y = (nw / math.sqrt(dt) * rng.standard_normal(n)
             + np.cumsum(k * math.sqrt(dt) * rng.standard_normal(n))
             + np.diff(q * rng.standard_normal(n + 1)) / dt)
        av.append(compute_oadev(y, 1 / dt, identify_noise=False).variance)
    av = np.array(av)
    ms = tuple(2**j for j in range(av.shape[1]))
    cov = covariance_basis(ms, n + 1, dt).covariance({"N": nw**2, "K": k**2, "Q": q**2})
    emp = np.cov(av.T)
    np.testing.assert_allclose(np.diag(emp)[:9], np.diag(cov)[:9], rtol=0.2)
    sd, sde = np.sqrt(np.diag(cov)), np.sqrt(np.diag(emp))
    corr, corr_e = cov / np.outer(sd, sd), emp / np.outer(sde, sde)
    assert 0.4 < np.mean(np.diag(corr, 1)[:8]) < 0.65  # neighbouring octaves: ρ ≈ 0.5
    np.testing.assert_allclose(np.diag(corr_e, 1)[:8], np.diag(corr, 1)[:8], atol=0.12)


def simulate(truth: dict[str, float], rate: float, n: int, seed: int, f0: float = 1.0):
    y = NoiseGenerator(model_of(truth, f0), 1 / rate, rng=seed).generate(n)[:, 0]
    return compute_oadev(y, rate)


def test_slope_lines_and_allan_minimum() -> None:
    truth = {"white": 2e-3, "bias_instability": 5e-4, "random_walk": 4e-4}
    res = simulate(truth, 100.0, 1 << 17, seed=3, f0=10.0)
    fit = fit_noise_terms(res, terms=tuple(truth))
    n_read = fit.reading("white")
    assert n_read is not None and n_read.method == "slope-line"
    assert abs(n_read.value_si - truth["white"]) <= 4 * n_read.std_si
    assert n_read.tau_range_s[0] == pytest.approx(0.01)
    k_read = fit.reading("random_walk")
    assert k_read is not None and abs(k_read.value_si / truth["random_walk"] - 1) < 0.5
    smin = fit.reading("bias_instability_allan_minimum")
    b = fit.reading("bias_instability")
    assert smin is not None and b is not None
    assert smin.value_si == pytest.approx(res.deviation.min())
    assert b.value_si == pytest.approx(smin.value_si / 0.6643, rel=1e-4)
    assert "no 0.664" in smin.label and "0.664" in b.label
    assert smin.tau_range_s[0] == pytest.approx(res.taus_s[np.argmin(res.deviation)])
    assert fit.reading("rate_ramp") is None  # not fitted, so not read


def test_absent_term_is_not_detected() -> None:
    res = simulate({"white": 1e-3}, 100.0, 1 << 15, seed=4)
    fit = fit_noise_terms(res)
    assert fit.term("white").detected
    for name in ("random_walk", "rate_ramp", "bias_instability"):
        term = fit.term(name)
        assert not term.detected and term.std_si > 0, name
    assert fit.chi2 < 3 * fit.dof + 10


def test_markov_term() -> None:
    model = NoiseModel(white_density=1e-3, markov_sigma=2e-3, markov_time_constant_s=20.0)
    y = NoiseGenerator(model, 0.01, rng=3).generate(1 << 18)[:, 0]
    fit = fit_noise_terms(compute_oadev(y, 100.0), terms=("white", "markov_sigma"))
    sigma, tc = fit.term("markov_sigma"), fit.term("markov_time_constant")
    assert abs(sigma.value_si - 2e-3) < 4 * sigma.std_si
    assert tc.value_si == pytest.approx(20.0, rel=0.3) and tc.method == "grid-search"
    given = fit_noise_terms(compute_oadev(y, 100.0), terms=("white", "markov_sigma"),
                            markov_time_constant_s=20.0)
    assert given.term("markov_time_constant").method == "given"


def test_conversions_of_a_fitted_term_and_round_trip() -> None:
    res = simulate({"white": 1e-3, "quantization": 2e-4}, 50.0, 1 << 14, seed=5)
    fit = fit_noise_terms(res, terms=("quantization", "white"))
    n = fit.term("white")
    shown = {(u.unit, u.note.split(",")[0]): u.value for u in n.display}
    assert shown[("°/√h", "ARW")] == pytest.approx(n.value_si / units.DEG * 60)
    assert shown[("(°/s)/√Hz", "two-sided")] == pytest.approx(n.value_si / units.DEG)
    assert shown[("(°/s)/√Hz", "one-sided (datasheet) = √2·N")] == pytest.approx(
        math.sqrt(2) * n.value_si / units.DEG)
    assert "two-sided" in n.convention
    back = NoiseFit.from_dict(json.loads(json.dumps(fit.to_dict())))
    assert back.terms == fit.terms and back.slope_readings == fit.slope_readings
    np.testing.assert_array_equal(back.coefficients, fit.coefficients)
    np.testing.assert_array_equal(back.covariance, fit.covariance)
    model = fit.model_avar(res.taus_s)
    np.testing.assert_allclose(model["total"], model["quantization"] + model["white"])


def test_fit_bad_inputs() -> None:
    y = np.random.default_rng(0).standard_normal(4096)
    with pytest.raises(InvalidInputError, match="must be an overlapping Allan deviation "
                                                r"\(kind 'oadev'\); got 'mdev'"):
        from imucalib.analysis import compute_mdev
        fit_noise_terms(compute_mdev(y, 1.0))
    res = compute_oadev(y, 1.0)
    with pytest.raises(InvalidInputError, match="`sensor` must be 'gyro' or 'accel'; got 'mag'"):
        fit_noise_terms(res, sensor="mag")
    with pytest.raises(InvalidInputError, match=r"unknown noise term\(s\) \['flicker'\]"):
        fit_noise_terms(res, terms=("white", "flicker"))
    with pytest.raises(InvalidInputError, match=r"2 Allan point\(s\) in range for 5 term\(s\)"):
        fit_noise_terms(res, tau_range_s=(1.0, 2.0))
    fit = fit_noise_terms(res, terms=("white",))
    with pytest.raises(InvalidInputError,
                       match=r"no fitted term 'random_walk'; terms: \['white'\]"):
        fit.term("random_walk")
    with pytest.raises(InvalidInputError, match="unknown noise term 'flicker'"):
        convert_noise_term("gyro", "flicker", 1.0)
    with pytest.raises(InvalidInputError, match=r"`sensor` must be one of \['gyro', 'accel'\]"):
        convert_noise_term("baro", "white", 1.0)


def test_a_constant_signal_is_refused_not_fitted() -> None:
    # issue 27: a column of zeros sent NaN into the Cholesky factor (an internal error)
    res = compute_oadev(np.zeros(4096), 100.0)
    with pytest.raises(InvalidInputError, match=r"the Allan variance is 0 at τ = 0.01 s \(\d+ of "
                                                r"\d+ points\); a noise fit needs a signal"):
        fit_noise_terms(res)
