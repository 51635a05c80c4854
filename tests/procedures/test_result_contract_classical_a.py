"""The tumble, rate-transfer, installation and P3 results satisfy the result contract.

Small synthetic results (docs/procedures.md, "The result contract"): each is a
:class:`~imucalib.models.procedure_result.ProcedureResult`; its rows are ReportedParameter with
σ ≥ σ before Birge scaling ≥ 0, the ratio the fit's Birge factor where a fit is a misfit and 1
where none is; its decision is the one ``passed`` says (*no decision* for the three without
acceptance limits, P3's U(K2) against its target); its version-4 document is strict JSON, valid
against the schema, with the triad parameters' names and reported variances. The rate
transfer's nonlinearity σ (RT-6a) against a Monte Carlo of the means (docs/rate-transfer.md).
"""

from __future__ import annotations

import dataclasses
import json
import math
from typing import Any

import jsonschema
import numpy as np
import pytest

from imucalib.models.decision import Decision
from imucalib.models.fit_quality import assess_fit
from imucalib.models.procedure_result import ProcedureResult
from imucalib.models.reported import ReportedParameter
from imucalib.models.result_document import result_document, result_schema
from imucalib.procedures.common.rate_windows import RateWindow
from imucalib.procedures.installation.analysis import InstallationResult
from imucalib.procedures.installation.misalignment import (
    closed_form_misalignment,
    lsq_misalignment,
)
from imucalib.procedures.p3.analysis import K2_CHECK, AccelerometerScale, P3Result
from imucalib.procedures.p3.roundrobin import (
    SERIES_NAMES,
    fit_series,
    scale_for_misfit,
    solve_round_robin,
)
from imucalib.procedures.rate_transfer.analysis import RateTransferResult, transfer_of_axis
from imucalib.procedures.rate_transfer.fit import fit_line
from imucalib.procedures.tumble.analysis import (
    AccelerometerTumble,
    TumbleResult,
    _combination_quality,
)
from imucalib.procedures.tumble.fourier import (
    fit_fourier,
    invert_coefficients,
    resolvable_coefficients,
)

G = 9.80665
UG = 1e-6 * G
REL = 1e-12  # rounding of σ / sigma_scale · sigma_scale


def check_contract(result: Any, aliases: dict[str, str] | None = None
                   ) -> dict[str, ReportedParameter]:
    """The members every result of one unit has; returns its rows by name.

    `aliases`: the row of a triad parameter reported under another name (P3's K2_T).
    """
    assert isinstance(result, ProcedureResult)
    assert isinstance(result.decision, Decision) and result.decision.passed is result.passed
    assert result.calibration is None and result.members == () and result.error == ""
    assert all(isinstance(n, str) for n in result.notes)
    rows = result.parameter_rows()
    assert rows and all(isinstance(r, ReportedParameter) for r in rows)
    for r in rows:
        assert 0.0 <= r.std_noise <= r.std * (1 + REL), r
    doc = result_document(result)
    text = json.dumps(doc, allow_nan=False)
    jsonschema.Draft202012Validator(result_schema()).validate(json.loads(text))
    names, values, cov = result.triad_parameters()
    assert doc["covariance"]["names"] == list(names) and len(names) > 0
    by_name = {r.name: r for r in rows}
    # the covariance is the one reported: its variances are the rows' σ²
    for k, n in enumerate(names):
        row = by_name[(aliases or {}).get(n, n)]
        assert row.value == values[k]
        assert math.sqrt(cov[k, k]) == pytest.approx(row.std, rel=REL), n
    return by_name


# --- tumble ---------------------------------------------------------------------------------

TUMBLE = {"K0": 3e-4, "K1": 1.00012, "delta": 2.5e-5, "K2": 1.5e-6, "Kip": 0.0, "K3": 4e-8,
          "Koq": 2e-6}


def _tumbled(sensor: str, head: str, pendulous: str, rng: np.random.Generator,
             noise: float = 1.0) -> AccelerometerTumble:
    """12 positions of (T.1), means scattering `noise` times their stated 10 µg."""
    n = 12
    th = 2 * np.pi * np.arange(n) / n
    c = TUMBLE
    ai, ap = G * np.cos(th), G * np.sin(th)
    y = c["K1"] * (c["K0"] + ai + c["delta"] * ap + c["K2"] * ai**2 + c["K3"] * ai**3
                   + c["Koq"] * ai * np.abs(ai))
    sd = np.full(n, 10 * UG)
    fourier = fit_fourier(th, y + rng.normal(0.0, noise * sd), sd, n // 2, n_positions=n)
    fit = invert_coefficients(fourier, G, resolvable_coefficients(n), n_positions=n,
                              group=f"accel {sensor} (head {head})")
    return AccelerometerTumble(sensor=sensor, head_axis=head, pendulous_axis=pendulous, fit=fit)


def _tumble(accels: tuple[AccelerometerTumble, ...], gravity_rel_std: float = 2e-5
            ) -> TumbleResult:
    return TumbleResult(unit="U1", gravity_mps2=G, gravity_rel_std=gravity_rel_std,
                        accelerometers=accels, method="lsq", windows=(),
                        triad_fit=_combination_quality(accels))


def _three(rng: np.random.Generator, noise_x_head_z: float = 1.0
           ) -> tuple[AccelerometerTumble, ...]:
    """x about head axes z and y (combined in the triad), y about z."""
    return (_tumbled("x", "z", "y", rng, noise_x_head_z), _tumbled("y", "z", "x", rng),
            _tumbled("x", "y", "z", rng))


def test_a_tumble_without_misfit_reports_equal_sigmas_and_no_decision() -> None:
    result = _tumble(_three(np.random.default_rng(1)))
    assert not any(q.misfit for q in result.fit_quality)
    rows = check_contract(result)
    assert all(r.std == r.std_noise for r in rows.values())  # bit-identical: nothing scaled
    assert result.passed is None and result.decision.verdict == "NO DECISION"
    assert "no acceptance limits" in result.decision.rule
    assert {"accel_bias_x", "accel_M_xy", "accel_M_xz", "accel_K2_y"} <= set(rows)
    assert result.to_dict()["decision"]["passed"] is None


def test_a_tumble_misfit_scales_its_own_rows_and_the_triad_through_the_combination() -> None:
    result = _tumble(_three(np.random.default_rng(2), noise_x_head_z=6.0))
    bad = result.get("x", "z")
    s = bad.fit.quality.sigma_scale
    assert bad.fit.quality.misfit and s > 2.0
    rows = check_contract(result)
    for name in bad.fit.names:
        r = rows[f"{name}_{bad.key}"]
        if name == "K1":  # the gravity's Type B σ is in both, unscaled
            continue
        assert r.std == pytest.approx(r.std_noise * s, rel=REL), name
    k1, gk = rows[f"K1_{bad.key}"], bad.fit.value("K1") * result.gravity_rel_std
    assert k1.std**2 - gk**2 == pytest.approx((k1.std_noise**2 - gk**2) * s**2, rel=1e-9)
    # the combined bias of x holds the misfit part (scaled; weighted little: 1/s² of the
    # other), y's holds none
    assert rows["accel_bias_x"].std > 1.001 * rows["accel_bias_x"].std_noise
    t = result.triad_fit.sigma_scale if result.triad_fit is not None else 1.0
    assert rows["accel_bias_y"].std == pytest.approx(rows["accel_bias_y"].std_noise * t,
                                                     rel=1e-9)
    assert "accel" in " ".join(result.decision.notes)  # the misfit said with the decision


def test_a_tumble_whose_every_fit_is_scaled_alike_has_std_noise_the_std_over_the_factors() -> None:
    """Every part's covariance × s²: the GLS weights unchanged, σ_noise = σ / (s·s_triad)."""
    s = 3.0

    def misfit(a: AccelerometerTumble) -> AccelerometerTumble:
        q = a.fit.quality
        fit = dataclasses.replace(a.fit, quality=assess_fit(q.group, s**2 * q.dof, q.dof),
                                  covariance=a.fit.covariance_noise * s**2)
        return dataclasses.replace(a, fit=fit)

    accels = tuple(misfit(a) for a in _three(np.random.default_rng(3)))
    assert all(a.fit.quality.sigma_scale == pytest.approx(s) for a in accels)
    result = _tumble(accels, gravity_rel_std=0.0)
    rows = check_contract(result)
    t = result.triad_fit.sigma_scale if result.triad_fit is not None else 1.0
    names, _, _ = result.triad_parameters()
    for n in names:
        assert rows[n].std == pytest.approx(rows[n].std_noise * s * t, rel=1e-9), n


# --- rate transfer --------------------------------------------------------------------------

EARTH_UP = 7.292115e-5 * math.sin(math.radians(45.0))


def _turns(rng: np.random.Generator, axis: str, rates_dps: tuple[float, ...], *,
           k2: float = 4e-4, asym: float = 1e-4, k3: float = 0.0, se: float = 2e-5,
           noise: float = 1.0, m: np.ndarray | None = None) -> list[RateWindow]:
    """± turns about `axis` of a gyro triad with E′ = 1.0003, a quadratic and an asymmetry."""
    k = "xyz".index(axis)
    mm = np.diag([3e-4, -2e-4, 1e-4]) if m is None else m
    out = []
    for j, r in enumerate(rates_dps):
        x = math.radians(r) + EARTH_UP
        u = (np.eye(3) + mm)[:, k] * x
        y = 1e-4 + u + k2 * u**2 + k3 * u**3 + asym / 2 * np.abs(u)
        out.append(RateWindow(step_index=j, label=f"{axis}{r:+g}", axis=axis,
                              commanded_rate_dps=r, table_rate_rps=math.radians(r),
                              n_revolutions=2, gyro_mean_rps=y + rng.normal(0, noise * se, 3),
                              gyro_se_rps=np.full(3, se), duration_s=20.0,
                              block_variance=(10, np.zeros(3))))
    return out


def _rate_transfer(rng: np.random.Generator, **kwargs: Any) -> RateTransferResult:
    both = (20.0, -20.0, 45.0, -45.0, 90.0, -90.0)
    windows = [*_turns(rng, "x", both, **kwargs), *_turns(rng, "y", both, **kwargs),
               *_turns(rng, "z", (20.0, 45.0, 90.0), **kwargs)]  # z: one sign, no second fit
    axes = tuple(transfer_of_axis(a, windows, EARTH_UP) for a in "xyz")
    return RateTransferResult(unit="U1", axes=axes, earth_rate_up_rps=EARTH_UP,
                              n_turns=len(windows))


def test_a_rate_transfer_reports_each_fits_scaling_and_the_nonlinearity_sigma() -> None:
    result = _rate_transfer(np.random.default_rng(4))
    rows = check_contract(result)
    assert result.passed is None and "no acceptance limits" in result.decision.rule
    for a in result.axes:
        k, line = a.axis, a.line
        assert line.quality.misfit  # the line misfits: the quadratic term is the nonlinearity
        s = line.quality.sigma_scale
        for name in (f"gyro_scale_factor_{k}", f"gyro_bias_line_{k}"):
            assert rows[name].std == pytest.approx(rows[name].std_noise * s, rel=REL)
        nl = rows[f"gyro_nonlinearity_{k}"]
        assert nl.value == line.nonlinearity_ppm * 1e-6 and nl.std_noise > 0
        if a.transfer is None:  # gyro_M_kk from the line, like the triad parameters
            assert k == "z" and rows[f"gyro_M_{k}{k}"].std == rows[f"gyro_scale_factor_{k}"].std
            assert nl.std == pytest.approx(nl.std_noise * s, rel=REL)
        else:  # the second fit models the shape: no misfit, nothing scaled
            assert not a.transfer.quality.misfit
            assert nl.std == nl.std_noise and rows[f"gyro_E2_{k}"].std == rows[
                f"gyro_E2_{k}"].std_noise
    assert result.triad_parameters()[0] == ["gyro_M_xx", "gyro_M_yy", "gyro_M_zz"]


def test_a_rate_transfer_whose_second_fit_misfits_scales_its_rows_and_the_nonlinearity() -> None:
    result = _rate_transfer(np.random.default_rng(5), k3=2e-4)
    rows = check_contract(result)
    a = result.axis("x")
    assert a.transfer is not None and a.transfer.quality.misfit
    s = a.transfer.quality.sigma_scale
    for name in ("gyro_M_xx", "gyro_bias_up_x", "gyro_asymmetry_x", "gyro_E2_x",
                 "gyro_nonlinearity_x"):
        assert rows[name].std == pytest.approx(rows[name].std_noise * s, rel=REL), name
    assert result.decision.notes  # the misfits said with the (no) decision


X_RATES = np.radians([20.0, -20.0, 45.0, -45.0, 90.0, -90.0]) + 5e-5
NL_SE = np.full(6, 2e-5)


@pytest.mark.parametrize(("case", "k2", "k3", "asym", "low", "high"), [
    # one deviation stands out (+90 °/s: an even and an odd term): σ is the spread
    ("dominant", 4e-4, 2e-4, 0.0, 0.9, 1.1),
    # ±90 °/s tie (an even nonlinearity): their maximum scatters a little less
    ("tie", 4e-4, 0.0, 1e-4, 0.8, 1.05),
    # no nonlinearity: the largest of the noise, σ an upper bound
    ("none", 0.0, 0.0, 0.0, 0.4, 1.0),
])
def test_the_nonlinearity_sigma_against_a_monte_carlo(case: str, k2: float, k3: float,
                                                      asym: float, low: float, high: float
                                                      ) -> None:
    """The spread of the nonlinearity over 2000 draws of the means / its mean σ (RT-6a).

    Measured: 1.03 (dominant), 0.92 (tie), 0.61 (none).
    """
    x = X_RATES
    y0 = 1e-4 + 1.0003 * x + k2 * x**2 + k3 * x**3 + asym / 2 * np.abs(x)
    rng = np.random.default_rng(6)
    fits = [fit_line(x, y0 + rng.normal(0.0, NL_SE), NL_SE) for _ in range(2000)]
    spread = float(np.std([f.nonlinearity_ppm for f in fits]))
    ratio = spread / float(np.mean([f.nonlinearity_noise_std_ppm for f in fits]))
    assert low < ratio < high, (case, ratio)


# --- installation ---------------------------------------------------------------------------

def _installation(rng: np.random.Generator, noise: float = 1.0) -> InstallationResult:
    m = np.array([[3e-4, 2e-4, -1e-4], [-3e-4, -2e-4, 4e-4], [1e-4, 5e-4, 1e-4]])
    windows = [w for a in "xyz" for w in _turns(rng, a, (30.0, -30.0, 60.0, -60.0), k2=0.0,
                                                asym=0.0, se=1e-5, noise=noise, m=m)]
    return InstallationResult(unit="U1", closed_form=closed_form_misalignment(windows, EARTH_UP),
                              lsq=lsq_misalignment(windows, EARTH_UP), earth_rate_up_rps=EARTH_UP,
                              n_turns=len(windows))


@pytest.mark.parametrize("noise", [1.0, 5.0])
def test_an_installation_result_scales_the_least_squares_rows_only(noise: float) -> None:
    result = _installation(np.random.default_rng(7), noise)
    rows = check_contract(result)
    q = result.lsq.quality
    assert q is not None and q.misfit is (noise > 1.0)
    assert result.passed is None and "no acceptance limits" in result.decision.rule
    for name, r in rows.items():
        if name.endswith("_closed"):
            assert r.std == r.std_noise
        else:
            assert r.std == pytest.approx(r.std_noise * q.sigma_scale, rel=REL)
            assert (r.std == r.std_noise) is (not q.misfit)
    assert len(result.triad_parameters()[0]) == 6


# --- P3 -------------------------------------------------------------------------------------

R_T, R_R = 1.0, 1.0 / 3
RATES = np.sqrt(np.linspace(4.0, 20.0, 5) * G / R_T)
P3_TRUTH = {"K2_A": 30e-6 / G, "K2_B": -20e-6 / G, "K2_T": 50e-6 / G, "c": 1.5e-8,
            "c_loaded": 10e-6 / RATES[-1] ** 2}
LAYOUT = {"A1": ("K2_A", R_R, +1, "c"), "B1": ("K2_B", R_R, -1, "c"),
          "A2": ("K2_A", R_R, -1, "c"), "B2": ("K2_B", R_R, +1, "c"),
          "A3": ("K2_A", R_R, +1, "c_loaded"), "B3": ("K2_B", R_R, -1, "c_loaded"),
          "T3": ("K2_T", R_T, +1, "c_loaded")}
K1 = 1.3e-3
#: P3's triad parameter is the test accelerometer's K2 (its input axis x)
P3_ALIAS = {"accel_K2_x": "K2_T"}


def _p3(rng: np.random.Generator, *, noise: float = 1.0, target: float = 1e-7,
        shift_a2: float = 0.0) -> P3Result:
    """The seven series (2 µg means scattering `noise` times that), A2's m shifted by
    `shift_a2` of its σ (the seven equations inconsistent)."""
    w = np.concatenate([[0.0, 0.0], RATES])
    series = {}
    for name, (k2, r, side, c) in LAYOUT.items():
        a = w**2 * (r + side * P3_TRUTH[c] * w**2)
        sd = np.full(w.size, K1 * 2 * UG)
        y = 2e-4 * K1 + K1 * (a + P3_TRUTH[k2] * a**2) + rng.normal(0.0, noise * sd)
        series[name] = fit_series(w, y, sd, k1=K1, k1_std=K1 * 2e-5, name=name)
    if shift_a2:
        a2 = series["A2"]
        series["A2"] = dataclasses.replace(a2, m=a2.m + shift_a2 * a2.m_std)
    scaled, pooled = scale_for_misfit(series)
    roles = {"ref-a": "A", "ref-b": "B", "test": "T"}
    scales = {u: AccelerometerScale(u, K1, K1 * 2e-5, 2e-4 * K1, 1e-9, "input")
              for u in roles.values()}
    return P3Result(unit="T", roles=roles, estimate=solve_round_robin(scaled), series=scaled,
                    scales=scales, windows=(), k2_target_g_per_g2=target, series_fit=pooled)


def test_p3_passes_on_white_means_with_equal_sigmas() -> None:
    result = _p3(np.random.default_rng(8))
    rows = check_contract(result, P3_ALIAS)
    assert not result.estimate.quality.misfit
    assert all(s.sigma_scale == 1.0 for s in result.series.values())
    assert all(r.std == r.std_noise for r in rows.values())  # bit-identical: nothing scaled
    d = result.decision
    assert d.passed is True and d.verdict == "PASS" and d.failed == ()
    (check,) = d.checks
    assert check.name == K2_CHECK and check.rows[0].value == 2 * result.k2_test_g_per_g2[1]
    assert check.rows[0].limit == 1e-7
    assert result.triad_parameters()[0] == ["accel_K2_x"]


def test_p3_fails_on_a_tight_target_and_scales_sigma_of_noisy_series() -> None:
    result = _p3(np.random.default_rng(9), noise=2.0, target=1e-9)
    rows = check_contract(result, P3_ALIAS)
    assert result.series_fit is not None and result.series_fit.misfit
    assert all(s.sigma_scale > 1.0 for s in result.series.values())
    assert rows["K2_T"].std > 1.2 * rows["K2_T"].std_noise
    assert rows["K2_T_naive"].std > 1.2 * rows["K2_T_naive"].std_noise
    assert rows["K1_test"].std == rows["K1_test"].std_noise
    d = result.decision
    assert d.passed is False and result.passed is False and d.failed == (K2_CHECK,)
    assert 2 * result.k2_test_g_per_g2[1] > result.k2_target_g_per_g2
    assert d.notes  # the misfit said with the decision


def test_p3_round_robin_misfit_scales_by_its_birge_factor() -> None:
    result = _p3(np.random.default_rng(10), shift_a2=8.0)
    q = result.estimate.quality
    assert q.misfit and all(s.sigma_scale == 1.0 for s in result.series.values())
    rows = check_contract(result, P3_ALIAS)
    for name in ("K2_A", "K2_B", "c", "c_loaded", "K2_T"):
        assert rows[name].std == pytest.approx(rows[name].std_noise * q.sigma_scale, rel=REL)
    assert rows["K2_T_naive"].std == rows["K2_T_naive"].std_noise
    assert set(SERIES_NAMES) == set(result.series)
