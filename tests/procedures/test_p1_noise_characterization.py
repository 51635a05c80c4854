"""A unit's noise characterisation in place of the grade's noise, in P1's prediction and optimiser.

docs/test-design.md, "A noise characterisation in place of the grade's": the noise JSON that
``imucalib allan`` writes is read as the unit's noise model
(:func:`~imucalib.procedures.common.grade.characterization_noise`), and the optimiser predicts
the default plan and every candidate with it (``OptimizeRequest.noise_characterization``).
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest

from imucalib import units
from imucalib.errors import InvalidInputError
from imucalib.models.noise import NoiseModel
from imucalib.models.noise_generator import simulate_noise
from imucalib.procedures import NoiseCharacterization
from imucalib.procedures.allan.analysis import analyze_allan_arrays
from imucalib.procedures.common.grade import characterization_noise, grade_noise
from imucalib.procedures.common.prediction import OptimizeRequest
from imucalib.procedures.p1.optimize import optimize_request
from imucalib.procedures.p1.plan import generate_p1_plan
from imucalib.procedures.p1.predict import predict_p1

RATE_HZ = 100.0
#: A unit twice as noisy as a tactical one in white noise and flicker, with a rate random walk.
GYRO = NoiseModel(white_density=0.25 * units.DEG_PER_RTH, bias_instability=2 * units.DEG_PER_H,
                  random_walk=[2e-7, 3e-7, 4e-7])
ACCEL = NoiseModel(white_density=100 * units.UG_PER_RTHZ, bias_instability=40 * units.UG)
COLUMNS = ("gyro_x_rps", "gyro_y_rps", "gyro_z_rps", "accel_x_mps2", "accel_y_mps2",
           "accel_z_mps2")


def _characterise(n: int, *, white_accel: bool = False) -> NoiseCharacterization:
    gyro = simulate_noise(GYRO, n, 1 / RATE_HZ, rng=11)
    accel_model = NoiseModel(white_density=ACCEL.white_density) if white_accel else ACCEL
    accel = simulate_noise(accel_model, n, 1 / RATE_HZ, rng=12) + np.array([0.0, 0.0, 9.81])
    cols = {c: (gyro if c.startswith("gyro") else accel)[:, i % 3] for i, c in enumerate(COLUMNS)}
    return analyze_allan_arrays(np.arange(n) / RATE_HZ, cols, source="static.csv")


@pytest.fixture(scope="module")
def noise_file(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, NoiseCharacterization]:
    result = _characterise(1 << 18)  # 44 min at 100 Hz
    path = tmp_path_factory.mktemp("noise") / "unit.noise.json"
    result.save(path)
    return path, result


def test_the_models_are_the_files_fitted_terms(noise_file):
    path, result = noise_file
    models, line = characterization_noise(path)
    seg = result.segments[0]
    for sensor in ("gyro", "accel"):
        for i, a in enumerate("xyz"):
            fit = seg.channel(f"{sensor}_{a}").fit
            assert fit.term("white").detected
            assert models[sensor].white_density[i] == fit.term("white").value_si
            b = fit.term("bias_instability")
            assert models[sensor].bias_instability[i] == (
                b.value_si if b.detected else b.upper_bound_si)
    assert line.startswith("noise characterisation unit.noise.json (record 'whole record', ")
    # the fitted white noise is the unit's (the flicker of 44 min is known to about ±30 %)
    np.testing.assert_allclose(models["gyro"].white_density, GYRO.white_density, rtol=0.05)
    np.testing.assert_allclose(models["accel"].white_density, ACCEL.white_density, rtol=0.05)


def test_an_undetected_term_takes_its_upper_bound(tmp_path):
    result = _characterise(1 << 15, white_accel=True)
    path = result.save(tmp_path / "white.json")
    models, _ = characterization_noise(path)
    for i, a in enumerate("xyz"):
        term = result.segments[0].channel(f"accel_{a}").fit.term("bias_instability")
        want = term.value_si if term.detected else term.upper_bound_si
        assert want is not None and np.isfinite(want) and want > 0
        assert models["accel"].bias_instability[i] == pytest.approx(want)


def test_the_prediction_follows_the_characterisation(noise_file):
    """A unit noisier than its grade: every bias σ predicted larger than with the grade's."""
    path, _ = noise_file
    models, _ = characterization_noise(path)
    plan = generate_p1_plan(repetitions=2, static_s=600.0, sample_rate_hz=RATE_HZ)
    unit = predict_p1(plan, noise=models).std()
    grade = predict_p1(plan, noise=grade_noise(plan)).std()
    for name in ("accel_bias_x", "gyro_bias_z"):
        u, g = unit[name], grade[name]
        assert u is not None and g is not None and u > 1.3 * g, name


def test_the_optimiser_predicts_both_plans_with_the_characterisation(noise_file):
    path, _ = noise_file
    models, _ = characterization_noise(path)
    result = optimize_request(OptimizeRequest(noise_characterization=str(path), coarse=True,
                                              min_static_s=120.0))
    reference = predict_p1(generate_p1_plan(), noise=models).std()
    assert result.reference.std() == pytest.approx(reference, rel=1e-12)
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    assert result.notes[0] == (f"noise model of both plans: characterisation unit.noise.json "
                               f"(sha256 {digest[:12]}…), carried by both plans as [imu.noise]")
    # the optimised plan names the characterisation: its run's analysis needs no file
    noise = result.plan.imu.noise
    assert noise is not None and noise.source_sha256 == digest
    assert (noise.record, round(noise.record_duration_s)) == ("whole record", 2621)
    assert result.worst_ratio <= 1.0 + 1e-6
    assert result.prediction.station_time_s < result.reference.station_time_s


@pytest.mark.parametrize(("text", "message"), [
    ("not json", r"noise characterisation bad\.json: expected the JSON `imucalib allan` "
                 r"writes; got text that is not JSON"),
    (json.dumps({"format": "imucalib-calibration-result"}),
     r"expected format 'imucalib-noise-characterization' .*; got 'imucalib-calibration-result'"),
    (json.dumps({"format": "imucalib-noise-characterization", "format_version": 9}),
     r"format_version 9 is not supported; this imucalib reads 1\.\.1"),
    (json.dumps({"format": "imucalib-noise-characterization", "format_version": 1,
                 "segments": []}), r"expected at least one record"),
])
def test_bad_files_are_refused_in_one_line(tmp_path, text, message):
    path = tmp_path / "bad.json"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(InvalidInputError, match=message):
        characterization_noise(path)


def test_a_record_without_the_accelerometer_is_refused(tmp_path):
    n = 1 << 14
    gyro = simulate_noise(GYRO, n, 1 / RATE_HZ, rng=3)
    result = analyze_allan_arrays(np.arange(n) / RATE_HZ,
                                  {c: gyro[:, i] for i, c in enumerate(COLUMNS[:3])},
                                  source="gyro.csv")
    path = result.save(tmp_path / "gyro.json")
    with pytest.raises(InvalidInputError, match="missing accel_x, accel_y, accel_z"):
        characterization_noise(path)
    with pytest.raises(InvalidInputError, match="cannot read it"):
        characterization_noise(tmp_path / "absent.json")
