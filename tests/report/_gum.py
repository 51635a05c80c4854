"""GUM 7.2.6 rounding and P1 display units written independently of imucalib.report, for tests."""

from __future__ import annotations

from decimal import ROUND_HALF_UP, Decimal

from imucalib import units


def expected_cells(value: float, big_u: float) -> tuple[str, str]:
    """GUM 7.2.6 (docs/reporting.md), written independently of imucalib.report.numbers."""
    u = Decimal(f"{big_u:.12g}")
    exp_u = u.adjusted()
    q = Decimal(1).scaleb(exp_u - 1)  # two significant digits
    u2 = u.quantize(q, rounding=ROUND_HALF_UP)
    if u2 >= Decimal(100).scaleb(exp_u - 1):  # 9.96 -> 10
        q = Decimal(1).scaleb(exp_u)
        u2 = u.quantize(q, rounding=ROUND_HALF_UP)
    v = Decimal(repr(value)).quantize(q, rounding=ROUND_HALF_UP)
    place = q.as_tuple().exponent
    assert isinstance(place, int)
    lead = max(u2.adjusted(), v.adjusted() if v != 0 else u2.adjusted())
    if place > 0 or lead < -3 or lead >= 6:
        scale = Decimal(1).scaleb(-lead)
        vm, um, decimals, suffix = v * scale, u2 * scale, max(0, lead - place), f"e{lead}"
    else:
        vm, um, decimals, suffix = v, u2, max(0, -place), ""
    v_text = f"{abs(vm):.{decimals}f}"
    if vm != 0:
        v_text = ("-" if vm < 0 else "+") + v_text
    return v_text + suffix, f"{um:.{decimals}f}" + suffix


def shown_p1(name: str, value: float, sigma: float) -> tuple[float, float, str]:
    """A P1 parameter in its display unit (docs/reporting.md, "Units in the P1 table")."""
    triad, symbol, axes = name.split("_")
    if symbol == "bias":
        scale, unit = (units.UG, "µg") if triad == "accel" else (units.DEG_PER_H, "°/h")
    elif symbol == "M":
        scale, unit = (units.PPM, "ppm") if axes[0] == axes[1] else (units.URAD, "µrad")
    else:
        scale, unit = units.DEG_PER_H / units.G0_MPS2, "(°/h)/g"
    return value / scale, sigma / scale, unit
