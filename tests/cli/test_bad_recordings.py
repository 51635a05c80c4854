"""Damaged Recordings on the command line: exit code 2, one clear line on stderr, no traceback."""

from __future__ import annotations

import importlib.util
import re
import shutil
import subprocess
import sys
from pathlib import Path
from types import ModuleType

import h5py
import numpy as np
import pytest
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.io import _probe

runner = CliRunner()
IO_TESTS = Path(__file__).parents[1] / "io"
CLI = [sys.executable, "-m", "imucalib.cli"]


def _load(name: str, file: str) -> ModuleType:
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, IO_TESTS / file)
        assert spec is not None and spec.loader is not None
        sys.modules[name] = module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    return sys.modules[name]


damage = _load("imucalib_tests_damage", "damage.py")


@pytest.fixture(scope="module")
def template(tmp_path_factory) -> Path:
    return damage.write_small(tmp_path_factory.mktemp("valid") / "small.h5")


def _damaged(template: Path, folder: Path, name: str, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A copy of `template` with damage `name`; a probe that hangs gives up after 1 s, not 10."""
    if name == "zeroed-global-heap":
        monkeypatch.setattr(_probe, "PROBE_TIMEOUT_S", 1.0)
    path = folder / f"{name}.h5"
    shutil.copyfile(template, path)
    damage.DAMAGES[name][0](path)
    return path


def _line(name: str, path: Path) -> re.Pattern[str]:
    """The error line on stderr: ``error: <message>`` on a line of its own."""
    message = damage.expected_message(name, path)
    rest = message[1:] if message.startswith("^") else ".*" + message
    return re.compile("^error: " + rest, re.MULTILINE)


def _check_refused(result, name: str, path: Path) -> None:
    assert result.exit_code == 2, (result.exit_code, result.output, result.exception)
    assert isinstance(result.exception, SystemExit)
    assert _line(name, path).search(result.stderr), result.stderr
    assert "Traceback" not in result.output


@pytest.mark.parametrize("name", sorted(damage.DAMAGES))
def test_inspect_and_export_refuse_a_damaged_file(template, tmp_path, name, monkeypatch):
    path = _damaged(template, tmp_path, name, monkeypatch)
    _check_refused(runner.invoke(app, ["inspect", str(path)]), name, path)
    out = tmp_path / "out.csv"
    result = runner.invoke(app, ["export", str(path), "--stream", "imu/IMU-0001", "--out",
                                 str(out)])
    _check_refused(result, name, path)
    assert not out.exists()


@pytest.mark.parametrize("name", ["no-log", "commanded-not-json", "flipped-stream-header",
                                  "zeroed-global-heap", "time-huge", "commit-negative"])
def test_calibrate_refuses_a_damaged_file(template, tmp_path, name, monkeypatch):
    path = _damaged(template, tmp_path, name, monkeypatch)
    _check_refused(runner.invoke(app, ["calibrate", str(path), "--out", str(tmp_path)]),
                   name, path)


def test_calibrate_and_export_refuse_a_nan_time_stamp_in_a_passing_run(tactical_run, tmp_path):
    path = tmp_path / "run.h5"
    shutil.copyfile(tactical_run, path)
    with h5py.File(path, "r+") as f:
        f["streams/imu/IMU-0001/time_s"][1000] = np.nan
    line = re.compile(rf"^error: {re.escape(str(path))} is damaged: stream imu/IMU-0001 time_s "
                      r"row 1000 is nan; expected finite times from 0 to 1e9 s that never "
                      rf"decrease; run `imucalib recover {re.escape(str(path))}` to copy out the "
                      r"rows before row 1000$", re.MULTILINE)
    result = runner.invoke(app, ["calibrate", str(path), "--out", str(tmp_path)])
    assert result.exit_code == 2 and line.search(result.stderr), result.output
    assert "PASS" not in result.output and not list(tmp_path.glob("*.json"))
    result = runner.invoke(app, ["export", str(path), "--stream", "imu/IMU-0001", "--out",
                                 str(tmp_path / "x.csv")])
    assert result.exit_code == 2 and line.search(result.stderr), result.output
    assert not (tmp_path / "x.csv").exists()
    # recover copies the rows before the bad one; the copy exports
    result = runner.invoke(app, ["recover", str(path)])
    assert result.exit_code == 0, result.output
    assert "rows from 1000 dropped: time_s row 1000 is nan" in " ".join(result.output.split())
    fixed = tmp_path / "run.recovered.h5"
    result = runner.invoke(app, ["export", str(fixed), "--stream", "imu/IMU-0001", "--out",
                                 str(tmp_path / "x.csv")])
    assert result.exit_code == 0, result.output
    assert len((tmp_path / "x.csv").read_text().splitlines()) == 1 + 1000


@pytest.mark.parametrize("name", ["no-log", "commanded-not-json", "time-nan", "column-short"])
def test_recover_mends_a_damaged_file_and_inspect_then_works(template, tmp_path, name, monkeypatch):
    path = _damaged(template, tmp_path, name, monkeypatch)
    result = runner.invoke(app, ["recover", str(path)])
    assert result.exit_code == 0, result.output
    assert "the original is damaged:" in result.output and "verified" in result.output
    result = runner.invoke(app, ["inspect", str(tmp_path / f"{name}.recovered.h5")])
    assert result.exit_code == 0, result.output


def test_recover_refuses_a_file_that_hangs_hdf5(template, tmp_path, monkeypatch):
    path = _damaged(template, tmp_path, "zeroed-global-heap", monkeypatch)
    _check_refused(runner.invoke(app, ["recover", str(path)]), "zeroed-global-heap", path)


def test_a_real_process_prints_no_traceback(template, tmp_path, monkeypatch):
    path = _damaged(template, tmp_path, "commanded-not-json", monkeypatch)
    out = subprocess.run([*CLI, "inspect", str(path)], capture_output=True, text=True,
                         timeout=120, check=False)
    assert out.returncode == 2, out.stderr
    assert "Traceback" not in out.stderr + out.stdout
    assert _line("commanded-not-json", path).search(out.stderr), out.stderr


def test_inspect_of_a_file_left_open_says_what_to_do(tmp_path):
    path = tmp_path / "open.h5"
    out = subprocess.run([sys.executable, str(IO_TESTS / "crash_writer.py"), str(path), "5",
                          "manual", "1"], capture_output=True, text=True, timeout=60, check=False)
    assert out.returncode == -9, out.stderr
    result = runner.invoke(app, ["inspect", str(path)])
    assert result.exit_code == 0, result.output
    text = " ".join(result.output.split())
    assert f"`imucalib run --resume {path}` finishes a station run" in text
    assert f"`imucalib recover {path}` copies what was flushed into a cleanly closed file" in text
