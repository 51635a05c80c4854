"""A value with its uncertainty as text, rounded as the GUM asks (JCGM 100:2008, 7.2.6).

Contents
--------
:func:`round_pair`
    The value and its uncertainty rounded together: a :class:`RoundedPair` of cell texts (for
    tables with a value and an uncertainty column).
:func:`format_pm`
    ``"1.234 ± 0.056"``, ``"(1.234 ± 0.056)e-7"``.
:func:`format_concise`
    ``"1.2345(56)"``, ``"1.234(56)e-7"``: the uncertainty in units of the last digit.

The rule (docs/reporting.md)
----------------------------
1. The uncertainty u is rounded to `digits` significant digits (two by default, GUM 7.2.6:
   "at most two significant digits"). Rounding is **to the nearest**, a tie (a discarded part of
   exactly one half) going up, away from zero (ISO 80000-1, Annex B); ``rounding="up"`` instead
   always rounds up (towards +∞), which GUM 7.2.6 allows so that the uncertainty is never
   understated. The decimal digits rounded are those of u read to 12 significant digits, so
   float noise (0.12000000000000001) neither breaks ties nor rounds 0.12 up to 0.13, and 0.095
   stays 0.095.
2. A carry that adds a digit (9.96 → 10.0, 0.0996 → 0.100) is written with `digits` digits at the
   new place: 10, 0.10.
3. The value is rounded to the same decimal place as the rounded uncertainty (to the nearest,
   ties away from zero), whatever its size: 1234.5678 ± 0.012 → 1234.568 ± 0.012, and 0.003 ±
   2.8 → 0.0 ± 2.8. A value that rounds to zero prints without a sign.
4. Scientific notation with one common exponent is used when the last kept digit is left of the
   units place (rounded u ≥ 100, whose trailing zeros would be ambiguous), when the larger of
   |value| and u is below 0.001 (leading zeros) or is 10⁶ or more: ``(1.0 ± 2.8)e2``,
   ``(1.234 ± 0.056)e-7``, ``(1.2345678 ± 0.0000012)e6``. The exponent is that of the leading
   digit of the larger of the rounded |value| and u.
5. Without a usable uncertainty the value is shown to `fallback_digits` significant digits
   (``"%.6g"`` by default) and the uncertainty as ``"0"`` (exact), ``"—"`` (NaN: unknown) or
   ``"∞"``. A NaN value is ``"—"``; an infinite one ``"inf"`` / ``"-inf"``.

Minus signs are ASCII hyphen-minus, so a printed number can be pasted into a program.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from decimal import ROUND_CEILING, ROUND_HALF_UP, Decimal, localcontext
from typing import Literal

from imucalib.errors import InvalidInputError

__all__ = ["RoundedPair", "format_concise", "format_pm", "round_pair"]

Rounding = Literal["nearest", "up"]

#: Significant digits of the uncertainty read before rounding (drops float noise, rule 1).
_U_READ_DIGITS = 12
#: Rule 4: scientific notation when the larger of |value| and u is below 10**_SMALL_EXP …
_SMALL_EXP = -3
#: … or reaches 10**_LARGE_EXP.
_LARGE_EXP = 6


@dataclass(frozen=True)
class RoundedPair:
    """A value and its uncertainty rounded together (module docstring, rules 1-5).

    Attributes
    ----------
    value, uncertainty : str
        The mantissas, without the exponent (``"1.234"``, ``"0.056"``).
    exponent : int or None
        The common power of ten when scientific notation is used (rule 4), else None.
    place : int or None
        The decimal place of the last digit kept (−3 for 0.001); None without a usable
        uncertainty (rule 5).
    """

    value: str
    uncertainty: str
    exponent: int | None = None
    place: int | None = None

    @property
    def suffix(self) -> str:
        """``"e-7"`` for a common exponent, ``""`` otherwise."""
        return "" if self.exponent is None else f"e{self.exponent}"

    @property
    def value_text(self) -> str:
        """The value as a table cell: the mantissa and the common exponent."""
        return self.value + self.suffix if _is_number(self.value) else self.value

    @property
    def uncertainty_text(self) -> str:
        """The uncertainty as a table cell: the mantissa and the common exponent."""
        return self.uncertainty + self.suffix if _is_number(self.uncertainty) else self.uncertainty


def _is_number(text: str) -> bool:
    return text[-1:].isdigit()


def _check(value: float, uncertainty: float, digits: int, rounding: str) -> None:
    if not isinstance(digits, int) or isinstance(digits, bool) or not 1 <= digits <= 6:
        raise InvalidInputError(f"`digits` must be an integer from 1 to 6; got {digits!r}")
    if rounding not in ("nearest", "up"):
        raise InvalidInputError(f"`rounding` must be 'nearest' or 'up'; got {rounding!r}")
    if uncertainty < 0:
        raise InvalidInputError(f"`uncertainty` must not be negative; got {uncertainty!r}")


def _round_uncertainty(u: float, digits: int, rounding: Rounding) -> tuple[Decimal, int]:
    """Rules 1 and 2: (rounded u, decimal place of its last digit), for a finite u > 0."""
    d = Decimal(format(u, f".{_U_READ_DIGITS}g"))
    mode = ROUND_HALF_UP if rounding == "nearest" else ROUND_CEILING
    place = d.adjusted() - digits + 1
    r = d.quantize(Decimal(1).scaleb(place), rounding=mode)
    if r.adjusted() > d.adjusted():  # a carry added a digit: 9.96 -> 10.0 -> 10
        place += 1
        r = r.quantize(Decimal(1).scaleb(place), rounding=ROUND_HALF_UP)  # exact
    return r, place


def _fixed(d: Decimal, place: int, sign: bool) -> str:
    """`d` (already a multiple of 10**place) written with max(0, −place) decimals."""
    text = f"{abs(d):.{max(0, -place)}f}"
    if d.is_zero():
        return text
    return ("-" if d < 0 else "+" if sign else "") + text


def _fallback(value: float, uncertainty: float, sign: bool, fallback_digits: int,
              digits: int, rounding: Rounding) -> RoundedPair:
    """Rule 5: no usable uncertainty (or no usable value)."""
    if math.isnan(uncertainty):
        u_text = "—"
    elif math.isinf(uncertainty):
        u_text = "∞"
    elif uncertainty == 0:
        u_text = "0"
    else:  # a usable uncertainty beside a NaN or infinite value: rules 1 and 2 alone
        u_text = _fixed(*_round_uncertainty(uncertainty, digits, rounding), False)
    if math.isnan(value):
        return RoundedPair("—", u_text)
    if math.isinf(value):
        return RoundedPair(("-" if value < 0 else "+" if sign else "") + "inf", u_text)
    text = f"{value:{'+' if sign else ''}.{fallback_digits}g}"
    return RoundedPair("0" if value == 0 else text, u_text)


def round_pair(value: float, uncertainty: float, *, digits: int = 2,
               rounding: Rounding = "nearest", sign: bool = False,
               fallback_digits: int = 6) -> RoundedPair:
    """Round a value and its uncertainty together (JCGM 100:2008, 7.2.6; module docstring).

    Parameters
    ----------
    value : float
        The estimate, in the unit it is shown in.
    uncertainty : float
        Its standard (or expanded) uncertainty, same unit, ≥ 0 (NaN and inf allowed: rule 5).
    digits : int
        Significant digits of the uncertainty, 1 to 6 (default 2).
    rounding : {"nearest", "up"}
        How the uncertainty is rounded (rule 1); the value is always rounded to the nearest.
    sign : bool
        Write ``+`` before a positive value (tables of signed parameters).
    fallback_digits : int
        Significant digits of the value when there is no usable uncertainty (rule 5).

    Returns
    -------
    RoundedPair

    Raises
    ------
    InvalidInputError
        A negative uncertainty, `digits` outside 1..6, or an unknown `rounding`.
    """
    value, uncertainty = float(value), float(uncertainty)
    _check(value, uncertainty, digits, rounding)
    if not math.isfinite(value) or not math.isfinite(uncertainty) or uncertainty == 0:
        return _fallback(value, uncertainty, sign, fallback_digits, digits, rounding)
    u, place = _round_uncertainty(uncertainty, digits, rounding)
    exact = Decimal(repr(value))
    with localcontext() as ctx:  # digits enough for a value far larger than its uncertainty
        ctx.prec = max(ctx.prec, exact.adjusted() - place + 3)
        v = exact.quantize(Decimal(1).scaleb(place), rounding=ROUND_HALF_UP)
    lead = max(u.adjusted(), v.adjusted() if not v.is_zero() else u.adjusted())
    if place > 0 or lead < _SMALL_EXP or lead >= _LARGE_EXP:
        shift = Decimal(1).scaleb(-lead)
        return RoundedPair(_fixed(v * shift, place - lead, sign),
                           _fixed(u * shift, place - lead, False), lead, place)
    return RoundedPair(_fixed(v, place, sign), _fixed(u, place, False), None, place)


def format_pm(value: float, uncertainty: float, *, digits: int = 2,
              rounding: Rounding = "nearest", sign: bool = False, unit: str = "",
              fallback_digits: int = 6) -> str:
    """``"value ± uncertainty"`` rounded by :func:`round_pair` (same parameters).

    ``"1.234 ± 0.056 µg"``, ``"(1.234 ± 0.056)e-7 µg"``; without a usable uncertainty the value
    alone for u = 0, ``"value ± —"`` for NaN and ``"value ± ∞"`` for inf. `unit`, when given,
    follows after a space.
    """
    r = round_pair(value, uncertainty, digits=digits, rounding=rounding, sign=sign,
                   fallback_digits=fallback_digits)
    tail = f" {unit}" if unit else ""
    if r.place is None:
        return (r.value if r.uncertainty == "0" else f"{r.value} ± {r.uncertainty}") + tail
    if r.exponent is None:
        return f"{r.value} ± {r.uncertainty}{tail}"
    return f"({r.value} ± {r.uncertainty}){r.suffix}{tail}"


def format_concise(value: float, uncertainty: float, *, digits: int = 2,
                   rounding: Rounding = "nearest", sign: bool = False, unit: str = "",
                   fallback_digits: int = 6) -> str:
    """Write the concise form ``"1.2345(56)"`` (JCGM 100:2008, 7.2.2, its second form).

    The digits in parentheses are the uncertainty in units of the value's last digit; one that
    reaches past the decimal point keeps its point (``"10.3(1.2)"``); with a common exponent the
    form is ``"1.234(56)e-7"``. Other parameters and rule 5 as in :func:`format_pm`.
    """
    r = round_pair(value, uncertainty, digits=digits, rounding=rounding, sign=sign,
                   fallback_digits=fallback_digits)
    tail = f" {unit}" if unit else ""
    if r.place is None:
        return (r.value if r.uncertainty == "0" else f"{r.value} ± {r.uncertainty}") + tail
    u = r.uncertainty
    inner = u if "." in u and not u.startswith("0") else str(int(u.replace(".", "")))
    return f"{r.value}({inner}){r.suffix}{tail}"
