"""P2's predicted σ of the temperature models and its optimiser (docs/test-design.md, "P2")."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.errors import CalibrationError, ConfigurationError
from imucalib.models.noise import NoiseModel
from imucalib.models.result import triad_parameter_unit
from imucalib.plan.budget import estimate_plan_recording
from imucalib.procedures import registry
from imucalib.procedures.common.grade import grade_noise
from imucalib.procedures.common.noise import window_mean_se
from imucalib.procedures.common.prediction import OptimizeRequest, optimize_plan, predict_plan
from imucalib.procedures.common.reference import site_vectors
from imucalib.procedures.p2.optimize import (
    OptimizeSettingsP2,
    optimize_p2,
    parse_targets_p2,
    placement,
)
from imucalib.procedures.p2.options import P2PlanOptions
from imucalib.procedures.p2.plan import generate_p2_plan
from imucalib.procedures.p2.predict import (
    _point_fit,
    _rows,
    min_points,
    plan_points,
    predict_p2,
    predict_p2_detail,
)
from imucalib.procedures.p2.reduction import ORIENTATIONS, PARAM_NAMES, PointWindows, least_squares


def _white(grade: str = "tactical") -> dict[str, NoiseModel]:
    g = grade_noise(generate_p2_plan(grade=grade))
    return {k: NoiseModel(white_density=v.white_density) for k, v in g.items()}


def test_names_and_units_are_the_results_then_the_coefficients() -> None:
    plan = generate_p2_plan()
    pred = registry.get("p2").predict(plan)
    names = [p.name for p in pred.parameters]
    assert names[:36] == list(PARAM_NAMES)  # the result's parameters at T0 (c_0)
    assert all(p.unit == triad_parameter_unit(p.name) for p in pred.parameters[:36])
    # then c_1 … c_3 of each, and the largest σ over the range
    assert len(names) == 36 * 4 + 36
    assert "gyro_bias_x_c1" in names and "accel_K2_z_c3" in names
    assert "accel_M_xy_range" in names
    unit = {p.name: p.unit for p in pred.parameters}
    assert unit["gyro_bias_x_c1"] == "rad/s/K" and unit["accel_M_xx_c2"] == "1/K^2"
    assert pred.identifiable and all(p.predicted_std and p.predicted_std > 0
                                     for p in pred.parameters)
    # the run with ramps, approaches, soaks, re-soaks and settling (10.25 h)
    assert pred.station_time_s == pytest.approx(estimate_plan_recording(plan).duration_s)
    assert pred.to_dict()["parameters"][0]["name"] == "gyro_bias_x"


def test_the_point_estimator_is_the_analysis_least_squares() -> None:
    """Per point, the predicted covariance equals least_squares' on the same windows."""
    plan = generate_p2_plan(grade="tactical")
    noise = grade_noise(plan)
    g, earth = site_vectors(45.0, 0.0, None)
    point = next(p for p in plan_points(plan) if not p.held_out)
    groups = _rows(point)
    assert not isinstance(groups, str)
    fit = _point_fit(point, groups, noise, g, float(earth[2]))
    # the windows as the analysis would see them: nominal means, σ the Allan deviation
    se = {w: window_mean_se(noise, w.duration_s) for w in point.windows}
    rows: dict[str, list[np.ndarray]] = {k: [] for k in ("s", "sse", "pg", "pgse", "mg",
                                                         "mgse", "pa", "pase", "ma", "mase")}
    rates: dict[str, list[float]] = {"p": [], "m": []}
    for o in ORIENTATIONS:
        mine = [w for w in point.windows if w.pose == o]
        st = [w for w in mine if w.kind == "static"]
        rows["s"].append(np.zeros(3))
        rows["sse"].append(np.sqrt(sum(se[w][1] ** 2 for w in st)) / len(st))
        for sign, key in ((1, "p"), (-1, "m")):
            turn = [w for w in mine if w.kind == "rate" and np.sign(w.rate_rps) == sign]
            rows[key + "g"].append(np.zeros(3))
            rows[key + "a"].append(np.zeros(3))
            rows[key + "gse"].append(np.sqrt(sum(se[w][0] ** 2 for w in turn)) / len(turn))
            rows[key + "ase"].append(np.sqrt(sum(se[w][1] ** 2 for w in turn)) / len(turn))
            rates[key].append(float(np.mean([w.rate_rps for w in turn])))
    ups = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1.0]])
    pw = PointWindows(
        static_accel_mps2=g * ups, static_accel_se_mps2=np.array(rows["sse"]),
        plus_gyro_rps=ups * (np.array(rates["p"])[:, None] + earth[2]),
        plus_gyro_se_rps=np.array(rows["pgse"]),
        minus_gyro_rps=ups * (np.array(rates["m"])[:, None] + earth[2]),
        minus_gyro_se_rps=np.array(rows["mgse"]), plus_accel_mps2=g * ups,
        plus_accel_se_mps2=np.array(rows["pase"]), minus_accel_mps2=g * ups,
        minus_accel_se_mps2=np.array(rows["mase"]), plus_rate_rps=np.array(rates["p"]),
        minus_rate_rps=np.array(rates["m"]), gravity_mps2=g, earth_rate_up_rps=float(earth[2]))
    ls = least_squares(pw)
    np.testing.assert_allclose(fit.var, np.diag(ls.covariance)[:36], rtol=1e-6)


def test_four_times_the_dwell_halves_the_white_limited_sigma() -> None:
    noise = _white()
    short = predict_p2(generate_p2_plan(grade="tactical", static_s=10.0, revolutions=2),
                       noise=noise, temperature_std_degc=0.0)
    long = predict_p2(generate_p2_plan(grade="tactical", static_s=40.0, revolutions=8),
                      noise=noise, temperature_std_degc=0.0)
    ratio = np.array([b / a for a, b in zip(short.std().values(), long.std().values(),
                                             strict=True)])  # type: ignore[operator]
    np.testing.assert_allclose(ratio, 0.5, rtol=0.01)
    assert long.station_time_s > short.station_time_s


def test_coloured_noise_and_the_chamber_raise_the_sigma_above_what_calibrate_reports() -> None:
    plan = generate_p2_plan(grade="tactical")
    coloured = predict_p2_detail(plan)
    reported = predict_p2_detail(plan, covariance="analysis")
    ratio = np.sqrt(np.diag(coloured.covariance) / np.diag(reported.covariance))
    assert np.all(ratio >= 1.0 - 1e-9)
    # the biases rest on the flicker shared by windows minutes apart (TD.2)
    i = coloured.names.index("accel_bias_x")
    assert ratio[i] > 3.0
    no_band = predict_p2(plan, temperature_std_degc=0.0).std()
    assert no_band["gyro_G_xx"] < coloured.prediction.std()["gyro_G_xx"]  # (TD.P3)


def test_a_cubic_the_points_cannot_determine_is_confounded() -> None:
    assert min_points(3) == 6 and min_points(3, "fixed") == 4 and min_points(2, "cv", 1) == 5
    five = generate_p2_plan(temperatures_degc=(-40.0, -10.0, 20.0, 50.0, 85.0),
                            held_out_degc=(0.0,))
    pred = predict_p2(five)
    assert set(pred.confounded) == {f"{n}_c3" for n in PARAM_NAMES}
    std = pred.std()
    assert std["gyro_bias_x_c3"] is None and std["gyro_bias_x_c2"] is not None
    assert any("order 2" in n for n in pred.notes)
    three = predict_p2(generate_p2_plan(temperatures_degc=(-40.0, 20.0, 85.0)))
    assert {f"{n}_c{j}" for n in PARAM_NAMES for j in (1, 2, 3)} == set(three.confounded)
    assert three.std()["gyro_bias_x"] is not None  # order 0 still determined
    # a fixed order needs only q points
    assert predict_p2(five, criterion="fixed").identifiable


def test_a_hysteresis_sweep_predicts_the_leg_term() -> None:
    pred = predict_p2(generate_p2_plan(hysteresis=True, grade="tactical"))
    std = pred.std()
    assert std["accel_bias_x_leg"] is not None and std["accel_bias_x_leg"] > 0
    assert pred.identifiable


def test_placements() -> None:
    assert placement("equal", 6, -40.0, 85.0) == (-40.0, -15.0, 10.0, 35.0, 60.0, 85.0)
    cheb = placement("chebyshev", 5, -1.0, 1.0)
    np.testing.assert_allclose(cheb, [-1.0, -0.7, 0.0, 0.7, 1.0], atol=0.05)
    lob = placement("lobatto", 4, -1.0, 1.0)
    np.testing.assert_allclose(lob, [-1.0, -0.4, 0.4, 1.0], atol=0.05)  # ±1/√5
    with pytest.raises(ConfigurationError):
        placement("random", 4, 0.0, 1.0)


def test_the_optimiser_meets_the_default_sigma_in_less_time() -> None:
    settings = OptimizeSettingsP2.coarse(noise=_white("tactical"), temperature_std_degc=0.0,
                                         max_points=7)
    res = optimize_p2(P2PlanOptions(grade="tactical"), settings=settings)
    assert res.best.worst_ratio <= 1.0 + 1e-6
    assert res.best.station_time_s < res.reference.station_time_s  # coarse grid: 0.99
    assert len(res.best.design.temperatures_degc) == 6
    std = res.best.prediction.std()
    for name, target in res.targets.items():
        assert std[name] is not None and std[name] <= target * (1 + 1e-6)  # type: ignore[operator]


def test_unidentifiable_and_impossible_requests_are_refused_in_one_line() -> None:
    with pytest.raises(ConfigurationError) as exc:
        optimize_p2(settings=OptimizeSettingsP2(order=5, max_points=7))
    assert "order 5 needs at least 8" in str(exc.value) and "\n" not in str(exc.value)
    with pytest.raises(CalibrationError) as exc2:
        optimize_plan(registry.get("p2"), OptimizeRequest(targets="spec"))
    assert "\n" not in str(exc2.value)
    with pytest.raises(CalibrationError) as exc3:
        optimize_p2(P2PlanOptions(grade="tactical"), targets={"gyro_bias_x": 1e-12},
                    settings=OptimizeSettingsP2(max_points=6, spacings=("equal",),
                                                static_s_grid=(10.0, 30.0),
                                                revolutions_grid=(2,)))
    assert "best worst σ/target" in str(exc3.value) and "\n" not in str(exc3.value)


def test_targets_by_coefficient() -> None:
    names = predict_p2_detail(generate_p2_plan()).names
    t = parse_targets_p2("gyro_bias=1e-5,accel_M_xx_c1=2e-7", names)
    assert t == {"gyro_bias_x": 1e-5, "gyro_bias_y": 1e-5, "gyro_bias_z": 1e-5,
                 "accel_M_xx_c1": 2e-7}
    t1 = parse_targets_p2("gyro_bias_c1=1e-7", names)
    assert set(t1) == {"gyro_bias_x_c1", "gyro_bias_y_c1", "gyro_bias_z_c1"}
    with pytest.raises(ConfigurationError):
        parse_targets_p2("gyro_bias_q=1", names)


def test_cli_predict_json_and_optimize(tmp_path) -> None:
    runner = CliRunner()
    path = tmp_path / "p2.toml"
    r = runner.invoke(app, ["plan", "new", "p2", "--out", str(path), "--grade", "tactical"])
    assert r.exit_code == 0, r.output
    r = runner.invoke(app, ["plan", "show", str(path), "--predict", "--json"])
    assert r.exit_code == 0, r.output
    data = json.loads(r.output)
    assert set(data) >= {"station_time_s", "parameters", "confounded"}
    assert data["confounded"] == [] and data["procedure"] == "p2"
    assert data["parameters"][0] == {"name": "gyro_bias_x",
                                     "predicted_std": pytest.approx(data["parameters"][0][
                                         "predicted_std"]), "unit": "rad/s"}
    assert predict_plan(registry.get("p2"), generate_p2_plan()).procedure == "p2"
    few = tmp_path / "few.toml"
    assert runner.invoke(app, ["plan", "new", "p2", "--out", str(few),
                               "--temperatures=-40,20,85"]).exit_code == 0
    r = runner.invoke(app, ["plan", "show", str(few), "--predict", "--json"])
    assert r.exit_code == 2 and "cannot identify gyro_bias_x_c1" in r.output
    r = runner.invoke(app, ["plan", "optimize", "p2", "--out", str(tmp_path / "o.toml"),
                            "--target-from-spec"])
    assert r.exit_code == 2 and "not available for P2" in r.output
