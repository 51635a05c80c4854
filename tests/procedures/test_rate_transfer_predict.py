"""The rate transfer's predicted σ and D-optimal rate set (docs/rate-transfer.md, TD.R1–R4)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from imucalib.procedures import registry
from imucalib.procedures.common.prediction import predict_plan
from imucalib.procedures.rate_transfer.design import (
    basis,
    compare_rate_designs,
    d_efficiency,
    information_matrix,
    lobatto_points,
    optimal_design,
)
from imucalib.procedures.rate_transfer.plan import generate_rate_transfer_plan
from imucalib.procedures.rate_transfer.predict import parameter_names, predict_rate_transfer

from ._rate_twin import run, with_unit


def _log_det(model: str, u: np.ndarray, w: np.ndarray) -> float:
    sign, value = np.linalg.slogdet(information_matrix(model, u, w))
    return value if sign > 0 else -np.inf


@pytest.mark.parametrize("order", [1, 2, 3])
def test_lobatto_design_is_d_optimal(order: int) -> None:
    model = f"poly{order}"
    pts = lobatto_points(order)
    assert d_efficiency(model, pts) == pytest.approx(1.0, abs=1e-12)
    rng = np.random.default_rng(order)
    for _ in range(20):  # any other design is worse
        u = rng.uniform(-1.0, 1.0, 8)
        assert d_efficiency(model, u, rng.uniform(0.1, 1.0, 8)) < 1.0


@pytest.mark.parametrize("order", [1, 2])
def test_lobatto_matches_an_independent_grid_search(order: int) -> None:
    """Exhaustive search over symmetric designs on a grid (not the multiplicative algorithm)."""
    model = f"poly{order}"
    grid = np.linspace(0.0, 1.0, 41)
    best = -np.inf
    for a in grid:  # support {±a, ±1} (order 1) or {0, ±a, ±1} with weights
        for w0 in np.linspace(0.0, 0.9, 46) if order == 2 else (0.0,):
            u = np.array([0.0, -a, a, -1.0, 1.0])
            for wa in np.linspace(0.0, 1.0 - w0, 21):
                w = np.array([w0, wa / 2, wa / 2, (1 - w0 - wa) / 2, (1 - w0 - wa) / 2])
                best = max(best, _log_det(model, u, w))
    m = order + 1
    star = _log_det(model, lobatto_points(order), np.full(m, 1.0 / m))
    assert star >= best - 1e-9
    assert np.exp((best - star) / m) > 0.999  # the grid reaches it


def test_issue_figures_for_11_equally_spaced_rates() -> None:
    """The issue's 0.63 (linear) and 0.77 (cubic): exponent 1/m, m = number of parameters."""
    u = np.linspace(-1.0, 1.0, 11)
    assert d_efficiency("poly1", u) == pytest.approx(np.sqrt(0.4), abs=1e-12)  # 0.632
    assert d_efficiency("poly2", u) == pytest.approx(0.6959, abs=1e-4)
    assert d_efficiency("poly3", u) == pytest.approx(0.7694, abs=1e-4)


def test_transfer_model_optimum_satisfies_the_equivalence_theorem() -> None:
    u, w = optimal_design("transfer")
    assert np.allclose(u, -u[::-1], atol=1e-9)
    f = basis("transfer", np.linspace(-1.0, 1.0, 2001))
    d = np.einsum("ij,jk,ik->i", f, np.linalg.inv(information_matrix("transfer", u, w)), f)
    assert np.max(d) == pytest.approx(4.0, rel=2e-3)  # Kiefer–Wolfowitz: max d = m


def test_optimised_rates_reach_the_default_generalized_variance_sooner() -> None:
    plan = generate_rate_transfer_plan(axes=("x",))
    for model in ("poly1", "poly3", "transfer"):
        c = compare_rate_designs(plan, model)
        assert c.efficiency_plan_dwell < c.efficiency_equal_dwell < 1.0
        assert c.optimal_station_s < c.default_station_s
        assert min(c.optimal_revolutions) >= 2


def test_prediction_names_match_the_result() -> None:
    plan = generate_rate_transfer_plan()
    prediction = predict_plan(registry.get("rate-transfer"), plan)
    assert prediction.identifiable
    names = [p.name for p in prediction.parameters]
    assert names == [n for k in "xyz" for n, _ in parameter_names(k)]
    assert all(p.predicted_std is not None and p.predicted_std > 0 for p in prediction.parameters)
    assert prediction.to_dict()["procedure"] == "rate-transfer"


def test_too_few_rates_name_the_confounded_parameters() -> None:
    two = predict_rate_transfer(generate_rate_transfer_plan(rates_dps=(10.0, 20.0),
                                                            axes=("z",)))
    assert two.confounded == ("gyro_bias_up_z", "gyro_asymmetry_z", "gyro_E2_z")
    assert two.std()["gyro_M_zz"] == two.std()["gyro_scale_factor_z"]
    plan = generate_rate_transfer_plan(rates_dps=(10.0,), axes=("x",))
    one_sign = plan.model_copy(update={"steps": tuple(
        s for s in plan.steps if getattr(s, "rate_dps", 1.0) > 0)})
    p = predict_rate_transfer(one_sign)
    assert "gyro_scale_factor_x" in p.confounded and not p.identifiable


def test_predicted_sigma_matches_calibrate_on_the_twin(tmp_path: Path) -> None:
    plan = with_unit(generate_rate_transfer_plan(rates_dps=(20.0, 45.0, 90.0),
                                                 sample_rate_hz=50.0, seed=4), seed=4)
    predicted = predict_rate_transfer(plan).std()
    result = registry.get("rate-transfer").analyze(run(plan, tmp_path / "rt.h5"))
    ratios = {r.name: r.std_noise / (predicted[r.name] or np.nan)
              for r in result.parameter_rows() if not r.name.startswith("gyro_nonlinearity")}
    assert all(0.85 < v < 1.15 for v in ratios.values()), ratios
