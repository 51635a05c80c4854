"""P3's operator checks and centrifuge guards on the twin station.

Unit swaps and load changes (``OperatorCheckStep.swap_units`` / ``centrifuge_load_kg``) move the
twin's units and change its unbalance once confirmed, are logged, checked against the station
before anything moves, and restored on resume; the centrifuge controller's imbalance alarm and
the station's over-speed guard trip a spinning step.
"""

from __future__ import annotations

import numpy as np
import pytest
from pydantic import ValidationError
from rich.console import Console

from imucalib import units
from imucalib.errors import ConfigurationError
from imucalib.io import EventKind, open_recording
from imucalib.io.inspect import summarize_recording
from imucalib.plan import OperatorCheckStep, Plan, describe_plan, parse_plan, plan_to_toml
from imucalib.plan.equipment import TwinEquipment
from imucalib.sim.scenario import Scenario
from imucalib.station.guards import check_overspeed
from imucalib.station.runner import (
    check_plan_against_station,
    find_resume_point,
    resume_run,
    run_plan,
)
from imucalib.station.sim import SimStation

LIMITS = {"max_accel_dps2": 90.0}  # the twin centrifuge's


def arm_twin(c0: float = 0.0, c_per_kg: float = 0.0, alarm_um: float = 200.0) -> dict:
    """A centrifuge with a test unit T at +0.6 m and references A at +0.2 m, B at −0.2 m."""
    return TwinEquipment.model_validate({
        "seed": 8,
        "centrifuge": {"enabled": True, "static_radius_m": 0.6, "unbalance_c0_m_per_rps_sq": c0,
                       "unbalance_c_m_per_rps_sq_per_kg": c_per_kg,
                       "imbalance_alarm_um": alarm_um},
        "fixture": {"kind": "arm", "arm_radii_m": [0.6, 0.2, -0.2]},
        "imus": [{"name": n, "grade": "navigation", "sample_rate_hz": 100.0, "noise": "white"}
                 for n in ("T", "A", "B")]}).model_dump(mode="json")


def spin_step(rate_dps: float, label: str, record_s: float = 2.0) -> dict:
    return {"kind": "centrifuge", "label": label, "rate_dps": rate_dps, "settle_s": 2.0,
            "record_s": record_s}


def swap_plan(record_s: float = 2.0) -> Plan:
    return Plan.model_validate({
        "name": "p3-swap", "twin": arm_twin(c_per_kg=1e-7),
        "guards": {"on_trip": "stop"}, "limits": LIMITS,
        "steps": [spin_step(180.0, "spin 1", record_s),
                  {"kind": "operator-check", "label": "swap", "item": "exchange A and B, load 5 kg",
                   "swap_units": ["A", "B"], "centrifuge_load_kg": 5.0},
                  spin_step(180.0, "spin 2", record_s),
                  spin_step(180.0, "spin 3", record_s)]})


def mean_accel_x(path, label: str, unit: str) -> float:
    with open_recording(path) as rec:
        for s in rec.steps:
            if s.status == "done" and s.label == label:
                return float(rec.read_step(s.index, "imu", unit, ["accel_x_mps2"])
                             .columns["accel_x_mps2"].mean())
    raise AssertionError(f"no done step {label!r}")


def test_schema_fields_round_trip_and_describe():
    plan = swap_plan()
    again = parse_plan(plan_to_toml(plan), "t")
    assert again.steps[1] == plan.steps[1]
    assert again.steps[1].swap_units == ("A", "B") and again.steps[1].centrifuge_load_kg == 5.0
    assert describe_plan(plan)[1].what == ("operator confirms: exchange A and B, load 5 kg "
                                           "(swap: A ↔ B; centrifuge load 5 kg)")
    plain = OperatorCheckStep(kind="operator-check", item="x")
    assert plain.swap_units is None and plain.centrifuge_load_kg is None


@pytest.mark.parametrize(("fields", "match"), [
    ({"swap_units": ["A", "A"]}, "two different units; got 'A' twice"),
    ({"swap_units": ["A"]}, "swap_units"),
    ({"swap_units": ["A", " "]}, "empty name"),
    ({"centrifuge_load_kg": -1.0}, "greater than or equal to 0"),
    ({"centrifuge_load_kg": 2000.0}, "less than or equal to 1000"),
])
def test_schema_errors(fields, match):
    with pytest.raises(ValidationError, match=match):
        OperatorCheckStep.model_validate({"kind": "operator-check", "item": "x", **fields})


def test_swaps_and_loads_are_checked_against_the_twin_and_the_station():
    data = swap_plan().model_dump(mode="json")
    data["steps"][1]["swap_units"] = ["A", "X"]
    with pytest.raises(ValidationError, match=r"names unit\(s\) \['X'\] the station does not"):
        Plan.model_validate(data)
    no_fuge = {"imus": [{"name": "A"}, {"name": "B"}], "fixture": {"kind": "array"},
               "table": {"kind": "single-axis"}}
    check = {"kind": "operator-check", "item": "load", "centrifuge_load_kg": 1.0}
    with pytest.raises(ValidationError, match="centrifuge_load_kg 1 kg needs a centrifuge"):
        Plan.model_validate({"name": "x", "twin": no_fuge, "steps": [check]})
    with pytest.raises(ValidationError, match="needs a centrifuge"):
        Scenario.model_validate({**no_fuge, "name": "sc", "steps": [check]})
    with pytest.raises(ValidationError, match=r"\['X'\]"):
        Scenario.model_validate({**arm_twin(), "name": "sc", "steps": [
            {"kind": "operator-check", "item": "swap", "swap_units": ["X", "T"]}]})
    # a plan without a twin is checked against the station it runs on
    bare = Plan.model_validate({"name": "x", "steps": [
        {"kind": "operator-check", "item": "swap", "swap_units": ["T", "Q"]}]})
    with pytest.raises(ConfigurationError, match=r"\['Q'\]"):
        check_plan_against_station(bare, SimStation(TwinEquipment.model_validate(arm_twin())))
    bare = Plan.model_validate({"name": "x", "steps": [check]})
    with pytest.raises(ConfigurationError, match="needs a centrifuge"):
        check_plan_against_station(bare, SimStation(TwinEquipment.model_validate(no_fuge)))


def test_a_confirmed_swap_and_load_move_the_twin_and_are_logged(tmp_path):
    plan = swap_plan()
    station = SimStation(plan.twin)
    summary = run_plan(plan, station, tmp_path / "r.h5")
    assert summary.status == "done" and summary.steps_invalid == 0, summary.trips
    assert [(a, b) for _, a, b in station.swaps] == [("A", "B")]
    assert station.rig.centrifuge.load_kg == 5.0
    assert station.rig.fixture.mount("A").lever_arm_m_m[0] == -0.2
    # A and B read ω²·0.2 on either side; the swap moves each to the other's place, and the
    # load (c = 5e-7) moves A (now on the far side) in and B (now on the test side) out
    w2 = (180.0 * units.DEG) ** 2
    shift = 5e-7 * w2 * w2
    path = tmp_path / "r.h5"
    for unit, sign in (("A", -1.0), ("B", +1.0)):
        before, after = mean_accel_x(path, "spin 1", unit), mean_accel_x(path, "spin 2", unit)
        assert after - before == pytest.approx(sign * shift, abs=2e-4)
    with open_recording(path) as rec:
        typed = [(e.kind, e.source, e.message) for e in rec.events()]
    assert typed == [(EventKind.SWAP, "event:swap", "units swapped: A ↔ B"),
                     (EventKind.LOAD, "event:load", "centrifuge load set: 5 kg")]
    events = [m for _, _, m in typed]
    summary_ = summarize_recording(path)
    assert [m for _, m in summary_.swaps_and_loads] == events
    console = Console(record=True, width=200)
    summary_.render(console)
    assert "2 unit swap(s) or load change(s) above" in console.export_text()


def test_a_station_without_swap_or_load_only_logs(tmp_path):
    plan = swap_plan()
    station = SimStation(plan.twin)
    station.swap_units = None  # type: ignore[assignment]  # as a real station: no such methods
    station.set_centrifuge_load = None  # type: ignore[assignment]
    assert run_plan(plan, station, tmp_path / "r.h5").status == "done"
    assert station.rig.fixture.mount("A").lever_arm_m_m[0] == 0.2
    assert station.rig.centrifuge.load_kg == 0.0
    with open_recording(tmp_path / "r.h5") as rec:
        assert len(rec.events(EventKind.SWAP)) == 1 and len(rec.events("load")) == 1


def test_resume_restores_the_swaps_and_the_load(tmp_path):
    plan = swap_plan(record_s=4.0)
    station = SimStation(plan.twin)
    done: list[str] = []

    def drop_after_swap() -> None:  # the link drops for good in "spin 2", after the swap
        station.centrifuge.drop_connection(permanent=True)
        done.append("dropped")

    original = station.swap_units

    def swap_then_schedule(a: str, b: str) -> None:
        original(a, b)
        station.at(station.clock.now_s() + 5.0, drop_after_swap)

    station.swap_units = swap_then_schedule  # type: ignore[method-assign]
    first = run_plan(plan, station, tmp_path / "r.h5")
    assert first.status == "aborted" and done == ["dropped"]
    point = find_resume_point(tmp_path / "r.h5")
    assert point.first_step == 2
    assert point.swaps == (("A", "B"),) and point.centrifuge_load_kg == 5.0
    made: list[SimStation] = []

    def make(p: Plan, t: float) -> SimStation:
        made.append(SimStation(p.twin, start_time_s=t))
        return made[-1]

    summary = resume_run(tmp_path / "r.h5", make)
    assert summary.status == "done", summary.trips
    rig = made[0].rig
    np.testing.assert_array_equal(rig.fixture.mount("A").lever_arm_m_m, [-0.2, 0.0, 0.0])
    np.testing.assert_array_equal(rig.imus["B"].mount.lever_arm_m_m, [0.2, 0.0, 0.0])
    assert rig.centrifuge.load_kg == 5.0
    assert [(a, b) for _, a, b in made[0].swaps] == [("A", "B")]
    with open_recording(tmp_path / "r.h5") as rec:
        swaps = [e.message for e in rec.events(EventKind.SWAP)]
        loads = [e.message for e in rec.events(EventKind.LOAD)]
    assert swaps[-1] == "units swapped: A ↔ B (the completed swaps, restored on resume)"
    assert loads[-1] == "centrifuge load set: 5 kg (the last completed load, restored on resume)"
    # after the resume, A still reads as on the far side with the load
    assert mean_accel_x(tmp_path / "r.h5", "spin 3", "A") == pytest.approx(
        mean_accel_x(tmp_path / "r.h5", "spin 1", "A")
        - 5e-7 * (180.0 * units.DEG) ** 4, abs=2e-4)


def test_resume_point_without_swaps(tmp_path):
    plan = Plan.model_validate({"name": "plain", "twin": arm_twin(), "limits": LIMITS,
                                "steps": [spin_step(0.0, "rest"), spin_step(0.0, "rest 2")]})
    station = SimStation(plan.twin)
    station.at(0.5, lambda: station.centrifuge.drop_connection(permanent=True))
    run_plan(plan, station, tmp_path / "p.h5")
    point = find_resume_point(tmp_path / "p.h5")
    assert point.swaps == () and point.centrifuge_load_kg is None


def test_the_imbalance_alarm_trips_a_spin_past_it(tmp_path):
    # c = 1e-5 m/(rad/s)²: 10 µm at 1 rad/s, 395 µm at 360 °/s (alarm at 200 µm: ω ≈ 256 °/s)
    plan = Plan.model_validate({"name": "unbalanced", "twin": arm_twin(c0=1e-5),
                                "guards": {"on_trip": "stop"}, "limits": LIMITS,
                                "steps": [spin_step(360.0, "fast")]})
    station = SimStation(plan.twin)
    summary = run_plan(plan, station, tmp_path / "u.h5")
    assert summary.status != "done"
    assert len(summary.trips) == 1
    trip = summary.trips[0]
    assert "imbalance alarm: the rotor is" in trip and "alarm at 200 µm" in trip
    excursion = float(trip.split("the rotor is ")[1].split(" µm")[0])
    assert 200.0 < excursion < 205.0  # caught within a feedback block of the crossing
    fuge, now = station.rig.centrifuge.table, station.rig.now_s
    assert fuge.mode(0, now) != "rate"  # the controller brakes the spin to rest
    assert fuge.axis_motion(0, np.array([now + 10.0]))[1][0] == 0.0
    # below the alarm the same spin runs
    calm = plan.model_copy(update={"twin": TwinEquipment.model_validate(arm_twin(c0=1e-6))})
    assert run_plan(calm, SimStation(calm.twin), tmp_path / "c.h5").status == "done"


def test_check_overspeed():
    limit = 800.0 * units.DEG
    assert check_overspeed(np.array([[799.0], [-800.0]]) * units.DEG, limit, "main") is None
    assert check_overspeed(np.zeros((0, 1)), limit, "main") is None
    assert check_overspeed(np.array([[790.0], [-812.3]]) * units.DEG, limit, "main") == (
        "centrifuge 'main' over-speed: 812.3 °/s measured, limit 800 °/s")


def test_an_over_speed_reading_trips_the_step(tmp_path):
    plan = Plan.model_validate({"name": "fast", "twin": arm_twin(),
                                "limits": {**LIMITS, "max_centrifuge_rate_dps": 200.0},
                                "guards": {"on_trip": "stop"},
                                "steps": [spin_step(180.0, "spin", record_s=6.0)]})
    station = SimStation(plan.twin)
    station.at(6.0, lambda: station.centrifuge.add_rate_error(0, 30.0 * units.DEG, 1.0))
    summary = run_plan(plan, station, tmp_path / "o.h5")
    assert summary.status != "done"
    assert summary.trips[0] == ("centrifuge 'main' over-speed: 210.0 °/s measured, limit "
                                "200 °/s")
