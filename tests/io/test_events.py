"""Station events (remount, swap, load): typed in the log's ``source``, and the version 1 fallback.

A file written before the events were typed (the runner's messages ``fixture remounted: …``,
``units swapped: …``, ``centrifuge load set: …`` with source ``"runner"``) and a file written
now (source ``"event:<kind>"``) give the same events, to ``Recording.events`` and to
``imucalib inspect`` (``docs/recording-format.md``, "Station events").
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.errors import InvalidInputError
from imucalib.io import ColumnSpec, EventKind, RecordingWriter, StreamSpec, open_recording
from imucalib.io._schema import LOG_FIELDS
from imucalib.io.events import (
    event_kind,
    event_message,
    event_source,
    v1_event_kind,
)
from imucalib.io.inspect import summarize_recording

SPEC = StreamSpec("imu", "U", {"accel_z_mps2": ColumnSpec("m/s^2")})

#: (time [s], kind, details) of the events both files hold, in the order logged.
EVENTS = (
    (1.0, EventKind.REMOUNT, "+x up, yaw 90°"),
    (2.0, EventKind.SWAP, "A ↔ B"),
    (3.0, EventKind.LOAD, "5 kg"),
    (4.0, EventKind.REMOUNT, "-z up, yaw 0° (the pose of completed step 2, restored on resume)"),
)
#: The messages the runner wrote before the events were typed (the version 1 wording).
V1_MESSAGES = {
    EventKind.REMOUNT: "fixture remounted: {}",
    EventKind.SWAP: "units swapped: {}",
    EventKind.LOAD: "centrifuge load set: {}",
}


def write(path: Path, *, typed: bool) -> Path:
    """A small Recording whose log holds :data:`EVENTS`, typed or as the old runner wrote them,
    between other events (one of them an operator's note that reads like a remount)."""
    with RecordingWriter(path, streams=[SPEC]) as w:
        w.append("imu", "U", {"time_s": np.arange(5.0), "accel_z_mps2": np.full(5, 9.81)})
        w.log_event(0.5, "info", "runner", "plan 'x' started")
        w.log_event(0.6, "info", "operator:alice",
                    "fixture remounted by hand — confirmed by alice")
        for time_s, kind, detail in EVENTS:
            if typed:
                w.log_station_event(time_s, kind, detail)
            else:
                w.log_event(time_s, "info", "runner", V1_MESSAGES[kind].format(detail))
        w.log_event(4.5, "warning", "guard", "rate error 0.2 % — continuing")
    return path


@pytest.fixture(params=[True, False], ids=["typed", "version-1"])
def either(request, tmp_path) -> Path:
    return write(tmp_path / "r.h5", typed=request.param)


def test_typed_events_are_stored_in_the_source_column(tmp_path):
    with open_recording(write(tmp_path / "r.h5", typed=True)) as rec:
        events = rec.events()
    assert [e.source for e in events] == ["event:remount", "event:swap", "event:load",
                                          "event:remount"]
    assert {e.level for e in events} == {"info"}
    # an older imucalib found the events by their message: it still does
    assert [e.message for e in events] == [V1_MESSAGES[k].format(d) for _, k, d in EVENTS]
    assert event_source("remount") == "event:remount"
    assert event_message(EventKind.SWAP, "A ↔ B") == "units swapped: A ↔ B"


def test_old_and_new_logs_give_the_same_events(tmp_path):
    got = {}
    for typed in (True, False):
        with open_recording(write(tmp_path / f"{typed}.h5", typed=typed)) as rec:
            got[typed] = [(e.time_s, e.kind, e.message) for e in rec.events()]
            assert [e.time_s for e in rec.events("remount")] == [1.0, 4.0]
            assert [e.time_s for e in rec.events(EventKind.SWAP)] == [2.0]
            assert [e.time_s for e in rec.events(EventKind.LOAD)] == [3.0]
            assert [e.kind for e in rec.log] == [None, None, *(k for _, k, _ in EVENTS), None]
    assert got[True] == got[False]
    assert [(t, k) for t, k, _ in got[True]] == [(t, k) for t, k, _ in EVENTS]


def test_inspect_lists_the_events_of_either_file(either):
    summary = summarize_recording(either)
    assert [t for t, _ in summary.remounts] == [1.0, 4.0]
    assert summary.swaps_and_loads == ((2.0, "units swapped: A ↔ B"),
                                       (3.0, "centrifuge load set: 5 kg"))
    result = CliRunner().invoke(app, ["inspect", str(either)])  # `imucalib inspect FILE`
    assert result.exit_code == 0, result.output
    text = " ".join(result.output.split())
    assert "fixture remounted: +x up, yaw 90°" in text and "units swapped: A ↔ B" in text
    assert ("7 logged event(s), 2 fixture remount(s) above, 2 unit swap(s) or load change(s) "
            "above") in text
    assert "fixture remounted by hand" not in text  # an operator's note is no event


def test_the_kind_of_a_log_row():
    assert event_kind("event:load", "anything at all") is EventKind.LOAD
    # a kind of a newer writer: no kind here (and no fallback to the message)
    assert event_kind("event:tilt", "fixture remounted: +x up") is None
    # the version 1 mapping: the runner's messages only, by their first words
    assert event_kind("runner", "fixture remounted: +x up, yaw 0°") is EventKind.REMOUNT
    assert event_kind("runner", "plan 'x' started") is None
    assert event_kind("operator:bob", "units swapped: A ↔ B") is None
    assert v1_event_kind("runner", "centrifuge load set: 2 kg") is EventKind.LOAD
    assert v1_event_kind("runner", "the fixture remounted") is None


def test_unknown_kinds_are_refused(tmp_path):
    with pytest.raises(InvalidInputError, match="unknown event kind 'tilt'"):
        event_source("tilt")
    path = write(tmp_path / "r.h5", typed=True)
    with open_recording(path) as rec, pytest.raises(InvalidInputError, match="'tilt'"):
        rec.events("tilt")
    with RecordingWriter(tmp_path / "w.h5", streams=[SPEC]) as w, \
            pytest.raises(InvalidInputError, match="'tilt'"):
        w.log_station_event(0.0, "tilt", "x")


def test_the_log_fields_are_unchanged():
    """Typed events need no new field: the log's fields and their sizes are those of before."""
    assert {k: (v.kind, v.max_bytes) for k, v in LOG_FIELDS.items()} == {
        "time_s": ("f8", 0), "level": ("text", 16), "source": ("text", 128),
        "message": ("text", 4096)}
    assert max(len(event_source(k).encode()) for k in EventKind) <= 128
