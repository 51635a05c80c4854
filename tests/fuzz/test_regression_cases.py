"""The reproducers of the issue-27 campaign, kept as cases (``tests/fuzz/cases/<name>/``).

Each case is a folder with ``case.toml`` and its small input files:

``args``
    The command line; ``{case}`` is the case's folder and ``{tmp}`` a fresh temporary folder.
``expect``
    A phrase the output must hold (for exit 2: the one ``error:`` line).
``exit``
    The exit code (default 2: one ``error:`` line on stderr, nothing else).
``build``
    Optional: a builder below that writes into ``{tmp}`` what is too large or too binary to keep
    (a 2 MiB field, a Recording a crashed writer left open).
``found``
    What the campaign measured before the fix (documentation only).

Records-database cases (``records_*``) are the records suite's (``test_records_fuzz.py``).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from ._harness import check_outcome, run_cli
from ._still_imu import CHILD_PATH

CASES = Path(__file__).with_name("cases")
CASE_DIRS = sorted(p.parent for p in CASES.glob("*/case.toml") if not p.parent.name.startswith(
    "records_"))


def _long_field(tmp: Path) -> None:
    """A CSV whose first data row has a 2 MiB field, and one whose field is 200 000 characters."""
    header = "time_s,gyro_x_rps,gyro_y_rps,gyro_z_rps,accel_x_mps2,accel_y_mps2,accel_z_mps2"
    rows = [f"{k * 0.01:.2f},0.001,0.002,0.003,0.01,0.02,9.81" for k in range(50)]
    for name, size in (("long.csv", 2 << 20), ("long_within.csv", 200_000)):
        fields = rows[0].split(",")
        fields[2] = "x" * size
        text = "\n".join([header, ",".join(fields), *rows[1:]]) + "\n"
        (tmp / name).write_text(text, encoding="utf-8")


_OPEN_BAD_UTF8 = CHILD_PATH + r"""
import os, sys
import h5py
import numpy as np
from _still_imu import still_imu_columns
from imucalib.io.recording import RecordingWriter
from imucalib.io.streams import imu_stream_spec

cols = still_imu_columns(400)
w = RecordingWriter(sys.argv[1], streams=[imu_stream_spec("IMU-0001")],
                    metadata={"operator": "fz"}, chunk_rows=256)
w.__enter__()
w.append("imu", "IMU-0001", cols)
w.flush()
del w._file.attrs["operator"]
w._file.attrs.create("operator", data=np.array(b"\xff\xfe op", dtype=object),
                     dtype=h5py.string_dtype("utf-8"))
w._file.flush()
sys.stdout.flush()
os._exit(0)  # a crash: the file stays open for write
"""


def _open_recording_bad_utf8(tmp: Path) -> None:
    """A Recording left open by a crashed writer, its ``operator`` not valid UTF-8."""
    done = subprocess.run([sys.executable, "-c", _OPEN_BAD_UTF8, str(tmp / "open.h5")],
                          capture_output=True, text=True, timeout=120,
                          env={**os.environ, "PYTHONWARNINGS": "ignore"})
    assert done.returncode == 0, done.stderr


def _triad_result(tmp: Path) -> None:
    """A small triad result (identity-like parameters) for ``apply``."""
    from imucalib.models.result import (
        CalibrationResult,
        Provenance,
        ResidualStats,
        triad_parameter_names,
    )

    names = (*triad_parameter_names("accel", "triad"), *triad_parameter_names("gyro", "triad"))
    k = len(names)
    result = CalibrationResult(
        sensor_id="IMU-0001", procedure="p1", model="triad", param_names=names,
        values=np.zeros(k), covariance=np.eye(k) * 1e-10, units=dict.fromkeys(names, "1"),
        residuals={"accel: Z up": ResidualStats((0.0,) * 3, (1e-3,) * 3, 100, "m/s^2")},
        provenance=Provenance(plan_hash="ab" * 32, recording_sha256="cd" * 32,
                              recording="run.h5", software_version="0.1.0",
                              created_utc="2026-11-29T00:00:00Z", details={}),
        notes=())
    (tmp / "result.json").write_text(result.to_json(), encoding="utf-8")


BUILDERS = {"long_field": _long_field, "open_recording_bad_utf8": _open_recording_bad_utf8,
            "triad_result": _triad_result}


def _load(folder: Path) -> dict[str, Any]:
    return tomllib.loads((folder / "case.toml").read_text(encoding="utf-8"))


def test_every_case_is_complete():
    assert len(CASE_DIRS) >= 12
    for folder in CASE_DIRS:
        case = _load(folder)
        assert {"args", "expect", "found"} <= set(case), folder.name
        assert case.get("build") is None or case["build"] in BUILDERS, folder.name


@pytest.mark.parametrize("folder", CASE_DIRS, ids=[p.name for p in CASE_DIRS])
def test_reproducer_gives_one_clear_line(folder: Path, tmp_path: Path):
    case = _load(folder)
    if case.get("build"):
        BUILDERS[case["build"]](tmp_path)
    args = [a.replace("{case}", str(folder)).replace("{tmp}", str(tmp_path))
            for a in case["args"]]
    code, out, err = run_cli(*args)
    check_outcome(code, out, err, f"{args[0]} (case {folder.name})", door="cases")
    expected = case.get("exit", 2)
    assert code == expected, f"{folder.name}: exit {code}, expected {expected}\n{out}{err}"
    if expected == 2:
        lines = [ln for ln in err.splitlines() if ln.strip()]
        assert len(lines) == 1 and lines[0].startswith("error: "), f"{folder.name}:\n{err}"
        assert out.strip() == "", f"{folder.name}: printed\n{out}"
    text = " ".join((out + err).split())
    assert case["expect"] in text, f"{folder.name}: {case['expect']!r} not in\n{out}{err}"
