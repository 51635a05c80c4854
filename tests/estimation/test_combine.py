"""Combining the triad parameters of several tests into one model, Eqs. (C.1)–(C.2)."""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.errors import InsufficientExcitationError, InvalidInputError
from imucalib.estimation.combine import TriadPart, combine_triad_parameters
from imucalib.models.result import (
    CalibrationResult,
    triad_parameter_names,
    triad_parameter_unit,
)

GYRO = triad_parameter_names("gyro", "triad")
ACCEL = triad_parameter_names("accel", "triad", k2=True)


def _part(source, names, values, sigma):
    return TriadPart(source, tuple(names), np.asarray(values, float),
                     np.diag(np.full(len(names), sigma) ** 2))


def test_disjoint_parts_keep_their_values_and_overlaps_are_weighted_means(tmp_path):
    rng = np.random.default_rng(0)
    truth = dict(zip(GYRO, rng.normal(0, 1e-4, len(GYRO)), strict=True))
    bias = [n for n in GYRO if "_bias_" in n]
    diag = [n for n in GYRO if n[-1] == n[-2] and "_M_" in n]
    off = [n for n in GYRO if n not in bias and n not in diag]
    rate = _part("rate-transfer", bias + diag, [truth[n] for n in bias + diag], 1e-6)
    inst = _part("installation", off, [truth[n] for n in off], 2e-6)
    # a second, less precise bias estimate (g-sensitivity's D0), off by +1σ of its own
    gsens = _part("g-sensitivity", bias, [truth[n] + 3e-6 for n in bias], 3e-6)
    result = combine_triad_parameters([rate, inst, gsens], sensor_id="U1")
    assert isinstance(result, CalibrationResult) and result.model == "triad"
    assert result.param_names == GYRO
    for n in off + diag:
        assert result.value(n) == pytest.approx(truth[n], abs=1e-15)
    w1, w2 = 1 / 1e-6**2, 1 / 3e-6**2
    for n in bias:  # the inverse-variance weighted mean, its σ the combined one
        assert result.value(n) == pytest.approx(truth[n] + 3e-6 * w2 / (w1 + w2), rel=1e-9)
        assert result.std()[n] == pytest.approx((w1 + w2) ** -0.5, rel=1e-9)
    assert result.units["gyro_bias_x"] == "rad/s" and result.units["gyro_M_xy"] == "1"
    (quality,) = result.fit_quality
    assert quality.dof == 3 and not quality.misfit
    path = tmp_path / "combined.json"
    path.write_text(result.to_json())
    assert CalibrationResult.load(path).param_names == GYRO


def test_disagreeing_tests_are_flagged_and_scaled():
    bias = [n for n in GYRO if "_bias_" in n]
    rest = [n for n in GYRO if n not in bias]
    parts = [_part("a", bias, [0.0, 0.0, 0.0], 1e-6), _part("b", rest, np.zeros(9), 1e-6),
             _part("c", bias, [5e-5, 5e-5, 5e-5], 1e-6)]  # 35σ apart
    combined = combine_triad_parameters(parts, sensor_id="U")
    (quality,) = combined.fit_quality
    assert quality.group == "gyro" and quality.misfit and quality.birge_ratio > 20
    # the reported σ are Birge-scaled (they were not: the group did not match the names)
    noise, scaled = combined.std(), combined.std(scaled=True)
    for name in GYRO:
        assert scaled[name] == pytest.approx(noise[name] * quality.birge_ratio, rel=1e-12)


def test_an_incomplete_triad_names_what_is_missing():
    bias = [n for n in ACCEL if "_bias_" in n]
    with pytest.raises(InsufficientExcitationError, match=r"accel triad is incomplete.*"
                                                          r"accel_M_xx"):
        combine_triad_parameters([_part("tumble", bias, np.zeros(3), 1e-5)], sensor_id="U")
    with pytest.raises(InvalidInputError, match="not accel triad parameters"):
        combine_triad_parameters([_part("x", ["accel_Kip_x"], [0.0], 1.0)], sensor_id="U")
    with pytest.raises(InvalidInputError, match="nothing to combine"):
        combine_triad_parameters([], sensor_id="U")
    assert triad_parameter_unit("accel_K2_x") == "1/(m/s^2)"
    assert triad_parameter_unit("gyro_G_xz") == "rad/s/(m/s^2)"
