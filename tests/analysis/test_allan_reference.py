"""Exactness of the Allan-family deviations: NIST's published NBS14 values and allantools.

Provenance of the reference files: ``tests/data/README.md``.
"""

from __future__ import annotations

import csv
import math
from decimal import Decimal, getcontext
from fractions import Fraction
from pathlib import Path

import allantools
import numpy as np
import pytest

from imucalib.analysis import DEVIATION_KINDS, compute_deviation, resolve_averaging_factors

DATA = Path(__file__).parents[1] / "data"
# the two printed values that are not correctly rounded (tests/data/README.md)
MISPRINTS = {("nbs14_1000", "hdev", 100), ("nbs14_10", "hdev", 1)}


def nbs14_1000() -> np.ndarray:
    n = [1234567890]
    for _ in range(999):
        n.append((16807 * n[-1]) % 2147483647)
    return np.array(n, dtype=np.float64) / 2147483647


def published() -> list[dict[str, str]]:
    with open(DATA / "nbs14_published.csv", newline="") as f:
        return list(csv.DictReader(f))


def ten_point() -> tuple[list[str], list[str]]:
    with open(DATA / "nbs14_10point.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    return [r["phase"] for r in rows], [r["frequency"] for r in rows if r["frequency"]]


def printed_digits(text: str) -> int:
    """Significant digits printed in `text` (mantissa digits)."""
    mantissa = text.lower().split("e")[0].replace("-", "").replace(".", "").lstrip("0")
    return len(mantissa)


def round_like(value: float, text: str) -> float:
    digits = printed_digits(text)
    return float(f"{value:.{digits - 1}e}")


def exact_deviation(kind: str, phase: list[Fraction], m: int) -> Decimal:
    """Reference value in exact rational arithmetic (only the final square root is rounded)."""
    if kind == "hdev":
        xs = phase[::m]
        d = [xs[k + 3] - 3 * xs[k + 2] + 3 * xs[k + 1] - xs[k] for k in range(len(xs) - 3)]
        var = sum(v * v for v in d) / (6 * len(d) * m * m)
    else:  # pragma: no cover - only hdev is needed
        raise AssertionError(kind)
    getcontext().prec = 40
    return (Decimal(var.numerator) / Decimal(var.denominator)).sqrt()


def test_lcg_file_matches_generator_and_published_first_values() -> None:
    with open(DATA / "nbs14_1000_lcg.csv", newline="") as f:
        n = [int(r["n_lcg"]) for r in csv.DictReader(f)]
    assert n[1:4] == [395529916, 1209410747, 633705974]  # printed in Riley's paper
    assert np.array_equal(np.array(n) / 2147483647, nbs14_1000())


@pytest.mark.parametrize("row", [r for r in published() if r["dataset"] == "nbs14_1000"
                                 and ("nbs14_1000", r["kind"], int(r["tau_s"])) not in MISPRINTS],
                         ids=lambda r: f"{r['kind']}-{r['tau_s']}")
def test_nbs14_1000_point_every_printed_digit(row: dict[str, str]) -> None:
    kind, tau = row["kind"], int(row["tau_s"])
    got = compute_deviation(kind, nbs14_1000(), 1.0, taus=[tau]).deviation[0]
    assert f"{round_like(got, row['printed_value']):.6e}" == f"{float(row['printed_value']):.6e}"


@pytest.mark.parametrize("data_type", ["angle", "rate"])
def test_nbs14_10_point_every_printed_digit(data_type: str) -> None:
    phase, freq = ten_point()
    data = [float(v) for v in (phase if data_type == "angle" else freq)]
    checked = 0
    for row in (r for r in published() if r["dataset"] == "nbs14_10"):
        kind, tau = row["kind"], int(row["tau_s"])
        if ("nbs14_10", kind, tau) in MISPRINTS:
            continue
        got = compute_deviation(kind, data, 1.0, data_type=data_type, taus=[tau],
                                identify_noise=False).deviation[0]
        assert round_like(got, row["printed_value"]) == pytest.approx(
            float(row["printed_value"]), rel=1e-12), (kind, tau)
        checked += 1
    assert checked == 13


def test_misprinted_values_are_off_in_the_table() -> None:
    rows = {(r["dataset"], r["kind"], int(r["tau_s"])): r["printed_value"] for r in published()}
    # 1000-point HDEV at τ = 100 s
    y = [Fraction(int(v * 2147483647 + 0.5), 2147483647) for v in nbs14_1000()]
    x = [Fraction(0)]
    for v in y:
        x.append(x[-1] + v)
    exact = exact_deviation("hdev", x, 100)
    got = compute_deviation("hdev", nbs14_1000(), 1.0, taus=[100]).deviation[0]
    assert got == pytest.approx(float(exact), rel=1e-13)
    printed = rows[("nbs14_1000", "hdev", 100)]
    assert f"{float(exact):.6e}" != printed  # the correctly rounded value differs …
    assert abs(float(exact) - float(printed)) <= 1e-8  # … by less than one printed unit
    # 10-point HDEV at τ = 1 s equals OHDEV at τ = 1 s, printed one unit apart
    phase = [Fraction(v) for v in ten_point()[0]]
    exact10 = exact_deviation("hdev", phase, 1)
    got10 = compute_deviation("hdev", [float(v) for v in ten_point()[0]], 1.0,
                              data_type="angle", taus=[1], identify_noise=False).deviation[0]
    assert got10 == pytest.approx(float(exact10), rel=1e-13)
    assert f"{float(exact10):.5f}" == rows[("nbs14_10", "ohdev", 1)]
    assert rows[("nbs14_10", "hdev", 1)] != rows[("nbs14_10", "ohdev", 1)]


def random_record(n: int, seed: int) -> np.ndarray:
    """White + random-walk rate with a large offset (exercises the mean removal)."""
    rng = np.random.default_rng(seed)
    return 3.0 + rng.standard_normal(n) + 0.01 * np.cumsum(rng.standard_normal(n))


@pytest.mark.parametrize("kind", DEVIATION_KINDS)
@pytest.mark.parametrize("taus", ["octave", "decade"])
def test_agrees_with_allantools_to_1e12(kind: str, taus: str) -> None:
    y = random_record(50_001, seed=7)
    rate = 250.0
    ours = compute_deviation(kind, y, rate, taus=taus, identify_noise=False)
    tau_ref, dev_ref, _, n_ref = getattr(allantools, kind)(y, rate=rate, data_type="freq",
                                                           taus=taus)
    common, i_ours, i_ref = np.intersect1d(np.round(ours.taus_s * rate),
                                           np.round(tau_ref * rate), return_indices=True)
    assert common.size >= ours.taus_s.size - 1  # allantools keeps totdev up to m < n
    np.testing.assert_allclose(ours.deviation[i_ours], dev_ref[i_ref], rtol=1e-12, atol=0)
    np.testing.assert_array_equal(ours.n_terms[i_ours], n_ref[i_ref])


@pytest.mark.parametrize("kind", ["oadev", "mdev", "ohdev"])
def test_agrees_with_allantools_on_angle_input(kind: str) -> None:
    rng = np.random.default_rng(3)
    phase = np.cumsum(rng.standard_normal(20_000))
    ours = compute_deviation(kind, phase, 10.0, data_type="angle", identify_noise=False)
    _, dev_ref, _, _ = getattr(allantools, kind)(phase, rate=10.0, data_type="phase",
                                                 taus=ours.taus_s)
    np.testing.assert_allclose(ours.deviation, dev_ref, rtol=1e-12)


def test_all_taus_agree_with_allantools_on_a_short_record() -> None:
    y = random_record(300, seed=1)
    ours = compute_deviation("oadev", y, 1.0, taus="all", identify_noise=False)
    tau_ref, dev_ref, _, _ = allantools.oadev(y, rate=1.0, data_type="freq", taus="all")
    np.testing.assert_array_equal(ours.taus_s, tau_ref)
    np.testing.assert_allclose(ours.deviation, dev_ref, rtol=1e-12)


def test_tau_grids() -> None:
    assert resolve_averaging_factors("octave", 1001, 1.0).tolist() == [1, 2, 4, 8, 16, 32, 64,
                                                                       128, 256]
    assert resolve_averaging_factors("decade", 1001, 1.0).tolist() == [1, 2, 4, 10, 20, 40,
                                                                       100, 200, 400]
    per_decade = resolve_averaging_factors(5, 10_001, 1.0)
    assert per_decade[:8].tolist() == [1, 2, 3, 4, 6, 10, 16, 25]
    assert np.all(np.diff(np.log10(per_decade[5:])) == pytest.approx(0.2, abs=0.03))
    # explicit τ in seconds round to the sample interval
    assert resolve_averaging_factors([0.1, 0.25, 1.0], 10_001, 100.0).tolist() == [10, 25, 100]
    assert resolve_averaging_factors("octave", 1001, 1.0, "totdev")[-1] == 256  # m ≤ (n−1)/2
    assert resolve_averaging_factors("octave", 1001, 1.0, "mdev")[-1] == 256  # n − 3m + 1 ≥ 2


def test_tdev_is_tau_mdev_over_root3() -> None:
    y = random_record(10_000, seed=2)
    md = compute_deviation("mdev", y, 5.0, identify_noise=False)
    td = compute_deviation("tdev", y, 5.0, identify_noise=False)
    np.testing.assert_allclose(td.deviation, md.taus_s * md.deviation / math.sqrt(3), rtol=1e-14)
