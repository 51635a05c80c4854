"""Tests of imucalib.models.noise (coefficients, conversions) and noise_generator (its statistics).

Allan-deviation checks use an overlapping ADEV (checked against allantools) and NIST SP 1065
equivalent degrees of freedom (EDF) for their statistical tolerance: the relative standard
deviation of an ADEV estimate is about 1/√(2·edf); Allan checks allow 4 of those (plus the
documented model error where there is one).
"""

from __future__ import annotations

import dataclasses
import json
import math
import pickle
from collections.abc import Callable

import allantools
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import stats

from imucalib import units
from imucalib.errors import ConfigurationError, InvalidInputError
from imucalib.models.noise import FLICKER_ALLAN_FACTOR, NoiseModel, compute_theoretical_adev
from imucalib.models.noise_generator import NoiseGenerator, _ma_factor, simulate_noise


# -- helpers ------------------------------------------------------------------------------------
def oadev(rate: np.ndarray, dt: float, ms: list[int]) -> np.ndarray:
    """Overlapping Allan deviation of rate samples (n, 3) at τ = m·dt; shape (len(ms), 3)."""
    theta = np.concatenate([np.zeros((1, rate.shape[1])), np.cumsum(rate, axis=0) * dt])
    out = []
    for m in ms:
        d = theta[2 * m:] - 2 * theta[m:-m] + theta[: -2 * m]
        out.append(np.sqrt(np.mean(d**2, axis=0) / (2 * (m * dt) ** 2)))
    return np.array(out)


def rel_sd(edf: float) -> float:
    return 1.0 / math.sqrt(2.0 * edf)


def edf_white_fm(n: int, m: int) -> float:  # NIST SP 1065 §5.2.4, overlapping ADEV
    n += 1  # phase points
    return (3 * (n - 1) / (2 * m) - 2 * (n - 2) / n) * 4 * m**2 / (4 * m**2 + 5)


def edf_flicker_fm(n: int, m: int) -> float:
    n += 1
    return 5 * n**2 / (4 * m * (n + 3 * m)) if m > 1 else 2 * (n - 2) ** 2 / (2.3 * n - 4.9)


def edf_rw_fm(n: int, m: int) -> float:
    n += 1
    return (n - 2) / m * ((n - 1) ** 2 - 3 * m * (n - 1) + 4 * m**2) / (n - 3) ** 2


def assert_adev(measured: np.ndarray, expected: np.ndarray, sd: float, model_err: float = 0.0,
                ) -> None:
    ratio = measured / expected
    assert np.all(np.abs(ratio - 1) < model_err + 4 * sd), (ratio, sd)


# -- the model ----------------------------------------------------------------------------------
def test_defaults_are_zero_and_scalars_broadcast() -> None:
    assert NoiseModel().is_zero()
    m = NoiseModel(white_density=2e-3, rate_ramp=-1e-6)
    assert m.white_density.shape == (3,) and np.all(m.white_density == 2e-3)
    assert np.all(m.rate_ramp == -1e-6)  # the ramp keeps its sign
    assert not m.is_zero()
    with pytest.raises(ValueError, match="read-only"):
        m.white_density[0] = 1.0


def test_replace_and_pickle_keep_a_valid_model() -> None:
    m = NoiseModel(1e-3, markov_sigma=[1e-4, 0.0, 0.0], markov_time_constant_s=[5.0, 0.0, 0.0])
    r = dataclasses.replace(m, random_walk=2e-5)
    assert np.all(r.random_walk == 2e-5) and r.white_density[0] == 1e-3
    assert pickle.loads(pickle.dumps(m)).isclose(m, atol=0.0)
    with pytest.raises(InvalidInputError, match="`random_walk` must be finite and ≥ 0"):
        dataclasses.replace(m, random_walk=-1.0)


def test_markov_time_constant_alone_is_still_zero_noise() -> None:
    assert NoiseModel(markov_time_constant_s=10.0).is_zero()


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"white_density": -1e-3}, r"`white_density` must be finite and ≥ 0; got \[-0.001"),
        ({"bias_instability": [1e-6, float("nan"), 0.0]}, r"`bias_instability`.*nan"),
        ({"random_walk": float("inf")}, r"`random_walk` must be finite and ≥ 0; got \[inf"),
        ({"quantization": [1.0, 2.0]}, r"`quantization` must be a scalar or have shape \(3,\)"),
        ({"rate_ramp": float("nan")}, r"`rate_ramp` must be finite; got \[nan"),
        ({"markov_sigma": 1e-3}, r"`markov_time_constant_s` must be > 0 where `markov_sigma`"),
        ({"markov_time_constant_s": -1.0}, r"`markov_time_constant_s` must be finite and ≥ 0"),
        ({"bias_instability_corner_hz": 0.0}, r"`bias_instability_corner_hz` must be > 0"),
        ({"bias_instability_low_hz": 2.0}, r"`bias_instability_low_hz` must be below"),
        ({"white_density": "a lot"}, r"`white_density` must be numeric"),
    ],
)
def test_bad_coefficients_raise_naming_field_and_value(kwargs: dict, match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        NoiseModel(**kwargs)


def test_isclose() -> None:
    a = NoiseModel(white_density=[1e-3, 2e-3, 3e-3], markov_sigma=1e-4, markov_time_constant_s=5)
    b = NoiseModel(white_density=[1e-3, 2e-3, 3e-3 + 1e-9], markov_sigma=1e-4,
                   markov_time_constant_s=5)
    assert a.isclose(b, atol=1e-8)
    assert not a.isclose(b, atol=1e-10)
    assert not a.isclose(NoiseModel(white_density=a.white_density, markov_sigma=1e-4,
                                    markov_time_constant_s=6), atol=1.0)
    assert not a.isclose("not a model", atol=1.0)  # type: ignore[arg-type]


finite_coef = st.floats(min_value=0.0, max_value=1e3, allow_nan=False, allow_infinity=False)


@settings(max_examples=60, deadline=None)
@given(
    coefs=st.lists(finite_coef, min_size=18, max_size=18),
    ramp=st.lists(st.floats(-1e3, 1e3, allow_nan=False), min_size=3, max_size=3),
    tc=st.lists(st.floats(1e-3, 1e6), min_size=3, max_size=3),
    f0=st.floats(1e-2, 1e3),
)
def test_json_round_trip_is_exact(coefs: list[float], ramp: list[float], tc: list[float],
                                  f0: float) -> None:
    m = NoiseModel(white_density=coefs[0:3], bias_instability=coefs[3:6],
                   random_walk=coefs[6:9], quantization=coefs[9:12], markov_sigma=coefs[12:15],
                   markov_time_constant_s=tc, rate_ramp=ramp, bias_instability_corner_hz=f0,
                   bias_instability_low_hz=f0 * coefs[15] / 2e3 + 1e-9 * f0)
    back = NoiseModel.from_dict(json.loads(json.dumps(m.to_dict())))
    for name, value in m.to_dict().items():
        got = back.to_dict()[name]
        assert got == value, name
    assert back.isclose(m, atol=0.0)


def test_from_dict_rejects_unknown_keys_and_one_sided_convention() -> None:
    d = NoiseModel(white_density=1e-3).to_dict()
    assert d["density_convention"] == "two-sided"
    with pytest.raises(InvalidInputError, match=r"unknown key\(s\) \['arw'\]"):
        NoiseModel.from_dict({**d, "arw": 1.0})
    with pytest.raises(InvalidInputError, match=r"must be 'two-sided'.*got 'one-sided'"):
        NoiseModel.from_dict({**d, "density_convention": "one-sided"})
    with pytest.raises(InvalidInputError, match="must be a mapping"):
        NoiseModel.from_dict([1, 2])  # type: ignore[arg-type]


# -- datasheet conversions ----------------------------------------------------------------------
def test_one_sided_density_matches_arw_example_of_standards() -> None:
    """docs/equations.md §1: 0.008 (°/s)/√Hz one-sided is 0.34 °/√h (60·ND/√2), not 60·ND."""
    m = NoiseModel.from_datasheet(noise_density_dps_rthz=0.008)
    assert m.white_density[0] == 0.008 * units.DEG / math.sqrt(2)
    arw_deg_rth = m.white_density / units.DEG_PER_RTH
    np.testing.assert_allclose(arw_deg_rth, 60 * 0.008 / math.sqrt(2), rtol=1e-14)
    assert abs(arw_deg_rth[0] - 0.34) < 0.001
    from_arw = NoiseModel.from_datasheet(arw_deg_rth=0.34)
    np.testing.assert_allclose(from_arw.white_density, 0.34 * units.DEG / 60, rtol=1e-15)
    np.testing.assert_allclose(from_arw.white_density, m.white_density, rtol=0.002)
    si = NoiseModel.from_datasheet(noise_density_one_sided=0.008 * units.DEG)
    np.testing.assert_allclose(si.white_density, m.white_density, rtol=1e-15)


@pytest.mark.parametrize(
    ("kwargs", "field", "expected"),
    [
        ({"vrw_mps_rth": 0.06}, "white_density", 0.001),
        ({"noise_density_ug_rthz": 100.0}, "white_density", 100 * 9.80665e-6 / math.sqrt(2)),
        ({"bias_instability_dph": 1.0}, "bias_instability", math.pi / 180 / 3600),
        ({"bias_instability_dph": 0.6643, "bias_instability_is_allan_minimum": True},
         "bias_instability", 0.6643 / FLICKER_ALLAN_FACTOR * math.pi / 180 / 3600),
        ({"bias_instability_ug": 20.0}, "bias_instability", 20 * 9.80665e-6),
        ({"rrw_deg_h_rth": 1.0}, "random_walk", math.pi / 180 / 3600 / 60),
        ({"random_walk_ug_rth": 60.0}, "random_walk", 9.80665e-6),
        ({"rate_ramp_dph_per_h": -2.0}, "rate_ramp", -2 * math.pi / 180 / 3600**2),
        ({"rate_ramp_ug_per_h": 3600.0}, "rate_ramp", 9.80665e-6),
        ({"quantization_arcsec": 1.0}, "quantization", 4.84813681109536e-6),
        ({"quantization_mps": 1e-4}, "quantization", 1e-4),
        ({"markov_sigma_dph": 3600.0, "markov_time_constant_s": 100.0}, "markov_sigma",
         math.pi / 180),
        ({"markov_sigma_ug": 1.0, "markov_time_constant_s": 100.0}, "markov_time_constant_s",
         100.0),
    ],
)
def test_datasheet_conversions(kwargs: dict, field: str, expected: float) -> None:
    m = NoiseModel.from_datasheet(**kwargs)
    np.testing.assert_allclose(getattr(m, field), expected, rtol=1e-12)


def test_datasheet_per_axis_values_and_band_edges() -> None:
    m = NoiseModel.from_datasheet(bias_instability_dph=[1.0, 2.0, 3.0],
                                  bias_instability_corner_hz=0.5, bias_instability_low_hz=1e-6)
    np.testing.assert_allclose(m.bias_instability / units.DEG_PER_H, [1, 2, 3], rtol=1e-14)
    assert (m.bias_instability_corner_hz, m.bias_instability_low_hz) == (0.5, 1e-6)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"arw_deg_rth": 0.1, "noise_density_dps_rthz": 0.01},
         r"give one of `noise_density_dps_rthz` and `arw_deg_rth`, not both"),
        ({"arw_deg_rth": 0.1, "bias_instability_ug": 10.0}, "gyro and accelerometer units"),
        ({"markov_sigma_dph": 1.0}, "`markov_sigma_dph` needs `markov_time_constant_s`"),
        ({"arw_deg_rth": -0.1}, r"`white_density` must be finite and ≥ 0"),
    ],
)
def test_datasheet_bad_inputs(kwargs: dict, match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        NoiseModel.from_datasheet(**kwargs)


# -- theoretical Allan deviation (the docs/equations.md §8 relations) ---------------------------
def test_theoretical_adev_reads_the_coefficients_at_their_taus() -> None:
    n, q, k, r, b = 1e-3, 2e-4, 3e-5, 4e-6, 5e-5
    one = np.ones(3)
    checks = [
        (NoiseModel(white_density=n), 1.0, n),
        (NoiseModel(quantization=q), math.sqrt(3), q),
        (NoiseModel(random_walk=k), 3.0, k),
        (NoiseModel(rate_ramp=-r), math.sqrt(2), r),
        (NoiseModel(bias_instability=b, bias_instability_corner_hz=1.0), 100.0, 0.6643 * b),
    ]
    for model, tau, expected in checks:
        np.testing.assert_allclose(compute_theoretical_adev(model, [tau])[0], expected * one,
                                   rtol=0.005 if model.bias_instability[0] else 1e-12)
    # Markov: peak σ = 0.4365·q_c·√T_c at τ = 1.892·T_c, q_c = σ·√(2/T_c)
    sigma, tc = 2e-3, 7.0
    model = NoiseModel(markov_sigma=sigma, markov_time_constant_s=tc)
    tau = np.linspace(1.5, 2.3, 801) * tc
    adev = compute_theoretical_adev(model, tau)[:, 0]
    assert abs(tau[np.argmax(adev)] / tc - 1.892) < 0.002
    np.testing.assert_allclose(adev.max(), 0.4365 * sigma * math.sqrt(2 / tc) * math.sqrt(tc),
                               rtol=2e-4)
    # continuity of the small-τ series of the Markov term
    small = compute_theoretical_adev(model, [tc * 0.999e-3, tc * 1.001e-3])[:, 0]
    assert abs(small[1] / small[0] - math.sqrt(1.001 / 0.999)) < 1e-5
    with pytest.raises(InvalidInputError, match=r"`tau_s` must be > 0"):
        compute_theoretical_adev(model, [0.0, 1.0])


def test_flicker_bank_design_matches_ieee_plateau_analytically() -> None:
    """The documented bank (one Markov element per decade, f0 … f_low/10, σ² = B²·ln10/π) has an
    Allan deviation within 1.5 % of the IEEE flicker closed form on [2/f0, 0.1/f_low]."""
    b, f0, f_low = 1.0, 1.0, 1e-5
    model = NoiseModel(bias_instability=b, bias_instability_corner_hz=f0,
                       bias_instability_low_hz=f_low)
    tau = np.logspace(math.log10(2 / f0), math.log10(0.1 / f_low), 200)
    n_el = math.ceil(math.log10(f0 / f_low)) + 2
    tc = 1 / (2 * np.pi * f0 * 10.0 ** -np.arange(n_el))
    var = b**2 * math.log(10) / math.pi
    avar = sum(compute_theoretical_adev(
        NoiseModel(markov_sigma=math.sqrt(var), markov_time_constant_s=t), tau)[:, 0] ** 2
        for t in tc)
    ratio = np.sqrt(avar) / compute_theoretical_adev(model, tau)[:, 0]
    assert np.all(np.abs(ratio - 1) < 0.015), (ratio.min(), ratio.max())


# -- generator: statistics ----------------------------------------------------------------------
def test_overlapping_adev_helper_matches_allantools() -> None:
    y = simulate_noise(NoiseModel(white_density=1e-3, random_walk=1e-4), 20_000, 0.01, rng=5)
    ms = [1, 10, 100, 1000]
    mine = oadev(y, 0.01, ms)[:, 0]
    _, ref, _, _ = allantools.oadev(y[:, 0], rate=100.0, data_type="freq",
                                    taus=np.array(ms) * 0.01)
    np.testing.assert_allclose(mine, ref, rtol=1e-9)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_white_noise_sample_std_and_allan_at_one_second(seed: int) -> None:
    n_coef = np.array([1e-3, 2e-3, 5e-4])
    dt, n = 0.01, 400_000
    y = simulate_noise(NoiseModel(white_density=n_coef), n, dt, rng=seed)
    np.testing.assert_allclose(y.std(axis=0), n_coef / math.sqrt(dt),
                               rtol=3.5 / math.sqrt(2 * n))
    assert_adev(oadev(y, dt, [100])[0], n_coef, rel_sd(edf_white_fm(n, 100)))


def test_white_noise_is_gaussian_and_uncorrelated() -> None:
    y = simulate_noise(NoiseModel(white_density=1.0), 300_000, 1.0, rng=11)[:, 0]
    assert stats.kstest(y, "norm").pvalue > 1e-3
    assert abs(stats.kurtosis(y)) < 3.5 * math.sqrt(24 / y.size)
    assert abs(np.corrcoef(y[1:], y[:-1])[0, 1]) < 3.5 / math.sqrt(y.size)


def test_white_plus_quantization_has_the_ma1_autocovariance() -> None:
    dt, n_coef, q = 0.01, 1e-3, 1e-4
    y = simulate_noise(NoiseModel(white_density=n_coef, quantization=q), 400_000, dt, rng=3)
    a2, b2 = n_coef**2 / dt, (q / dt) ** 2
    np.testing.assert_allclose(y.var(axis=0), a2 + 2 * b2, rtol=0.02)
    for ax in range(3):
        rho = np.corrcoef(y[1:, ax], y[:-1, ax])[0, 1]
        assert abs(rho - (-b2 / (a2 + 2 * b2))) < 3.5 / math.sqrt(y.shape[0])


def test_quantization_allan_is_root3_q_over_tau() -> None:
    q = np.array([1e-4, 3e-4, 5e-5])
    dt, n = 0.01, 200_000
    y = simulate_noise(NoiseModel(quantization=q), n, dt, rng=4)
    ms = [1, 2, 4, 16, 173]  # 173·0.01 s ≈ √3 s
    q_read = oadev(y, dt, ms) * (np.array(ms) * dt)[:, None] / math.sqrt(3)
    assert np.all(np.abs(q_read / q - 1) < 3.5 * 2 / math.sqrt(n) * np.sqrt(ms)[:, None])


def test_quantization_angle_error_stays_bounded() -> None:
    """Angle quantization is a rate (e_k − e_{k−1})/Δt: its integral θ_k = e_k − e_{−1} never
    accumulates, across generated blocks and chunks alike (std of θ over k equals Q)."""
    q, dt = 1e-4, 1e-3
    gen = NoiseGenerator(NoiseModel(quantization=q), dt, rng=2)
    y = np.concatenate([gen.generate(c) for c in (100_000, 1, 299_999, 400_000)])
    theta = np.cumsum(y, axis=0) * dt
    np.testing.assert_allclose(theta.std(axis=0), q, rtol=0.02)
    assert np.abs(theta - theta.mean(axis=0)).max() < 7 * q


def test_random_walk_allan_at_long_tau() -> None:
    k = np.array([1e-4, 3e-4, 5e-5])
    dt, n = 0.1, 500_000
    y = simulate_noise(NoiseModel(random_walk=k), n, dt, rng=6)
    ms = [30, 100, 300]  # τ = 3, 10, 30 s
    k_read = oadev(y, dt, ms) / np.sqrt(np.array(ms) * dt / 3)[:, None]
    for row, m in zip(k_read, ms, strict=True):
        assert_adev(row, k, rel_sd(edf_rw_fm(n, m)))


def test_random_walk_with_white_noise_on_the_decimated_grid() -> None:
    model = NoiseModel(white_density=1e-3, random_walk=[1e-4, 2e-4, 5e-5])
    dt, n = 0.01, 2_000_000
    gen = NoiseGenerator(model, dt, rng=8)
    assert gen.decimation > 1  # the random walk is on the slow grid here
    y = gen.generate(n)
    ms = [1, 10, 100, 1000, 5000]
    expected = compute_theoretical_adev(model, np.array(ms) * dt)
    for row, exp_row, m in zip(oadev(y, dt, ms), expected, ms, strict=True):
        assert_adev(row, exp_row, rel_sd(edf_rw_fm(n, m)))


def test_flicker_plateau_is_0664_b() -> None:
    b = np.array([1e-4, 2e-4, 5e-5])
    model = NoiseModel(bias_instability=b, bias_instability_corner_hz=1.0,
                       bias_instability_low_hz=1e-4)
    dt, n = 0.01, 2_000_000
    gen = NoiseGenerator(model, dt, rng=9)
    assert gen.decimation == 10
    y = gen.generate(n)
    ms = [200, 500, 1000, 2000]  # τ = 2 … 20 s
    for row, m in zip(oadev(y, dt, ms), ms, strict=True):
        assert_adev(row, FLICKER_ALLAN_FACTOR * b, rel_sd(edf_flicker_fm(n, m)), model_err=0.015)


@pytest.mark.slow
def test_flicker_decimated_grid_matches_full_rate() -> None:
    """Allan deviation with the automatic slow grid (h = 0.1 s at 1 kHz) equals that of the
    full-rate bank (D = 1) and the IEEE closed form from τ = 1/f0 on."""
    model = NoiseModel(bias_instability=1e-4, bias_instability_corner_hz=1.0,
                       bias_instability_low_hz=1e-3)
    dt, n = 1e-3, 2_000_000
    fast = NoiseGenerator(model, dt, rng=10)
    exact = NoiseGenerator(model, dt, rng=10, decimation=1)
    assert (fast.decimation, exact.decimation) == (100, 1)
    ms = [1000, 2000, 5000]
    expected = compute_theoretical_adev(model, np.array(ms) * dt)
    a_fast, a_exact = oadev(fast.generate(n), dt, ms), oadev(exact.generate(n), dt, ms)
    for m, rf, re, ex in zip(ms, a_fast, a_exact, expected, strict=True):
        sd = rel_sd(edf_flicker_fm(n, m))
        assert_adev(rf, ex, sd, model_err=0.03)  # 1/f0 is below the specified 2/f0
        assert_adev(re, ex, sd, model_err=0.03)
        assert np.all(np.abs(rf / re - 1) < 3.5 * math.sqrt(2) * sd)


@pytest.mark.parametrize("seed", [0, 1])
def test_markov_allan_peak(seed: int) -> None:
    sigma = np.array([1e-3, 2e-3, 5e-4])
    tc = np.array([1.0, 2.0, 0.5])
    model = NoiseModel(markov_sigma=sigma, markov_time_constant_s=tc)
    dt, n = 0.01, 1_000_000
    y = NoiseGenerator(model, dt, rng=seed).generate(n)
    np.testing.assert_allclose(y.std(axis=0), sigma, rtol=0.06)  # ~1e4·T_c of data
    q_c = sigma * np.sqrt(2 / tc)
    for ax in range(3):
        m_peak = round(1.892 * tc[ax] / dt)
        peak, low, high = oadev(y[:, [ax]], dt, [m_peak, m_peak // 8, m_peak * 8])[:, 0]
        assert abs(peak / (0.4365 * q_c[ax] * math.sqrt(tc[ax])) - 1) < (
            3.5 * rel_sd(edf_rw_fm(n, m_peak)))
        assert peak > low and peak > high
        # the shape of the curve fixes T_c: σ² ≈ q_c²τ/3 below it, 2σ²T_c/τ above it
        ms = [m_peak // 8, m_peak // 2, m_peak * 4]
        expected = compute_theoretical_adev(model, np.array(ms) * dt)[:, ax]
        for got, ex, m in zip(oadev(y[:, [ax]], dt, ms)[:, 0], expected, ms, strict=True):
            assert abs(got / ex - 1) < 3.5 * rel_sd(edf_rw_fm(n, m))


def test_full_rate_markov_next_to_a_slow_grid() -> None:
    """A Markov term too fast for the slow grid (T_c < 20·h) runs at the full rate, merged with
    the white noise and quantization of its axis."""
    model = NoiseModel(markov_sigma=1e-3, markov_time_constant_s=0.05, bias_instability=1e-12,
                       white_density=[0.0, 1e-4, 5e-5], quantization=[0.0, 0.0, 2e-7])
    dt, n = 1e-3, 1_000_000
    gen = NoiseGenerator(model, dt, rng=12)
    assert gen.decimation * dt * 20 > 0.05
    y = gen.generate(n)
    ms = [10, 95, 300, 1000]
    expected = compute_theoretical_adev(model, np.array(ms) * dt)
    for row, ex, m in zip(oadev(y, dt, ms), expected, ms, strict=True):
        assert_adev(row, ex, rel_sd(edf_rw_fm(n, m)))


@pytest.mark.slow
def test_markov_terms_start_stationary() -> None:
    """The first sample already has the stationary variance, on the grid and at the full rate
    (axis 0: T_c = 30 s on the slow grid, plus quantization; axes 1, 2: T_c = 20 ms merged with
    white noise or quantization)."""
    model = NoiseModel(white_density=[0.0, 1e-3, 0.0], quantization=[1e-5, 0.0, 1e-5],
                       markov_sigma=1e-2, markov_time_constant_s=[30.0, 0.02, 0.02],
                       bias_instability=1e-12)
    dt, n_gen = 1e-3, 1500
    first = np.array([NoiseGenerator(model, dt, rng=s).generate(1)[0] for s in range(n_gen)])
    expected = model.white_density**2 / dt + 2 * (model.quantization / dt) ** 2 + 1e-4
    np.testing.assert_allclose(first.var(axis=0), expected, rtol=3.5 * math.sqrt(2 / n_gen))


@settings(max_examples=300, deadline=None)
@given(white=st.floats(0.0, 1e3), quant=st.floats(0.0, 1e3), gap=st.floats(1e-15, 1.0),
       c2=st.floats(1e-12, 1e6))
def test_ma_factor_reproduces_the_spectrum(white: float, quant: float, gap: float,
                                           c2: float) -> None:
    """(1 − φz⁻¹)·(white + quantization MA(1)) + Markov innovation = β(z)·u, minimum phase,
    with the autocovariance and, to 1e-5, the zero-frequency power (A·B + c2) preserved."""
    phi = 1.0 - gap
    s = math.sqrt(white**2 + 4 * quant**2)
    alpha = np.convolve([(s + white) / 2, -(s - white) / 2], [1.0, -phi])
    r = np.correlate(alpha, alpha, "full")[2:]
    r[0] += c2
    beta = _ma_factor(white**2, quant**2, gap**2, phi, c2)
    np.testing.assert_allclose(np.correlate(beta, beta, "full")[2:], r, rtol=0, atol=1e-12 * r[0])
    np.testing.assert_allclose(beta.sum() ** 2, white**2 * gap**2 + c2, rtol=1e-5)
    assert beta[0] > 0
    if np.any(beta[1:]):
        assert np.all(np.abs(np.roots(np.trim_zeros(beta, "b"))) < 1)


def test_rate_ramp_is_a_deterministic_slope() -> None:
    r = np.array([1e-5, -2e-5, 0.0])
    gen = NoiseGenerator(NoiseModel(rate_ramp=r), 0.01, rng=0)
    y = np.concatenate([gen.generate(k) for k in (1, 999, 70_000, 29_000)])
    t = np.arange(y.shape[0]) * 0.01
    np.testing.assert_allclose(y, r * t[:, None], rtol=1e-9, atol=1e-18)


# -- generator: chunking, reproducibility, edge cases -------------------------------------------
FULL = NoiseModel(white_density=[1e-3, 2e-3, 1e-3], bias_instability=1e-4, random_walk=1e-5,
                  rate_ramp=[1e-7, 0.0, -1e-7], quantization=[1e-5, 0.0, 2e-5],
                  markov_sigma=[1e-4, 1e-4, 0.0], markov_time_constant_s=[30.0, 0.01, 0.0])


@pytest.mark.parametrize("chunks", [[1, 7, 1000, 40_000, 3, 65_536, 12_345], [200_001]])
def test_chunked_generation_equals_one_shot_exactly(chunks: list[int]) -> None:
    one = NoiseGenerator(FULL, 1e-3, rng=42).generate(sum(chunks))
    gen = NoiseGenerator(FULL, 1e-3, rng=42)
    parts = np.concatenate([gen.generate(c) for c in chunks])
    np.testing.assert_array_equal(parts, one)


def test_same_seed_reproduces_and_other_seed_differs() -> None:
    a = [NoiseGenerator(FULL, 1e-3, rng=7).generate(5000) for _ in range(2)]
    np.testing.assert_array_equal(a[0], a[1])
    b = NoiseGenerator(FULL, 1e-3, rng=np.random.default_rng(8)).generate(5000)
    assert not np.allclose(a[0], b)
    np.testing.assert_array_equal(simulate_noise(FULL, 5000, 1e-3, rng=7), a[0])


def test_zero_model_returns_zeros_without_drawing() -> None:
    rng = np.random.default_rng(3)
    before = rng.bit_generator.state
    y = NoiseGenerator(NoiseModel(), 0.01, rng).generate(10)
    assert y.shape == (10, 3) and not y.any()
    assert rng.bit_generator.state == before
    assert NoiseGenerator(FULL, 0.01, rng=1).generate(0).shape == (0, 3)


@pytest.mark.parametrize(
    ("call", "error", "match"),
    [
        (lambda: NoiseGenerator(FULL, 0.0), InvalidInputError, r"`sample_interval_s` must be > 0"),
        (lambda: NoiseGenerator(FULL, 1.0), ConfigurationError,
         r"`bias_instability_corner_hz` must be below the Nyquist frequency 0.5 Hz"),
        (lambda: NoiseGenerator(FULL, 1e-3, decimation=0), InvalidInputError,
         r"`decimation` must be an integer ≥ 1; got 0"),
        (lambda: NoiseGenerator("model", 1e-3), InvalidInputError,  # type: ignore[arg-type]
         r"`model` must be a NoiseModel"),
        (lambda: NoiseGenerator(FULL, 1e-3).generate(-1), InvalidInputError,
         r"`n_samples` must be an integer ≥ 0; got -1"),
        (lambda: NoiseGenerator(FULL, 1e-3).generate(2.5), InvalidInputError,  # type: ignore[arg-type]
         r"`n_samples` must be an integer ≥ 0; got 2.5"),
    ],
)
def test_generator_bad_inputs(call: Callable[[], object], error: type[Exception],
                              match: str) -> None:
    with pytest.raises(error, match=match):
        call()


def _reference_adev(m: NoiseModel, tau_s) -> np.ndarray:
    """docs/equations.md §8 term by term, every term evaluated (zero coefficients included)."""
    from scipy import special

    tau = np.asarray(tau_s, dtype=float).reshape(-1, 1)
    x = np.pi * m.bias_instability_corner_hz * tau
    flicker = (2 / np.pi) * (np.log(2.0) - np.sin(x) ** 3 / (2 * x**2)
                             * (np.sin(x) + 4 * x * np.cos(x))
                             + special.sici(2 * x)[1] - special.sici(4 * x)[1])
    used = m.markov_sigma > 0
    tc = np.where(used, m.markov_time_constant_s, 1.0)
    r = tau / tc
    with np.errstate(divide="ignore", invalid="ignore"):
        bracket = 1 - (-4 * np.expm1(-r) + np.expm1(-2 * r)) / (2 * r)
    bracket = np.where(r < 1e-3, r**2 / 3 - r**3 / 4 + 7 * r**4 / 60, bracket)
    avar = (3 * m.quantization**2 / tau**2 + m.white_density**2 / tau
            + m.random_walk**2 * tau / 3 + m.rate_ramp**2 * tau**2 / 2
            + m.bias_instability**2 * flicker
            + np.where(used, 2 * m.markov_sigma**2 * tc / tau * bracket, 0.0))
    return np.sqrt(avar)


@pytest.mark.parametrize("model", [
    NoiseModel(),
    NoiseModel(white_density=[0.1, 0.2, 0.3]),
    NoiseModel(white_density=0.1, bias_instability=[0.01, 0.0, 0.02], random_walk=1e-3,
               quantization=1e-4, rate_ramp=[1e-6, -1e-6, 0.0], bias_instability_corner_hz=3.0),
    NoiseModel(markov_sigma=[0.1, 0.0, 0.2], markov_time_constant_s=[10.0, 0.0, 1.0]),
    NoiseModel(bias_instability=1e-3),
])
def test_theoretical_adev_skips_only_zero_terms(model: NoiseModel) -> None:
    tau = [1e-5, 1e-3, 0.5, 6.0, 1e3, 1e5]
    for _ in range(2):  # the second call uses the per-model cache
        got = compute_theoretical_adev(model, tau)
        np.testing.assert_allclose(got, _reference_adev(model, tau), rtol=1e-12, atol=0.0)
        one = compute_theoretical_adev(model, np.array([6.0]))
        np.testing.assert_array_equal(one[0], got[3])
