"""Closed form (IN-2) and least squares (IN-3) on synthetic whole-revolution means."""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.errors import InsufficientExcitationError, MissingSegmentError
from imucalib.procedures.installation.misalignment import (
    closed_form_misalignment,
    lsq_misalignment,
)
from imucalib.procedures.rate_transfer.observations import RateWindow

M_TRUE = np.array([[2e-4, 5e-4, -3e-4], [-4e-4, -1e-4, 6e-4], [3e-4, -7e-4, 5e-5]])
G_TRUE = np.full((3, 3), 5e-7)
EARTH_UP = 5.2e-5
SE = 2e-5


def windows(rng: np.random.Generator, rates_dps: tuple[float, ...] = (30.0,),
            se: float = SE) -> list[RateWindow]:
    """±ω turns of 2 revolutions about each axis, means of y = b + G·g e_k + (I + M)·x."""
    out = []
    b = np.array([1e-5, -2e-5, 3e-5])
    for k, axis in enumerate("xyz"):
        for mag in rates_dps:
            for sign in (1.0, -1.0):
                w = np.deg2rad(sign * mag)
                x = np.zeros(3)
                x[k] = w + EARTH_UP
                y = b + G_TRUE[:, k] * 9.8 + (np.eye(3) + M_TRUE) @ x + rng.normal(0, se, 3)
                out.append(RateWindow(
                    step_index=len(out), label="", axis=axis, commanded_rate_dps=sign * mag,
                    table_rate_rps=w, n_revolutions=2, gyro_mean_rps=y,
                    gyro_se_rps=np.full(3, se), duration_s=4 * np.pi / abs(w),
                    block_variance=(10, np.full(3, se ** 2))))
    return out


def test_closed_form_and_least_squares_agree_and_recover_the_truth() -> None:
    rng = np.random.default_rng(3)
    for rates in ((30.0,), (20.0, 60.0)):
        ws = windows(rng, rates)
        closed = closed_form_misalignment(ws, EARTH_UP)
        lsq = lsq_misalignment(ws, EARTH_UP)
        # the same data: agreement far inside the closed form's σ
        assert np.max(np.abs(lsq.matrix - closed.matrix) / closed.std) < 0.05
        assert np.max(np.abs(closed.matrix - M_TRUE) / closed.std) < 4.0
        assert np.max(np.abs(lsq.matrix - M_TRUE) / lsq.std) < 4.0
        # the chapter's formula on integrated angles: (Θ₊ − Θ₋)/(2·2π·n)
        p, m = ws[0], ws[1]
        theta = (p.angle_rad - m.angle_rad) / (2 * 2 * np.pi * 2)
        if len(rates) == 1:
            assert theta[1:] == pytest.approx(closed.matrix[1:, 0], rel=1e-3, abs=1e-9)


def test_common_bias_form_has_redundancy_and_agrees() -> None:
    rng = np.random.default_rng(4)
    ws = windows(rng)
    lsq = lsq_misalignment(ws, EARTH_UP, common_bias=True)
    closed = closed_form_misalignment(ws, EARTH_UP)
    assert lsq.quality is not None and lsq.quality.dof == 6
    assert np.max(np.abs(lsq.matrix - closed.matrix) / closed.std) < 1.0


@pytest.mark.slow
def test_sigma_matches_the_monte_carlo_spread() -> None:
    rng = np.random.default_rng(5)
    draws, sig = [], []
    for _ in range(1500):
        c = closed_form_misalignment(windows(rng), EARTH_UP)
        draws.append(c.matrix.ravel())
        sig.append(c.std.ravel())
    ratio = np.std(draws, axis=0) / np.mean(sig, axis=0)
    assert np.all(np.abs(ratio - 1.0) < 0.15), ratio


def test_bad_inputs() -> None:
    ws = windows(np.random.default_rng(6))
    with pytest.raises(MissingSegmentError, match="−30 °/s turn is missing"):
        closed_form_misalignment([w for i, w in enumerate(ws) if i != 1], EARTH_UP)
    only_plus = [w for w in ws if w.commanded_rate_dps > 0]
    with pytest.raises(InsufficientExcitationError, match="pose constants"):
        lsq_misalignment(only_plus, EARTH_UP)
