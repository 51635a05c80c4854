"""A P1 plan that names the unit's noise characterisation: its ``[imu.noise]`` on the twin.

docs/test-design.md, "A noise characterisation in place of the grade's"; docs/p1.md, "Noise
model of the window means". A tactical plan whose unit is in fact consumer-noisy (2.4–8× the
grade's noise) runs a 130-s static, too short for the flicker floor, so the analysis takes the
declared flicker and random walk (Type B). Declared by the grade, the biases' σ are 2–7× too
small; declared by a characterisation of the unit (an Allan fit of 22 min of the unit's own noise
model), they are the σ predicted with the unit's true noise — the Cramér–Rao bound that
bench/p1_prediction_montecarlo.py checks against the Monte-Carlo spread — and the estimates lie
within 4σ of the twin's truth.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import pytest

from imucalib.io import open_recording
from imucalib.models import ImuModel
from imucalib.models.imu import sample_imu_model
from imucalib.models.noise_generator import simulate_noise
from imucalib.plan import Plan
from imucalib.procedures import registry
from imucalib.procedures.allan.analysis import analyze_allan_arrays
from imucalib.procedures.common.grade import characterization_noise, declared_noise
from imucalib.procedures.p1.plan import generate_p1_plan
from imucalib.procedures.p1.predict import predict_p1

RATE_HZ = 100.0
BIASES = [f"{t}_bias_{a}" for t in ("accel", "gyro") for a in "xyz"]
#: A short P1 plan at 200 Hz whose 130-s static cannot show the flicker floor (τ_max 41 s).
SHORT = dict(grade="tactical", seed=4, repetitions=1, static_s=130.0, warm_up_s=10.0,
             sample_rate_hz=200.0, revolutions=2, settle_s=5.0, rate_settle_s=3.0,
             record_s=10.0)


def _consumer_unit(plan: Plan) -> Plan:
    """The plan with its twin's unit consumer grade (noisier than the tactical plan says)."""
    tw = plan.twin
    assert tw is not None
    tw = tw.model_copy(update={
        "table": tw.table.model_copy(update={"grade": "ideal"}),
        "imus": tuple(i.model_copy(update={"nonlinear": False, "grade": "consumer"})
                      for i in tw.imus)})
    return plan.model_copy(update={"twin": tw})


@pytest.fixture(scope="module")
def unit_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The noise JSON of `imucalib allan` from 22 min at 100 Hz of the consumer unit's noise."""
    noise = sample_imu_model("consumer", 0, nonlinear=False)
    n = 1 << 17
    gyro = simulate_noise(noise.gyro_noise, n, 1 / RATE_HZ, rng=21)
    accel = simulate_noise(noise.accel_noise, n, 1 / RATE_HZ, rng=22) + np.array([0, 0, 9.81])
    cols = {f"{s}_{a}_{u}": (gyro if s == "gyro" else accel)[:, i]
            for s, u in (("gyro", "rps"), ("accel", "mps2")) for i, a in enumerate("xyz")}
    result = analyze_allan_arrays(np.arange(n) / RATE_HZ, cols, source="unit.csv")
    return result.save(tmp_path_factory.mktemp("unit") / "unit.noise.json")


@pytest.fixture(scope="module")
def runs(unit_file, tmp_path_factory, p1_tools):
    """Two twin runs of one seed (the same samples) declaring the grade's and the unit's noise."""
    folder = tmp_path_factory.mktemp("declared")
    out = {}
    for label, extra in (("grade", {}), ("unit", {"noise_characterization": str(unit_file)})):
        plan = _consumer_unit(generate_p1_plan(**SHORT, **extra))
        path = p1_tools.run_twin(plan, folder / f"{label}.h5")
        analysis = registry.get("p1").analyze(path)
        with open_recording(path) as rec:
            truth = ImuModel.from_dict(rec.truth["imu_models"][analysis.result.sensor_id])
        out[label] = (plan, analysis, truth)
    return out


def test_the_plan_carries_the_characterisation_and_declares_it(unit_file):
    plan = generate_p1_plan(**SHORT, noise_characterization=str(unit_file))
    cfg = plan.imu.noise
    digest = hashlib.sha256(unit_file.read_bytes()).hexdigest()
    assert cfg is not None and cfg.source == "unit.noise.json" and cfg.source_sha256 == digest
    models, source = declared_noise(plan)
    assert source == f"characterisation unit.noise.json (sha256 {digest[:12]}…)"
    fitted, _ = characterization_noise(unit_file)
    for triad in ("gyro", "accel"):
        for term in ("white_density", "bias_instability", "random_walk"):
            np.testing.assert_array_equal(getattr(models[triad], term),
                                          getattr(fitted[triad], term))
    # without it the grade's, as before
    assert declared_noise(generate_p1_plan(**SHORT))[1] == "grade tactical"


def test_the_prediction_names_the_declared_noise(unit_file):
    plan = generate_p1_plan(**SHORT, noise_characterization=str(unit_file))
    prediction = predict_p1(plan)
    assert prediction.notes[0].startswith("noise model (characterisation unit.noise.json (sha256 ")
    same = predict_p1(plan, noise=characterization_noise(unit_file)[0])
    assert prediction.std() == same.std()
    assert predict_p1(generate_p1_plan(**SHORT)).notes[0].startswith("noise model (grade "
                                                                    "tactical)")


def test_the_declared_floor_takes_the_characterisation(runs, unit_file):
    declared, _ = characterization_noise(unit_file)
    digest = hashlib.sha256(unit_file.read_bytes()).hexdigest()
    _, unit, _ = runs["unit"]
    _, grade, _ = runs["grade"]
    for triad in ("accel", "gyro"):  # every axis floored: 41 s < 8 corners (11–18 s)
        noise = unit.observations.noise[triad]
        np.testing.assert_array_equal(noise.bias_instability, declared[triad].bias_instability)
        np.testing.assert_array_equal(noise.random_walk, declared[triad].random_walk)
    floor = [n for n in unit.result.notes if "flicker floor is not determined" in n]
    assert len(floor) == 1
    assert f"characterisation unit.noise.json (sha256 {digest[:12]}…) bias instability" in floor[0]
    assert any("flicker floor is not determined" in n and "grade tactical" in n
               for n in grade.result.notes)


def test_the_biases_sigma_are_the_units_not_the_grades(runs):
    """σ of the six biases against the bound with the unit's true noise (the MC spread)."""
    plan, unit, truth = runs["unit"]
    _, grade, _ = runs["grade"]
    true_noise = declared_noise(_consumer_unit(generate_p1_plan(**{**SHORT,
                                                                   "grade": "consumer"})))[0]
    bound = predict_p1(plan, noise=true_noise).std()
    s_unit, s_grade = unit.result.std(), grade.result.std()
    values = dict(zip(unit.result.param_names, unit.result.values, strict=True))
    grade_values = dict(zip(grade.result.param_names, grade.result.values, strict=True))
    true = {f"{t}_bias_{a}": float(getattr(truth, t).bias[i])
            for t in ("accel", "gyro") for i, a in enumerate("xyz")}
    z_unit = np.array([(values[n] - true[n]) / s_unit[n] for n in BIASES])
    z_grade = np.array([(grade_values[n] - true[n]) / s_grade[n] for n in BIASES])
    for a, b in zip(unit.observations.windows, grade.observations.windows, strict=True):
        np.testing.assert_array_equal(a.accel_mean_mps2, b.accel_mean_mps2)  # the same samples
        np.testing.assert_array_equal(a.gyro_mean_rps, b.gyro_mean_rps)
    for n in BIASES:
        assert 0.8 < s_unit[n] / bound[n] < 1.6, (n, s_unit[n] / bound[n])
        assert s_grade[n] / bound[n] < 0.6, (n, s_grade[n] / bound[n])
    assert np.all(np.abs(z_unit) < 4.0), z_unit
    # under the grade's declared noise the same errors are many of its σ: it under-reports
    assert np.sqrt(np.mean(z_grade**2)) > 3.0 > np.sqrt(np.mean(z_unit**2)), (z_grade, z_unit)


def test_a_coefficient_out_of_the_plans_bounds_is_one_line(unit_file, tmp_path):
    """A fit that gives a gyro white density of 5000 rad/√s is refused naming the field."""
    import json

    from imucalib.errors import InvalidInputError
    from imucalib.procedures.common.grade import characterization_config

    data = json.loads(unit_file.read_text(encoding="utf-8"))
    seg = max(data["segments"], key=lambda s: s["t_end_s"] - s["t_start_s"])
    channel = next(c for c in seg["channels"] if c["channel"].startswith("gyro_y"))
    term = next(t for t in channel["fit"]["terms"] if t["name"] == "white")
    term["value_si"], term["detected"] = 5000.0, True
    bad = tmp_path / "huge.noise.json"
    bad.write_text(json.dumps(data), encoding="utf-8")
    with pytest.raises(InvalidInputError, match=r"^noise characterisation huge\.noise\.json: "
                                                r"gyro_white_rps_rthz\.1 .*; got 5000\.0$"):
        characterization_config(bad)
