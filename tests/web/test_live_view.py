"""The live view's data (docs/web.md, "Live view"): window means with their σ, the soak
criterion, the temperature trace, the snapshot's history, and the bounds of the decimation."""

from __future__ import annotations

import json
import math
import queue
import time
from pathlib import Path

import numpy as np
import pytest

from imucalib.io import open_recording
from imucalib.plan.schema import Plan, SoakStep
from imucalib.station.session import RunStatus
from imucalib.web import live, live_follow
from imucalib.web.events import MAX_SAMPLES, MAX_TOTAL, SubscriberQueue
from imucalib.web.run_files import RunFiles
from imucalib.web.run_reporter import RunReporter
from imucalib.web.run_tap import SignalTap
from imucalib.web.supervisor import FOLLOW_S, RunSupervisor
from imucalib.web.window_stats import MAX_BINS, BinnedMoments, find_window, window_stats


@pytest.fixture
def plan_file(tmp_path: Path, p1_tools) -> Path:
    folder = tmp_path / "plans"
    folder.mkdir()
    return p1_tools.small_plan_file(folder)


@pytest.fixture
def sup(tmp_path: Path):
    s = RunSupervisor(tmp_path / "runs", record=False)
    yield s
    s.close()


def _run_to_end(sup: RunSupervisor, run_id: str, timeout_s: float = 40.0):
    deadline = time.monotonic() + timeout_s
    answered = False
    while time.monotonic() < deadline:
        v = sup.view(run_id)
        if v.prompt is not None and not answered:
            sup.answer(run_id, v.prompt.prompt_id, v.prompt.step_index, True, "alice")
            answered = True
        if v.status in ("finished", "stopped", "failed"):
            return v
        time.sleep(0.05)
    raise AssertionError("the run did not end")


def _events(sup: RunSupervisor, run_id: str) -> list[dict]:
    text = (sup.runs_dir / run_id / "events.jsonl").read_text(encoding="utf-8")
    return [json.loads(line) for line in text.splitlines()]


# --- window means -----------------------------------------------------------------------------

def test_a_twin_run_gives_each_recorded_window_s_mean_and_sigma_as_the_recording_holds_it(
        sup, plan_file):
    run_id = sup.start(plan_file, station="sim", serials=[], operator="alice")
    v = _run_to_end(sup, run_id)
    assert v.status == "finished", v.error
    windows = [e for e in _events(sup, run_id) if e["type"] == "window"]
    with open_recording(v.recording_path) as rec:
        recorded = {int(s.commanded["plan_step"]): s for s in rec.steps
                    if s.status == "done" and s.kind in live_follow.WINDOW_KINDS}
        assert sorted(e["step_index"] for e in windows) == sorted(recorded)
        for e in windows:
            step = recorded[e["step_index"]]
            # the window found from the ticks is the runner's own valid window
            assert e["t_start_s"] == pytest.approx(step.valid_start_s, abs=1e-6)
            assert e["t_end_s"] == pytest.approx(step.valid_end_s, abs=1e-3)
            [(unit, stats)] = e["units"].items()
            data = rec.read_step(step.index, "imu", unit)
            gyro = np.degrees(np.column_stack([data.columns[f"gyro_{a}_rps"] for a in "xyz"]))
            assert abs(stats["n"] - len(gyro)) <= 2 * stats["bin_s"] * 100 + 1
            se = np.asarray(stats["gyro_se_dps"])
            sd = np.asarray(stats["gyro_sd_dps"])
            assert np.all(se > 0) and np.allclose(se, sd / math.sqrt(stats["n"]))
            assert np.all(np.abs(gyro.mean(axis=0) - stats["gyro_dps"]) < 4 * se + 1e-12)
            assert np.allclose(gyro.std(axis=0, ddof=1), sd, rtol=0.2)
        # the runner's own recording-log lines are the page's log lines too, in order
        runner_lines = [f"[t={e.time_s:.1f} s, {e.source}] {e.message}" for e in rec.log]
    logged = [e["line"].split(": ", 1)[1] for e in _events(sup, run_id) if e["type"] == "log"]
    assert [line for line in logged if line.startswith("[t=")] == runner_lines
    assert any("plan 'cli-run' started" in line for line in runner_lines)
    rate = next(e for e in windows if e["kind"] == "rate" and e["commanded"]["rate_dps"] == 90.0)
    axis = rate["commanded"]["axis"]
    assert rate["duration_s"] == pytest.approx(4.0)  # one revolution at 90 °/s
    assert max(abs(g) for g in rate["units"]["IMU-0001"]["gyro_dps"]) == pytest.approx(
        90.0, rel=0.02), axis


def test_find_window_of_a_fixed_length_and_of_whole_revolutions():
    ticks = [10.0, 12.0, 14.0, 15.0, 17.0]
    assert find_window(ticks, 3.0) == (14.0, 17.0)          # the latest pair
    assert find_window(ticks, 5.0) == (12.0, 17.0)
    assert find_window(ticks, 2.5) is None
    angles = [0.0, 0.0, 180.0, 270.0, 450.0]               # 90 °/s from 12 s on
    # from a start the runner chose: the crossing, interpolated between 15 s and 17 s
    assert find_window(ticks[1:], 4.0, angles_deg=angles[1:], turn_deg=360.0,
                       from_first=True) == (12.0, 16.0)
    # from the angles alone: the earliest start whose turn ends in the last tick
    assert find_window(ticks, 4.0, angles_deg=angles, turn_deg=360.0) == (10.0, 16.0)
    assert find_window(ticks, 8.0, angles_deg=angles, turn_deg=720.0) is None


def test_binned_moments_stay_bounded_and_give_the_plain_mean_and_sigma():
    rng = np.random.default_rng(1)
    m = BinnedMoments()
    rate_hz, block_s = 200.0, 2.0
    gyro_all, accel_all, t_all = [], [], []
    for k in range(3600):                   # two hours of one unit at 200 Hz
        t = k * block_s + np.arange(int(block_s * rate_hz)) / rate_hz
        gyro = 1e-3 + 1e-4 * rng.standard_normal((t.size, 3))
        accel = np.array([0.0, 0.0, 9.80665]) + 1e-4 * rng.standard_normal((t.size, 3))
        m.add(t, gyro, accel)
        assert len(m) <= MAX_BINS
        if k >= 3590:
            gyro_all.append(gyro)
            accel_all.append(accel)
            t_all.append(t)
    assert m.bin_s > 0.05                   # coarsened to stay within MAX_BINS
    start = 3590 * block_s
    s = window_stats(m, start, 3600 * block_s)
    g, a = np.vstack(gyro_all), np.vstack(accel_all)
    assert s is not None and abs(s["n"] - g.shape[0]) <= 2 * s["bin_s"] * rate_hz
    np.testing.assert_allclose(s["gyro_dps"], np.degrees(g.mean(axis=0)), atol=3e-5)
    np.testing.assert_allclose(s["accel_sd_g"], a.std(axis=0, ddof=1) / 9.80665, rtol=0.05)
    m.drop_before(1e9)
    assert len(m) == 0 and m.bin_s == pytest.approx(0.05)


# --- the soak, the trace -----------------------------------------------------------------------

def _soak_plan() -> Plan:
    return Plan(name="soak", steps=(SoakStep(kind="soak", temperature_degc=25.0, band_degc=0.5,
                                             imu_band_degc=0.2, stable_for_s=60.0,
                                             timeout_s=600.0),))


def test_a_soak_s_criterion_and_progress_are_in_the_state_the_page_reads(tmp_path, monkeypatch):
    monkeypatch.setattr(live_follow, "TRACE_HZ", 1e9)    # no wall-time limit for this test
    files = RunFiles(tmp_path / "20261129T120000Z-abcdef")
    files.folder.mkdir()
    tap = SignalTap()
    rep = RunReporter(files, _soak_plan(), "alice", tap)
    air = [30.0, 27.0, 25.6, 25.4, 25.2, 25.1, 25.0, 24.9, 25.0, 25.0]
    for k, a in enumerate(air):
        tap.chamber = {"air_degc": a, "setpoint_degc": 25.0}
        tap.imus = {"U1": {"temperature_degc": 26.0 - 0.05 * k}}
        rep.on_status(RunStatus(step_index=0, time_s=10.0 * (k + 1)))
    rep.write(force=True)                                 # as the next tick, 0.2 s on, would
    rep.close()
    state = files.read_state()
    assert state is not None
    soak = state["signals"]["soak"]
    assert soak["setpoint_degc"] == 25.0 and soak["band_degc"] == 0.5
    assert soak["stable_for_s"] == 60.0 and soak["imu_band_degc"] == 0.2
    assert soak["in_band_s"] == pytest.approx(100.0 - 40.0)   # within ±0.5 °C from 40 s on
    assert soak["unit_span_degc"]["U1"] == pytest.approx(0.05 * 6)  # over the last 60 s
    trace = [json.loads(line) for line in files.events.read_text().splitlines()
             if '"trace"' in line]
    assert [p["air_degc"] for p in trace] == air
    assert trace[-1]["unit_degc"] == {"U1": pytest.approx(25.55)}


def test_the_trace_is_decimated_in_station_and_in_wall_time():
    tap = SignalTap()
    tap.chamber = {"air_degc": 25.0}
    f = live_follow.LiveFollower(_soak_plan(), tap)
    got = [f.trace_point(0.5 * k, 0) for k in range(200)]   # 100 s of station time at once
    assert sum(p is not None for p in got) == 1             # at most TRACE_HZ a wall second


# --- what the page gets -------------------------------------------------------------------------

def test_the_snapshot_carries_the_window_means_and_the_trace_so_far(browser, supervisor,
                                                                    tmp_path):
    run = supervisor.runs()[0].run_id
    folder = tmp_path / "runs" / run
    folder.mkdir(parents=True)
    lines = [{"type": "log", "line": "x"}]
    lines += [{"type": "trace", "time_s": float(k), "air_degc": 25.0} for k in range(5000)]
    lines += [{"type": "window", "step_index": 3, "units": {"U1": {"n": 10}}}]
    (folder / "events.jsonl").write_text(
        "".join(json.dumps(e) + "\n" for e in lines) + '{"type": "trace", "ti', encoding="utf-8")
    with browser("observer").client.websocket_connect(
            f"/ws/runs/{run}", headers={"origin": "http://testserver"}) as ws:
        first = ws.receive_json()
    history = first["history"]
    assert first["type"] == "snapshot" and [w["step_index"] for w in history["windows"]] == [3]
    times = [p["time_s"] for p in history["trace"]]
    assert len(times) <= 2 * live.HISTORY_TRACE and times[0] == 0.0
    assert len(set(np.diff(times))) == 1 and times[-1] >= 5000 - history["trace_stride"]


# --- bounds ---------------------------------------------------------------------------------------

def test_a_paced_run_s_events_stay_within_the_rate_and_queue_limits(sup, plan_file):
    run_id = sup.start(plan_file, station="sim", serials=[], operator="alice", pace=0.02)
    reader = sup.subscribe(run_id)
    idle = sup.subscribe(run_id)             # a page that never reads
    assert isinstance(idle, SubscriberQueue)
    received: list[tuple[float, dict]] = []
    biggest = 0
    deadline = time.monotonic() + 50
    answered = False
    while time.monotonic() < deadline:
        try:
            event = reader.get(timeout=0.2)
        except queue.Empty:
            event = None
        biggest = max(biggest, idle.qsize())
        if event is None:
            continue
        received.append((time.monotonic(), event))
        if event["type"] == "prompt" and not answered:
            sup.answer(run_id, event["prompt_id"], event["step_index"], True, "alice")
            answered = True
        if event["type"] == "end":
            break
    assert received and received[-1][1]["type"] == "end", [e["type"] for _t, e in received]
    signals = [t for t, e in received if e["type"] == "signals"]
    assert len(signals) > 20
    per_s = max(sum(1 for u in signals if t <= u < t + 1.0) for t in signals)
    assert per_s <= 1.0 / FOLLOW_S + 1
    assert biggest <= MAX_TOTAL
    kept = [idle.get_nowait() for _ in range(idle.qsize())]
    assert sum(e["type"] == "signals" for e in kept) <= MAX_SAMPLES
    assert {"status", "step", "window", "end"} <= {e["type"] for e in kept}  # never dropped
    sizes = [len(json.dumps(e)) for _t, e in received if e["type"] == "signals"]
    assert max(sizes) < 8_000                # one sample: bytes, not a block of samples
    sup.unsubscribe(run_id, reader)
    sup.unsubscribe(run_id, idle)


def test_a_failing_live_view_never_stops_the_run_s_reporting(tmp_path, monkeypatch, capsys):
    from imucalib.station.devices import ImuBlock
    from imucalib.web import window_stats

    def broken(*_a, **_k):
        raise RuntimeError("live view bug")

    monkeypatch.setattr(live_follow.LiveFollower, "tick", broken)
    monkeypatch.setattr(live_follow.LiveFollower, "trace_point", broken)
    monkeypatch.setattr(window_stats.BinnedMoments, "add", broken)
    files = RunFiles(tmp_path / "20261129T120000Z-abcdef")
    files.folder.mkdir()
    tap = SignalTap()
    n = 10
    tap.imu("U1", ImuBlock(time_s=np.arange(n) * 0.01, device_time_s=np.full(n, np.nan),
                           counter=np.arange(n), gyro_rps=np.zeros((n, 3)),
                           accel_mps2=np.zeros((n, 3)), temperature_degc=np.full(n, 25.0),
                           saturated=np.zeros(n, dtype=bool)))
    assert tap.imus["U1"]["samples"] == n and "U1" not in tap.moments  # the read went on
    rep = RunReporter(files, _soak_plan(), "alice", tap)
    rep.on_status(RunStatus(step_index=0, time_s=10.0))
    rep.on_status(RunStatus(step_index=0, time_s=20.0))
    rep.close()
    assert files.read_state()["steps"] == ["running"]
    assert capsys.readouterr().err.count("RuntimeError: live view bug") == 1   # told once


def test_a_page_waits_for_its_events_on_the_loop_without_a_thread_of_its_own():
    """``SubscriberQueue.next_event``: woken by a publish from another thread, at once."""
    import asyncio
    import threading

    q = SubscriberQueue()
    q.publish({"type": "snapshot"})

    async def page() -> list[tuple[str | None, float]]:
        got = []
        threads = threading.active_count()
        first = await q.next_event(0.5)                      # already there
        got.append((first and first["type"], 0.0))
        t0 = time.monotonic()
        assert await q.next_event(0.2) is None               # nothing: the timeout
        got.append((None, time.monotonic() - t0))
        sent: list[float] = []

        def publish_later() -> None:
            time.sleep(0.1)
            sent.append(time.monotonic())
            q.publish({"type": "status"})

        threading.Thread(target=publish_later).start()
        event = await q.next_event(5.0)
        got.append((event and event["type"], time.monotonic() - sent[0]))
        assert threading.active_count() <= threads + 1       # the publisher's thread only
        return got

    first, empty, woken = asyncio.run(page())
    assert first[0] == "snapshot"
    assert empty[0] is None and 0.15 < empty[1] < 1.0
    assert woken[0] == "status" and woken[1] < 0.05          # woken, not polled
