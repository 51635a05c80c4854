"""GUM 7.2.6 rounding of a value and its uncertainty (report/numbers.py, docs/reporting.md)."""

from __future__ import annotations

import math
import re
from decimal import Decimal

import numpy as np
import pytest

from imucalib.errors import InvalidInputError
from imucalib.report.numbers import format_concise, format_pm, round_pair

NAN, INF = float("nan"), float("inf")

# (value, uncertainty, keyword arguments, "value ± u", concise form)
CASES = [
    (1.23456, 0.0567, {}, "1.235 ± 0.057", "1.235(57)"),
    # the 0.095 / 0.10 boundary: 0.095 already has two digits; 0.0995 is a tie and goes up
    (1.23456, 0.095, {}, "1.235 ± 0.095", "1.235(95)"),
    (1.23456, 0.0995, {}, "1.23 ± 0.10", "1.23(10)"),
    (1.23456, 0.09949, {}, "1.235 ± 0.099", "1.235(99)"),
    (1.23456, 0.0951, {"rounding": "up"}, "1.235 ± 0.096", "1.235(96)"),
    (1.23456, 0.095, {"rounding": "up"}, "1.235 ± 0.095", "1.235(95)"),
    (1.23456, 0.1 + 0.02, {"rounding": "up"}, "1.23 ± 0.12", "1.23(12)"),  # float noise
    # carries that add a digit: 9.96 -> 10, 0.0996 -> 0.10
    (12.345, 9.96, {}, "12 ± 10", "12(10)"),
    (0.5, 0.0996, {}, "0.50 ± 0.10", "0.50(10)"),
    (9.99996, 0.0012, {}, "10.0000 ± 0.0012", "10.0000(12)"),
    # value zero, rounding to zero, negative values, explicit sign, ties of the value
    (0.0, 0.034, {}, "0.000 ± 0.034", "0.000(34)"),
    (-0.0004, 0.034, {}, "0.000 ± 0.034", "0.000(34)"),
    (-3.14159, 0.021, {}, "-3.142 ± 0.021", "-3.142(21)"),
    (2.5, 0.3, {"sign": True}, "+2.50 ± 0.30", "+2.50(30)"),
    (0.1225, 0.011, {}, "0.123 ± 0.011", "0.123(11)"),
    (-0.1225, 0.011, {}, "-0.123 ± 0.011", "-0.123(11)"),
    # uncertainty larger than the value
    (0.3, 2.8, {}, "0.3 ± 2.8", "0.3(2.8)"),
    (0.003, 2.8, {}, "0.0 ± 2.8", "0.0(2.8)"),
    (10.345, 1.234, {}, "10.3 ± 1.2", "10.3(1.2)"),
    # value much larger than the uncertainty
    (123456.789, 0.012, {}, "123456.789 ± 0.012", "123456.789(12)"),
    # scientific notation: u >= 100, tiny or huge magnitudes
    (103.5726, 276.1, {}, "(1.0 ± 2.8)e2", "1.0(2.8)e2"),
    (-56789.0, 1234.0, {}, "(-5.68 ± 0.12)e4", "-5.68(12)e4"),
    (1.234e-7, 5.6e-9, {}, "(1.234 ± 0.056)e-7", "1.234(56)e-7"),
    (5e-4, 2e-5, {}, "(5.00 ± 0.20)e-4", "5.00(20)e-4"),
    (1e-3, 2e-5, {}, "0.001000 ± 0.000020", "0.001000(20)"),
    (1234567.891, 0.012, {}, "(1.234567891 ± 0.000000012)e6", "1.234567891(12)e6"),
    (0.0, 3.3e-9, {}, "(0.0 ± 3.3)e-9", "0.0(3.3)e-9"),
    # one significant digit
    (1.23456, 0.0567, {"digits": 1}, "1.23 ± 0.06", "1.23(6)"),
    # no usable uncertainty: the value to 6 significant digits
    (1.23456789, 0.0, {}, "1.23457", "1.23457"),
    (0.0, 0.0, {}, "0", "0"),
    (1.5, NAN, {}, "1.5 ± —", "1.5 ± —"),
    (-1.5, INF, {}, "-1.5 ± ∞", "-1.5 ± ∞"),
    (NAN, 0.0567, {}, "— ± 0.057", "— ± 0.057"),
    (-INF, 1.0, {}, "-inf ± 1.0", "-inf ± 1.0"),
]


@pytest.mark.parametrize(("value", "u", "kw", "pm", "concise"), CASES)
def test_table_of_cases(value: float, u: float, kw: dict, pm: str, concise: str) -> None:
    assert format_pm(value, u, **kw) == pm
    assert format_concise(value, u, **kw) == concise


def test_unit_follows_and_cells_carry_the_common_exponent() -> None:
    assert format_pm(1.234e-7, 5.6e-9, unit="rad") == "(1.234 ± 0.056)e-7 rad"
    r = round_pair(1.234e-7, 5.6e-9)
    assert (r.value_text, r.uncertainty_text, r.exponent, r.place) == (
        "1.234e-7", "0.056e-7", -7, -10)
    r = round_pair(103.5726, 27.6132, sign=True)
    assert (r.value_text, r.uncertainty_text, r.exponent) == ("+104", "28", None)
    assert round_pair(1.0, NAN).uncertainty_text == "—"


@pytest.mark.parametrize(("kw", "match"), [
    ({"uncertainty": -0.1}, "negative"),
    ({"digits": 0}, "digits"),
    ({"digits": True}, "digits"),
    ({"rounding": "down"}, "rounding"),
])
def test_bad_arguments_are_named(kw: dict, match: str) -> None:
    args = {"value": 1.0, "uncertainty": 0.1} | kw
    with pytest.raises(InvalidInputError, match=match):
        round_pair(args.pop("value"), args.pop("uncertainty"), **args)


_CELL = re.compile(r"^\(?([+-]?\d+(?:\.\d+)?) ± (\d+(?:\.\d+)?)\)?(?:e(-?\d+))?$")


@pytest.mark.parametrize("rounding", ["nearest", "up"])
def test_random_pairs_follow_the_rule(rounding: str) -> None:
    rng = np.random.default_rng(11)
    for _ in range(3000):
        u = float(10.0 ** rng.uniform(-12, 9))
        value = float(rng.choice([-1, 1]) * u * 10.0 ** rng.uniform(-3, 8))
        text = format_pm(value, u, rounding=rounding)  # type: ignore[arg-type]
        m = _CELL.match(text)
        assert m, text
        v_txt, u_txt, exp = m.groups()
        e = int(exp or 0)
        assert len(u_txt.replace(".", "").lstrip("0")) == 2, text
        decimals = len(u_txt.partition(".")[2])
        assert len(v_txt.partition(".")[2]) == decimals, text  # same decimal place
        ulp = Decimal(1).scaleb(e - decimals)
        shown_u = Decimal(u_txt).scaleb(e)
        shown_v = Decimal(v_txt).scaleb(e)
        exact_u = Decimal(format(u, ".12g"))
        assert abs(shown_v - Decimal(repr(value))) <= ulp / 2, text
        if rounding == "nearest":
            assert abs(shown_u - exact_u) <= ulp / 2, text
        else:
            assert Decimal(0) <= shown_u - exact_u < ulp, text
        assert math.isclose(float(shown_u), u, rel_tol=0.11), text


def test_a_value_far_larger_than_its_uncertainty_keeps_every_digit() -> None:
    # an Allan fit of a log whose time column was off by 1000 (issue 27): 1.89 ± 3.4e-30 needs
    # 32 digits, more than the default decimal context's 28
    assert format_pm(1.8946383186684301, 3.42986531479226e-30) == \
        "1.8946383186684301000000000000000 ± 0.0000000000000000000000000000034"
    assert format_pm(1e30, 1e-3) == ("(1.0000000000000000000000000000000000 ± "
                                     "0.0000000000000000000000000000000010)e30")
