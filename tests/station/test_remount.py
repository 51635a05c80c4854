"""Remount operator checks (P2): the session moves the twin's cube, logs it, and resume restores it.

A plan of operator checks with ``remount`` and short static records runs on a two-IMU cube (one on
face +z, one on face +x, 50 Hz); the recorded accelerometers show the pose of each step.
"""

from __future__ import annotations

import numpy as np
import pytest
from pydantic import ValidationError
from rich.console import Console

from imucalib.conventions import ACCEL_COLUMNS
from imucalib.io import EventKind, open_recording
from imucalib.io.inspect import summarize_recording
from imucalib.plan import OperatorCheckStep, Plan, describe_plan, parse_plan, plan_to_toml
from imucalib.plan.equipment import TwinEquipment
from imucalib.station.operator import ScriptedOperator
from imucalib.station.runner import find_resume_point, resume_run, run_plan
from imucalib.station.session import RunOptions
from imucalib.station.sim import SimStation

G = 9.806

TWIN = TwinEquipment.model_validate({
    "seed": 5, "table": {"kind": "single-axis", "grade": "ideal"},
    "fixture": {"kind": "hexahedral", "half_edge_m": 0.05,
                "mounts": [{"face": "+z"}, {"face": "+x", "offset_m": [0.01, -0.02]}]},
    "imus": [{"name": "ZP", "grade": "navigation", "sample_rate_hz": 50.0},
             {"name": "XP", "grade": "navigation", "sample_rate_hz": 50.0}]})


def remount_plan(name: str = "remounts", static_s: float = 2.0) -> Plan:
    steps: list[dict] = []
    for up, yaw in (("+z", 0.0), ("-z", 0.0), ("+x", 90.0)):
        steps.append({"kind": "operator-check", "label": f"remount {up}", "remount": up,
                      "remount_yaw_deg": yaw, "item": f"place the cube with {up} up"})
        # a position step settles (the accelerometers' filters after the step change of the
        # remount) before it records; a static step straight after would record the transient
        steps.append({"kind": "position", "label": f"static {up}", "angles_deg": [0.0],
                      "settle_s": 1.0, "record_s": static_s})
    return Plan.model_validate({"name": name, "twin": TWIN.model_dump(mode="json"),
                                "steps": steps})


def step_means(path) -> dict[str, dict[str, np.ndarray]]:
    """Mean accelerometer of each IMU in each done static step, by step label."""
    out: dict[str, dict[str, np.ndarray]] = {}
    with open_recording(path) as rec:
        for s in rec.steps:
            if s.status == "done" and s.kind == "position":
                out[s.label] = {
                    n: np.array([rec.read_step(s.index, "imu", n, [c]).columns[c].mean()
                                 for c in ACCEL_COLUMNS]) for n in ("ZP", "XP")}
    return out


def test_schema_fields_round_trip_and_describe():
    plan = remount_plan()
    again = parse_plan(plan_to_toml(plan), "t")
    assert again.steps[4] == plan.steps[4]
    assert again.steps[4].remount == "+x" and again.steps[4].remount_yaw_deg == 90.0
    rows = describe_plan(plan)
    assert rows[4].what == "operator confirms: place the cube with +x up (remount: +x up, yaw 90°)"
    assert rows[0].what.endswith("(remount: +z up)")
    plain = OperatorCheckStep(kind="operator-check", item="IMU mounted")
    assert plain.remount is None and plain.remount_yaw_deg == 0.0


@pytest.mark.parametrize(("fields", "match"), [
    ({"remount_yaw_deg": 10.0}, r"`remount_yaw_deg` \(10\) needs `remount`"),
    ({"remount": "up"}, "remount"),
    ({"remount": "+z", "remount_yaw_deg": 400.0}, "less than or equal to 360"),
])
def test_schema_errors(fields, match):
    with pytest.raises(ValidationError, match=match):
        OperatorCheckStep.model_validate({"kind": "operator-check", "item": "x", **fields})


def test_confirmed_remounts_move_the_twin_and_are_logged(tmp_path):
    plan = remount_plan()
    station = SimStation(plan.twin)
    summary = run_plan(plan, station, tmp_path / "r.h5")
    assert summary.status == "done" and summary.steps_invalid == 0
    assert [(up, yaw) for _, up, yaw in station.remounts] == [("+z", 0.0), ("-z", 0.0),
                                                              ("+x", 90.0)]
    assert station.pose == ("+x", 90.0)
    means = step_means(tmp_path / "r.h5")
    tol = 0.02 * G
    np.testing.assert_allclose(means["static +z"]["ZP"], [0, 0, G], atol=tol)
    np.testing.assert_allclose(means["static -z"]["ZP"], [0, 0, -G], atol=tol)
    np.testing.assert_allclose(means["static -z"]["XP"], [G, 0, 0], atol=tol)  # x_b = −z_m
    np.testing.assert_allclose(means["static +x"]["XP"], [0, 0, G], atol=tol)
    np.testing.assert_allclose(means["static +x"]["ZP"], [G, 0, 0], atol=tol)
    with open_recording(tmp_path / "r.h5") as rec:
        typed = rec.events()
        events = [e.message for e in rec.events(EventKind.REMOUNT)]
        commanded = [s.commanded for s in rec.steps if s.kind == "operator-check"]
    assert [(e.kind, e.source) for e in typed] == [(EventKind.REMOUNT, "event:remount")] * 3
    assert events == ["fixture remounted: +z up, yaw 0°", "fixture remounted: -z up, yaw 0°",
                      "fixture remounted: +x up, yaw 90°"]
    assert [c["remount"] for c in commanded] == ["+z", "-z", "+x"]
    # `imucalib inspect` lists them
    summary_ = summarize_recording(tmp_path / "r.h5")
    assert [m for _, m in summary_.remounts] == events
    console = Console(record=True, width=200)
    summary_.render(console)
    text = console.export_text()
    assert "fixture remounted: +x up, yaw 90°" in text and "3 fixture remount(s) above" in text


def test_a_declined_remount_moves_nothing(tmp_path):
    plan = remount_plan()
    station = SimStation(plan.twin)
    options = RunOptions(operator=ScriptedOperator([True, False]))
    summary = run_plan(plan, station, tmp_path / "r.h5", options=options)
    assert summary.status != "done"
    assert station.pose == ("+z", 0.0) and len(station.remounts) == 1
    with open_recording(tmp_path / "r.h5") as rec:
        assert len(rec.events("remount")) == 1


def test_a_station_without_remount_only_logs(tmp_path):
    plan = remount_plan()
    station = SimStation(plan.twin)
    station.remount = None  # type: ignore[assignment]  # as a real station: no such method
    assert run_plan(plan, station, tmp_path / "r.h5").status == "done"
    assert station.rig.fixture.rot_pm.magnitude() == 0.0  # never moved
    with open_recording(tmp_path / "r.h5") as rec:
        assert len(rec.events("remount")) == 3
    means = step_means(tmp_path / "r.h5")
    np.testing.assert_allclose(means["static -z"]["ZP"], [0, 0, G], atol=0.02 * G)


def test_resume_restores_the_pose_of_the_last_completed_remount(tmp_path):
    plan = remount_plan(static_s=6.0)
    station = SimStation(plan.twin)
    # the link drops for good inside the second static record (after the "-z" remount)
    station.at(13.0, lambda: station.table.drop_connection(permanent=True))
    first = run_plan(plan, station, tmp_path / "r.h5")
    assert first.status == "aborted"
    point = find_resume_point(tmp_path / "r.h5")
    assert point.first_step == 3 and point.remount == ("-z", 0.0, 2)
    made: list[SimStation] = []

    def make(p: Plan, t: float) -> SimStation:
        made.append(SimStation(p.twin, start_time_s=t))
        return made[-1]

    summary = resume_run(tmp_path / "r.h5", make)
    assert summary.status == "done"
    assert made[0].remounts[0][1:] == ("-z", 0.0)
    assert made[0].pose == ("+x", 90.0)
    means = step_means(tmp_path / "r.h5")
    np.testing.assert_allclose(means["static -z"]["ZP"], [0, 0, -G], atol=0.02 * G)
    np.testing.assert_allclose(means["static +x"]["XP"], [0, 0, G], atol=0.02 * G)
    with open_recording(tmp_path / "r.h5") as rec:
        remounts = [e.message for e in rec.events(EventKind.REMOUNT)]
    assert "fixture remounted: -z up, yaw 0° (the pose of completed step 2, restored on resume)" \
        in remounts


def test_resume_point_of_a_run_without_remounts(tmp_path):
    plan = Plan.model_validate({"name": "plain", "twin": TWIN.model_dump(mode="json"),
                                "steps": [{"kind": "static", "duration_s": 1.0},
                                          {"kind": "static", "duration_s": 1.0}]})
    station = SimStation(plan.twin)
    station.at(0.5, lambda: station.table.drop_connection(permanent=True))
    run_plan(plan, station, tmp_path / "p.h5")
    assert find_resume_point(tmp_path / "p.h5").remount is None


def test_a_scenario_with_remounts_simulates(tmp_path):
    from imucalib.sim.scenario import Scenario
    from imucalib.station.simulate import simulate_scenario

    plan = remount_plan(static_s=1.0)
    sc = Scenario.model_validate({**TWIN.model_dump(mode="json"), "name": "remount-sc",
                                  "steps": [s.model_dump(mode="json") for s in plan.steps]})
    simulate_scenario(sc, tmp_path / "s.h5")
    means = step_means(tmp_path / "s.h5")
    np.testing.assert_allclose(means["static -z"]["ZP"], [0, 0, -G], atol=0.02 * G)
    assert len(summarize_recording(tmp_path / "s.h5").remounts) == 3
