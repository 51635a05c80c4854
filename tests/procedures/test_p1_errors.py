"""Bad P1 inputs get typed errors naming the missing or bad part."""

from __future__ import annotations

import h5py
import numpy as np
import pytest

from imucalib.errors import (
    InsufficientExcitationError,
    InvalidInputError,
    RecordingError,
    UnitError,
)
from imucalib.io import open_recording
from imucalib.models.correct import correct_imu
from imucalib.procedures.p1.analysis import P1Options, analyze_p1
from imucalib.station.runner import run_plan
from imucalib.station.sim import SimStation

FAST = P1Options(hash_recording=False)


def without(plan, label_part: str):
    steps = tuple(s for s in plan.steps if label_part not in s.label)
    return plan.model_copy(update={"steps": steps})


def test_a_recording_missing_a_position(p1_tools, tmp_path):
    plan = without(p1_tools.p1_plan("tactical", 2), "X down")
    path = p1_tools.run_twin(plan, tmp_path / "m.h5")
    with pytest.raises(InsufficientExcitationError,
                       match=r"needs the six P1 positions; the recording has 5") as err:
        analyze_p1(path, options=FAST)
    assert "accel_M_xx" in err.value.unobservable


def test_a_rank_deficient_plan_without_z_rates_names_the_z_parameters(p1_tools, tmp_path):
    plan = p1_tools.p1_plan("tactical", 2, z_rates=False)
    path = p1_tools.run_twin(plan, tmp_path / "z.h5")
    with pytest.raises(InsufficientExcitationError) as err:
        analyze_p1(path, options=FAST)
    assert {"gyro_M_xz", "gyro_M_yz", "gyro_M_zz"} <= set(err.value.unobservable)
    assert "gyro_M_zz" in str(err.value)


def test_nan_samples_in_a_window(p1_tools, tmp_path):
    # a navigation-grade twin does not quantize: its samples are stored as float64, which can
    # hold NaN (the counts of a quantizing IMU cannot)
    path = p1_tools.run_twin(p1_tools.p1_plan("navigation", 4), tmp_path / "n.h5")
    with open_recording(path) as rec:
        step = next(s for s in rec.steps if "six-position" in rec.metadata["plan_toml"]
                    and s.label.endswith("(pitch 0, roll 0)"))
        i0, _ = rec.row_range("imu", "IMU-0001", step.valid_start_s, step.valid_end_s)
    with h5py.File(path, "r+") as f:
        f["streams/imu/IMU-0001/accel_x_mps2"][i0 + 5] = np.nan
    with pytest.raises(InvalidInputError, match=rf"step {step.index}: the window holds NaN"):
        analyze_p1(path, options=FAST)


def test_a_table_that_never_settled_leaves_no_valid_window(p1_tools, tmp_path):
    plan = p1_tools.p1_plan("tactical", 6)
    data = plan.model_dump(mode="json", exclude_none=True)
    data["guards"]["settle_timeout_s"] = 5.0
    data["guards"]["on_trip"] = "stop"
    import tomli_w

    from imucalib.plan import parse_plan

    strict = parse_plan(tomli_w.dumps(data))
    station = SimStation(strict.twin)
    station.at(20.0, lambda: station.table.add_position_drift(0, 2e-5, 1e6))
    summary = run_plan(strict, station, tmp_path / "s.h5")
    assert summary.status == "aborted" and "never settled" in summary.reason
    with pytest.raises(RecordingError, match=r"no completed calibration or verification window "
                                             r"for IMU-0001 \(step 2 \(rep1 Z up .*never settled"):
        analyze_p1(tmp_path / "s.h5", options=FAST)


def test_a_recording_without_a_plan(tmp_path, p1_tools):
    p1_tools.write_planless_recording(tmp_path / "np.h5")
    with pytest.raises(RecordingError, match="holds no plan"):
        analyze_p1(tmp_path / "np.h5", options=FAST)


def test_wrong_units_when_applying_a_result(tactical_run):
    result = analyze_p1(tactical_run, options=FAST).result
    samples = np.zeros((4, 3))
    with pytest.raises(UnitError, match=r"made from accel data in 'm/s\^2'; the data given are "
                                         r"in 'counts'"):
        correct_imu(samples, samples, result, accel_unit="counts")
    with pytest.raises(InvalidInputError, match="needs the accelerometer data too"):
        correct_imu(samples, None, result)
