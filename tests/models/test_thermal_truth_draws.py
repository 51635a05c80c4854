"""Drawn temperature-dependent truths: typical cubic swings, hysteresis, determinism."""

from __future__ import annotations

import json

import numpy as np
import pytest

from imucalib import units
from imucalib.errors import ConfigurationError, InvalidInputError
from imucalib.models.imu import (
    THERMAL_GRADES,
    THERMAL_RANGE_DEGC,
    ImuModel,
    sample_imu_model,
)

GRID = np.linspace(*THERMAL_RANGE_DEGC, 501)


def _swings(grade: str) -> dict[str, tuple[float, np.ndarray]]:
    th = THERMAL_GRADES[grade]
    scale = {"gyro": th.gyro_scale_ppm * units.PPM, "accel": th.accel_scale_ppm * units.PPM}
    mis = {"gyro": th.gyro_misalignment_mrad * units.MRAD,
           "accel": th.accel_misalignment_mrad * units.MRAD}
    bias = {"gyro": th.gyro_bias_dph * units.DEG_PER_H, "accel": th.accel_bias_ug * units.UG}
    out = {}
    for triad in ("gyro", "accel"):
        m = np.full((3, 3), mis[triad])
        m[np.diag_indices(3)] = scale[triad]
        out[triad] = (bias[triad], m)
    return out


def _curves(coeffs: np.ndarray, t0: float) -> np.ndarray:
    """Values of Σ c_k (T − T0)^k on GRID, shape (GRID, *parameter_shape)."""
    dt = (GRID - t0).reshape(-1, *([1] * (coeffs.ndim - 1)))
    return sum(coeffs[k] * dt ** (k + 1) for k in range(coeffs.shape[0]))


@pytest.mark.parametrize("grade", ["consumer", "tactical", "navigation"])
def test_typical_draws_have_the_stated_magnitudes_and_a_real_cubic(grade):
    t0 = 25.0
    model = sample_imu_model(grade, 3, temperature_dependence="typical",
                             hysteresis_fraction=0.3, reference_temperature_degc=t0)
    swings = _swings(grade)
    signs = []
    for triad, tm in (("gyro", model.gyro), ("accel", model.accel)):
        dep = tm.temperature
        assert dep is not None and dep.reference_temperature_degc == t0
        assert dep.hysteresis_width_degc == 5.0
        for name, typical in zip(("bias", "scale_misalignment"), swings[triad], strict=True):
            coeffs = dep.coefficients[name]
            assert coeffs.shape[0] == 3  # c1, c2, c3
            values = _curves(coeffs, t0)
            span = values.max(axis=0) - values.min(axis=0)
            ratio = span / typical
            assert np.all((ratio >= 0.5 - 1e-9) & (ratio <= 1.5 + 1e-9)), (triad, name, ratio)
            # the cubic monomial alone spans ≥ 20 % of the swing
            cubic = np.abs(coeffs[2]) * ((GRID[-1] - t0) ** 3 - (GRID[0] - t0) ** 3)
            assert np.all(cubic >= 0.2 * span)
            # and a quadratic in T leaves residuals of ≥ 20 % of the swing
            flat = values.reshape(GRID.size, -1)
            basis = np.vander(GRID - t0, 3)
            resid = flat - basis @ np.linalg.lstsq(basis, flat, rcond=None)[0]
            assert np.all(np.ptp(resid, axis=0) >= 0.2 * span.reshape(-1))
            h = dep.hysteresis[name]
            np.testing.assert_allclose(np.abs(h), 0.3 * span, rtol=1e-9, atol=0)
            signs.extend(np.sign(h).ravel())
    assert 0 < sum(s > 0 for s in signs) < len(signs)  # random signs


def test_typical_draws_are_deterministic_and_round_trip():
    a = sample_imu_model("tactical", 42, temperature_dependence="typical",
                         hysteresis_fraction=0.2)
    b = sample_imu_model("tactical", 42, temperature_dependence="typical",
                         hysteresis_fraction=0.2)
    assert a.to_dict() == b.to_dict()
    back = ImuModel.from_dict(json.loads(json.dumps(a.to_dict())))
    assert back.to_dict() == a.to_dict()
    assert back.accel.temperature is not None and back.accel.temperature.has_hysteresis
    c = sample_imu_model("tactical", 43, temperature_dependence="typical")
    assert c.to_dict() != a.to_dict()
    assert c.gyro.temperature is not None and not c.gyro.temperature.hysteresis


def test_none_leaves_the_draws_unchanged():
    for grade in ("consumer", "tactical", "navigation"):
        plain = sample_imu_model(grade, 9)
        none = sample_imu_model(grade, 9, temperature_dependence="none")
        assert plain.to_dict() == none.to_dict()
        assert none.gyro.temperature is None and none.accel.temperature is None
        typical = sample_imu_model(grade, 9, temperature_dependence="typical",
                                   hysteresis_fraction=0.5)
        # the base values (at T0) are the plain draw's
        stripped = ImuModel(gyro=typical.gyro.replace(temperature=None),
                            accel=typical.accel.replace(temperature=None),
                            gyro_noise=typical.gyro_noise, accel_noise=typical.accel_noise,
                            gyro_output=typical.gyro_output, accel_output=typical.accel_output,
                            sample_rate_hz=typical.sample_rate_hz)
        assert stripped.to_dict() == plain.to_dict()
    # a caller's generator continues the same after either draw
    g1, g2 = np.random.default_rng(5), np.random.default_rng(5)
    sample_imu_model("tactical", g1)
    sample_imu_model("tactical", g2, temperature_dependence="typical")
    assert g1.random() == g2.random()


def test_parameters_at():
    model = sample_imu_model("tactical", 8, temperature_dependence="typical",
                             hysteresis_fraction=0.4, reference_temperature_degc=20.0)
    at_t0 = model.parameters_at(20.0)
    assert at_t0["accel_bias_y"] == model.accel.bias[1]
    assert at_t0["gyro_M_xz"] == model.gyro.scale_misalignment[0, 2]
    assert at_t0["gyro_G_zy"] == model.gyro.g_sensitivity[2, 1]
    assert len(at_t0) == 12 + 12 + 9
    dep = model.accel.temperature
    assert dep is not None
    dt = 60.0 - 20.0
    c = dep.coefficients["scale_misalignment"][:, 1, 0]
    want = (model.accel.scale_misalignment[1, 0] + c[0] * dt + c[1] * dt**2 + c[2] * dt**3
            - dep.hysteresis["scale_misalignment"][1, 0])
    assert model.parameters_at(60.0, -1.0)["accel_M_yx"] == pytest.approx(want, rel=1e-12)
    hot, cold = model.parameters_at(60.0, 1.0), model.parameters_at(60.0, -1.0)
    assert hot["gyro_bias_z"] - cold["gyro_bias_z"] == pytest.approx(
        2.0 * model.gyro.temperature.hysteresis["bias"][2], rel=1e-9)
    with pytest.raises(InvalidInputError, match="hysteresis_state"):
        model.parameters_at(20.0, 2.0)
    plain = sample_imu_model("tactical", 8)
    assert plain.parameters_at(80.0, 1.0) == plain.parameters_at(-10.0)


def test_bad_thermal_options():
    with pytest.raises(InvalidInputError, match="hysteresis_fraction"):
        sample_imu_model("tactical", 1, temperature_dependence="typical", hysteresis_fraction=0.6)
    with pytest.raises(InvalidInputError, match="typical"):
        sample_imu_model("tactical", 1, hysteresis_fraction=0.1)
    with pytest.raises(ConfigurationError, match="temperature_dependence"):
        sample_imu_model("tactical", 1, temperature_dependence="extreme")  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="reference_temperature_degc"):
        sample_imu_model("tactical", 1, temperature_dependence="typical",
                         reference_temperature_degc=float("nan"))
