"""P1 and P2 read their windows through the shared reader (procedures/common/window_checks.py).

A sample flagged saturated or a dropout beyond the limits refuses the window that holds it,
naming it, as in every other procedure; untouched windows give the same observations.
"""

from __future__ import annotations

import shutil

import h5py
import pytest

from imucalib.errors import MissingSegmentError, SaturationError
from imucalib.io import open_recording
from imucalib.procedures.common.window_checks import BlockNoiseLimits, WindowLimits
from imucalib.procedures.p1.observations import P1Processing, extract_p1_observations
from imucalib.procedures.p2.batch import analyze_p2
from imucalib.procedures.p2.observations import P2Processing

from ._p2_twin import run_twin_p2, twin_equipment, twin_plan
from .test_p2_bad_inputs import _SMALL


def _first_static_window(path, unit, role):
    with open_recording(path) as rec:
        step = next(s for s in rec.steps if s.role == role and s.has_valid_window
                    and s.status == "done")
        i0, i1 = rec.row_range("imu", unit, step.valid_start_s, step.valid_end_s)
    return step, i0, i1


def _flag(path, unit, row, column="saturated", value=True):
    with h5py.File(path, "r+") as f:
        f[f"streams/imu/{unit}/{column}"][row] = value


def test_p1_and_p2_options_compose_the_window_limits():
    assert issubclass(P1Processing, WindowLimits) and issubclass(P2Processing, WindowLimits)
    assert not issubclass(P1Processing, BlockNoiseLimits)  # their σ come from noise models
    assert P1Processing().max_lost_fraction == P2Processing().max_lost_fraction == 0.01


def test_p1_refuses_a_saturated_window_and_a_dropout(consumer_run, tmp_path):
    with open_recording(consumer_run) as rec:
        unit = next(s.unit for s in rec.streams if s.device == "imu")
    step, i0, i1 = _first_static_window(consumer_run, unit, "p1.accel-position")
    bad = tmp_path / "saturated.h5"
    shutil.copy(consumer_run, bad)
    _flag(bad, unit, (i0 + i1) // 2)
    with open_recording(bad) as rec, pytest.raises(
            SaturationError, match=rf"^step {step.index}: 1 of \d+ samples flagged saturated"):
        extract_p1_observations(rec)
    gap = tmp_path / "gap.h5"
    shutil.copy(consumer_run, gap)
    with h5py.File(gap, "r+") as f:  # the counter jumps: 0.5 s of samples lost mid-window
        counter = f[f"streams/imu/{unit}/counter"]
        counter[(i0 + i1) // 2:] = counter[(i0 + i1) // 2:] + 60  # > 0.5 s at 100 Hz
    with open_recording(gap) as rec, pytest.raises(MissingSegmentError,
                                                   match=r"lost to dropouts"):
        extract_p1_observations(rec)
    tight = P1Processing(max_lost_fraction=0.5, max_gap_s=0.1)  # the limits are options
    with open_recording(gap) as rec, pytest.raises(
            MissingSegmentError, match=rf"^step {step.index}: 60 of \d+ samples lost to dropouts "
                                       r"\(longest gap .* at most 50% and 0.1 s are accepted"):
        extract_p1_observations(rec, processing=tight)


def test_p2_names_the_saturated_window_of_one_unit(tmp_path):
    plan = twin_plan(twin_equipment(1), **_SMALL)
    path = run_twin_p2(plan, tmp_path / "p2.h5", truth_streams=False)
    with open_recording(path) as rec:
        unit = next(s.unit for s in rec.streams if s.device == "imu")
    step, i0, _ = _first_static_window(path, unit, "p2.static")
    _flag(path, unit, i0 + 3)
    (result,) = analyze_p2(path).results
    # a refused window loses its temperature point, which fails the unit (docs/p2.md)
    assert result.error_type == "MissingSegmentError", result.error
    assert f"unit {unit}, temperature point 0" in result.error
    assert f"step {step.index} " in result.error and "flagged saturated" in result.error
