"""Kalibr / OpenVINS YAML and the datasheet table: every conversion checked numerically."""

from __future__ import annotations

import csv
import io
import math
import re

import numpy as np
import pytest

from imucalib import units
from imucalib.analysis import NoiseFit, NoiseTerm, compute_oadev, fit_noise_terms, make_noise_term
from imucalib.analysis.noise_parameters import ImuNoiseParameters, noise_parameters_from_fits
from imucalib.errors import InvalidInputError
from imucalib.models.noise import NoiseModel
from imucalib.models.noise_generator import simulate_noise
from imucalib.procedures.allan.noise_exports import (
    format_kalibr_yaml,
    format_noise_table,
    format_openvins_yaml,
    write_kalibr_yaml,
    write_openvins_yaml,
)

RT2 = math.sqrt(2)


def fit_of(sensor: str, terms: list[NoiseTerm], readings: tuple[NoiseTerm, ...] = ()) -> NoiseFit:
    names = tuple(t.name for t in terms)
    return NoiseFit(sensor=sensor, terms=tuple(terms), slope_readings=readings,
                    fitted_terms=names, coefficients=np.zeros(len(names)),
                    covariance=np.zeros((len(names), len(names))), chi2=0.0, dof=1,
                    taus_s=np.ones(3))


def triad(sensor: str, white: list[float], walk: list[float], detected: bool = True
          ) -> list[NoiseFit]:
    return [fit_of(sensor, [make_noise_term(sensor, "white", n, 0.01 * n),
                            make_noise_term(sensor, "random_walk", k, 0.1 * k,
                                            detected=detected)])
            for n, k in zip(white, walk, strict=True)]


def yaml_values(text: str) -> dict[str, str]:
    """Flat `key: value` pairs of the YAML text (comments dropped)."""
    out = {}
    for line in text.splitlines():
        body = line.split("#")[0].strip() if not line.startswith("%") else ""
        if ":" in body and not body.startswith("-"):
            key, _, value = body.partition(":")
            if value.strip():
                out[key.strip()] = value.strip().strip('"')
    return out


def test_datasheet_conversions_are_numerically_right() -> None:
    # 0.008 (°/s)/√Hz one-sided (an ADIS16470-class datasheet) is N = ND/√2 = 0.3394 °/√h
    n = 0.008 * units.DEG / RT2
    shown = {(u.unit, u.note.split(" ")[0]): u.value
             for u in make_noise_term("gyro", "white", n).display}
    assert shown[("°/√h", "ARW,")] == pytest.approx(0.008 / RT2 * 60, rel=1e-12)
    assert shown[("°/√h", "ARW,")] == pytest.approx(0.33941, abs=1e-5)
    assert shown[("(°/s)/√Hz", "one-sided")] == pytest.approx(0.008, rel=1e-12)
    assert shown[("(°/s)/√Hz", "two-sided")] == pytest.approx(0.008 / RT2, rel=1e-12)
    assert shown[("(°/h)/√Hz", "two-sided")] == pytest.approx(0.008 / RT2 * 3600, rel=1e-12)
    # RRW: 1 °/h/√h = (π/180)/3600^1.5 rad/s²/√Hz
    k = make_noise_term("gyro", "random_walk", units.DEG / 3600**1.5)
    assert k.display[0].unit == "°/h/√h" and k.display[0].value == pytest.approx(1.0)
    # bias 10 °/h; ramp 1 °/h²; quantization 1″
    assert make_noise_term("gyro", "bias_instability", 10 * units.DEG_PER_H).display[0].value \
        == pytest.approx(10.0)
    assert make_noise_term("gyro", "rate_ramp", units.DEG / 3600**2).display[0].value \
        == pytest.approx(1.0)
    assert make_noise_term("gyro", "quantization", units.ARCSEC).display[0].value \
        == pytest.approx(1.0)
    # accelerometer: 100 µg/√Hz one-sided → N = 100·9.80665e-6/√2; VRW = 60·N m/s/√h
    na = 100e-6 * 9.80665 / RT2
    acc = {(u.unit, u.note.split(" ")[0]): u.value
           for u in make_noise_term("accel", "white", na).display}
    assert acc[("µg/√Hz", "one-sided")] == pytest.approx(100.0, rel=1e-12)
    assert acc[("µg/√Hz", "two-sided")] == pytest.approx(100.0 / RT2, rel=1e-12)
    assert acc[("m/s/√h", "VRW,")] == pytest.approx(60 * na, rel=1e-12)
    assert make_noise_term("accel", "random_walk", 9.80665e-6 / 60).display[0].value \
        == pytest.approx(1.0)  # 1 µg/√h
    assert make_noise_term("accel", "rate_ramp", 9.80665e-6 / 3600).display[0].value \
        == pytest.approx(1.0)  # 1 µg/h


def test_kalibr_yaml_values_are_the_two_sided_si_densities(tmp_path) -> None:
    gyro = triad("gyro", [1.0e-4, 1.7e-4, 1.2e-4], [2e-6, 1e-6, 3e-6])
    accel = triad("accel", [2e-3, 1e-3, 1.5e-3], [3e-4, 4e-4, 1e-4])
    params = noise_parameters_from_fits(gyro, accel, 200.0)
    assert params.gyroscope_noise_density == pytest.approx(1.7e-4)  # max over axes
    assert params.gyroscope_random_walk == pytest.approx(3e-6)
    assert params.accelerometer_noise_density == pytest.approx(2e-3)
    assert params.accelerometer_random_walk == pytest.approx(4e-4)
    values = yaml_values(format_kalibr_yaml(params, rostopic="/imu/data"))
    assert float(values["gyroscope_noise_density"]) == pytest.approx(1.7e-4, rel=1e-6)
    assert float(values["gyroscope_random_walk"]) == pytest.approx(3e-6, rel=1e-6)
    assert float(values["accelerometer_noise_density"]) == pytest.approx(2e-3, rel=1e-6)
    assert float(values["accelerometer_random_walk"]) == pytest.approx(4e-4, rel=1e-6)
    assert float(values["update_rate"]) == 200.0 and values["rostopic"] == "/imu/data"
    rms = noise_parameters_from_fits(gyro, accel, 200.0, combine="rms", noise_inflation=5.0,
                                     walk_inflation=10.0)
    assert rms.gyroscope_noise_density == pytest.approx(
        5 * math.sqrt((1e-8 + 1.7e-4**2 + 1.2e-4**2) / 3))
    assert rms.accelerometer_random_walk == pytest.approx(
        10 * math.sqrt((9e-8 + 16e-8 + 1e-8) / 3))
    path = write_kalibr_yaml(tmp_path / "imu.yaml", params)
    assert yaml_values(path.read_text()) == values | {"rostopic": "/imu0"}


def test_openvins_yaml_block(tmp_path) -> None:
    params = ImuNoiseParameters(1.6968e-4, 1.9393e-5, 2.0e-3, 3.0e-3, 400.0)
    text = format_openvins_yaml(params, rostopic="/imu0", time_offset_s=0.002)
    assert text.startswith("%YAML:1.0")
    assert "\nimu0:\n  T_i_b:\n    - [1, 0, 0, 0]\n" in text
    values = yaml_values(text)
    assert float(values["gyroscope_noise_density"]) == pytest.approx(1.6968e-4)
    assert float(values["gyroscope_random_walk"]) == pytest.approx(1.9393e-5)
    assert float(values["accelerometer_noise_density"]) == pytest.approx(2.0e-3)
    assert float(values["accelerometer_random_walk"]) == pytest.approx(3.0e-3)
    assert values["model"] == "kalibr" and float(values["time_offset"]) == 0.002
    assert float(values["update_rate"]) == 400.0
    for name in ("Tw", "R_IMUtoGYRO", "Ta", "R_IMUtoACC", "Tg"):
        assert f"\n  {name}:\n    - [" in text
    tg = np.full((3, 3), 1e-3)
    custom = format_openvins_yaml(params, intrinsics={"Tg": tg})
    assert "  Tg:\n    - [0.001, 0.001, 0.001]" in custom
    with pytest.raises(InvalidInputError, match=r"unknown intrinsics \['Tx'\]"):
        format_openvins_yaml(params, intrinsics={"Tx": tg})
    with pytest.raises(InvalidInputError, match=r"`t_i_b` must be 4x4; got shape \(3, 3\)"):
        format_openvins_yaml(params, t_i_b=np.eye(3))
    assert write_openvins_yaml(tmp_path / "chain.yaml", params).read_text().startswith("%YAML")


def test_undetected_random_walk_uses_its_scale_and_says_so() -> None:
    gyro = triad("gyro", [1e-4] * 3, [0.0] * 3, detected=False)
    accel = triad("accel", [1e-3] * 3, [1e-4] * 3)
    gyro = [fit_of("gyro", [make_noise_term("gyro", "white", 1e-4),
                            make_noise_term("gyro", "random_walk", 0.0, 5e-7, detected=False)])
            for _ in range(3)]
    params = noise_parameters_from_fits(gyro, accel, 100.0)
    assert params.gyroscope_random_walk == pytest.approx(5e-7)
    text = format_kalibr_yaml(params)
    assert "# gyro axis 0: random_walk not detected; its 1-sigma scale 5e-07 rad/s/√s" in text


def test_export_bad_inputs() -> None:
    gyro = triad("gyro", [1e-4] * 3, [1e-6] * 3)
    accel = triad("accel", [1e-3] * 3, [1e-4] * 3)
    with pytest.raises(InvalidInputError, match="gyro fit 0 is a 'accel' fit"):
        noise_parameters_from_fits(accel, accel, 100.0)
    with pytest.raises(InvalidInputError, match="no accel fits given"):
        noise_parameters_from_fits(gyro, [], 100.0)
    with pytest.raises(InvalidInputError, match="`combine` must be 'max' or 'rms'; got 'mean'"):
        noise_parameters_from_fits(gyro, accel, 100.0, combine="mean")
    with pytest.raises(InvalidInputError, match=r"`update_rate_hz` must be > 0; got 0\.0"):
        noise_parameters_from_fits(gyro, accel, 0.0)
    with pytest.raises(InvalidInputError, match="`fmt` must be 'text', 'csv' or 'markdown'"):
        format_noise_table({"gyro_x": gyro[0]}, fmt="html")
    with pytest.raises(InvalidInputError, match="`fits` is empty"):
        format_noise_table({})


def _pm(cell: str) -> tuple[float, float]:
    """(value, half a unit of its last digit) of a ``"v ± u"`` or ``"(v ± u)eN"`` cell."""
    m = re.fullmatch(r"\(?([+-]?\d+(?:\.(\d+))?) ± (\d+(?:\.(\d+))?)\)?(?:e(-?\d+))?", cell)
    assert m, cell
    assert len(m.group(3).replace(".", "").lstrip("0")) == 2, cell  # u: two significant digits
    assert len(m.group(2) or "") == len(m.group(4) or ""), cell  # the value at the same place
    exp = int(m.group(5) or 0)
    return float(m.group(1)) * 10.0 ** exp, 0.5 * 10.0 ** (exp - len(m.group(2) or ""))


def test_datasheet_table_from_a_real_fit() -> None:
    truth_n, truth_b = 2e-3, 4e-4
    model = NoiseModel(white_density=truth_n, bias_instability=truth_b,
                       bias_instability_corner_hz=10.0)
    y = simulate_noise(model, 1 << 16, 0.01, rng=7)
    fits = {f"gyro_{ax}": fit_noise_terms(compute_oadev(y[:, i], 100.0), sensor="gyro")
            for i, ax in enumerate("xyz")}
    table = format_noise_table(fits, fmt="csv")
    rows = list(csv.reader(io.StringIO(table)))
    assert rows[0] == ["parameter", "unit", "gyro_x", "gyro_y", "gyro_z"]
    by_name = {r[0]: r for r in rows}
    arw, half = _pm(by_name["Angle random walk"][2])
    assert arw == pytest.approx(fits["gyro_x"].term("white").value_si / units.DEG_PER_RTH,
                                abs=half * 1.000001)  # rounded as GUM 7.2.6 asks
    nd, _ = _pm(by_name["Noise density (one-sided)"][2])
    assert nd == pytest.approx(RT2 * truth_n / units.DEG, rel=0.02)
    reading = fits["gyro_x"].reading("bias_instability_allan_minimum")
    assert reading is not None
    cell = by_name["Allan minimum (no factor)"][2]
    if reading.detected:
        amin, half = _pm(cell)
        assert amin == pytest.approx(reading.value_si / units.DEG_PER_H, abs=half * 1.000001)
    else:  # 655 s of white-dominated record: an upper bound (docs/noise.md)
        assert reading.upper_bound_si is not None
        bound = float(cell.removeprefix("< ").removesuffix(" (n.d.)"))
        assert bound == pytest.approx(reading.upper_bound_si / units.DEG_PER_H, rel=1e-2)
    assert "n.d." in by_name["Rate ramp"][3]
    md = format_noise_table(fits, fmt="markdown")
    assert md.startswith("| parameter | unit | gyro_x | gyro_y | gyro_z |\n|---|---|---|---|---|")
    text = format_noise_table(fits)
    assert "Angle random walk" in text and "one-sided datasheet value sqrt(2)*N" in text
