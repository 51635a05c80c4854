"""Durable before done: a step's record never claims samples the file does not hold.

Kills at every step boundary, at random instants and during the final close; the state on disk
after every HDF5 flush of a run; full disks (a file-size limit, a small tmpfs) during a run.
``IMUCALIB_KILL_CAMPAIGN=N`` runs N random-instant kills instead of the CI's three.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from imucalib.errors import StorageFullError
from imucalib.io import open_recording
from imucalib.io.coverage import uncovered_done_steps
from imucalib.plan import write_plan
from imucalib.station.runner import RunOptions, find_resume_point, resume_run, run_plan
from imucalib.station.sim import SimStation

from .conftest import small_p1

CHILD = Path(__file__).with_name("_run_child.py")
N_RANDOM_KILLS = int(os.environ.get("IMUCALIB_KILL_CAMPAIGN", "3"))


def tiny_plan():
    """Nine steps of a small P1 plan: check, warm-up, positions, static, two pitch rates."""
    plan = small_p1(name="tiny", static_s=30.0, warm_up_s=2.0)
    return plan.model_copy(update={"steps": tuple(plan.steps[i] for i in (0, 1, 2, 3, 8, 9, 10, 11,
                                                                          13))})


def station_factory(plan, start_time_s):
    return SimStation(plan.twin, start_time_s=start_time_s)


def child(plan_file: Path, out: Path, *mode: str, timeout_s: float = 120) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, str(CHILD), str(plan_file), str(out), *mode],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def window_data(path: Path) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """IMU time and gyro of every done step's valid window, by plan step."""
    out = {}
    with open_recording(path) as rec:
        for s in rec.steps:
            if s.status == "done" and s.has_valid_window:
                d = rec.read_step(s.index, "imu", "IMU-0001", ["gyro_x_rps"])
                out[s.commanded["plan_step"]] = (d.time_s, d.columns["gyro_x_rps"])
    return out


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """One uninterrupted run of the tiny plan, and its plan file."""
    folder = tmp_path_factory.mktemp("reference")
    plan = tiny_plan()
    plan_file = write_plan(plan, folder / "plan.toml")
    station = SimStation(plan.twin)
    summary = run_plan(plan, station, folder / "ref.h5",
                       options=RunOptions(truth=station.truth, tick_s=2.0))
    assert summary.status == "done"
    return plan, plan_file, folder / "ref.h5"


def check_resumed_against_reference(path: Path, reference_path: Path, done_before: set[int]):
    """Resume must finish; done steps cover their windows; steps finished before are identical."""
    summary = resume_run(path, station_factory, options=RunOptions(tick_s=2.0))
    assert summary.status == "done", summary
    with open_recording(path) as rec:
        assert uncovered_done_steps(rec) == {}
        done = {s.commanded["plan_step"] for s in rec.steps if s.status == "done"}
        assert done == set(range(len(find_resume_point(path).plan.steps)))
    got, ref = window_data(path), window_data(reference_path)
    for k in done_before & set(ref):  # steps with a valid window
        np.testing.assert_array_equal(got[k][0], ref[k][0])
        np.testing.assert_array_equal(got[k][1], ref[k][1])


def test_every_flush_leaves_no_done_step_short_of_its_samples(tmp_path, monkeypatch):
    """Snapshot the file after every HDF5 flush (what a SIGKILL then leaves) and check it."""
    plan = tiny_plan()
    path = tmp_path / "run.h5"
    snapshots: list[Path] = []
    original = h5py.File.flush

    def flush_and_snapshot(self):
        original(self)
        if Path(self.filename) == path and self.mode == "r+":
            snap = tmp_path / f"snap{len(snapshots):04d}.h5"
            shutil.copyfile(path, snap)
            snapshots.append(snap)

    monkeypatch.setattr(h5py.File, "flush", flush_and_snapshot)
    run_plan(plan, SimStation(plan.twin), path, options=RunOptions(tick_s=2.0))
    monkeypatch.undo()
    assert len(snapshots) > 3 * len(plan.steps)  # at least the per-step commits
    seen_done = 0
    for snap in snapshots:
        with open_recording(snap) as rec:
            assert rec.was_open_for_write
            assert uncovered_done_steps(rec) == {}, snap.name
            seen_done = max(seen_done, sum(s.status == "done" for s in rec.steps))
    assert seen_done == len(plan.steps)


def test_a_done_step_short_of_its_samples_is_found_and_run_again(reference, tmp_path):
    """A file whose done step lost its last samples (as before the fix): resume re-runs it."""
    _plan, _, ref_path = reference
    path = tmp_path / "cut.h5"
    shutil.copyfile(ref_path, path)
    with open_recording(path) as rec:
        static = next(s for s in rec.steps if s.kind == "static")
        i_end = rec.row_range("imu", "IMU-0001", None, static.valid_end_s - 1.0)[1]
        entries = list(rec.committed_rows())
    # cut every stream's committed rows at 1 s before the end of the static window
    with h5py.File(path, "r+") as f:
        rows = f["commit/rows"][:]
        for j, entry in enumerate(entries):
            if entry.startswith("streams/"):
                t = f[f"{entry}/time_s"][:]
                rows[j] = min(rows[j], int(np.searchsorted(t, static.valid_end_s - 1.0)))
        f["commit/rows"][:] = rows
        f["steps/status"][static.index + 1:] = b"running"  # nothing after it finished
    with open_recording(path) as rec:
        assert rec.row_range("imu", "IMU-0001")[1] == i_end
        problems = uncovered_done_steps(rec)
    assert list(problems) == [static.index]
    assert "no committed sample in the last 0.025 s of the valid window" in problems[static.index]
    point = find_resume_point(path)
    assert point.first_step == static.commanded["plan_step"]
    assert point.uncovered == problems
    summary = resume_run(path, station_factory, options=RunOptions(tick_s=2.0))
    assert summary.status == "done"
    with open_recording(path) as rec:
        assert uncovered_done_steps(rec) == {}
        assert rec.step(static.index).status == "invalid"
        assert "samples lost when the runner stopped" in rec.step(static.index).note
        assert any("was marked done but" in e.message for e in rec.log)


def test_kill_right_after_each_step_is_done_then_resume(reference, tmp_path):
    """One file, killed after every step boundary in turn and resumed each time."""
    plan, plan_file, ref_path = reference
    path = tmp_path / "k.h5"
    kept: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    for k in range(1, len(plan.steps)):
        proc = child(plan_file, path, "done", "1")  # a run, then resumes: one more step each
        proc.communicate(timeout=120)
        assert proc.returncode == -signal.SIGKILL, (k, proc.returncode)
        with open_recording(path) as rec:
            assert rec.was_open_for_write
            assert uncovered_done_steps(rec) == {}
            done = {s.commanded["plan_step"] for s in rec.steps if s.status == "done"}
        assert done == set(range(k)), (k, done)  # the k-th done reached the file before the kill
        data = window_data(path)
        for step, (t, gyro) in kept.items():  # what was done stays byte for byte
            np.testing.assert_array_equal(data[step][0], t)
            np.testing.assert_array_equal(data[step][1], gyro)
        kept = data
        if k == 1:
            first = {i: d for i, d in data.items()}
    check_resumed_against_reference(path, ref_path, set())
    ref = window_data(ref_path)
    for step, (t, gyro) in first.items():  # before the first kill: as an uninterrupted run
        np.testing.assert_array_equal(t, ref[step][0])
        np.testing.assert_array_equal(gyro, ref[step][1])


@pytest.mark.parametrize("seed", range(N_RANDOM_KILLS))
def test_kill_at_a_random_instant_then_resume(reference, tmp_path, seed):
    _plan, plan_file, ref_path = reference
    path = tmp_path / "r.h5"
    proc = child(plan_file, path, "stall")  # a late kill lands before the close, not after it
    deadline = time.monotonic() + 60
    while not path.exists():  # the imports take about 1.5 s
        assert time.monotonic() < deadline and proc.poll() is None
        time.sleep(0.005)
    # the tiny plan then takes about 1.5 s of wall-clock time
    time.sleep(float(np.random.default_rng(seed).uniform(0.0, 1.2)))
    proc.send_signal(signal.SIGKILL)
    proc.communicate(timeout=60)
    assert proc.returncode == -signal.SIGKILL, f"seed {seed}: the run ended before the kill"
    with open_recording(path) as rec:
        assert uncovered_done_steps(rec) == {}
        done = {s.commanded["plan_step"] for s in rec.steps if s.status == "done"}
    check_resumed_against_reference(path, ref_path, done)


def test_kill_during_the_final_close_is_finished_by_resume(reference, tmp_path):
    _plan, plan_file, _ = reference
    path = tmp_path / "c.h5"
    proc = child(plan_file, path, "close")
    proc.communicate(timeout=120)
    assert proc.returncode == -signal.SIGKILL
    with open_recording(path) as rec:
        assert rec.was_open_for_write
        assert all(s.status == "done" for s in rec.steps)
    result = subprocess.run([sys.executable, "-m", "imucalib.cli", "run", "--resume", str(path),
                             "--no-live"], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert "note: every step was already done; the interrupted close was finished" in \
        result.stdout
    assert path.with_name("c.crashed.h5").exists()
    with open_recording(path, strict=True) as rec:  # closed cleanly now
        assert any("its file was not closed; closed by resume" in e.message for e in rec.log)
    again = subprocess.run([sys.executable, "-m", "imucalib.cli", "run", "--resume", str(path),
                            "--no-live"], capture_output=True, text=True, timeout=120)
    assert again.returncode == 2
    assert "already done and the file is closed; there is nothing to resume" in again.stderr


def run_child_with_fsize(plan_file, path, limit_bytes, at_s, min_free_bytes=None):
    mode = ["fsize", str(limit_bytes), str(at_s)]
    if min_free_bytes is not None:
        mode.append(str(min_free_bytes))
    proc = child(plan_file, path, *mode)
    out, err = proc.communicate(timeout=120)
    return proc.returncode, out, err


@pytest.mark.parametrize(("extra", "min_free", "expected"), [
    (8 << 20, None, "error: disk nearly full"),  # the run's guard stops it (128 MiB default)
    (6 << 20, 0, "error: no room to write rows"),  # no guard: the writer's reserve refuses
    (-(1 << 20), 0, "error: no room to "),  # a limit below what the file holds
], ids=["run-guard", "writer-reserve", "hdf5-fails"])
def test_a_file_size_limit_mid_run_ends_cleanly_and_resume_completes(reference, tmp_path, extra,
                                                                       min_free, expected):
    plan, plan_file, ref_path = reference
    path = tmp_path / "f.h5"
    rc, out, err = run_child_with_fsize(plan_file, path, extra, 60.0, min_free)
    assert rc == 2, (out, err)
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    assert err.startswith(expected), err
    assert "imucalib run --resume" in err
    assert ("could not be closed cleanly" in err) is (extra < 0)
    clean = extra > 0
    with open_recording(path, strict=clean) as rec:  # closed cleanly unless HDF5 failed
        assert rec.was_open_for_write is not clean
        if clean:
            assert rec.steps[-1].status == "aborted"
            assert "StorageFullError" in rec.steps[-1].note
        assert uncovered_done_steps(rec) == {}
        done = {s.commanded["plan_step"] for s in rec.steps if s.status == "done"}
    assert 0 < len(done) < len(plan.steps)
    check_resumed_against_reference(path, ref_path, done)  # the limit ended with the child


def test_disk_guard_stops_the_equipment_safely(tmp_path):
    plan = tiny_plan()
    station = SimStation(plan.twin)
    path = tmp_path / "g.h5"
    options = RunOptions(tick_s=2.0)

    def disk_fills_up() -> None:  # as seen by the guard: 10 TiB must stay free from t = 20 s
        options.min_free_bytes = 10 << 40

    station.at(20.0, disk_fills_up)
    with pytest.raises(StorageFullError, match=r"disk nearly full: .* left for .*g\.h5 \(the run "
                       r"stops below 10995 GB\); the equipment was stopped safely"):
        run_plan(plan, station, path, options=options)
    status = station.table.status()
    assert set(status.modes) == {"off"} and not status.interlock_closed
    with open_recording(path, strict=True) as rec:
        assert rec.steps[-1].status == "aborted"


def _can_mount_tmpfs(folder: Path) -> bool:
    if os.geteuid() != 0 or shutil.which("mount") is None:
        return False
    folder.mkdir()
    ok = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64m", "tmpfs", str(folder)],
                        capture_output=True).returncode == 0
    return ok


def test_a_small_tmpfs_filling_up_mid_run(reference, tmp_path):
    plan, _, ref_path = reference
    disk = tmp_path / "disk"
    if not _can_mount_tmpfs(disk):
        pytest.skip("needs root to mount a tmpfs (CI runs as root); the file-size-limit test "
                    "covers the same path without it")
    try:
        path = disk / "t.h5"
        station = SimStation(plan.twin)
        filler = disk / "filler"

        def fill() -> None:  # another program takes all but 12 MB of the 64 MB disk
            free = shutil.disk_usage(disk).free
            filler.write_bytes(b"\0" * max(free - (12 << 20), 0))

        station.at(60.0, fill)
        with pytest.raises(StorageFullError, match="disk nearly full"):
            run_plan(plan, station, path, options=RunOptions(tick_s=2.0, min_free_bytes=16 << 20))
        assert set(station.table.status().modes) == {"off"}
        with open_recording(path, strict=True) as rec:
            done = {s.commanded["plan_step"] for s in rec.steps if s.status == "done"}
            assert uncovered_done_steps(rec) == {}
        filler.unlink()  # space freed
        summary = resume_run(path, station_factory,
                             options=RunOptions(tick_s=2.0, min_free_bytes=16 << 20))
        assert summary.status == "done"
        shutil.copyfile(path, tmp_path / "t.h5")
    finally:
        subprocess.run(["umount", str(disk)], check=False)
    with open_recording(tmp_path / "t.h5") as rec:
        assert uncovered_done_steps(rec) == {}
    got, ref = window_data(tmp_path / "t.h5"), window_data(ref_path)
    for k in done & set(ref):
        np.testing.assert_array_equal(got[k][1], ref[k][1])


def test_a_run_that_would_not_fit_is_refused_before_anything_moves(tmp_path):
    plan = tiny_plan()
    station = SimStation(plan.twin)
    free = shutil.disk_usage(tmp_path).free
    with pytest.raises(StorageFullError, match=r"not enough room for the run: its recording "
                       r"needs about .* MB and .* must stay free, but .* has .* \(free space, or "
                       r"what the file-size limit leaves\); free some space or write elsewhere"):
        run_plan(plan, station, tmp_path / "x.h5", options=RunOptions(min_free_bytes=free))
    assert not (tmp_path / "x.h5").exists()
    assert station.table.status().modes == ("off", "off")  # nothing moved
