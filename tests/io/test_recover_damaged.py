"""recover_recording on damaged files: the copy passes every check, and every change is reported."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from imucalib.errors import RecordingCorruptError
from imucalib.io import _probe, open_recording, recover_recording

from . import damage

IMU, TABLE, TRUTH = "streams/imu/IMU-0001", "streams/table/main", "truth/streams/imu/IMU-0001"

#: What the report says (a piece of its summary) and rows copied per table, for each damage.
EXPECTED: dict[str, tuple[str, dict[str, int]]] = {
    "no-log": ("log  0 rows copied (missing in the original: written empty)", {"log": 0}),
    "no-steps": ("missing in the original: written empty", {"steps": 0, "log": 2}),
    "no-streams": ("/streams missing in the original: no streams copied", {TRUTH: 5000}),
    "no-commit": ("/commit unreadable or missing (absent)", {IMU: 5000, TABLE: 500}),
    "commanded-not-json": ("step 1 commanded state not JSON: cleared", {"steps": 3}),
    "flipped-root-attribute-heap": ("root attributes unreadable", {IMU: 5000}),
    "flipped-link-heap": ("steps  0 rows copied (unreadable in the original", {"steps": 0}),
    "flipped-stream-header": (f"{IMU}  0 rows copied (unreadable", {TABLE: 500}),
    "time-nan": ("rows from 1234 dropped: time_s row 1234 is nan", {IMU: 1234}),
    "time-huge": ("time_s row 1234 is 1e+308, later than 1e9 s", {IMU: 1234}),
    "time-negative": ("time_s row 0 is -1.0, negative", {IMU: 0, TABLE: 500}),
    "time-decreasing": ("time_s row 300 is 1.0, before the previous", {TABLE: 300}),
    "truth-time-inf": ("time_s row 7 is inf", {TRUTH: 7}),
    "commit-negative": ("/commit count -5 of 'streams/imu/IMU-0001' is invalid", {IMU: 5000}),
    "commit-too-few": ("/commit counts do not match its entries", {IMU: 5000}),
    "commit-unknown-entry": ("names 'streams/imu/IMU-9', which the file does not hold",
                             {IMU: 5000}),
    "commit-entries-not-json": ("/commit unreadable", {TABLE: 500}),
    "column-short": (f"{TABLE}  490 rows copied, 10 dropped", {TABLE: 490}),
    "format-version-missing": ("its root has no `format_version` attribute", {IMU: 5000}),
    "format-version-str": ("its `format_version` attribute is str '1'", {IMU: 5000}),
    "columns-json-not-json": ("columns_json rebuilt from the datasets", {TABLE: 500}),
    "columns-json-missing": ("columns_json rebuilt from the datasets", {TABLE: 500}),
    "column-undeclared": ("rate_rps not declared in columns_json: not copied", {TABLE: 500}),
    "column-missing": ("column rate_rps unreadable or of another dtype: dropped", {TABLE: 500}),
    "column-dtype": ("column rate_rps unreadable or of another dtype: dropped", {TABLE: 500}),
    "time-not-first": ("columns_json rebuilt from the datasets", {TABLE: 500}),
    "step-field-missing": ("field note missing or unreadable: filled with empty values",
                           {"steps": 3}),
    "step-status-unknown": ("step 0 status 'finished' unknown: set to 'invalid'", {"steps": 3}),
    "step-window-inf": ("1 infinite valid_end_s set to NaN", {"steps": 3}),
    "step-index-wrong": ("step numbers rewritten as 0, 1, 2, …", {"steps": 3}),
    "log-level-unknown": ("1 event(s) with an unknown level or a non-finite time dropped",
                          {"log": 1}),
    "log-time-nan": ("1 event(s) with an unknown level or a non-finite time dropped", {"log": 1}),
    "truth-json": ("/truth `model_json` is not JSON: not copied", {TRUTH: 5000}),
}
BEYOND_RECOVERY = {"flipped-root-header", "zeroed-global-heap"}


@pytest.fixture(scope="module")
def template(tmp_path_factory) -> Path:
    return damage.write_small(tmp_path_factory.mktemp("valid") / "small.h5")


def test_every_damage_is_covered():
    assert set(EXPECTED) | BEYOND_RECOVERY == set(damage.DAMAGES)


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_recover_mends_what_open_recording_refuses(template, tmp_path, name):
    path = tmp_path / "run.h5"
    shutil.copyfile(template, path)
    damage.DAMAGES[name][0](path)
    original = path.read_bytes()
    report = recover_recording(path, tmp_path / "fixed.h5")
    assert path.read_bytes() == original
    text = report.summary()
    snippet, rows = EXPECTED[name]
    assert " ".join(snippet.split()) in " ".join(text.split()), text
    assert report.damage and "is damaged: " in report.damage and report.verified
    copied = {t.name: t.rows_copied for t in report.tables}
    for table, n in rows.items():
        assert copied[table] == n, (table, copied)
    with open_recording(report.output, strict=True) as rec:  # passes every check
        rec.metadata, rec.truth, rec.log  # noqa: B018
        assert [s.index for s in rec.steps] == list(range(copied["steps"]))
        for s in rec.streams:
            data = rec.read_stream(s.device, s.unit)
            assert len(data) == copied[f"streams/{s.device}/{s.unit}"]
            assert np.all(np.diff(data.time_s) >= 0)
        if name == "commanded-not-json":
            assert [s.commanded for s in rec.steps][:2] == [{"angle_deg": [0, 90]}, None]
        if name == "flipped-root-attribute-heap":
            assert rec.metadata["format"] == "imucalib-recording"


@pytest.mark.parametrize("name", sorted(BEYOND_RECOVERY))
def test_recover_refuses_what_it_cannot_read(template, tmp_path, monkeypatch, name):
    monkeypatch.setattr(_probe, "PROBE_TIMEOUT_S", 1.0)
    path = tmp_path / "run.h5"
    shutil.copyfile(template, path)
    damage.DAMAGES[name][0](path)
    with pytest.raises(RecordingCorruptError, match=r"restore it from a copy$"):
        recover_recording(path, tmp_path / "fixed.h5")
    assert not (tmp_path / "fixed.h5").exists()
    assert not list(tmp_path.glob(".*partial"))
