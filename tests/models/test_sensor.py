"""Tests of imucalib.models.sensor: low-pass, saturation, quantization and their chunked state."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imucalib.errors import ConfigurationError, InvalidInputError
from imucalib.models.sensor import OutputChain, SensorSpec, apply_output_chain

FS = 1000.0


def sine_amplitude(y: np.ndarray, f_hz: float, fs: float) -> float:
    """Least-squares amplitude of a sine of known frequency in y."""
    t = np.arange(y.size) / fs
    basis = np.column_stack([np.sin(2 * np.pi * f_hz * t), np.cos(2 * np.pi * f_hz * t)])
    coef, *_ = np.linalg.lstsq(basis, y, rcond=None)
    return float(np.hypot(*coef))


def test_empty_spec_passes_values_through_as_a_copy() -> None:
    x = np.random.default_rng(0).standard_normal((100, 3))
    out = apply_output_chain(x, SensorSpec(), FS)
    np.testing.assert_array_equal(out.values, x)
    assert out.values is not x and not out.saturated.any()
    assert out.saturated.shape == (100, 3) and out.saturated.dtype == bool


def test_saturation_clips_and_flags() -> None:
    x = np.array([[2.0, -3.0, 0.5], [1.0, -1.0, 0.999]])
    out = apply_output_chain(x, SensorSpec(range=1.0), FS)
    np.testing.assert_array_equal(out.values, [[1.0, -1.0, 0.5], [1.0, -1.0, 0.999]])
    np.testing.assert_array_equal(out.saturated, [[True, True, False], [False, False, False]])


def test_resolution_bits_give_a_twos_complement_grid() -> None:
    spec = SensorSpec(range=1.0, resolution_bits=8)
    lsb = 2.0 / 256
    assert spec.effective_lsb == lsb and spec.code_limits() == (-128.0, 127.0)
    x = np.array([[0.3, -1.0, 1.5], [1.0 - lsb, -1.0 - 0.6 * lsb, 1.0 - 0.4 * lsb]])
    out = apply_output_chain(x, spec, FS)
    np.testing.assert_array_equal(out.values, [[38 * lsb, -1.0, 1.0 - lsb],
                                               [1.0 - lsb, -1.0, 1.0 - lsb]])
    # the top code is range − LSB: an input rounding above it is clipped and flagged
    np.testing.assert_array_equal(out.saturated, [[False, False, True], [False, True, True]])


def test_lsb_alone_gives_a_symmetric_grid() -> None:
    spec = SensorSpec(range=1.0, lsb=0.3)
    assert spec.code_limits() == (-3.0, 3.0)
    out = apply_output_chain(np.array([[0.44, -0.46, 5.0]]), spec, FS)
    np.testing.assert_allclose(out.values, [[0.3, -0.6, 0.9]], rtol=1e-15)
    np.testing.assert_array_equal(out.saturated, [[False, False, True]])
    # no range: no limit; ties round half to even (codes 0.5, 1.5, −2.5 → 0, 2, −2)
    unlimited = apply_output_chain(np.array([[0.125, 0.375, -0.625], [1e9 + 0.1, 0.0, 0.0]]),
                                   SensorSpec(lsb=0.25), FS)
    np.testing.assert_array_equal(unlimited.values, [[0.0, 0.5, -0.5], [1e9, 0.0, 0.0]])
    assert not unlimited.saturated.any()


@settings(max_examples=50, deadline=None)
@given(
    bits=st.integers(4, 24),
    full_scale=st.floats(1e-3, 1e3),
    seed=st.integers(0, 2**32 - 1),
    bandwidth=st.one_of(st.none(), st.floats(1.0, 400.0)),
)
def test_outputs_lie_on_the_lsb_grid_within_the_codes(bits: int, full_scale: float, seed: int,
                                                        bandwidth: float | None) -> None:
    spec = SensorSpec(range=full_scale, resolution_bits=bits, bandwidth_hz=bandwidth)
    x = np.random.default_rng(seed).normal(0.0, full_scale, (300, 3))
    out = apply_output_chain(x, spec, FS)
    codes = out.values / spec.effective_lsb
    np.testing.assert_allclose(codes, np.rint(codes), atol=1e-6)
    assert codes.min() >= -(2 ** (bits - 1)) - 1e-6 and codes.max() <= 2 ** (bits - 1) - 1 + 1e-6
    lo, hi = spec.code_limits()  # type: ignore[misc]
    on_rail = (codes <= lo + 1e-6) | (codes >= hi - 1e-6)
    assert np.all(~out.saturated | on_rail)  # a flagged sample sits on a rail


def test_low_pass_attenuates_above_and_passes_below_bandwidth() -> None:
    bw = 20.0
    spec = SensorSpec(bandwidth_hz=bw)
    t = np.arange(20_000) / FS
    for f_hz, lo, hi in [(0.1 * bw, 0.999, 1.0001), (bw, 0.7061, 0.7081), (10 * bw, 0.0, 0.012)]:
        x = np.repeat(np.sin(2 * np.pi * f_hz * t)[:, None], 3, axis=1)
        y = apply_output_chain(x, spec, FS).values[5000:, 0]  # past the transient
        amp = sine_amplitude(y, f_hz, FS)
        assert lo < amp < hi, (f_hz, amp)


def test_low_pass_starts_in_steady_state() -> None:
    x = np.tile([1.5, -2.0, 9.81], (50, 1))
    out = apply_output_chain(x, SensorSpec(bandwidth_hz=100.0), FS)
    np.testing.assert_allclose(out.values, x, rtol=1e-12)


def test_chunked_processing_equals_one_shot_exactly() -> None:
    spec = SensorSpec(range=2.0, resolution_bits=12, bandwidth_hz=50.0)
    x = np.random.default_rng(1).normal(0.0, 1.5, (10_000, 3))
    one = apply_output_chain(x, spec, FS)
    chain = OutputChain(spec, FS)
    parts = [chain.process(x[a:b]) for a, b in [(0, 1), (1, 7), (7, 4000), (4000, 4000),
                                                (4000, 10_000)]]
    np.testing.assert_array_equal(np.concatenate([p.values for p in parts]), one.values)
    np.testing.assert_array_equal(np.concatenate([p.saturated for p in parts]), one.saturated)
    assert one.saturated.any() and not one.saturated.all()


def test_process_leaves_the_input_untouched() -> None:
    x = np.random.default_rng(2).standard_normal((500, 3))
    keep = x.copy()
    for spec in (SensorSpec(range=0.5, lsb=0.01), SensorSpec(bandwidth_hz=10.0, range=0.5)):
        apply_output_chain(x, spec, FS)
        np.testing.assert_array_equal(x, keep)


def test_fortran_ordered_and_integer_input_are_accepted() -> None:
    x = np.asfortranarray(np.arange(30, dtype=np.int64).reshape(10, 3))
    out = apply_output_chain(x, SensorSpec(lsb=2.0), FS)
    np.testing.assert_array_equal(out.values, 2 * np.rint(x / 2))


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"resolution_bits": 16}, r"`resolution_bits` \(16\) requires `range`"),
        ({"range": 1.0, "resolution_bits": 16, "lsb": 1e-3}, r"give `resolution_bits`.*not both"),
        ({"range": 1.0, "resolution_bits": 0}, r"`resolution_bits` must be an integer in 1 … 64"),
        ({"range": 1.0, "resolution_bits": True}, r"`resolution_bits` must be an integer"),
        ({"range": 1.0, "resolution_bits": 12.5}, r"`resolution_bits` must be an integer"),
        ({"range": -1.0}, r"`range` must be > 0; got -1.0"),
        ({"lsb": float("nan")}, r"`lsb` must be finite; got nan"),
        ({"bandwidth_hz": 0.0}, r"`bandwidth_hz` must be > 0"),
    ],
)
def test_bad_specs(kwargs: dict, match: str) -> None:
    with pytest.raises(ConfigurationError, match=match):
        SensorSpec(**kwargs)


def test_bandwidth_at_or_above_half_the_output_rate_is_rejected() -> None:
    with pytest.raises(ConfigurationError, match=r"below half the output data rate \(500.0 Hz\); "
                                                 r"got 500.0 Hz"):
        OutputChain(SensorSpec(bandwidth_hz=500.0), FS)
    OutputChain(SensorSpec(bandwidth_hz=499.0), FS)  # just below is fine


@pytest.mark.parametrize(
    ("values", "match"),
    [
        (np.array([[0.0, math.nan, 1.0]]), r"`values` must be finite; got 1 NaN"),
        (np.array([[0.0, math.inf, -math.inf]]), r"`values` must be finite; got 2 NaN"),
        (np.zeros((4, 2)), r"`values` must have shape \(n, 3\); got \(4, 2\)"),
        ("abc", r"`values` must be numeric"),
    ],
)
def test_bad_values(values: object, match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        OutputChain(SensorSpec(bandwidth_hz=10.0), FS).process(values)  # type: ignore[arg-type]


def test_bad_chain_arguments() -> None:
    with pytest.raises(InvalidInputError, match=r"`sample_rate_hz` must be > 0"):
        OutputChain(SensorSpec(), 0.0)
    with pytest.raises(InvalidInputError, match=r"`spec` must be a SensorSpec"):
        OutputChain({"range": 1.0}, FS)  # type: ignore[arg-type]


def test_empty_chunk_keeps_the_state() -> None:
    spec = SensorSpec(bandwidth_hz=30.0)
    x = np.random.default_rng(3).standard_normal((200, 3))
    chain = OutputChain(spec, FS)
    first = chain.process(x[:100]).values
    assert chain.process(np.zeros((0, 3))).values.shape == (0, 3)
    second = chain.process(x[100:]).values
    np.testing.assert_array_equal(np.concatenate([first, second]),
                                  apply_output_chain(x, spec, FS).values)
