"""The compiled forward-backward filter gives scipy's sosfiltfilt bit for bit."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from imucalib.processing import _sos_kernel
from imucalib.processing._sos_kernel import sosfiltfilt_columns
from imucalib.processing.filtering import _butter_lowpass


@pytest.mark.parametrize("order", [1, 2, 3, 4, 7, 10])
@pytest.mark.parametrize("wn", [0.03, 0.2, 0.5, 0.93])
def test_equals_scipy_sosfiltfilt_bit_for_bit(order, wn):
    rng = np.random.default_rng(order * 100 + int(wn * 100))
    sos, padlen = _butter_lowpass(order, wn)
    zi = signal.sosfilt_zi(sos)
    shapes = [(padlen + 1, 1), (padlen + 7, 6), (3000, 6), (2500, 2)]
    for n, k in shapes:
        x = rng.normal(size=(n, k)) * 10.0 ** rng.uniform(-8, 4) + rng.normal() * 50.0
        want = signal.sosfiltfilt(sos, x, axis=0)
        got = sosfiltfilt_columns(sos, zi, x, padlen)
        assert got.shape == x.shape
        np.testing.assert_array_equal(got, want)
    x = np.asfortranarray(rng.normal(size=(400, 3)))  # any layout in, the same values
    np.testing.assert_array_equal(sosfiltfilt_columns(sos, zi, x, padlen),
                                  signal.sosfiltfilt(sos, x, axis=0))


def test_the_compiled_kernel_runs_and_the_input_is_left_alone():
    sos, padlen = _butter_lowpass(4, 0.2)
    x = np.random.default_rng(1).normal(size=(1000, 6))
    before = x.copy()
    a = sosfiltfilt_columns(sos, signal.sosfilt_zi(sos), x, padlen)
    assert _sos_kernel._STATE["kernel"] is not None, _sos_kernel._STATE["error"]
    np.testing.assert_array_equal(x, before)
    b = sosfiltfilt_columns(sos, signal.sosfilt_zi(sos), x, padlen, backend="scipy")
    np.testing.assert_array_equal(a, b)


def test_a_constant_and_a_step_pass_as_scipy_passes_them():
    sos, padlen = _butter_lowpass(4, 0.1)
    zi = signal.sosfilt_zi(sos)
    const = np.full((200, 2), 9.80665)
    np.testing.assert_array_equal(sosfiltfilt_columns(sos, zi, const, padlen),
                                  signal.sosfiltfilt(sos, const, axis=0))
    step = np.repeat([[0.0], [1.0]], 150, axis=0)
    np.testing.assert_array_equal(sosfiltfilt_columns(sos, zi, step, padlen),
                                  signal.sosfiltfilt(sos, step, axis=0))
