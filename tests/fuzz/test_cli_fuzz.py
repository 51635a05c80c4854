"""Property-based fuzzing of the CLI's doors: plans, scenarios, CSV, result JSON, recordings.

Every mutated input must end in exit code 0 (and then no non-finite number in what was written) or
exit code 2 with a one-line ``error:`` message: never a traceback, never the ``internal error``
safety net of :func:`imucalib.cli.main`, never a hang (:mod:`._harness` has the rules, the
per-case time limit and the tally). Recordings are fed to one child process that opens them
one by one under an alarm, so that a hang inside HDF5 is caught as a death by SIGALRM.
Example counts are bounded so that the suite stays within its time budget; the
``IMUCALIB_FUZZ_EXAMPLES`` environment variable multiplies them for a longer campaign
(``make fuzz``), and ``IMUCALIB_FUZZ_TALLY=FILE`` appends each outcome to FILE as a JSON line.
The doors added for issue 27 (import specs, Allan, field, recover, report, export) are in
``test_input_fuzz.py``; the reproducers of that campaign in ``test_regression_cases.py``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from imucalib.models.result import (
    CalibrationResult,
    Provenance,
    ResidualStats,
    triad_parameter_names,
)
from imucalib.plan import plan_to_toml
from imucalib.procedures import generate_p1_plan

from ._harness import (  # noqa: F401 (run_cli and the rest are used by sibling fuzz files too)
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
    tally,
)
from ._still_imu import still_imu_columns

FUZZ = fuzz_settings(10)


def _numbers(doc: object) -> list[float]:
    """Every number in a JSON document (nested lists and objects)."""
    if isinstance(doc, bool) or doc is None or isinstance(doc, str):
        return []
    if isinstance(doc, int | float):
        return [float(doc)]
    items = doc.values() if isinstance(doc, dict) else doc
    return [v for item in items for v in _numbers(item)]


# ------------------------------------------------------------------------------------ plans
@pytest.fixture(scope="module")
def plan_text() -> str:
    plan = generate_p1_plan(name="fz", grade="consumer", rates_dps=(-60.0, 0.0, 60.0),
                            held_out_rates_dps=(), revolutions=1, static_s=20.0, settle_s=3.0,
                            record_s=2.0, rate_settle_s=2.0, repetitions=1, warm_up_s=5.0,
                            sample_rate_hz=200.0, seed=4)
    return plan_to_toml(plan)


@FUZZ
@given(data=st.data())
def test_mutated_plans_are_refused_cleanly(plan_text, tmp_path, data):
    text = data.draw(st.sampled_from([mutate_numbers, mutate_lines]))(plan_text, data)
    path = tmp_path / "plan.toml"
    path.write_text(text, encoding="utf-8")
    for command in ("validate", "show"):
        check_outcome(*run_cli("plan", command, str(path)), f"plan {command}\n{text[:2000]}")


# -------------------------------------------------------------------------------------- CSV
CSV_HEADERS = ["time_s,gyro_x_rps,gyro_y_rps,gyro_z_rps,accel_x_mps2,accel_y_mps2,accel_z_mps2",
               "time_s [s],gyro_x_rps [deg/s],gyro_y_rps [deg/s],gyro_z_rps [deg/s],"
               "accel_x_mps2 [g],accel_y_mps2 [g],accel_z_mps2 [g]"]


def csv_text(data: st.DataObject) -> str:
    header = data.draw(st.sampled_from(CSV_HEADERS))
    n = data.draw(st.integers(0, 400))
    rng = np.random.default_rng(data.draw(st.integers(0, 2**16)))
    t = np.arange(n) * 0.01
    cols = [t, *(rng.normal(0, 0.01, n) for _ in range(3)),
            *(rng.normal(0, 0.05, n) for _ in range(2)), 9.8 + rng.normal(0, 0.05, n)]
    body = "\n".join(",".join(f"{c[i]:.6g}" for c in cols) for i in range(n))
    text = header + "\n" + body + ("\n" if n else "")
    mutation = data.draw(st.sampled_from(["numbers", "lines", "header", "bytes", "none"]))
    if mutation == "numbers":
        text = mutate_numbers(text, data)
    elif mutation == "lines":
        text = mutate_lines(text, data)
    elif mutation == "header":
        names = header.split(",")
        j = data.draw(st.integers(0, len(names) - 1))
        names[j] = data.draw(st.sampled_from(["time_s [furlong]", names[0], "gyro_x_rps [deg/h]",
                                              "", "x y", names[j] + "," + names[j]]))
        text = ",".join(names) + text[len(header):]
    elif mutation == "bytes":
        raw = bytearray(text.encode())
        for _ in range(data.draw(st.integers(1, 5))):
            if raw:
                raw[data.draw(st.integers(0, len(raw) - 1))] = data.draw(st.integers(0, 255))
        return raw.decode("latin-1")
    return text


@FUZZ
@given(data=st.data())
def test_mutated_csv_through_segments_and_apply(result_file, tmp_path, data):
    text = csv_text(data)
    path = tmp_path / "data.csv"
    path.write_bytes(text.encode("latin-1", errors="replace"))
    seg_json = tmp_path / "seg.json"
    seg_json.unlink(missing_ok=True)
    code, out, err = run_cli("segments", str(path), "--json", str(seg_json))
    check_outcome(code, out, err, f"segments\n{text[:1000]}")
    if code == 0:
        doc = json.loads(seg_json.read_text(encoding="utf-8"))
        assert all(math.isfinite(v) for v in _numbers(doc)), doc
    fixed = tmp_path / "fixed.csv"
    fixed.unlink(missing_ok=True)
    code, out, err = run_cli("apply", str(result_file), str(path), "--out", str(fixed))
    check_outcome(code, out, err, f"apply\n{text[:1000]}")
    if code == 0:
        assert_finite_csv(fixed)


# ------------------------------------------------------------------------------ result JSON
@pytest.fixture(scope="module")
def result_file(tmp_path_factory) -> Path:
    names = (*triad_parameter_names("accel", "triad"),
             *triad_parameter_names("gyro", "triad", g_sensitivity=True))
    k = len(names)
    a = np.random.default_rng(0).normal(size=(k, k))
    result = CalibrationResult(
        sensor_id="IMU-0001", procedure="p1", model="triad", param_names=names,
        values=np.random.default_rng(1).normal(0, 1e-3, k), covariance=a @ a.T * 1e-10,
        units=dict.fromkeys(names, "1"),
        residuals={"accel: Z up": ResidualStats((1e-4, -2e-4, 3.5e-5), (1e-3,) * 3, 2000,
                                                "m/s^2")},
        provenance=Provenance(plan_hash="ab" * 32, recording_sha256="cd" * 32,
                              recording="run.h5", software_version="0.1.0",
                              created_utc="2026-11-23T00:00:00Z", details={}),
        notes=())
    path = tmp_path_factory.mktemp("result") / "result.json"
    path.write_text(result.to_json(), encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def clean_csv(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("csv") / "clean.csv"
    t = np.arange(200) * 0.01
    rows = [CSV_HEADERS[0]] + [f"{x:.3f},0.001,0.002,0.003,0.01,0.02,9.81" for x in t]
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    return path


@FUZZ
@given(data=st.data())
def test_mutated_result_json_through_apply(result_file, clean_csv, tmp_path, data):
    text = result_file.read_text(encoding="utf-8")
    how = data.draw(st.sampled_from(["numbers", "lines", "key", "bytes", "value"]))
    if how == "numbers":
        text = mutate_numbers(text, data, n=2)
    elif how == "lines":
        text = mutate_lines(text, data)
    elif how in ("key", "value"):
        obj = json.loads(text)
        key = data.draw(st.sampled_from(sorted(obj)))
        if how == "key":
            del obj[key]
        else:
            obj[key] = data.draw(st.one_of(st.none(), st.integers(), st.floats(), st.text(),
                                           st.lists(st.floats(), max_size=3)))
        text = json.dumps(obj)
    raw = text.encode("utf-8")
    if how == "bytes":
        raw = bytearray(raw)
        raw[data.draw(st.integers(0, len(raw) - 1))] = data.draw(st.integers(128, 255))
    path = tmp_path / "r.json"
    path.write_bytes(bytes(raw))
    fixed = tmp_path / "fixed.csv"
    fixed.unlink(missing_ok=True)
    code, out, err = run_cli("apply", str(path), str(clean_csv), "--out", str(fixed))
    check_outcome(code, out, err, f"apply with\n{text[:1500]}")
    if code == 0:
        assert_finite_csv(fixed)


# ------------------------------------------------------------------------------- scenarios
SCENARIO = """\
name = "fz"
seed = 7
chunk_s = 10.0
[site]
latitude_deg = 52.0
[table]
kind = "dual-axis"
grade = "high"
feedback_rate_hz = 100.0
[[imus]]
name = "IMU-0001"
grade = "consumer"
sample_rate_hz = 100.0
[[steps]]
kind = "position"
angles_deg = [0.0, 180.0]
settle_s = 2.0
record_s = 3.0
[[steps]]
kind = "rate"
axis = 1
rate_dps = 60.0
settle_s = 2.0
revolutions = 1
"""


@FUZZ
@given(data=st.data())
def test_mutated_scenarios_are_refused_or_simulated(tmp_path, data):
    text = data.draw(st.sampled_from([mutate_numbers, mutate_lines]))(SCENARIO, data)
    path = tmp_path / "sc.toml"
    path.write_text(text, encoding="utf-8")
    out_file = tmp_path / "sc.h5"
    out_file.unlink(missing_ok=True)
    code, out, err = run_cli("simulate", str(path), "--out", str(out_file))
    check_outcome(code, out, err, f"simulate\n{text}")
    if code == 0:
        assert_finite_recording(out_file, f"simulate\n{text}")


def assert_finite_recording(path: Path, what: str) -> None:
    """Every floating-point sample of every stream of a written recording is finite."""
    from imucalib.io import open_recording

    with open_recording(path) as rec:
        for info in rec.streams:
            for name, values in rec.read_stream(info.device, info.unit).columns.items():
                if values.dtype.kind == "f":
                    assert np.isfinite(values).all(), \
                        f"{what}: non-finite {info.device}/{info.unit}/{name}"


# ------------------------------------------------------------------------------ recordings
@pytest.fixture(scope="module")
def small_recording(tmp_path_factory) -> Path:
    from imucalib.io.recording import RecordingWriter
    from imucalib.io.streams import imu_stream_spec

    path = tmp_path_factory.mktemp("rec") / "small.h5"
    cols = still_imu_columns(2000)
    with RecordingWriter(path, streams=[imu_stream_spec("IMU-0001")],
                         metadata={"operator": "fz"}, chunk_rows=512) as w:
        w.append("imu", "IMU-0001", cols)
        i = w.begin_step("static", "level", 0.0, commanded={"plan_step": 0})
        w.update_step(i, t_end_s=9.9, valid_start_s=1.0, valid_end_s=9.0, status="done")
        w.log_event(0.0, "info", "fz", "hello")
    return path


def test_damaged_recordings_never_crash_hang_or_export_garbage(small_recording, tmp_path):
    rng = np.random.default_rng(2026)
    original = small_recording.read_bytes()
    files = []
    for i in range(16 * SCALE):
        path = tmp_path / f"m{i:03d}.h5"
        path.write_bytes(damage_bytes(original, i, rng))
        files.append(path)
    outcomes = run_child(tmp_path, files, ("inspect", "export"))
    assert len(outcomes) == 2 * len(files)
    for o in outcomes:
        check_outcome(o["code"], o["out"], o["err"], f"{o['args']}", door=o["args"][0])
        if o["code"] == 0 and o["args"][0] == "export":
            assert_finite_csv(Path(o["args"][-1]))
