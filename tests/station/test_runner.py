"""The plan runner on the twin: complete runs, settled windows, operator checks, bad plans."""

from __future__ import annotations

import math

import numpy as np
import pytest

from imucalib import units
from imucalib.errors import ConfigurationError, RecordingError
from imucalib.io import open_recording
from imucalib.io.streams import axis_columns
from imucalib.plan import parse_plan
from imucalib.station.operator import ScriptedOperator
from imucalib.station.runner import RunOptions, run_plan
from imucalib.station.sim import SimStation

from .conftest import small_p1


def run(plan, tmp_path, name="run.h5", **opts):
    station = SimStation(plan.twin)
    summary = run_plan(plan, station, tmp_path / name,
                       options=RunOptions(truth=station.truth, **opts))
    return station, summary, tmp_path / name


def test_a_p1_plan_completes_with_every_window_settled(plan, tmp_path):
    station, summary, path = run(plan, tmp_path)
    assert summary.status == "done" and summary.steps_invalid == 0
    assert summary.steps_done == len(plan.steps)
    with open_recording(path) as rec:
        steps = rec.steps
        assert [s.commanded["plan_step"] for s in steps] == list(range(len(plan.steps)))
        assert all(s.status == "done" for s in steps)
        assert len(rec.metadata["plan_hash"]) == 64 and "[twin" in rec.metadata["plan_toml"]
        tol = plan.guards.position_tolerance_arcsec * units.ARCSEC
        for s in steps:
            if s.kind == "position":
                fb = rec.read_step(s.index, "table", "main")
                for i, axis in enumerate(("pitch", "roll")):
                    target = math.radians(s.commanded["angles_deg"][i])
                    err = np.angle(np.exp(1j * (fb.columns[axis_columns(axis)[0]] - target)))
                    assert np.abs(err).max() <= tol, s.label
                imu = rec.read_step(s.index, "imu", "IMU-0001")
                assert len(imu) == pytest.approx(200 * (s.valid_end_s - s.valid_start_s), abs=1)
            if s.kind == "rate" and s.commanded["rate_dps"] != 0:
                axis = ("pitch", "roll")[s.commanded["axis"]]
                fb = rec.read_stream("table", "main", t_start_s=s.valid_start_s,
                                     t_end_s=s.valid_end_s + 1e-9)
                angle = fb.columns[axis_columns(axis)[0]]
                rate = fb.columns[axis_columns(axis)[1]]
                one_sample = abs(math.radians(s.commanded["rate_dps"])) / 100.0  # 100 Hz feedback
                encoder = 5.0 * units.ARCSEC  # the high-grade encoder's error, with margin
                turned = abs(angle[-1] - angle[0])
                assert abs(turned - 2 * math.pi * s.commanded["revolutions"]) <= \
                    one_sample + encoder
                assert np.abs(rate - math.radians(s.commanded["rate_dps"])).max() <= \
                    plan.guards.rate_tolerance_dps * units.DEG
        check = steps[0]
        assert check.kind == "operator-check" and check.note.startswith("confirmed by auto at ")
        assert any(e.source == "operator:auto" for e in rec.log)
        assert rec.truth["imu_models"]["IMU-0001"]
    assert station.rig.now_s == pytest.approx(summary.end_s)


def test_operator_who_declines_stops_the_run_before_anything_moves(plan, tmp_path):
    op = ScriptedOperator([False], who="J. Doe")
    station, summary, path = run(plan, tmp_path, operator=op)
    assert summary.status == "aborted" and "J. Doe did not confirm" in summary.reason
    assert op.asked == [plan.steps[0].item]
    with open_recording(path) as rec:
        assert [s.status for s in rec.steps] == ["aborted"]
        assert "declined by J. Doe" in rec.steps[0].note
    assert not [c for c in station.table.commands if c[1].startswith("move")]


def test_keyboard_interrupt_stops_safely_and_keeps_the_data(plan, tmp_path):
    station = SimStation(plan.twin)
    station.at(12.0, lambda: (_ for _ in ()).throw(KeyboardInterrupt()))
    with pytest.raises(KeyboardInterrupt):
        run_plan(plan, station, tmp_path / "k.h5")
    assert station.table.commands[-1][1] == "safe stop"
    assert station.table.status().modes == ("off", "off")
    with open_recording(tmp_path / "k.h5") as rec:  # closed cleanly: opens normally
        assert not rec.was_open_for_write
        assert rec.steps[-1].status == "aborted"
        assert "KeyboardInterrupt" in rec.steps[-1].note
        assert rec.stream_info("imu", "IMU-0001").n_samples > 0
        assert rec.log[-1].level == "error"


def test_existing_recording_is_not_overwritten(plan, tmp_path):
    (tmp_path / "x.h5").write_bytes(b"keep")
    with pytest.raises(RecordingError, match="exists"):
        run_plan(plan, SimStation(plan.twin), tmp_path / "x.h5")
    assert (tmp_path / "x.h5").read_bytes() == b"keep"


@pytest.mark.parametrize(("edit", "match"), [
    ({"steps": [{"kind": "spin", "rate_dps": 5}]}, r"steps\.0: Input tag 'spin'"),
    ({"steps": [{"kind": "static", "duration_s": -5}]},
     r"steps\.0\.static\.duration_s: Input should be greater than 0"),
    ({"steps": [{"kind": "rate", "rate_dps": 900, "record_s": 1}]},
     r"rate_dps 900 exceeds limits\.max_rate_dps 500"),
    ({"steps": [{"kind": "soak", "temperature_degc": 150}]},
     r"temperature_degc 150 is outside limits \[-55, 125\]"),
    ({"steps": [{"kind": "position", "angles_deg": [0, 0], "record_s": "long"}]},
     r"record_s: Input should be a valid number"),
    ({"steps": [{"kind": "rate", "rate_dps": 10}]}, "exactly one of `revolutions`"),
    ({"guards": {"position_tolerance_arcsec": float("nan")}}, "position_tolerance_arcsec"),
    ({"steps": [{"kind": "static", "duration_s": 1, "colour": "red"}]},
     r"steps\.0\.static\.colour: Extra inputs are not permitted"),
])
def test_malformed_plans_are_refused_naming_the_field(edit, match):
    import tomli_w

    data = {"name": "bad", **edit}
    with pytest.raises(ConfigurationError, match=match):
        parse_plan(tomli_w.dumps(data))


def test_plan_needing_a_device_the_station_lacks_is_refused_before_anything_moves(tmp_path):
    plan = small_p1()
    data = plan.model_dump(mode="json", exclude_none=True)
    data["steps"] = [{"kind": "soak", "temperature_degc": 40.0}, *data["steps"][1:3]]
    import tomli_w

    bad = parse_plan(tomli_w.dumps(data))
    station = SimStation(plan.twin)
    with pytest.raises(ConfigurationError, match=r"steps\.0 \(soak .*needs a thermal chamber"):
        run_plan(bad, station, tmp_path / "no.h5")
    assert not (tmp_path / "no.h5").exists()
    assert station.table.commands == []
