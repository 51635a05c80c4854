"""Format v2 step fields: role, tags and units are written, read, validated and recovered."""

from __future__ import annotations

import shutil
from pathlib import Path

import h5py
import pytest

from imucalib.errors import InvalidInputError, RecordingCorruptError
from imucalib.io import ColumnSpec, RecordingWriter, StreamSpec, open_recording
from imucalib.io.recover import recover_recording
from imucalib.io.step_roles import role_from_tags

SPEC = StreamSpec("imu", "IMU-0001", {"gyro_x_rps": ColumnSpec("rad/s")})
V1_FILE = Path(__file__).parents[1] / "data" / "p1_v1.h5"


def write(path: Path) -> Path:
    with RecordingWriter(path, streams=[SPEC]) as w:
        w.append("imu", "IMU-0001", {"time_s": [0.0, 1.0], "gyro_x_rps": [0.0, 0.0]})
        i = w.begin_step("position", "Z up", 0.0, commanded={"angles_deg": [0, 0]},
                         role="p1.accel-position",
                         tags=("calibration", "six-position", "repetition=2", "température"),
                         units=("IMU-0001",))
        w.update_step(i, t_end_s=1.0, valid_start_s=0.2, valid_end_s=0.9, status="done")
        w.begin_step("static", "old-style", 1.0)
    return path


def test_role_tags_and_units_round_trip(tmp_path):
    with open_recording(write(tmp_path / "r.h5")) as rec:
        assert rec.format_version >= 2  # version 2 added the step fields
        first, second = rec.steps
    assert first.role == "p1.accel-position"
    assert first.tags == ("calibration", "six-position", "repetition=2", "température")
    assert first.units == ("IMU-0001",)
    assert first.tag_value("repetition") == "2" and first.tag_value("orientation") is None
    assert first.concerns("IMU-0001") and not first.concerns("IMU-0002")
    assert (second.role, second.tags, second.units) == ("", (), ())
    assert second.concerns("IMU-0002")


def test_tags_and_units_can_be_updated(tmp_path):
    path = write(tmp_path / "r.h5")
    with RecordingWriter.reopen(path) as w:
        w.update_step(1, role="p1.gyro-bias", tags=["gyro-bias"], units=[])
    with open_recording(path) as rec:
        step = rec.steps[1]
    assert (step.role, step.tags, step.units) == ("p1.gyro-bias", ("gyro-bias",), ())


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"tags": "calibration"}, r"`tags` must be a sequence of strings"),
    ({"tags": ("ok", 3)}, r"`tags`\[1\] must be a string"),
    ({"units": ("IMU 1",)}, r"`units`\[0\] must match"),
    ({"role": "x" * 513}, r"`role` is 513 bytes"),
    ({"tags": ("t" * 5000,)}, r"`tags` is \d+ bytes"),
])
def test_bad_role_tags_or_units_are_refused(tmp_path, kwargs, message):
    with RecordingWriter(tmp_path / "r.h5", streams=[SPEC]) as w:
        with pytest.raises(InvalidInputError, match=message):
            w.begin_step("static", "s", 0.0, **kwargs)
        assert w.begin_step("static", "s", 0.0) == 0  # nothing was added


def test_tags_that_are_not_a_json_list_are_damage_and_recovery_clears_them(tmp_path):
    path = write(tmp_path / "r.h5")
    with h5py.File(path, "r+") as f:
        f["steps/tags"][0] = b'{"not": "a list"}'
    with pytest.raises(RecordingCorruptError,
                       match=r"/steps/tags row 0 is .*; expected a JSON list of strings"):
        open_recording(path)
    report = recover_recording(path)
    assert "step 0 tags not a JSON list of strings: cleared" in report.summary()
    with open_recording(report.output) as rec:
        assert rec.format_version >= 2  # version 2 added the step fields
        assert rec.steps[0].tags == () and rec.steps[0].role == "p1.accel-position"


def test_a_reopened_v1_file_stays_v1(tmp_path):
    """Resuming a v1 run appends v1 rows: role, tags and units have no field and are derived."""
    path = tmp_path / "v1.h5"
    shutil.copyfile(V1_FILE, path)
    with RecordingWriter.reopen(path) as w:
        i = w.begin_step("static", "extra", 400.0, commanded={"tags": ["gyro-bias"]},
                         role="ignored", tags=("ignored",), units=("IMU-0001",))
        w.update_step(i, t_end_s=401.0, status="done")
    with open_recording(path) as rec:
        assert rec.format_version == 1
        extra = rec.steps[-1]
    assert (extra.role, extra.tags, extra.units) == ("p1.gyro-bias", ("gyro-bias",), ())


@pytest.mark.parametrize(("kind", "tags", "procedure", "role"), [
    ("position", ("calibration", "six-position", "rep1"), "p1", "p1.accel-position"),
    ("static", ("calibration", "gyro-bias", "rep1"), "p1", "p1.gyro-bias"),
    ("rate", ("calibration", "rate", "rep1"), "p1", "p1.gyro-rate"),
    ("rate", ("verification", "rate", "rep1"), "", "p1.held-out-rate"),
    ("position", ("verification", "position", "rep1"), "p1", "p1.held-out-position"),
    ("position", ("rep1",), "p1", ""),
    ("static", ("allan", "T+20"), "allan", "allan.static"),
    ("rate", ("calibration", "rate"), "allan", ""),
    ("position", ("calibration", "six-position"), "p2", ""),
])
def test_roles_from_tags(kind, tags, procedure, role):
    assert role_from_tags(kind, tags, procedure) == role
