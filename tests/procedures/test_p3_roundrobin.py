"""P3's round-robin reduction on synthetic series with known truth (Eqs. (P3.1)–(P3.4))."""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.errors import InsufficientExcitationError, InvalidInputError
from imucalib.procedures.p3.roundrobin import (
    PARAMETERS,
    SERIES_NAMES,
    fit_series,
    solve_round_robin,
)

G0 = 9.80665
R_T = 0.6                       # test position [m]
R_R = R_T / 3                   # references [m]
EARTH_UP = 7.292115e-5 * np.sin(np.radians(45.0))
RATES = np.radians([120.0, 200.0, 260.0, 300.0, 330.0])   # up to ~20 g at R_T
#: K2 of A, B and the test accelerometer [1/(m/s²)] (tens of µg/g²), c, c′ [m/(rad/s)²]
TRUTH = {"K2_A": 30e-6 / G0, "K2_B": -20e-6 / G0, "K2_T": 50e-6 / G0,
         "c": 2e-7, "c_loaded": 3e-7}
#: which accelerometer, its radius, its side (+1: where the centre moves) and which c
LAYOUT = {"A1": ("K2_A", R_R, +1, "c"), "B1": ("K2_B", R_R, -1, "c"),
          "A2": ("K2_A", R_R, -1, "c"), "B2": ("K2_B", R_R, +1, "c"),
          "A3": ("K2_A", R_R, +1, "c_loaded"), "B3": ("K2_B", R_R, -1, "c_loaded"),
          "T3": ("K2_T", R_T, +1, "c_loaded")}
K1 = 1.3e-3                      # output per m/s² (a current-output accelerometer, A per m/s²)


def _series(rng, noise_ug: float = 1.0, truth=TRUTH):
    out = {}
    for name, (k2, r, side, c) in LAYOUT.items():
        we = RATES + EARTH_UP
        a = we**2 * (r + side * truth[c] * RATES**2)
        y = K1 * (a + truth[k2] * a**2)
        sd = np.full(RATES.size, K1 * noise_ug * 1e-6 * G0)
        out[name] = fit_series(RATES, y + rng.normal(0.0, sd), sd, k1=K1,
                               earth_rate_up_rps=EARTH_UP, name=name)
    return out


def test_noise_free_series_give_the_truth_and_the_naive_k2_is_biased_by_c_over_r2():
    """The truth to 1e-11 m/(rad/s)² for c, c′ and 5e-9 g/g² for the K2s.

    What remains without noise is the ω⁶ term the series' fit leaves out (measured 2.3e-9
    g/g² on K2_T): fifty times below the 1e-7 g/g² the method claims.
    """
    est = solve_round_robin(_series(np.random.default_rng(0), noise_ug=1e-9),
                            radius_a_m=R_R, radius_b_m=R_R, radius_t_m=R_T)
    for name in PARAMETERS:
        tol = 1e-11 if name.startswith("c") else 5e-9 / G0
        assert abs(est.value(name) - TRUTH[name]) < tol, name
    # ignoring the unbalance: K2_T off by c′/r_t² (≈ 8e-7 per m/s², 8 µg/g²)
    assert abs(est.naive_k2_t - TRUTH["K2_T"] - TRUTH["c_loaded"] / R_T**2) < 5e-9 / G0


@pytest.mark.slow
def test_compensated_k2_reaches_1e_7_g_per_g2_and_sigma_matches_the_spread():
    """With 0.05 µg window means (measured: 0.1 µg gives 1.1e-7 g/g², 0.03 µg 3.2e-8)."""
    errs, stds = [], []
    for seed in range(300):
        est = solve_round_robin(_series(np.random.default_rng(100 + seed), noise_ug=0.05),
                                radius_a_m=R_R, radius_b_m=R_R, radius_t_m=R_T)
        errs.append(est.values - [TRUTH[p] for p in PARAMETERS])
        stds.append(np.sqrt(np.diag(est.covariance)))
    errs_arr, stds_arr = np.array(errs), np.array(stds)
    k2t = PARAMETERS.index("K2_T")
    # the claim of the method: K2 of the test accelerometer to the 1e-7 g/g² level
    assert np.sqrt(np.mean(errs_arr[:, k2t] ** 2)) * G0 < 1e-7
    ratio = errs_arr.std(axis=0) / stds_arr.mean(axis=0)
    assert np.all(np.abs(ratio - 1.0) < 0.15), ratio.round(3)
    assert np.all(np.abs(errs_arr.mean(axis=0)) < 4 * stds_arr.mean(axis=0) / np.sqrt(300))


def test_bad_inputs_are_named():
    rng = np.random.default_rng(1)
    series = _series(rng)
    without_swap = {k: v for k, v in series.items() if k not in ("A2", "B2")}
    with pytest.raises(InvalidInputError, match=r"missing \['A2', 'B2'\].*swap"):
        solve_round_robin(without_swap, radius_a_m=R_R, radius_b_m=R_R, radius_t_m=R_T)
    with pytest.raises(InsufficientExcitationError, match="at least 4 rate points"):
        fit_series(RATES[:3], np.ones(3), np.ones(3), k1=K1, name="A1")
    with pytest.raises(InvalidInputError, match="K1"):
        fit_series(RATES, np.ones(5), np.ones(5), k1=-1.0)
    with pytest.raises(InvalidInputError, match="radius_t_m"):
        solve_round_robin(series, radius_a_m=R_R, radius_b_m=R_R, radius_t_m=0.0)
    assert set(series) == set(SERIES_NAMES)
