"""Tests of imucalib.processing.filtering: zero phase, −3/−6 dB points, validation."""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.errors import InvalidInputError
from imucalib.processing import compute_effective_cutoff_hz, lowpass_zero_phase

FS = 1000.0
T = np.arange(20_000) / FS  # 20 s


def _gain_phase(y: np.ndarray, f: float) -> tuple[float, float]:
    """Amplitude and phase of the f-component of y (middle half, away from the ends)."""
    mid = slice(T.size // 4, 3 * T.size // 4)
    A = np.column_stack([np.sin(2 * np.pi * f * T[mid]), np.cos(2 * np.pi * f * T[mid])])
    s, c = np.linalg.lstsq(A, y[mid], rcond=None)[0]
    return float(np.hypot(s, c)), float(np.arctan2(c, s))


@pytest.mark.parametrize("order", [2, 4, 6])
def test_gain_is_half_at_cutoff_and_root_half_at_effective_cutoff(order: int) -> None:
    res0 = lowpass_zero_phase(np.zeros(T.size), FS, bandwidth_hz=200.0, order=order)
    fc, f3 = res0.cutoff_hz, res0.effective_cutoff_hz
    assert fc == pytest.approx(50.0)
    assert f3 == pytest.approx(compute_effective_cutoff_hz(50.0, FS, order))
    for f, want in [(fc, 0.5), (f3, np.sqrt(0.5))]:
        y = lowpass_zero_phase(np.sin(2 * np.pi * f * T), FS, bandwidth_hz=200.0,
                               order=order).values
        gain, _ = _gain_phase(y, f)
        assert gain == pytest.approx(want, abs=2e-3)
    # the squared response: |H|² = 1/(1 + (tan(πf/fs)/tan(πfc/fs))^(2N)) at 2·fc
    f = 2 * fc
    y = lowpass_zero_phase(np.sin(2 * np.pi * f * T), FS, bandwidth_hz=200.0, order=order).values
    ratio = np.tan(np.pi * f / FS) / np.tan(np.pi * fc / FS)
    assert _gain_phase(y, f)[0] == pytest.approx(1 / (1 + ratio ** (2 * order)), rel=2e-2)


def test_zero_phase_in_passband_and_dc_preserved() -> None:
    for f in (1.0, 10.0, 30.0):
        x = np.sin(2 * np.pi * f * T + 0.3)
        y = lowpass_zero_phase(x, FS, bandwidth_hz=200.0).values
        _, ph_in = _gain_phase(x, f)
        _, ph_out = _gain_phase(y, f)
        assert ph_out == pytest.approx(ph_in, abs=1e-6)
    rng = np.random.default_rng(0)
    x = 3.0 + rng.normal(0.0, 1.0, T.size)
    y = lowpass_zero_phase(x, FS, bandwidth_hz=200.0, cutoff_fraction=0.2).values
    assert y.mean() == pytest.approx(x.mean(), abs=0.01)
    assert y.std() < 0.5 * x.std()  # 40 Hz of 500 Hz bandwidth kept


def test_columns_are_filtered_independently() -> None:
    rng = np.random.default_rng(1)
    x = rng.normal(size=(3000, 3))
    both = lowpass_zero_phase(x, FS, bandwidth_hz=150.0, cutoff_fraction=1 / 3).values
    for j in range(3):
        one = lowpass_zero_phase(x[:, j], FS, bandwidth_hz=150.0, cutoff_fraction=1 / 3).values
        np.testing.assert_allclose(both[:, j], one, rtol=1e-12, atol=1e-12)
    assert both.shape == x.shape


def test_fraction_limits_are_inclusive_and_overridable() -> None:
    x = np.random.default_rng(2).normal(size=500)
    for frac in (0.2, 0.25, 1 / 3):
        lowpass_zero_phase(x, FS, bandwidth_hz=200.0, cutoff_fraction=frac)
    res = lowpass_zero_phase(x, FS, bandwidth_hz=200.0, cutoff_fraction=0.5,
                             allow_any_fraction=True)
    assert res.cutoff_hz == pytest.approx(100.0)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"cutoff_fraction": 0.5}, r"`cutoff_fraction` must be within 1/5–1/3 of the IMU "
                                   r"bandwidth \(procedure P1, processing rule 2, docs/p1\.md\); "
                                   r"got 0\.5 \(pass allow_any_fraction=True"),
        ({"cutoff_fraction": 0.1}, r"must be within 1/5–1/3 .*; got 0.1"),
        ({"bandwidth_hz": 1500.0}, r"the cut-off 0.25 × 1500 Hz = 375 Hz must be below the Nyquist "
                                   r"frequency 250 Hz \(sample rate 500 Hz\)"),
        ({"order": 0}, r"`order` must be an integer in 1 … 10; got 0"),
        ({"order": 2.5}, r"`order` must be an integer in 1 … 10; got 2.5"),
        ({"values": np.ones(15)}, r"`values` must have more than 15 samples for an order-4 "
                                  r"zero-phase filter; got 15"),
        ({"values": [1.0, np.nan] * 20}, r"`values` must be finite"),
        ({"sample_rate_hz": -1.0}, r"`sample_rate_hz` must be > 0; got -1.0"),
    ],
)
def test_bad_inputs_raise_with_messages(kwargs: dict, match: str) -> None:
    args = {"values": np.ones(100), "sample_rate_hz": 500.0, "bandwidth_hz": 200.0}
    args.update(kwargs)
    values, fs = args.pop("values"), args.pop("sample_rate_hz")
    with pytest.raises(InvalidInputError, match=match):
        lowpass_zero_phase(values, fs, **args)


@pytest.mark.parametrize(("n", "k", "order", "frac", "fs", "bw"),
                         [(16, 1, 4, 0.25, 500.0, 200.0), (40, 3, 1, 0.2, 100.0, 40.0),
                          (6000, 6, 4, 0.25, 1000.0, 200.0), (3001, 2, 7, 1 / 3, 4000.0, 1000.0)])
def test_cached_design_equals_a_fresh_butter_and_sosfiltfilt(n: int, k: int, order: int,
                                                             frac: float, fs: float,
                                                             bw: float) -> None:
    # the cached design must give what a design made for this call gives, bit for bit
    from scipy import signal

    x = np.random.default_rng(n).normal(size=(n, k)) + 5.0
    for _ in range(2):  # the second call is served from the cache
        got = lowpass_zero_phase(x, fs, bandwidth_hz=bw, cutoff_fraction=frac, order=order)
        sos = signal.butter(order, frac * bw, btype="low", output="sos", fs=fs)
        np.testing.assert_array_equal(got.values, signal.sosfiltfilt(sos, x, axis=0))
    # a constant is kept exactly up to rounding (unit DC gain)
    const = lowpass_zero_phase(np.full(n, 2.5), fs, bandwidth_hz=bw, cutoff_fraction=frac,
                               order=order).values
    np.testing.assert_allclose(const, 2.5, rtol=1e-12)


def test_design_cache_keys_on_order_and_normalised_cutoff() -> None:
    from imucalib.processing.filtering import _butter_lowpass

    x = np.random.default_rng(4).normal(size=400)
    a = lowpass_zero_phase(x, 1000.0, bandwidth_hz=200.0).values  # 50 Hz of 1 kHz
    b = lowpass_zero_phase(x, 2000.0, bandwidth_hz=400.0).values  # 100 Hz of 2 kHz: same design
    c = lowpass_zero_phase(x, 1000.0, bandwidth_hz=160.0).values  # 40 Hz: another one
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, c)
    sos4, pad4 = _butter_lowpass(4, 0.1)
    sos3, pad3 = _butter_lowpass(3, 0.1)
    assert sos4.shape == (2, 6) and pad4 == 15 and sos3.shape == (2, 6) and pad3 == 12
