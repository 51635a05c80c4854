"""P1 fits a window's own Allan variance only where its standard error needs it.

With a static record long enough for the noise model (``NOISE_RECORD_MIN_S``), the model gives
every window its standard error, so the short windows skip their own fit; without one, every
window keeps its own. Either way the observations are those of fitting every window.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from imucalib.io import open_recording
from imucalib.procedures.common.noise import NOISE_RECORD_MIN_S
from imucalib.procedures.p1 import observations as p1_obs


def _all_own(todo):
    return [(step, role, True) for step, role in todo]


def _without(w, *names):
    return {k: v for k, v in dataclasses.asdict(w).items() if k not in names}


def _same(a, b) -> bool:
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True)
    return a == b


def test_short_windows_skip_their_own_fit_and_change_nothing(consumer_run, monkeypatch):
    with open_recording(consumer_run) as rec:
        fast = p1_obs.extract_p1_observations(rec)
        monkeypatch.setattr(p1_obs, "_with_noise_flags", _all_own)
        full = p1_obs.extract_p1_observations(rec)
    assert fast.noise and full.noise
    long = [w for w in fast.windows if w.kind == "static" and w.duration_s >= NOISE_RECORD_MIN_S]
    short = [w for w in fast.windows if w not in long]
    assert long and len(short) > 3
    assert all(w.allan_fit is not None for w in long)
    assert all(w.allan_fit is None for w in short)  # the fit this saves
    assert all(w.allan_fit is not None for w in full.windows)
    for a, b in zip(fast.windows, full.windows, strict=True):
        assert _same(_without(a, "allan_fit"), _without(b, "allan_fit"))
        assert np.all(np.isfinite(a.gyro_se_rps)) and np.all(np.isfinite(a.accel_se_mps2))


def test_without_a_noise_model_every_window_gets_its_own_fit(consumer_run, monkeypatch):
    monkeypatch.setattr(p1_obs, "estimate_noise", lambda windows: {})
    with open_recording(consumer_run) as rec:
        fast = p1_obs.extract_p1_observations(rec)  # guessed a model, reduced again without
        monkeypatch.setattr(p1_obs, "_with_noise_flags", _all_own)
        full = p1_obs.extract_p1_observations(rec)
    assert not fast.noise
    assert all(w.allan_fit is not None for w in fast.windows)
    for a, b in zip(fast.windows, full.windows, strict=True):
        assert _same(dataclasses.asdict(a), dataclasses.asdict(b))
        assert np.all(np.isfinite(a.gyro_se_rps))
