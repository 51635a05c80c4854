"""A plan scaled to seconds, run through the real drivers against their simulator servers.

The same plan runs once on the in-process twin (SimStation) and once through `DriverStation`:
ACUTROL ACL over TCP for the table and binary IMU packets over TCP, each served on 127.0.0.1 by
a simulator with an identical twin behind it, at 20× real time. The two recordings must be
equivalent: the same steps done, the same streams and units, the same number of IMU samples in
each valid window (to within the feedback granularity), and valid windows in settled data.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from imucalib import units
from imucalib.drivers import load_driver_station
from imucalib.drivers.simulators import LoopbackStation
from imucalib.io import EventKind, open_recording
from imucalib.io.streams import axis_columns
from imucalib.procedures import generate_p1_plan
from imucalib.sim.build import build_rig
from imucalib.station.runner import RunOptions, run_plan
from imucalib.station.sim import SimStation

SPEED = 20.0


def scaled_plan():
    plan = generate_p1_plan(name="scaled", grade="tactical", rates_dps=(-90.0, 0.0, 90.0),
                            held_out_rates_dps=(), revolutions=1, static_s=10.0, settle_s=2.0,
                            record_s=2.0, rate_settle_s=2.0, repetitions=1, warm_up_s=2.0,
                            sample_rate_hz=200.0, z_rates=False, seed=9)
    keep = tuple(s for s in plan.steps if s.kind != "warm-up")
    return plan.model_copy(update={"steps": keep})


def summary_of(path):
    with open_recording(path) as rec:
        steps = [(s.commanded["plan_step"], s.kind, s.status) for s in rec.steps]
        counts = {s.commanded["plan_step"]: len(rec.read_step(s.index, "imu", "IMU-0001"))
                  for s in rec.steps if s.status == "done" and s.has_valid_window}
        streams = {i.name: {c: spec.unit for c, spec in i.columns.items()} for i in rec.streams}
        windows = [(s, rec.read_step(s.index, "table", "main"))
                   for s in rec.steps if s.kind == "position" and s.status == "done"]
    return steps, counts, streams, windows


@pytest.mark.slow
def test_drivers_over_loopback_give_an_equivalent_recording(tmp_path):
    plan = scaled_plan()
    assert plan.twin is not None
    run_plan(plan, SimStation(plan.twin), tmp_path / "twin.h5")
    rig = build_rig(plan.twin).rig
    with LoopbackStation(rig, speed=SPEED, table="acutrol", imu="packet") as served:
        station_file = served.write_station_file(tmp_path / "station.toml")
        station = load_driver_station(station_file, clock=served.time_base)
        summary = run_plan(plan, station, tmp_path / "drivers.h5",
                           options=RunOptions(tick_s=0.5,
                                              station_toml=station_file.read_text()))
    assert summary.status == "done", summary.reason
    twin_steps, twin_counts, twin_streams, _ = summary_of(tmp_path / "twin.h5")
    drv_steps, drv_counts, drv_streams, windows = summary_of(tmp_path / "drivers.h5")
    assert drv_steps == twin_steps  # every step once, done
    assert set(drv_streams) == set(twin_streams) == {"imu/IMU-0001", "table/main"}
    for name, cols in twin_streams.items():
        for col, unit in cols.items():
            if col in drv_streams[name]:
                assert drv_streams[name][col] == unit
    assert set(drv_counts) == set(twin_counts)
    for k in twin_counts:
        # 200 Hz IMU, windows on station time: host receive timing at 20× real time moves a
        # window's edges by a few samples (1 ms of wall-clock jitter is 4 samples here, and a
        # loaded 2-core CI machine has a few ms)
        tol = max(10, round(0.05 * twin_counts[k]))
        assert abs(drv_counts[k] - twin_counts[k]) <= tol, (k, drv_counts[k], twin_counts[k])
    for step, fb in windows:  # valid windows lie in settled data, as the ACL controller reports
        for i, axis in enumerate(("pitch", "roll")):
            target = math.radians(step.commanded["angles_deg"][i])
            err = np.angle(np.exp(1j * (fb.columns[axis_columns(axis)[0]] - target)))
            assert np.abs(err).max() <= 5.0 * units.ARCSEC
    with open_recording(tmp_path / "drivers.h5") as rec:
        assert rec.metadata["station_toml"].startswith('name = "simulated station"')
        devices = rec.metadata["station_json"]["devices"]
        assert {d["role"]: d["kind"] for d in devices}["table"] == "acutrol"


@pytest.mark.slow
def test_a_dropped_table_connection_trips_stops_and_retries_over_tcp(tmp_path):
    plan = scaled_plan()
    assert plan.twin is not None
    rig = build_rig(plan.twin).rig
    with LoopbackStation(rig, speed=SPEED) as served:
        station = load_driver_station(served.write_station_file(tmp_path / "s.toml"),
                                      clock=served.time_base)
        dropped: list[float] = []

        def on_status(status):
            if status.step_index == 4 and status.phase == "" and not dropped and \
                    status.time_s > 0:
                dropped.append(status.time_s)
                served.servers["table"].drop_connections()

        summary = run_plan(plan, station, tmp_path / "d.h5",
                           options=RunOptions(tick_s=0.5, on_status=on_status))
    assert dropped and summary.status == "done", summary.reason
    assert summary.steps_invalid >= 1
    with open_recording(tmp_path / "d.h5") as rec:
        warnings = [e.message for e in rec.log if e.source == "guard"]
        assert warnings and "equipment stopped safely" in warnings[0]
        invalid = [s for s in rec.steps if s.status == "invalid"]
        assert invalid and invalid[0].commanded["plan_step"] == 4
        done = [s.commanded["plan_step"] for s in rec.steps if s.status == "done"]
        assert done == list(range(len(plan.steps)))


@pytest.mark.slow
def test_a_p3_plan_runs_on_an_acl_centrifuge_over_tcp(tmp_path):
    """P3 through the drivers: the ACUTROL (ACL) centrifuge served on 127.0.0.1, arm positions
    at rest, rates over whole revolutions, the swap and load checks (an operator's on a real
    station: logged, nothing to command), the over-speed guard watching every feedback block."""
    from imucalib.procedures.p3.plan import generate_p3_plan

    plan = generate_p3_plan(static_radius_m=0.5, test_range_g=1.0, n_rates=4,
                            rate_record_s=1.0, rest_record_s=0.5, settle_s=6.0,
                            tumble=False, sample_rate_hz=100.0, seed=3)
    assert plan.twin is not None
    rig = build_rig(plan.twin).rig
    with LoopbackStation(rig, speed=SPEED, centrifuge="acutrol", imu="packet") as served:
        station_file = served.write_station_file(tmp_path / "station.toml")
        station = load_driver_station(station_file, clock=served.time_base)
        assert station.centrifuge is not None and not hasattr(station, "swap_units")
        summary = run_plan(plan, station, tmp_path / "p3.h5", options=RunOptions(tick_s=0.5))
    assert summary.status == "done", summary.reason
    with open_recording(tmp_path / "p3.h5") as rec:
        done = [s for s in rec.steps if s.status == "done"]
        assert [s.commanded["plan_step"] for s in done] == list(range(len(plan.steps)))
        events = [(e.kind, e.message) for e in rec.events()]
        assert (EventKind.SWAP, "units swapped: REF-A ↔ REF-B") in events
        assert (EventKind.LOAD, "centrifuge load set: 2 kg") in events
        rates = [s for s in done if s.role == "p3.rate"]
        assert len(rates) == 12
        for s in rates:  # each rate record's centrifuge feedback turns at the commanded rate
            fb = rec.read_step(s.index, "centrifuge", "main")
            rate = fb.columns[axis_columns("spin")[1]]
            assert abs(np.median(rate) / units.DEG - s.commanded["rate_dps"]) < 0.5
