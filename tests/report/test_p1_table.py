"""The P1 parameter table on the terminal: each row's own unit, GUM 7.2.6 rounding of its cells.

The rule checked (docs/reporting.md): the standard uncertainty has two significant digits and the
value ends at the same decimal place (JCGM 100:2008, 7.2.6), with a common exponent when the
number is shown in scientific notation.
"""

from __future__ import annotations

import re
from decimal import Decimal
from types import SimpleNamespace

import numpy as np
import pytest
from rich.console import Console

from imucalib import units
from imucalib.models.result import CalibrationResult
from imucalib.procedures.p1.console import render_calibration

AXES = "xyz"


def _triad_result() -> tuple[CalibrationResult, dict[str, tuple[float, float]]]:
    """A triad-model result with values and σ chosen to exercise rounding; also (value, σ) shown."""
    names: list[str] = []
    shown: dict[str, tuple[float, float]] = {}  # name -> (value, σ) in the display unit
    values: list[float] = []
    sigmas: list[float] = []
    rng = np.random.default_rng(7)
    for triad in ("accel", "gyro"):
        bias_unit = units.UG if triad == "accel" else units.DEG_PER_H
        for a in AXES:
            names.append(f"{triad}_bias_{a}")
            shown[names[-1]] = (103.5726 * (-1) ** AXES.index(a), 27.6132 / (1 + AXES.index(a)))
        for a in AXES:
            for b in AXES:
                names.append(f"{triad}_M_{a}{b}")
                shown[names[-1]] = (float(rng.normal(0, 300)), float(rng.uniform(0.5, 99.7)))
        if triad == "gyro":
            for a in AXES:
                for b in AXES:
                    names.append(f"gyro_G_{a}{b}")
                    shown[names[-1]] = (float(rng.normal(0, 0.3)), 0.0996)
        for n in names[len(values):]:
            scale = (bias_unit if "_bias_" in n else units.PPM if "_M_" in n
                     else units.DEG_PER_H / units.G0_MPS2)
            values.append(shown[n][0] * scale)
            sigmas.append(shown[n][1] * scale)
    si = {n: ("m/s^2" if "accel_bias" in n else "rad/s" if "gyro_bias" in n
              else "1" if "_M_" in n else "rad/s/(m/s^2)") for n in names}
    res = CalibrationResult(sensor_id="IMU-1", procedure="p1", model="triad",
                            param_names=tuple(names), values=np.array(values),
                            covariance=np.diag(np.square(sigmas)), units=si)
    return res, shown


def _analysis(result: CalibrationResult) -> SimpleNamespace:
    decision = SimpleNamespace(passed=True, summary=lambda: "PASS")
    return SimpleNamespace(result=result, checks=[], kalman_max_difference_sigma=float("nan"),
                           crlb_ratio={}, decision=decision)


def _rows(result: CalibrationResult) -> dict[str, list[str]]:
    console = Console(record=True, width=200, color_system=None)
    render_calibration(console, _analysis(result), [])
    text = console.export_text()
    rows = {}
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip().strip("│┃").split("│")]
        if cells and cells[0] in result.param_names:
            rows[cells[0]] = cells
    assert set(rows) == set(result.param_names), text
    return rows


_NUMBER = re.compile(r"^([+-]?)(\d+)(?:\.(\d+))?(?:e([+-]?\d+))?$")


def _parse(cell: str) -> tuple[Decimal, int, int, str]:
    """(number, decimal places, exponent, mantissa digits) of a printed cell."""
    m = _NUMBER.match(cell.replace("\u2212", "-"))
    assert m, f"not a number: {cell!r}"
    sign, whole, frac, exp = m.groups()
    frac = frac or ""
    e = int(exp or 0)
    return Decimal(f"{sign}{whole}.{frac or '0'}e{e}"), len(frac), e, (whole + frac)


def _expected_unit(name: str) -> str:
    triad, symbol, axes = name.split("_")
    if symbol == "bias":
        return "µg" if triad == "accel" else "°/h"
    if symbol == "M":
        return "ppm" if axes[0] == axes[1] else "µrad"
    return "(°/h)/g"


def test_each_row_shows_its_own_unit_never_a_choice() -> None:
    result, _ = _triad_result()
    for name, cells in _rows(result).items():
        assert "|" not in cells[3], cells
        assert cells[3] == _expected_unit(name), (name, cells)


def test_value_and_uncertainty_follow_the_two_significant_digit_rule() -> None:
    result, shown = _triad_result()
    for name, cells in _rows(result).items():
        value, v_places, v_exp, _ = _parse(cells[1])
        sigma, u_places, u_exp, u_digits = _parse(cells[2])
        assert len(u_digits.lstrip("0")) == 2, (name, cells)  # two significant digits
        assert (v_places, v_exp) == (u_places, u_exp), (name, cells)  # same decimal place
        ulp = Decimal(1).scaleb(u_exp - u_places)  # one unit of the last shown digit
        true_v, true_u = (Decimal(repr(x)) for x in shown[name])
        assert abs(value - true_v) <= ulp / 2 + Decimal("1e-9") * ulp, (name, cells)
        assert abs(sigma - true_u) <= ulp / 2 + Decimal("1e-9") * ulp, (name, cells)


def test_known_rows_print_as_a_metrologist_expects() -> None:
    result, _ = _triad_result()
    rows = _rows(result)
    assert rows["accel_bias_x"][1:4] == ["+104", "28", "µg"]
    assert rows["accel_bias_y"][1:4] == ["-104", "14", "µg"]
    assert rows["gyro_bias_z"][1:4] == ["+103.6", "9.2", "°/h"]
    assert rows["gyro_G_xy"][2] == "0.10"  # 0.0996 carries to 0.10, two digits kept


@pytest.mark.parametrize("symbol", ["K", "b"])
def test_per_axis_rows_have_their_units(symbol: str) -> None:
    names = tuple(f"{t}_{s}_{a}" for t in ("accel", "gyro") for s in ("K", "b") for a in AXES)
    values = np.array([1.0 + 12e-6 if "_K_" in n else 3e-4 for n in names])
    res = CalibrationResult(sensor_id="IMU-2", procedure="p1", model="per-axis",
                            param_names=names, values=values,
                            covariance=np.diag(np.full(len(names), (2.5e-6) ** 2)),
                            units=dict.fromkeys(names, "1"))
    rows = _rows(res)
    for name, cells in rows.items():
        if f"_{symbol}_" not in name:
            continue
        if symbol == "K":
            assert cells[1:4] == ["+12.0", "2.5", "ppm"], cells
        else:
            assert cells[3] == ("µg" if name.startswith("accel") else "°/h"), cells
