"""P2's σ under coloured noise: the window means' covariance across the sweep (issue 30).

The temperature models are weighted least squares of the point estimates, whose covariance
across points (Eq. (P2.13) of docs/p2.md) carries the unit's flicker and random walk
(Eq. (TD.2) of docs/test-design.md); the reported σ are the sandwich W·Θ·Wᵀ of that estimator.
Before, the windows were treated as independent and the biases' σ at T0 came out several
times too small: each test here fails with that σ.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from imucalib.estimation import compute_window_mean_covariance
from imucalib.estimation.temperature_model import fit_temperature_model
from imucalib.models.noise import NoiseModel
from imucalib.procedures.common.noise import window_mean_se
from imucalib.procedures.p2.analysis import P2Options, analyze_unit, assemble_point
from imucalib.procedures.p2.observations import P2Window, UnitObservations, unit_noise
from imucalib.procedures.p2.reduction import ORIENTATIONS, PARAM_NAMES, least_squares

from .._p2_synthetic import EARTH_UP, G, draw_truth, unit_observations

#: A consumer-like unit: white, flicker and the gyro's rate random walk (SI, per axis).
NOISE = {"gyro": NoiseModel(white_density=8.7e-5, bias_instability=3.9e-5, random_walk=2.4e-6),
         "accel": NoiseModel(white_density=1.5e-3, bias_instability=5.9e-4)}
TEMPS = (-40.0, -20.0, 0.0, 25.0, 45.0, 65.0, 85.0)
_WINDOW_S = 10.0


def _timed(obs: UnitObservations) -> UnitObservations:
    """The windows on a sweep's clock: 40 s apart within a point, 40 min between points; each
    window's standard error the noise model's Allan deviation at its length."""
    se_g, se_a = window_mean_se(NOISE, _WINDOW_S)
    out, t, last = [], 600.0, None
    for w in obs.windows:
        if last is not None and w.point != last:
            t += 2400.0
        last = w.point
        out.append(dataclasses.replace(w, start_s=t, duration_s=_WINDOW_S, gyro_se_rps=se_g,
                                       accel_se_mps2=se_a))
        t += 40.0
    return dataclasses.replace(obs, windows=tuple(out), noise=NOISE)


def _noisy(base: UnitObservations, rng: np.random.Generator) -> UnitObservations:
    """`base`'s noise-free means plus a draw of the coloured noise of every window (TD.2)."""
    wins = base.windows
    starts = np.array([w.start_s for w in wins])
    durs = np.array([w.duration_s for w in wins])
    draw = {}
    for triad in ("gyro", "accel"):
        cov = compute_window_mean_covariance(NOISE[triad], starts, durs, reference_time_s=0.0)
        draw[triad] = np.column_stack([np.linalg.cholesky(c) @ rng.standard_normal(len(wins))
                                       for c in cov])
    out = [dataclasses.replace(w, gyro_mean_rps=w.gyro_mean_rps + draw["gyro"][j],
                               accel_mean_mps2=w.accel_mean_mps2 + draw["accel"][j])
           for j, w in enumerate(wins)]
    return dataclasses.replace(base, windows=tuple(out))


def _assert_same_covariance(got: np.ndarray, want: np.ndarray, tol: float = 1e-6) -> None:
    """Equal to `tol` in units of σ_i·σ_j (each element against its own scale)."""
    d = np.sqrt(np.diag(want))
    assert np.max(np.abs(got - want) / np.outer(d, d)) < tol


def _base(seed: int = 3) -> tuple[UnitObservations, object]:
    truth = draw_truth(np.random.default_rng(seed))
    obs = unit_observations(truth, np.random.default_rng(seed + 1), temperatures=TEMPS,
                            held_out=(), noise=False)
    return _timed(obs), truth


def test_the_point_gain_carries_the_means_into_the_parameters():
    """gain·diag(σ²)·gainᵀ is the least squares' covariance; gain·δ its change (linear)."""
    obs, _ = _base()
    wins = [dataclasses.replace(w, orientation=w.pose) for w in obs.windows if w.point == 0]
    pw = assemble_point("U1", 0, wins, G, EARTH_UP)
    ls = least_squares(pw)
    assert ls.gain is not None and ls.gain.shape == (39, 90)
    means, ses = pw.means_vector()
    _assert_same_covariance(ls.gain @ np.diag(ses**2) @ ls.gain.T, ls.covariance)
    delta = 0.1 * ses * np.random.default_rng(0).standard_normal(90)
    fields = [m for m, _ in pw._FIELDS]
    parts = np.split(means + delta, 5)
    moved = dataclasses.replace(pw, **{f: p.reshape(6, 3) for f, p in zip(fields, parts,
                                                                           strict=True)})
    change = least_squares(moved).values - ls.values
    # linear but for r̂ in the gyro's G·ω²·P_o·r̂ (second order, not propagated): to 1 %
    for block in (slice(0, 21), slice(21, 36)):
        np.testing.assert_allclose(change[block], (ls.gain @ delta)[block],
                                   atol=1e-2 * np.max(np.abs(change[block])))


def test_weighted_fit_with_a_known_covariance_reports_the_sandwich_and_the_gls_chi2():
    """Eqs. (2b)–(3b) of estimation/temperature_model.py on a constructed case."""
    temps = np.array([-30.0, -5.0, 20.0, 45.0, 70.0])
    times = np.arange(5) * 3600.0
    cov = 1e-8 * (np.diag([1.0, 1.2, 0.9, 1.1, 1.0]) + np.minimum.outer(times, times) / 3600.0)
    var = np.diag(cov) * 0.5
    p = np.array([1e-4, 2e-4, 2.5e-4, 4e-4, 6e-4])
    fit = fit_temperature_model(temps, p, cov, weights=var, order=1,
                                reference_temperature_degc=25.0)
    a = np.column_stack([np.ones(5), temps - 25.0])
    w = np.linalg.solve(a.T @ (a / var[:, None]), (a / var[:, None]).T)
    np.testing.assert_allclose(fit.model.coefficients, w @ p, rtol=1e-10)
    np.testing.assert_allclose(fit.covariance, w @ cov @ w.T, rtol=1e-8)
    ci = np.linalg.inv(cov)
    beta_gls = np.linalg.solve(a.T @ ci @ a, a.T @ ci @ p)
    r = p - a @ beta_gls
    assert fit.chi2 == pytest.approx(float(r @ ci @ r), rel=1e-8)
    # without weights: the GLS of Eq. (2), as before
    gls = fit_temperature_model(temps, p, cov, order=1, reference_temperature_degc=25.0)
    np.testing.assert_allclose(gls.model.coefficients, beta_gls, rtol=1e-8)
    np.testing.assert_allclose(gls.covariance, np.linalg.inv(a.T @ ci @ a), rtol=1e-8)


def _sandwich_in_the_test(res, obs: UnitObservations) -> np.ndarray:
    """Cov(c_0) = W·Θ·Wᵀ built here from the points' gains and Eq. (TD.2) (no Birge ratios)."""
    cal = [p for p in res.points if not p.held_out]
    n_par = len(PARAM_NAMES)
    wins = list(obs.windows)
    starts = np.array([w.start_s for w in wins])
    durs = np.array([w.duration_s for w in wins])
    c = {t: compute_window_mean_covariance(NOISE[t], starts, durs, reference_time_s=0.0)
         for t in ("gyro", "accel")}
    # J: ∂θ_k/∂(window j, channel) through the plain means of each orientation's windows
    big = np.zeros((n_par * len(cal), len(wins), 6))
    for k, p in enumerate(cal):
        mine = [j for j, w in enumerate(wins) if w.point == p.point]
        for o_i, o in enumerate(ORIENTATIONS):
            for kind, f_gyro, f_accel in (("static", None, 0), ("plus", 1, 3), ("minus", 2, 4)):
                sel = [j for j in mine if wins[j].pose == o and (
                    wins[j].kind == "static" if kind == "static" else
                    wins[j].kind == "rate" and (wins[j].table_rate_rps > 0) == (kind == "plus"))]
                for f, ch0 in ((f_gyro, 0), (f_accel, 3)):
                    if f is None:
                        continue
                    for a in range(3):
                        col = p.least_squares.gain[:n_par, 18 * f + 3 * o_i + a]
                        for j in sel:
                            big[k * n_par:(k + 1) * n_par, j, ch0 + a] += col / len(sel)
    theta = sum(big[:, :, ch] @ c["gyro" if ch < 3 else "accel"][ch % 3] @ big[:, :, ch].T
                for ch in range(6))
    temps = np.array([p.temperature_degc for p in cal])
    out_w = np.zeros((n_par, n_par * len(cal)))
    for i in range(n_par):
        var = np.array([p.least_squares.covariance_scaled()[i, i] for p in cal])
        a = np.column_stack([(temps - 25.0) ** j for j in range(4)])
        w = np.linalg.solve(a.T @ (a / var[:, None]), (a / var[:, None]).T)
        out_w[i, np.arange(len(cal)) * n_par + i] = w[0]
    return out_w @ theta @ out_w.T


def test_the_reported_covariance_is_the_sandwich_with_the_coloured_covariance():
    """The result's covariance at T0 (no misfit, noise-free means) is W·Θ·Wᵀ with Θ from the
    windows' coloured covariance; the biases' σ far exceed the independent windows' ones."""
    obs, _ = _base()
    res = analyze_unit(obs, P2Options(order=3))
    assert not any(m.quality.misfit for m in res.models.values())
    want = _sandwich_in_the_test(res, obs)
    _assert_same_covariance(res.result.covariance, want)
    std = np.sqrt(np.diag(res.result.covariance))
    np.testing.assert_allclose([res.std_noise[n] for n in PARAM_NAMES], std, rtol=1e-9)
    old = analyze_unit(dataclasses.replace(obs, noise=None), P2Options(order=3))
    np.testing.assert_array_equal(res.result.values, old.result.values)   # the same estimates
    ratio = std / np.sqrt(np.diag(old.result.covariance))
    biases = [i for i, n in enumerate(PARAM_NAMES) if "_bias_" in n]
    assert np.all(ratio[biases] > 3.0), ratio[biases]
    assert any("covariance of the window means" in n for n in res.notes)
    assert not any("understate" in n for n in res.notes)


def test_the_biases_sigma_covers_their_spread_under_coloured_noise():
    """20 draws of the coloured noise: z = (ĉ_0 − c_0)/σ of the six biases has RMS ≈ 1 (±6.5 %
    sampling error, 120 values); with the independent windows' σ it was several times larger.

    Measured: RMS z 0.93 (the independent windows' σ: 24)."""
    base, truth = _base(5)
    biases = [i for i, n in enumerate(PARAM_NAMES) if "_bias_" in n]
    # the old σ: independent windows with the same standard errors (no Birge ratio on the
    # noise-free means), the same in every draw
    old_std = np.sqrt(np.diag(analyze_unit(dataclasses.replace(base, noise=None),
                                           P2Options(order=3)).result.covariance))[biases]
    z_new, z_old = [], []
    rng = np.random.default_rng(11)
    for _ in range(20):
        res = analyze_unit(_noisy(base, rng), P2Options(order=3))
        err = (res.result.values - truth.coefficients[0])[biases]
        z_new.append(err / np.sqrt(np.diag(res.result.covariance))[biases])
        z_old.append(err / old_std)
    rms_new = float(np.sqrt(np.mean(np.square(z_new))))
    rms_old = float(np.sqrt(np.mean(np.square(z_old))))
    print(f"RMS z {rms_new:.3f}, old σ {rms_old:.3f}")
    assert 0.75 < rms_new < 1.3, rms_new
    assert rms_old > 2.5, rms_old


def test_short_windows_take_the_declared_flicker_and_random_walk():
    """P2's windows of seconds determine no flicker or random walk: the grade's (Type B) with
    the fitted white density; none for a grade declared white; the fit without a grade."""
    fit = np.zeros((3, 6))
    fit[0] = [1e-4] * 3 + [2e-3] * 3
    fit[1] = [4e-9] * 3 + [0.0] * 3            # a spurious flicker of the short fits
    fit[2] = [1e-6] * 3 + [0.0] * 3
    win = P2Window(step_index=0, label="s", point=0, leg="heating", held_out=False,
                   pose="+z", kind="static", table_rate_rps=0.0, n_revolutions=0,
                   gyro_mean_rps=np.zeros(3), accel_mean_mps2=np.zeros(3),
                   gyro_se_rps=np.ones(3), accel_se_mps2=np.ones(3), temperature_degc=25.0,
                   temperature_rate_degc_ps=0.0, duration_s=4.0, n_samples=200, n_lost=0,
                   allan_fit=fit, start_s=0.0)
    noise, note = unit_noise([win] * 3, 50.0, (NOISE, "consumer"))
    assert noise is not None and note is not None and "Type B" in note
    for t in ("gyro", "accel"):
        np.testing.assert_array_equal(noise[t].bias_instability, NOISE[t].bias_instability)
        np.testing.assert_array_equal(noise[t].random_walk, NOISE[t].random_walk)
    np.testing.assert_allclose(noise["gyro"].white_density, 1e-4)
    white = {t: NoiseModel(white_density=m.white_density) for t, m in NOISE.items()}
    noise, _ = unit_noise([win] * 3, 50.0, (white, "consumer"))
    assert noise is not None and np.all(noise["gyro"].bias_instability == 0.0)
    assert np.all(noise["gyro"].random_walk == 0.0)
    noise, note = unit_noise([win] * 3, 50.0, None)
    assert noise is not None and note is not None and "no declared grade" in note
    assert np.all(noise["gyro"].random_walk == 1e-6)
