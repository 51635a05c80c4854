"""The tumble's reduction on synthetic position means (docs/tumble.md, Eqs. (T.1)–(T.9)).

Known coefficients → exact means → Fourier fit (LSQ and DFT agree) → coefficients back; σ
against the closed forms of (T.9) and a Monte Carlo; identifiability by the aliasing rule.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from imucalib import units
from imucalib.errors import InsufficientExcitationError, InvalidInputError
from imucalib.procedures.tumble.fourier import (
    COEFFICIENTS,
    check_identifiable,
    closed_form_precision,
    fit_fourier,
    fourier_dft,
    invert_coefficients,
    koq_harmonic,
    resolvable_coefficients,
)

G = 9.80665
UG = 1e-6 * units.G0_MPS2
#: K0 [m/s²], K1, δ [rad], K2, Kip [1/(m/s²)], K3 [1/(m/s²)²], Koq [1/(m/s²)]
TRUTH = {"K0": 3e-4, "K1": 1.00012, "delta": 2.5e-5, "K2": 1.5e-6, "Kip": -8e-7,
         "K3": 4e-8, "Koq": 2e-6}


def means(theta: np.ndarray, c: dict[str, float], g: float = G) -> np.ndarray:
    """The output of (T.1) at gravity angles θ: K1·(K0 + a_i + δ a_p + K2 a_i² + …)."""
    ai, ap = g * np.cos(theta), g * np.sin(theta)
    return c["K1"] * (c["K0"] + ai + c["delta"] * ap + c["K2"] * ai**2 + c["Kip"] * ai * ap
                      + c["K3"] * ai**3 + c["Koq"] * ai * np.abs(ai))


def angles(n: int, start_deg: float = 0.0) -> np.ndarray:
    return np.radians(start_deg + 360.0 * np.arange(n) / n)


def test_koq_fourier_coefficients_match_quadrature() -> None:
    x = np.linspace(0.0, 2 * math.pi, 200_001)[:-1]
    for n in (1, 3, 5, 7, 9):
        numeric = 2 * np.mean(np.cos(x) * np.abs(np.cos(x)) * np.cos(n * x))
        assert koq_harmonic(n) == pytest.approx(numeric, abs=1e-9)
    assert koq_harmonic(1) == pytest.approx(8 / (3 * math.pi))
    assert koq_harmonic(5) == pytest.approx(-8 / (105 * math.pi))


@pytest.mark.parametrize("n", [4, 8, 12, 24])
def test_dft_equals_least_squares(n: int) -> None:
    rng = np.random.default_rng(n)
    th = angles(n, start_deg=90.0)
    y = means(th, TRUTH) + rng.normal(0, 10 * UG, n)
    sigma = rng.uniform(5, 15, n) * UG
    lsq = fit_fourier(th, y, sigma, n // 2, n_positions=n)
    dft = fourier_dft(th, y, sigma)
    assert lsq.names == dft.names and len(dft.names) == n
    assert np.max(np.abs(lsq.values - dft.values)) < 1e-12
    assert np.max(np.abs(lsq.covariance - dft.covariance)) < 1e-12 * np.max(dft.covariance)


@pytest.mark.parametrize("n", [4, 8, 12, 24])
def test_coefficients_recovered_exactly_without_noise(n: int) -> None:
    th = angles(n)
    wanted = resolvable_coefficients(n)
    truth = {c: (TRUTH[c] if c in wanted else 0.0) for c in COEFFICIENTS}
    for fourier in (fourier_dft(th, means(th, truth), 10 * UG),
                    fit_fourier(th, means(th, truth), 10 * UG, n // 2, n_positions=n)):
        fit = invert_coefficients(fourier, G, wanted)
        assert fit.names == wanted
        for c in wanted:
            assert fit.value(c) == pytest.approx(truth[c], rel=1e-6, abs=1e-15), c
        assert fit.quality.chi2 < 1e-12


def test_closed_form_precision_values() -> None:
    """(T.9) at N = 24, σ = 10 µg: 2.9 µrad, 5.8 µg/g², 11.5 µg/g³."""
    cf = closed_form_precision(10 * UG, 24, units.G0_MPS2)
    g0 = units.G0_MPS2
    assert cf["delta"] / 1e-6 == pytest.approx(2.887, abs=0.001)
    assert cf["K2"] * g0 / 1e-6 == pytest.approx(5.774, abs=0.001)
    assert cf["Kip"] * g0 / 1e-6 == pytest.approx(5.774, abs=0.001)
    assert cf["K3"] * g0**2 / 1e-6 == pytest.approx(11.547, abs=0.001)


@pytest.mark.parametrize("n", [8, 12, 24])
def test_reported_sigma_is_the_closed_form(n: int) -> None:
    th = angles(n)
    wanted = ("K0", "K1", "delta", "K2", "Kip", "K3")
    fit = invert_coefficients(fourier_dft(th, means(th, TRUTH | {"Koq": 0.0}), 10 * UG), G,
                              wanted)
    cf = closed_form_precision(10 * UG, n, G)
    k1 = fit.value("K1")
    for c in ("delta", "K2", "Kip", "K3"):
        # the coefficients are per unit of K1 (E/K1): their σ carries 1/K1
        assert fit.std(c) * k1 == pytest.approx(cf[c], rel=1e-3), c
    assert fit.fourier.std("A0") == pytest.approx(cf["A0"], rel=1e-12)
    assert fit.fourier.std("B2") == pytest.approx(cf["A_n"], rel=1e-12)


@pytest.mark.slow
@pytest.mark.parametrize("n", [12, 24])
def test_sigma_matches_monte_carlo(n: int) -> None:
    rng = np.random.default_rng(100 + n)
    th = angles(n)
    wanted = resolvable_coefficients(n)
    y0 = means(th, TRUTH)
    sigma = 10 * UG
    draws = np.array([invert_coefficients(fourier_dft(th, y0 + rng.normal(0, sigma, n), sigma),
                                          G, wanted).values for _ in range(1500)])
    ref = invert_coefficients(fourier_dft(th, y0, sigma), G, wanted)
    spread = draws.std(axis=0, ddof=1)
    reported = np.sqrt(np.diag(ref.covariance_noise))
    assert np.all(np.abs(spread / reported - 1) < 0.15), dict(zip(wanted, spread / reported,
                                                              strict=True))
    bias = (draws.mean(axis=0) - ref.values) / (spread / math.sqrt(len(draws)))
    assert np.all(np.abs(bias) < 4.5)


def test_koq_aliases_onto_k3_at_eight_positions() -> None:
    """N = 8: Koq's 5th harmonic lands on the 3rd, so K3 absorbs it (Table T.1)."""
    th = angles(8)
    truth = TRUTH | {"Kip": 0.0, "K3": 0.0}
    fit = invert_coefficients(fourier_dft(th, means(th, truth), 10 * UG), G,
                              resolvable_coefficients(8))
    assert "Koq" not in fit.names
    # A3 = ¼K3·g³ + (c3 + c5 + c11 + c13 …)·Koq·g²: the apparent K3 is 4(c3 + c5 + …)·Koq/g
    aliases = sum(koq_harmonic(n) for n in (3, 5, 11, 13, 19, 21, 27, 29))
    assert fit.value("K3") == pytest.approx(4 * aliases * truth["Koq"] / G, rel=1e-3)


@pytest.mark.parametrize(("n", "asked", "named"), [
    (4, ("K0", "K1", "Kip"), ["Kip"]),
    (4, ("K0", "K1", "K3"), ["K3"]),
    (4, ("K0", "K1", "delta", "K2", "Kip", "K3"), ["Kip", "K3"]),
    (8, ("K0", "K1", "K3", "Koq"), ["Koq"]),
    (8, COEFFICIENTS, ["Koq"]),
])
def test_unresolvable_coefficients_are_named(n: int, asked: tuple[str, ...],
                                             named: list[str]) -> None:
    th = angles(n)
    with pytest.raises(InsufficientExcitationError, match="cannot resolve") as info:
        invert_coefficients(fourier_dft(th, means(th, TRUTH), 10 * UG), G, asked)
    assert list(info.value.unobservable) == named
    with pytest.raises(InsufficientExcitationError) as rule:
        check_identifiable(asked, n_positions=n)
    assert list(rule.value.unobservable) == named


def test_resolvable_coefficients_by_n() -> None:
    assert resolvable_coefficients(4) == ("K0", "K1", "delta", "K2")
    assert resolvable_coefficients(8) == ("K0", "K1", "delta", "K2", "Kip", "K3")
    assert resolvable_coefficients(12) == COEFFICIENTS
    assert resolvable_coefficients(24) == COEFFICIENTS


def test_bad_requests() -> None:
    with pytest.raises(InvalidInputError, match="always estimates K0 and K1"):
        check_identifiable(["K0", "delta"], n_positions=12)
    with pytest.raises(InvalidInputError, match="distinct names"):
        check_identifiable(["K0", "K1", "K9"], n_positions=12)


def test_dft_refuses_positions_not_equally_spaced() -> None:
    th = np.radians([0.0, 30.0, 60.0, 95.0, 120.0, 150.0, 180.0, 210.0, 240.0, 270.0, 300.0,
                     330.0])
    y = means(th, TRUTH)
    with pytest.raises(InvalidInputError, match="equally spaced by 360°/N; got 12 positions"):
        fourier_dft(th, y, 10 * UG)
    # the least-squares form takes any angles
    fit = invert_coefficients(fit_fourier(th, y, 10 * UG, 5), G, COEFFICIENTS)
    for c in COEFFICIENTS:
        assert fit.value(c) == pytest.approx(TRUTH[c], rel=1e-5, abs=1e-15), c
