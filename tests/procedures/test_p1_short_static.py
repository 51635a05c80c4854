"""P1 with a static record too short for the flicker floor: the declared noise, Type B.

docs/p1.md, "Noise model of the window means": when the pooled static records' longest Allan
cluster is shorter than four flicker corners of the plan's declared (grade) noise, the flicker
and random walk come from the declared model and the white density from the records, so the
biases' σ are not under-reported; a long record keeps the fit unchanged. Also the K2 term of the
prediction (docs/test-design.md, "Truth on the twin").
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from imucalib.io import open_recording
from imucalib.models.noise import NoiseModel
from imucalib.procedures import registry
from imucalib.procedures.common.grade import grade_noise
from imucalib.procedures.common.noise import (
    FLICKER_CORNERS_MIN,
    FLICKER_FACTOR,
    estimate_noise,
    flicker_corner_s,
    longest_cluster_s,
    noise_records,
    with_declared_floor,
)
from imucalib.procedures.p1.observations import extract_p1_observations
from imucalib.procedures.p1.plan import generate_p1_plan
from imucalib.procedures.p1.predict import predict_p1

_N, _B, _K = 3.6e-5, 4.8e-6, 4e-8  # a tactical gyro: τ_c = N²/(0.441·B²) ≈ 127 s


def _declared() -> dict[str, NoiseModel]:
    return {"gyro": NoiseModel(white_density=_N, bias_instability=_B, random_walk=_K)}


def test_flicker_corner_and_longest_cluster():
    tau_c = flicker_corner_s(_declared()["gyro"])
    np.testing.assert_allclose(tau_c, _N**2 / (FLICKER_FACTOR * _B**2), rtol=1e-12)
    assert np.all(flicker_corner_s(NoiseModel(white_density=_N)) == 0.0)  # nothing to see
    # the largest power of two ≤ n/2 samples: 60 min at 1 kHz → 2^20 samples, 120 s at 100 Hz
    # → 2^12
    assert longest_cluster_s(3600.0, 1000.0) == pytest.approx(2**20 / 1000.0)
    assert longest_cluster_s(120.0, 100.0) == pytest.approx(2**12 / 100.0)


def test_short_record_takes_the_declared_flicker_and_random_walk():
    fitted = {"gyro": NoiseModel(white_density=[3.5e-5] * 3, bias_instability=[9e-6, 2e-6, 0.0],
                                 random_walk=[1.5e-6, 0.0, 4e-7])}
    out, note = with_declared_floor(fitted, _declared(), 41.0, source="grade tactical")
    np.testing.assert_array_equal(out["gyro"].white_density, fitted["gyro"].white_density)
    np.testing.assert_allclose(out["gyro"].bias_instability, _B)
    np.testing.assert_allclose(out["gyro"].random_walk, _K)
    assert note is not None and "grade tactical" in note and "gyro xyz" in note
    assert "not determined" in note and "Type B" in note


def test_long_record_keeps_the_fit_unchanged():
    fitted = {"gyro": NoiseModel(white_density=_N, bias_instability=1e-6, random_walk=0.0)}
    tau_max = longest_cluster_s(3600.0, 1000.0)  # the default plan's 60-min static
    assert tau_max >= FLICKER_CORNERS_MIN * float(np.max(flicker_corner_s(_declared()["gyro"])))
    out, note = with_declared_floor(fitted, _declared(), tau_max)
    assert note is None and out["gyro"] is fitted["gyro"]
    # nothing declared for a triad: its fit stays
    out, note = with_declared_floor(fitted, {}, 1.0)
    assert note is None and out["gyro"] is fitted["gyro"]


def test_a_static_step_of_exactly_the_minimum_length_counts():
    """A 120-s static averages 119.98 s at 100 Hz (its edge samples): it still gives a model."""
    fit = np.zeros((3, 6))
    fit[0] = 1e-4
    windows = [SimpleNamespace(kind="static", duration_s=119.98, allan_fit=fit)]
    assert len(noise_records(windows)) == 1 and estimate_noise(windows)
    assert not noise_records([SimpleNamespace(kind="static", duration_s=119.5, allan_fit=fit)])


@pytest.fixture(scope="module")
def short_static_run(tmp_path_factory, p1_tools):
    plan = p1_tools.p1_plan("tactical", 7, static_s=130.0)
    return plan, p1_tools.run_twin(plan, tmp_path_factory.mktemp("p1s") / "s.h5")


def test_short_static_twin_run_reports_at_least_the_declared_flicker_floor(short_static_run):
    """A tactical P1 run with a 130-s static: the biases' σ rest on the grade's flicker."""
    plan, path = short_static_run
    analysis = registry.get("p1").analyze(path)
    declared = grade_noise(plan)
    noise = analysis.observations.noise
    for triad in ("accel", "gyro"):
        np.testing.assert_array_equal(noise[triad].bias_instability,
                                      declared[triad].bias_instability)
        np.testing.assert_array_equal(noise[triad].random_walk, declared[triad].random_walk)
    assert any("flicker floor is not determined" in n for n in analysis.observations.notes)
    assert any("flicker floor is not determined" in n for n in analysis.result.notes)
    # the declared flicker floor alone (no white noise) bounds every bias's σ from below
    floor = predict_p1(plan, noise={k: NoiseModel(bias_instability=m.bias_instability,
                                                  random_walk=m.random_walk)
                                    for k, m in declared.items()}).std()
    reported = analysis.result.std()
    for name in (f"{t}_bias_{a}" for t in ("accel", "gyro") for a in "xyz"):
        assert reported[name] >= floor[name] > 0.0, name


def test_results_of_a_record_that_shows_the_floor_do_not_change(consumer_run, monkeypatch):
    """With the floor raised out of reach nothing changes; with it, only flicker and K."""
    from imucalib.procedures.common import noise as noise_mod

    with open_recording(consumer_run) as rec:
        floored = extract_p1_observations(rec)  # 5 min at 200 Hz: τ_max 82 s < 8 × 14 s
        monkeypatch.setattr(noise_mod, "FLICKER_CORNERS_MIN", 0.0)
        monkeypatch.setattr(noise_mod.with_declared_floor, "__kwdefaults__",
                            {"corners": 0.0, "source": "declared"})
        fitted = extract_p1_observations(rec)
    assert any("flicker floor is not determined" in n for n in floored.notes)
    assert not any("flicker floor" in n for n in fitted.notes)
    for triad in ("accel", "gyro"):
        np.testing.assert_array_equal(floored.noise[triad].white_density,
                                      fitted.noise[triad].white_density)
    for a, b in zip(floored.windows, fitted.windows, strict=True):
        np.testing.assert_array_equal(a.accel_mean_mps2, b.accel_mean_mps2)


def test_prediction_with_k2_white_noise_closed_form():
    """K2 in the accelerometer model: σ(K2) = (N/√T)·(√3/2)/g², σ(b) = (N/√T)/2 (white)."""
    n, t = 1e-3, 10.0
    plan = generate_p1_plan(repetitions=1, static_s=60.0, warm_up_s=10.0, record_s=t,
                            settle_s=5.0, rate_settle_s=3.0, revolutions=2)
    noise = {"accel": NoiseModel(white_density=n), "gyro": NoiseModel(white_density=1e-5)}
    without = predict_p1(plan, noise=noise).std()
    prediction = predict_p1(plan, noise=noise, accel_k2=True)
    std = prediction.std()
    g = 9.806  # the site's gravity, to 1e-4
    assert "accel_K2_x" not in without
    assert std["accel_K2_x"] == pytest.approx(n / math.sqrt(t) * math.sqrt(3.0) / 2 / g**2,
                                              rel=1e-3)
    assert std["accel_bias_x"] == pytest.approx(n / math.sqrt(t) / 2, rel=1e-9)
    assert std["accel_M_xx"] == pytest.approx(without["accel_M_xx"], rel=1e-9)
    assert std["gyro_bias_x"] == without["gyro_bias_x"]
    assert any("K2 in the model" in note for note in prediction.notes)
