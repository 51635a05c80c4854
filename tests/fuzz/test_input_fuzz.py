"""Property-based fuzzing of the doors issue 27 named: import specs, Allan, field, recover, report
and export of a result JSON.

The rules are those of :mod:`._harness` (exit 0 or 1, or exit 2 with one ``error:`` line; no
traceback, no internal error, no hang): every command runs in this process under the per-case
time limit, except ``recover``, whose damaged HDF5 files are opened in a child process
(:func:`._harness.run_child`) so that a hang or a crash inside HDF5 is caught too. What a
command writes with exit 0 must hold finite numbers only. The costly doors (Allan, field: a
successful case writes figures or a PDF) grow more slowly with ``IMUCALIB_FUZZ_EXAMPLES``.
"""

from __future__ import annotations

import functools
import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from ._harness import (
    ODD_NUMBERS,
    SCALE,
    assert_finite_csv,
    check_outcome,
    damage_bytes,
    fuzz_settings,
    mutate_lines,
    mutate_numbers,
    run_child,
    run_cli,
)
from ._still_imu import CHILD_PATH

#: The multiplier of the costly doors in a campaign (a fifth of the others').
SLOW_SCALE = max(1, SCALE // 5)
ODD_TEXT = st.sampled_from(["", " ", "tab", "\\t", "whitespace", ";", ",", "|", "1", ".", "-",
                            "\"", "ab", ",,", "furlong", "counts", "deg/s", "g", "m/s^2", "rad/s",
                            "x" * 300, "GyroX", "Time", "é", "\x00", "NaN", "1e308"])
ODD_TOML = st.sampled_from(["3", "-1", "1e308", "nan", "inf", "\"\"", "\"x\"", "true", "[]",
                            "[1, 2]", "{}", "{ a = 1 }", "\"counts\"", "0", "1e-320",
                            "\"whitespace\"", "\";\"", "\"tab\"", "99999999999999999999"])


def _strict_json(path: Path) -> Any:
    """Parse `path`, refusing NaN and ±Infinity."""
    def refuse(token: str) -> None:
        raise AssertionError(f"{path}: {token} written")

    return json.loads(path.read_text(encoding="utf-8"), parse_constant=refuse)


def _finite_outputs(folder: Path) -> None:
    """Every JSON and CSV a command wrote under `folder` holds finite numbers only."""
    for path in folder.rglob("*"):
        if path.suffix == ".json":
            _strict_json(path)
        elif path.suffix == ".csv":
            assert_finite_csv(path)


@functools.cache
def _text(path: Path) -> str:
    """The text of a fixture's file, read once."""
    return path.read_text(encoding="utf-8")


def _fresh(folder: Path) -> Path:
    """`folder`, emptied (hypothesis reuses a test's tmp_path for every example)."""
    import shutil

    shutil.rmtree(folder, ignore_errors=True)
    return folder


# ---------------------------------------------------------------------------- import specs
VENDOR_SPEC = """\
skip_rows = 2
delimiter = ";"
gyro_unit = "deg/s"
accel_unit = "g"
time_unit = "ms"

[columns]
t = "Time"
gx = "GyroX"
gy = "GyroY"
gz = "GyroZ"
ax = "AccX"
ay = "AccY"
az = "AccZ"
"""

COUNTS_SPEC = """\
gyro_unit = "counts"
gyro_scale = 131.0
gyro_offset = 12.0
accel_unit = "counts"
accel_scale = 16384.0
accel_offset = -20.0
sample_rate_hz = 100.0

[columns]
gx = "gx"
gy = "gy"
gz = "gz"
ax = "ax"
ay = "ay"
az = "az"
"""


@pytest.fixture(scope="module")
def vendor_logs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """A vendor log (preamble, semicolons, ms, °/s and g) and a raw-count log without time."""
    folder = tmp_path_factory.mktemp("vendor")
    rng = np.random.default_rng(27)
    n = 600
    gyro = rng.normal(0.0, 0.05, (n, 3))
    gyro[300:400, 2] += 90.0  # a turn about z
    accel = rng.normal(0.0, 0.002, (n, 3)) + np.array([0.0, 0.0, 1.0])
    rows = [f"{10 * k};" + ";".join(f"{v:.5f}" for v in (*gyro[k], *accel[k])) for k in range(n)]
    vendor = folder / "vendor.csv"
    vendor.write_text("# logger v2\n# 100 Hz\nTime;GyroX;GyroY;GyroZ;AccX;AccY;AccZ\n"
                      + "\n".join(rows) + "\n", encoding="utf-8")
    counts = folder / "counts.csv"
    raw = np.column_stack([gyro * 131.0 + 12.0, accel * 16384.0 - 20.0]).round()
    counts.write_text("gx,gy,gz,ax,ay,az\n" + "\n".join(",".join(f"{int(v)}" for v in r)
                                                         for r in raw) + "\n", encoding="utf-8")
    return {"vendor": vendor, "counts": counts}


def _mutated_spec(base: str, data: st.DataObject) -> str:
    how = data.draw(st.sampled_from(["numbers", "lines", "value", "key", "none"]))
    if how == "numbers":
        return mutate_numbers(base, data)
    if how == "lines":
        return mutate_lines(base, data)
    if how == "none":
        return base
    lines = base.splitlines()
    keyed = [i for i, ln in enumerate(lines) if " = " in ln]
    i = data.draw(st.sampled_from(keyed))
    key = lines[i].split(" = ")[0]
    if how == "value":
        lines[i] = f"{key} = {data.draw(ODD_TOML)}"
    else:
        name = data.draw(st.sampled_from(["columns", "units", "column_map", "skip_rows",
                                          "delimiter", "accel_file", "bogus", "sample_rate_hz",
                                          "time_column"]))
        lines.insert(data.draw(st.integers(0, len(lines))), f"{name} = {data.draw(ODD_TOML)}")
    return "\n".join(lines) + "\n"


_OPTIONS = ("--delimiter", "--column-map", "--units", "--gyro-unit", "--accel-unit",
            "--skip-rows", "--sample-rate-hz", "--time-column", "--time-unit", "--gyro-scale",
            "--accel-offset")


@fuzz_settings(40)
@given(data=st.data())
def test_mutated_import_specs_are_read_or_refused(vendor_logs, tmp_path, data):
    which = data.draw(st.sampled_from(["vendor", "counts"]))
    spec_text = _mutated_spec(VENDOR_SPEC if which == "vendor" else COUNTS_SPEC, data)
    spec = tmp_path / "spec.toml"
    spec.write_text(spec_text, encoding="utf-8")
    extra: list[str] = []
    for _ in range(data.draw(st.integers(0, 2))):
        option = data.draw(st.sampled_from(_OPTIONS))
        value = data.draw(st.one_of(ODD_TEXT, ODD_NUMBERS, st.sampled_from(
            ["gx=GyroX", "gx=NoSuch", "GyroX=gyro_x_rps", "t=Time,gx=GyroX", "gx", "=", "gx=",
             "gx=deg/s", "t=ms", "az=AccZ [g]"])))
        extra += [option, value]
    json_out = _fresh(tmp_path / "seg.json")
    code, out, err = run_cli("segments", str(vendor_logs[which]), "--import", str(spec),
                             "--json", str(json_out), *extra)
    check_outcome(code, out, err, f"import-spec segments {extra}\n{spec_text}")
    if code == 0:
        _strict_json(json_out)


# ---------------------------------------------------------------------------------- Allan
ALLAN_HEADER = "time_s,gyro_x_rps,gyro_y_rps,gyro_z_rps,accel_x_mps2,accel_y_mps2,accel_z_mps2"


@pytest.fixture(scope="module")
def allan_columns() -> np.ndarray:
    """A static log: 1500 samples at 100 Hz (time, gyro, accelerometer)."""
    rng = np.random.default_rng(952)
    n = 1500
    cols = np.column_stack([np.arange(n) * 0.01, rng.normal(0, 1e-3, (n, 3)),
                            rng.normal(0, 5e-3, (n, 3)) + np.array([0.0, 0.0, 9.81])])
    return cols


def _allan_text(cols: np.ndarray, data: st.DataObject) -> tuple[str, list[str]]:
    cols = cols.copy()
    header = ALLAN_HEADER.split(",")
    options: list[str] = []
    how = data.draw(st.sampled_from(["zero", "constant", "time-scale", "value-scale", "spike",
                                     "header", "numbers", "lines", "rows", "options", "none"]))
    j = data.draw(st.integers(0, cols.shape[1] - 1))
    if how == "zero":
        cols[:, j] = 0.0
    elif how == "constant":
        cols[:, j] = data.draw(st.sampled_from([1.0, -3.5, 1e30, 1e-300]))
    elif how == "time-scale":
        cols[:, 0] *= data.draw(st.sampled_from([1e-12, 1e-9, 1e-6, 1e-3, 10.0, 1e3, 1e6, 1e9]))
    elif how == "value-scale":
        cols[:, max(j, 1)] *= data.draw(st.sampled_from([1e-300, 1e-30, 1e-9, 1e9, 1e30, -1.0]))
    elif how == "spike":
        k = data.draw(st.integers(0, cols.shape[0] - 1))
        cols[k, max(j, 1)] = data.draw(st.sampled_from([1e30, -1e30, 1e5, 1e300, 1e-320]))
    elif how == "header":
        header[j] = data.draw(st.sampled_from(["time_s [ns]", "time_s [h]", header[j] + " [g]",
                                               "gyro_x_rps [deg/h]", "accel_z_mps2 [mg]",
                                               "temperature_degc", "foo", header[0]]))
    elif how == "rows":
        k = data.draw(st.integers(0, cols.shape[0] - 1))
        cols = data.draw(st.sampled_from([cols[:k], cols[k:], np.delete(cols, k, axis=0),
                                          np.insert(cols, k, cols[k], axis=0)]))
    elif how == "options":
        options = data.draw(st.sampled_from([["--sample-rate-hz", "1e9"],
                                             ["--time-unit", "ns"], ["--gyro-unit", "deg/h"],
                                             ["--accel-unit", "ug"], ["--delimiter", ";"]]))
    text = ",".join(header) + "\n" + "\n".join(",".join(repr(float(v)) for v in row)
                                               for row in cols) + "\n"
    if how == "numbers":
        text = mutate_numbers(text, data)
    elif how == "lines":
        text = mutate_lines(text, data)
    return text, options


@fuzz_settings(5, scale=SLOW_SCALE)
@given(data=st.data())
def test_mutated_static_logs_through_allan(allan_columns, tmp_path, data):
    text, options = _allan_text(allan_columns, data)
    path = tmp_path / "static.csv"
    path.write_text(text, encoding="utf-8")
    out_dir = _fresh(tmp_path / "allan")
    code, out, err = run_cli("allan", str(path), "--out", str(out_dir), "--no-record", *options)
    check_outcome(code, out, err, f"allan {options}\n{text[:600]}")
    if code == 0:
        _finite_outputs(out_dir)


# ---------------------------------------------------------------------------------- field
@pytest.fixture(scope="module")
def field_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A hand-held session (imucal's layout: t, acc_x … in m/s², gyr_x … in °/s).

    A path, not the text: hypothesis prints a failing case's arguments.
    """
    from imucalib.sim import handheld_session, write_session_csv

    s = handheld_session("consumer", seed=41, noise="white", n_poses=12)
    path = tmp_path_factory.mktemp("field") / "session.csv"
    write_session_csv(s, path)
    return path


def _field_text(text: str, data: st.DataObject) -> tuple[str, list[str]]:
    lines = text.splitlines()
    header, rows = lines[0], lines[1:]
    options: list[str] = []
    how = data.draw(st.sampled_from(["spike", "column", "rows", "header", "numbers",
                                     "options", "none"]))
    if how == "spike":  # one absurd value, as the campaign's 1e30
        for _ in range(data.draw(st.integers(1, 3))):
            k = data.draw(st.integers(0, len(rows) - 1))
            fields = rows[k].split(",")
            fields[data.draw(st.integers(1, 6))] = data.draw(st.one_of(ODD_NUMBERS, st.sampled_from(
                ["1e30", "-1e30", "1e5", "5e3", "1e7", "2e4"])))
            rows[k] = ",".join(fields)
    elif how == "column":  # a column zeroed, scaled or swapped
        j = data.draw(st.integers(1, 6))
        op = data.draw(st.sampled_from(["zero", "scale", "swap"]))
        factor = data.draw(st.sampled_from([1e-9, 1e-3, 57.3, 1e3, 1e9, -1.0]))
        other = data.draw(st.integers(1, 6))
        for k, row in enumerate(rows):
            fields = row.split(",")
            if op == "zero":
                fields[j] = "0"
            elif op == "scale":
                fields[j] = repr(float(fields[j]) * factor)
            else:
                fields[j], fields[other] = fields[other], fields[j]
            rows[k] = ",".join(fields)
    elif how == "rows":
        a = data.draw(st.integers(0, len(rows) - 1))
        b = data.draw(st.integers(a, min(len(rows), a + 5000)))
        rows = data.draw(st.sampled_from([rows[:a], rows[a:], rows[:a] + rows[b:],
                                          rows[:a] + rows[a:b] * 2 + rows[b:]]))
    elif how == "header":
        names = header.split(",")
        names[data.draw(st.integers(0, 6))] = data.draw(st.sampled_from(
            ["acc_x [g]", "gyr_x_rps", "time_ms", "foo", "", "gyr_z"]))
        header = ",".join(names)
    elif how == "options":
        options = data.draw(st.sampled_from([
            ["--gyro-form", "turns"], ["--gyro-form", "gravity"], ["--accel-form", "six-position"],
            ["--static-threshold", "1e-9"], ["--static-threshold", "1e9"],
            ["--init-static-s", "0"], ["--init-static-s", "1e6"], ["--gravity", "0"],
            ["--gravity", "1e30"], ["--latitude", "91"], ["--height", "-1e7"],
            ["--accel-instability-ug", "auto"], ["--accel-instability-ug", "-5"],
            ["--gyro-instability-dph", "1e30"], ["--gyro-unit", "rad/s"],
            ["--accel-unit", "g"], ["--sample-rate-hz", "1e-3"]]))
    text = header + "\n" + "\n".join(rows) + "\n"
    if how == "numbers":
        text = mutate_numbers(text, data, n=5)
    return text, options


@fuzz_settings(5, scale=SLOW_SCALE)
@given(data=st.data())
def test_mutated_field_logs_through_calibrate_field(field_log, tmp_path, data):
    text, options = _field_text(_text(field_log), data)
    path = tmp_path / "session.csv"
    path.write_text(text, encoding="utf-8")
    out_dir = _fresh(tmp_path / "field")
    code, out, err = run_cli("calibrate", "field", str(path), "-o", str(out_dir), "--no-record",
                             *options)
    check_outcome(code, out, err, f"field {options}\n{text[:400]}")
    if code in (0, 1, 3):
        _finite_outputs(out_dir)


# ------------------------------------------------------------------ report and export of JSON
@pytest.fixture(scope="module")
def field_result(field_log: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The result JSON of the field session (a real result: residuals, details, notes)."""
    folder = tmp_path_factory.mktemp("field-result")
    code, out, err = run_cli("calibrate", "field", str(field_log), "-o", str(folder),
                             "--no-record")
    assert code == 0, out + err
    return folder / "session.IMU.field.result.json"


def _mutated_json(text: str, data: st.DataObject) -> bytes:
    how = data.draw(st.sampled_from(["numbers", "lines", "key", "value", "deep", "bytes"]))
    if how == "numbers":
        return mutate_numbers(text, data, n=4).encode("utf-8")
    if how == "lines":
        return mutate_lines(text, data).encode("utf-8")
    if how == "bytes":
        raw = bytearray(text.encode("utf-8"))
        raw[data.draw(st.integers(0, len(raw) - 1))] = data.draw(st.integers(128, 255))
        return bytes(raw)
    obj = json.loads(text)
    odd = st.one_of(st.none(), st.integers(), st.floats(), st.text(max_size=20),
                    st.lists(st.floats(), max_size=3), st.just({}), st.just([]),
                    st.just(10**400), st.just("x" * 10_000))
    target = obj
    if how == "deep":  # somewhere inside: walk a few levels down
        for _ in range(data.draw(st.integers(1, 4))):
            inner = [k for k, v in (target.items() if isinstance(target, dict) else
                                    enumerate(target)) if isinstance(v, dict | list) and v]
            if not inner:
                break
            target = target[data.draw(st.sampled_from(inner))]
    keys = sorted(target) if isinstance(target, dict) else list(range(len(target)))
    if keys:
        key = data.draw(st.sampled_from(keys))
        if data.draw(st.booleans()) and isinstance(target, dict):
            del target[key]
        else:
            target[key] = data.draw(odd)
    try:
        return json.dumps(obj).encode("utf-8")
    except ValueError:  # an integer too long to write
        return json.dumps(obj, default=str).encode("utf-8")


EXPORT_FORMATS = ("result-json", "parameters-csv", "c-runtime", "mat", "ros-yaml", "kalibr-imu",
                  "openvins-imu", "report-html")


@fuzz_settings(25)
@given(data=st.data())
def test_mutated_result_json_through_report_and_export(field_result, tmp_path, data):
    raw = _mutated_json(_text(field_result), data)
    path = tmp_path / "r.result.json"
    path.write_bytes(raw)
    shown = raw[:1500].decode("utf-8", errors="replace")
    html = _fresh(tmp_path / "r.html")
    code, out, err = run_cli("report", str(path), "--format", "html", "-o", str(html))
    check_outcome(code, out, err, f"report\n{shown}")
    fmt = data.draw(st.sampled_from(EXPORT_FORMATS))
    folder = _fresh(tmp_path / "export")
    code, out, err = run_cli("export", str(path), "--format", fmt, "-o", str(folder))
    check_outcome(code, out, err, f"export --format {fmt}\n{shown}")
    if code == 0:
        _finite_outputs(folder)


# -------------------------------------------------------------------------------- recover
WRITE_OPEN = CHILD_PATH + r"""
import os, sys
import h5py
import numpy as np
from _still_imu import still_imu_columns
from imucalib.io.recording import RecordingWriter
from imucalib.io.streams import imu_stream_spec

folder = sys.argv[1]
cols = still_imu_columns(1200)
UTF8 = h5py.string_dtype("utf-8")
BAD = np.array(b"\xff\xfe{bad", dtype=object)
EDITS = {
    "plain": None,
    "operator-not-utf8": ("/", "operator", BAD, UTF8),
    "context-not-utf8": ("/", "context_json", BAD, UTF8),
    "station-not-json": ("/", "station_json", "{not json", None),
    "version-text": ("/", "format_version", "two", None),
    "latitude-text": ("/", "latitude_deg", "north", None),
    "format-bytes": ("/", "format", np.bytes_(b"\xff\xfe"), None),
    "columns-not-utf8": ("/streams/imu/IMU-0001", "columns_json", BAD, UTF8),
    "unit-not-utf8": ("/streams/imu/IMU-0001/gyro_x_rps", "unit", BAD, UTF8),
    "huge-attr": ("/", "operator", "x" * 60000, None),
}
writers = []
for name, edit in EDITS.items():
    w = RecordingWriter(os.path.join(folder, name + ".h5"),
                        streams=[imu_stream_spec("IMU-0001")],
                        metadata={"operator": "fz", "latitude_deg": 48.1,
                                  "station_json": "{}"}, chunk_rows=256)
    w.__enter__()
    w.append("imu", "IMU-0001", cols)
    i = w.begin_step("static", "level", 0.0, commanded={"plan_step": 0})
    w.update_step(i, t_end_s=5.9, valid_start_s=1.0, valid_end_s=5.0, status="done")
    w.log_event(0.0, "info", "fz", "hello")
    w.flush()
    if edit is not None:
        obj, key, value, dtype = edit
        node = w._file[obj]
        if key in node.attrs:
            del node.attrs[key]
        if dtype is None:
            node.attrs[key] = value
        else:
            node.attrs.create(key, data=value, dtype=dtype)
    w._file.flush()
    writers.append(w)
sys.stdout.flush()
os._exit(0)  # as a crash: every file is left open for write
"""


@pytest.fixture(scope="module")
def open_recordings(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Recordings a crashed writer left open: one plain, the others with damaged attributes."""
    folder = tmp_path_factory.mktemp("open")
    done = subprocess.run([sys.executable, "-c", WRITE_OPEN, str(folder)], capture_output=True,
                          text=True, timeout=120, env={**os.environ, "PYTHONWARNINGS": "ignore"})
    assert done.returncode == 0, done.stderr
    return {p.stem: p for p in sorted(folder.glob("*.h5"))}


def test_damaged_open_recordings_are_recovered_or_refused(open_recordings, tmp_path):
    rng = np.random.default_rng(27)
    files = [p for name, p in open_recordings.items()]
    original = open_recordings["plain"].read_bytes()
    for i in range(8 * SCALE):
        path = tmp_path / f"open{i:03d}.h5"
        path.write_bytes(damage_bytes(original, i, rng))
        files.append(path)
    outcomes = run_child(tmp_path, files, ("recover",))
    assert len(outcomes) == len(files)
    recovered = []
    for o in outcomes:
        check_outcome(o["code"], o["out"], o["err"], f"{o['args']}", door="recover")
        if o["code"] == 0:
            recovered.append(Path(o["args"][-1]))
    for name in ("plain", "operator-not-utf8", "context-not-utf8", "columns-not-utf8",
                 "unit-not-utf8"):  # the copy keeps the data whatever the metadata's bytes
        assert tmp_path / f"{name}.recovered.h5" in recovered, name
    # every copy opens and exports as a Recording does
    for o in run_child(tmp_path, recovered, ("inspect", "export")):
        check_outcome(o["code"], o["out"], o["err"], f"{o['args']}", door=o["args"][0])
        if o["code"] == 0 and o["args"][0] == "export":
            assert_finite_csv(Path(o["args"][-1]))
