"""One display-unit table per kind of quantity, for every console and report (docs/reporting.md,
"Display units"): each value converted by hand."""

from __future__ import annotations

import math

import pytest

from imucalib.report.console import display_parameter, display_unit

G0 = 9.80665


@pytest.mark.parametrize(("name", "value", "sigma", "unit", "expected"), [
    # an accelerometer bias or K0: 1 µg = 1e-6·g0 m/s²
    ("K0_x_head_z", 2.0e-4, 1.0e-5, "m/s^2", ("+20.4", "1.0", "µg")),
    # a gyro bias or drift: 1 °/h = π/180/3600 rad/s
    ("gyro_sigma_D0_x", 1.0e-5, 2.0e-7, "rad/s", ("+2.063", "0.041", "°/h")),
    # g-sensitivity, written two ways
    ("gyro_sigma_D1_x", 1.0e-6, 1.0e-7, "(rad/s)/(m/s^2)", ("+2.02", "0.20", "(°/h)/g")),
    ("gyro_G_xy", 1.0e-6, 1.0e-7, "rad/s/(m/s^2)", ("+2.02", "0.20", "(°/h)/g")),
    # K2 (output per input²): 1 µg/g² = 1e-6/g0 per (m/s²)
    ("K2_x_head_z", 1.0e-6, 2.0e-7, "1/(m/s^2)", ("+9.8", "2.0", "µg/g²")),
    ("K3_x_head_z", 1.0e-7, 5.0e-8, "1/(m/s^2)^2", ("+9.6", "4.8", "µg/g³")),
    # a scale factor about 1: its deviation from 1 in ppm
    ("K1_x_head_z", 1.0 + 12.3e-6, 2.5e-6, "1", ("+12.3", "2.5", "ppm")),
    ("gyro_scale_factor_x", 1.0 - 50e-6, 3e-6, "1", ("-50.0", "3.0", "ppm")),
    # a dimensionless deviation or nonlinearity: ppm as it is
    ("gyro_nonlinearity_x", 40e-6, 4e-6, "1", ("+40.0", "4.0", "ppm")),
    ("gyro_M_xx_closed", 40e-6, 4e-6, "1", ("+40.0", "4.0", "ppm")),
    # an off-diagonal M element is a small angle
    ("gyro_M_xy_closed", 40e-6, 4e-6, "1", ("+40.0", "4.0", "µrad")),
    ("delta_x_head_z", 1.0e-4, 1.0e-5, "rad", ("+100", "10", "µrad")),
    # a gyro's quadratic term: ppm per °/s
    ("gyro_E2_x", 1.0e-6, 1.0e-7, "s/rad", ("+0.0175", "0.0017", "ppm/(°/s)")),
    # a bias's drift over a session, a scale factor's temperature coefficient (docs/field.md)
    ("accel_bias_rate_x", 2.0 * G0 * 1e-6, 0.5 * G0 * 1e-6, "m/s^3", ("+2.00", "0.50", "µg/s")),
    ("gyro_bias_rate_x", 1.0e-6, 1.0e-7, "rad/s^2", ("+0.206", "0.021", "(°/h)/s")),
    ("accel_M_zz_tc", 2.2e-4, 7.6e-5, "1/K", ("+220", "76", "ppm/K")),
    # a temperature model's coefficients (P2's prediction: <name>_c1 … _c3): the base
    # quantity's display unit per K^j, an off-diagonal M's in ppm/K, not µrad
    ("accel_M_xy_c1", 2.0e-6, 1.0e-7, "1/K", ("+2.00", "0.10", "ppm/K")),
    ("accel_M_xy_c2", 2.0e-8, 1.0e-9, "1/K^2", ("+0.0200", "0.0010", "ppm/K^2")),
    ("accel_bias_x_c1", 2.0 * G0 * 1e-6, 0.5 * G0 * 1e-6, "m/s^2/K", ("+2.00", "0.50",
                                                                      "µg/K")),
    ("gyro_bias_x_c1", 1.0e-6, 1.0e-7, "rad/s/K", ("+0.206", "0.021", "(°/h)/K")),
    # a quantity without a display unit stays in SI
    ("latitude_from_gyro_x", 45.123, 0.05, "deg", ("+45.123", "0.050", "deg")),
    ("c", 1.0e-6, 1.0e-7, "m/(rad/s)^2", ("+1.00e-6", "0.10e-6", "m/(rad/s)^2")),
])
def test_each_kind_of_quantity_has_one_display_unit(name, value, sigma, unit, expected):
    assert display_parameter(name, value, sigma, unit) == expected


def test_a_triad_parameter_keeps_its_kind_whatever_unit_it_is_given():
    assert display_unit("accel_b_x", "1") == ("µg", 1e-6 * G0)
    unit, scale = display_unit("gyro_bias_x", "")
    assert unit == "°/h" and math.isclose(scale, math.pi / 180 / 3600)


def test_a_scale_error_is_shown_as_it_is_not_as_a_deviation_from_one():
    """The Earth-rate test's scale error ŝ (docs/earth-rate-bias.md, (6)) is K − 1 already."""
    value, sigma, unit = display_parameter("gyro_scale_error_from_earth_rate_x", 2.0e-4, 1.0e-5,
                                           "1")
    assert unit == "ppm" and value.startswith("+200") and sigma == "10"
    # a scale factor K is shown as its deviation from 1
    assert display_parameter("gyro_K_x", 1.0 + 2.0e-4, 1.0e-5, "1")[0].startswith("+200")
