"""P1's predicted uncertainty of a plan (docs/test-design.md): against calibrate, and refusals."""

from __future__ import annotations

import math

import numpy as np
import pytest

from imucalib.errors import ConfigurationError
from imucalib.models.noise import NoiseModel
from imucalib.plan.schema import PositionStep
from imucalib.procedures import registry
from imucalib.procedures.common.prediction import PredictionUnavailableError, predict_plan
from imucalib.procedures.p1.plan import generate_p1_plan
from imucalib.procedures.p1.predict import predict_p1
from imucalib.procedures.p1.roles import P1_ACCEL_POSITION


def _short(**kwargs):
    args = dict(repetitions=1, static_s=60.0, warm_up_s=10.0, record_s=10.0, settle_s=5.0,
                rate_settle_s=3.0, revolutions=2)
    args.update(kwargs)
    return generate_p1_plan(**args)


def test_predicted_sigma_is_calibrates_within_ten_percent(consumer_run, p1_tools):
    """Every σ calibrate reports is predicted within 10 % from the plan (docs/test-design.md).

    With the noise model the analysis fitted to the run's static record: what the prediction
    cannot know is that fit (a 5-min record's flicker estimate), and the model choice's
    uncertainty (TS.4), which the comparison removes from the reported σ.
    """
    plan = p1_tools.p1_plan("consumer", 5)  # the plan consumer_run ran
    analysis = registry.get("p1").analyze(consumer_run)
    reported = analysis.result.std()
    model_std: dict[str, float] = {}
    for choice in analysis.model_selection:
        model_std.update(choice["model_std"])
    prediction = predict_p1(plan, noise=analysis.observations.noise)
    predicted = prediction.std()
    assert list(predicted) == list(analysis.result.param_names)
    ratios = {n: predicted[n] / math.sqrt(reported[n] ** 2 - model_std.get(n, 0.0) ** 2)
              for n in predicted}
    worst = max(ratios, key=lambda n: abs(math.log(ratios[n])))
    assert 0.9 <= ratios[worst] <= 1.1, (worst, ratios[worst])
    assert prediction.identifiable and prediction.rank == prediction.n_parameters == 33
    assert 900.0 < prediction.station_time_s < 1400.0


def test_white_noise_six_positions_give_the_closed_form():
    """White noise only: the accelerometer bias σ is N/√T/√6, Eq. (3) of estimation.crlb."""
    n = 1e-3
    noise = {"accel": NoiseModel(white_density=n), "gyro": NoiseModel(white_density=1e-5)}
    prediction = predict_p1(_short(), noise=noise)
    sigma = prediction.std()["accel_bias_x"]
    assert sigma == pytest.approx(n / math.sqrt(10.0) / math.sqrt(6.0), rel=1e-9)


def test_plan_without_z_rates_is_refused_naming_the_confounded():
    prediction = predict_p1(_short(z_rates=False))
    assert prediction.confounded == ("gyro_M_xz", "gyro_M_yz", "gyro_M_zz")
    assert not prediction.identifiable
    std = prediction.std()
    assert std["gyro_bias_x"] is None and std["accel_bias_x"] is not None
    gyro = next(g for g in prediction.groups if g.name == "gyro")
    assert gyro.rank < gyro.n_parameters and math.isinf(gyro.condition_number)


def test_plan_missing_a_position_is_refused():
    plan = _short()
    steps = list(plan.steps)
    first = next(i for i, s in enumerate(steps)
                 if isinstance(s, PositionStep) and s.role == P1_ACCEL_POSITION)
    del steps[first]
    prediction = predict_p1(plan.model_copy(update={"steps": tuple(steps)}))
    assert "accel_bias_x" in prediction.confounded
    assert all(v is None for k, v in prediction.std().items() if k.startswith("accel"))


def test_to_dict_shape():
    data = predict_p1(_short()).to_dict()
    assert {"station_time_s", "parameters", "confounded"} <= set(data)
    assert data["confounded"] == []
    first = data["parameters"][0]
    assert set(first) == {"name", "predicted_std", "unit"}
    assert first["name"] == "accel_bias_x" and first["unit"] == "m/s^2"
    assert all(np.isfinite(p["predicted_std"]) for p in data["parameters"])


def test_procedure_without_predict_is_refused():
    allan = registry.get("allan")
    with pytest.raises(PredictionUnavailableError,
                       match=r"^prediction is not available for procedure allan yet$"):
        predict_plan(allan, allan.generate_plan())


def test_plan_of_another_procedure_is_refused():
    plan = _short().model_copy(update={"procedure": "allan"})
    with pytest.raises(ConfigurationError, match="not a p1 plan"):
        predict_p1(plan)
