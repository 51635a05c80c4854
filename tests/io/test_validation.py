"""open_recording validates a file at the door: every damage becomes a typed, one-line error."""

from __future__ import annotations

import json
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

from imucalib.errors import RecordingCorruptError, RecordingOpenForWriteError
from imucalib.io import open_recording
from imucalib.io._probe import run_probe
from imucalib.io._validate import first_bad_time
from imucalib.io.inspect import summarize_recording

from . import damage


@pytest.fixture(scope="module")
def template(tmp_path_factory) -> Path:
    return damage.write_small(tmp_path_factory.mktemp("valid") / "small.h5")


@pytest.fixture
def small(template, tmp_path) -> Path:
    path = tmp_path / "run.h5"
    shutil.copyfile(template, path)
    return path


def _read_everything(path: Path, **kwargs) -> None:
    with open_recording(path, **kwargs) as rec:
        rec.metadata, rec.truth, rec.steps, rec.log  # noqa: B018
        for s in rec.streams:
            rec.read_stream(s.device, s.unit)
        for s in rec.truth_streams:
            rec.read_truth_stream(s.device, s.unit)


def test_the_valid_file_opens_and_reads(small):
    _read_everything(small)
    _read_everything(small, probe=False)


@pytest.mark.parametrize("name", sorted(damage.DAMAGES))
def test_damage_is_refused_with_its_message(small, name):
    func, error, _ = damage.DAMAGES[name]
    func(small)
    timeout = 1.0 if name == "zeroed-global-heap" else None  # the default 10 s elsewhere
    with pytest.raises(error, match=damage.expected_message(name, small)) as info:
        _read_everything(small, probe_timeout_s=timeout)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("name", ["no-log", "commanded-not-json", "time-nan", "commit-negative",
                                  "column-short", "flipped-stream-header", "step-window-inf"])
def test_same_message_without_the_probe(small, name):
    func, error, _ = damage.DAMAGES[name]
    func(small)
    with pytest.raises(error, match=damage.expected_message(name, small)):
        _read_everything(small, probe=False)


def test_rows_after_the_commit_count_are_not_checked(small):
    with h5py.File(small, "r+") as f:
        entries = json.loads(f["commit"].attrs["entries_json"])
        rows = f["commit/rows"][()]
        rows[entries.index("streams/imu/IMU-0001")] = 1000
        f["commit/rows"][...] = rows
        f["streams/imu/IMU-0001/time_s"][1500] = np.nan  # not committed: never shown
    with open_recording(small) as rec:
        assert rec.stream_info("imu", "IMU-0001").n_samples == 1000
        assert np.isfinite(rec.read_stream("imu", "IMU-0001").time_s).all()


def test_h5py_errors_after_opening_become_corrupt_errors(small):
    with open_recording(small) as rec:
        with pytest.raises(RecordingCorruptError, match=r"is damaged: /nope is unreadable \("
                                                        r".*\); run `imucalib recover"):
            rec._guard("/nope", rec._file.__getitem__, "nope")

        def not_h5py() -> None:
            raise KeyError("a bug of ours")

        with pytest.raises(KeyError, match="a bug of ours"):  # not disguised as damage
            rec._guard("x", not_h5py)


@pytest.mark.parametrize("block", [1, 7, 1000, 1 << 20])
def test_first_bad_time_across_blocks(tmp_path, block):
    path = tmp_path / "t.h5"
    t = np.arange(5000) / 100.0
    with h5py.File(path, "w") as f:
        ds = f.create_dataset("t", data=t, chunks=(512,))
        assert first_bad_time(ds, 5000, block) is None
        assert first_bad_time(ds, 0, block) is None
        ds[1000] = ds[999]  # equal times are fine
        assert first_bad_time(ds, 5000, block) is None
        for row, value, what in [(2000, 5.0, "is 5.0, before the previous time stamp 19.99"),
                                 (7, np.nan, "is nan"), (0, -0.5, "is -0.5, negative"),
                                 (4999, 2e9, "is 2000000000.0, later than 1e9 s")]:
            ds[row] = value
            assert first_bad_time(ds, 5000, block) == (row, what)
            assert first_bad_time(ds, row, block) is None  # rows before it are valid
            ds[row] = t[row]


# --------------------------------------------------------------------------- the probe
def _hang(progress):
    progress("a very slow thing")
    time.sleep(60)


def test_probe_stops_a_hang_and_names_what_it_was_reading(tmp_path):
    t0 = time.monotonic()
    with pytest.raises(RecordingCorruptError, match=r"did not finish reading its metadata within "
                                                    r"0\.5 s \(it was reading a very slow thing\)"):
        run_probe(tmp_path / "x.h5", _hang, timeout_s=0.5)
    assert time.monotonic() - t0 < 5


def test_probe_reports_a_crash(tmp_path):
    def crash(progress):
        progress("the chunk index")
        os.kill(os.getpid(), signal.SIGSEGV)

    with pytest.raises(RecordingCorruptError, match=r"the HDF5 library crashed \(signal SIGSEGV\) "
                                                    r"reading the chunk index"):
        run_probe(tmp_path / "x.h5", crash, timeout_s=5)


def test_probe_returns_results_and_errors_and_reruns_bugs_here(tmp_path):
    assert run_probe(tmp_path / "x.h5", lambda progress: {"rows": [1, 2]}) == {"rows": [1, 2]}

    def refuse(progress):
        raise RecordingOpenForWriteError("still open")

    with pytest.raises(RecordingOpenForWriteError, match=r"^still open$"):
        run_probe(tmp_path / "x.h5", refuse)
    calls = []

    def buggy(progress):
        calls.append(os.getpid())
        raise ZeroDivisionError("bug")

    with pytest.raises(ZeroDivisionError):  # rerun in this process: the traceback is ours
        run_probe(tmp_path / "x.h5", buggy)
    assert calls == [os.getpid()]


def test_probe_costs_little(small):
    open_recording(small).close()
    t0 = time.perf_counter()
    for _ in range(5):
        open_recording(small).close()
    assert (time.perf_counter() - t0) / 5 < 1.0  # tens of ms; generous for loaded CI machines


# --------------------------------------------------------------------------- left open
@pytest.fixture(scope="module")
def left_open(tmp_path_factory, helpers) -> Path:
    path = tmp_path_factory.mktemp("open") / "open.h5"
    out = subprocess.run([sys.executable, str(helpers.crash_script), str(path), "5", "manual",
                          "1"], capture_output=True, text=True, timeout=60, check=False)
    assert out.returncode == -9, out.stderr
    return path


def test_a_file_left_open_says_how_to_finish_or_copy_it(left_open):
    with pytest.raises(RecordingOpenForWriteError,
                       match=rf"^{left_open} is still marked open for writing \(its writer "
                             r"crashed, was killed while closing, or is still running\); "
                             rf"`imucalib run --resume {left_open}` finishes a station run \(it "
                             rf"recovers and closes the file first\), `imucalib recover "
                             rf"{left_open}` copies what was flushed"):
        open_recording(left_open, strict=True)
    with open_recording(left_open) as rec:
        assert rec.was_open_for_write
    from rich.console import Console

    console = Console(record=True, width=300)
    summarize_recording(left_open).render(console)
    text = console.export_text()
    assert f"`imucalib run --resume {left_open}` finishes a station run" in text
    assert f"`imucalib recover {left_open}` copies what was flushed" in text
