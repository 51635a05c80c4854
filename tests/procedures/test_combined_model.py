"""One unit through four classical tests on the twin, combined into one triad model.

The same truth (one ImuConfig seed) in every run: the tumble gives the accelerometer triad
(biases, scale factors, misalignments, K2), the rate transfer the gyro scale factors, the
installation test the gyro misalignments, the g-sensitivity test the gyro biases and G.
`combine_triad_parameters` fuses them into one CalibrationResult (docs/procedures.md,
"Combining tests"), which must hold every parameter within 4σ of the truth and load back.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from imucalib.estimation.combine import combine_triad_parameters
from imucalib.io.opening import open_recording
from imucalib.models.result import CalibrationResult
from imucalib.plan.schema import Plan
from imucalib.procedures import registry
from imucalib.procedures.g_sensitivity.plan import generate_g_sensitivity_plan
from imucalib.procedures.installation.plan import generate_installation_plan
from imucalib.procedures.rate_transfer.plan import generate_rate_transfer_plan
from imucalib.procedures.tumble.plan import generate_tumble_plan

from ._rate_twin import run

UNIT = "IMU-0001"
G_TRUE = ((2e-5, -1e-5, 0.0), (0.0, 3e-5, 1e-5), (-1e-5, 0.0, 1.5e-5))  # rad/s per m/s²


def _same_unit(plan: Plan) -> Plan:
    """Every test's twin carries the same unit: tactical, seed 777, white noise, G injected."""
    assert plan.twin is not None
    imus = tuple(i.model_copy(update={"seed": 777, "grade": "tactical", "noise": "white",
                                      "errors": {"gyro.g_sensitivity": G_TRUE}})
                 for i in plan.twin.imus)
    return plan.model_copy(update={"twin": plan.twin.model_copy(update={"imus": imus})})


@pytest.mark.slow
def test_four_tests_combine_into_one_model_within_4_sigma(tmp_path: Path) -> None:
    plans = {
        "tumble": generate_tumble_plan(n_positions=12, record_s=20.0, settle_s=3.0,
                                       sample_rate_hz=50.0, seed=1),
        "rate-transfer": generate_rate_transfer_plan(rates_dps=(20.0, 45.0, 90.0),
                                                     sample_rate_hz=50.0, seed=2),
        "installation": generate_installation_plan(rate_dps=(30.0, 60.0), sample_rate_hz=50.0,
                                                   seed=3),
        "g-sensitivity": generate_g_sensitivity_plan(record_s=30.0, settle_s=5.0,
                                                     warm_up_s=10.0, sample_rate_hz=20.0,
                                                     seed=4),
    }
    results, truths = [], []
    for name, plan in plans.items():
        path = run(_same_unit(plan), tmp_path / f"{name}.h5")
        with open_recording(path) as rec:
            truths.append(rec.truth["imu_models"][UNIT])
        result = registry.get(name).analyze(path)
        assert result.procedure == name
        results.append(result)
    # one truth in every run
    for t in truths[1:]:
        for triad in ("gyro", "accel"):
            for key in ("bias", "scale_misalignment"):
                np.testing.assert_array_equal(t[triad][key], truths[0][triad][key])
    combined = combine_triad_parameters(results, sensor_id=UNIT)
    assert combined.model == "triad"
    truth = truths[0]
    expected = {}
    for triad in ("gyro", "accel"):
        m = np.asarray(truth[triad]["scale_misalignment"])
        for i, a in enumerate("xyz"):
            expected[f"{triad}_bias_{a}"] = truth[triad]["bias"][i]
            for j, b in enumerate("xyz"):
                expected[f"{triad}_M_{a}{b}"] = m[i, j]
    for i, a in enumerate("xyz"):
        expected[f"accel_K2_{a}"] = truth["accel"]["k2"][i]
        for j, b in enumerate("xyz"):
            expected[f"gyro_G_{a}{b}"] = G_TRUE[i][j]
    assert set(combined.param_names) == set(expected)
    std = combined.std(scaled=True)
    z = {n: (combined.value(n) - expected[n]) / std[n] for n in combined.param_names}
    assert max(abs(v) for v in z.values()) < 4.0, {k: round(v, 2) for k, v in z.items()
                                                   if abs(v) >= 4.0}
    path = tmp_path / "combined.json"
    path.write_text(combined.to_json())
    assert CalibrationResult.load(path).param_names == combined.param_names
