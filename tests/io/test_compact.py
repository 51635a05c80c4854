"""Compact recordings: integer-count columns with a scale, compression, and old files.

The round trip must return the very float64 values the writer was given (``np.array_equal``,
NaN in float columns kept), values off the LSB grid are refused without appending anything, a
live (SWMR) reader reads a compressed file, and a twin IMU stream of ~1e5 samples shrinks at
least 3× against float64 without compression.
"""

from __future__ import annotations

import math
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import h5py
import numpy as np
import pytest

from imucalib.errors import InvalidInputError, RecordingCorruptError, RecordingError
from imucalib.io import (
    FORMAT_VERSION,
    ColumnSpec,
    RecordingWriter,
    StreamSpec,
    open_recording,
    recover_recording,
)
from imucalib.io.compression import DEFAULT_COMPRESSION, column_filter_kwargs
from imucalib.io.streams import imu_stream_spec

LSB = 1000.0 * math.pi / 180.0 * 2.0 / 2**24  # a 24-bit gyro over ±1000 °/s [rad/s]
I32 = np.iinfo(np.int32)


def _spec(dtype: str = "i4", scale: float = LSB) -> StreamSpec:
    return StreamSpec("imu", "U", {
        "gyro_x_rps": ColumnSpec("rad/s", dtype=dtype, scale=scale),
        "accel_x_mps2": ColumnSpec("m/s^2"),  # stays float64
    })


def _values(n: int = 5000, seed: int = 0) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    counts = rng.integers(-4000, 4000, n).astype(np.int64)
    counts[:4] = [I32.min, I32.max, -1, 0]  # the int32 edges, negative counts and zero
    accel = rng.standard_normal(n)
    accel[[3, 77]] = np.nan  # NaN is data in a float column
    return {"time_s": np.arange(n) / 1000.0, "gyro_x_rps": counts * LSB, "accel_x_mps2": accel}


def test_scaled_column_round_trip_is_exact(tmp_path):
    data = _values()
    path = tmp_path / "r.h5"
    with RecordingWriter(path, streams=[_spec()]) as w:
        for a in range(0, 5000, 700):
            w.append("imu", "U", {k: v[a:a + 700] for k, v in data.items()})
    assert w.compression_skipped == ""
    with h5py.File(path, "r") as f:
        ds = f["streams/imu/U/gyro_x_rps"]
        assert ds.dtype == np.int32 and ds.attrs["scale"] == LSB
        assert ds[:4].tolist() == [I32.min, I32.max, -1, 0]  # the counts are stored
        assert ds.compression == "gzip" and ds.shuffle  # the default: shuffle + deflate
    with open_recording(path) as rec:
        assert rec.format_version == FORMAT_VERSION == 3
        info = rec.stream_info("imu", "U")
        assert info.columns["gyro_x_rps"].scale == LSB
        got = rec.read_stream("imu", "U")
        parts = list(rec.iter_stream("imu", "U", chunk_samples=999))
    assert got.columns["gyro_x_rps"].dtype == np.float64
    assert np.array_equal(got.columns["gyro_x_rps"], data["gyro_x_rps"])
    assert got.columns["gyro_x_rps"].tobytes() == data["gyro_x_rps"].tobytes()
    assert np.array_equal(got.columns["accel_x_mps2"], data["accel_x_mps2"], equal_nan=True)
    assert np.isnan(got.columns["accel_x_mps2"][[3, 77]]).all()
    joined = np.concatenate([p.columns["gyro_x_rps"] for p in parts])
    assert np.array_equal(joined, data["gyro_x_rps"])


def test_negative_zero_reads_as_zero(tmp_path):
    path = tmp_path / "z.h5"
    with RecordingWriter(path, streams=[_spec()]) as w:
        w.append("imu", "U", {"time_s": [0.0, 1.0], "gyro_x_rps": [-0.0, -LSB],
                              "accel_x_mps2": [0.0, 0.0]})
    with open_recording(path) as rec:
        g = rec.read_stream("imu", "U").columns["gyro_x_rps"]
    assert np.array_equal(g, [-0.0, -LSB]) and g[1] == -LSB


@pytest.mark.parametrize("bad, why", [
    (0.5 * LSB, "half a count"),
    (3 * LSB * (1 + 1e-12), "off the grid by a rounding"),
    (float("nan"), "NaN"),
    (float("inf"), "infinite"),
    ((I32.max + 1.0) * LSB, "beyond int32"),
    ((I32.min - 1.0) * LSB, "below int32"),
])
def test_values_off_the_grid_are_refused_and_nothing_is_appended(tmp_path, bad, why):
    path = tmp_path / "r.h5"
    with RecordingWriter(path, streams=[_spec()]) as w:
        w.append("imu", "U", {"time_s": [0.0], "gyro_x_rps": [LSB], "accel_x_mps2": [1.0]})
        with pytest.raises(InvalidInputError,
                           match=r"column 'gyro_x_rps'.* stores integer counts of .* rad/s in i4; "
                                 r"row 1 of this append is"):
            w.append("imu", "U", {"time_s": [1.0, 2.0], "gyro_x_rps": [2 * LSB, bad],
                                  "accel_x_mps2": [1.0, 1.0]})
    with open_recording(path) as rec:
        assert rec.stream_info("imu", "U").n_samples == 1, why


@pytest.mark.parametrize("spec, match", [
    (ColumnSpec("rad/s", dtype="f8", scale=LSB), "a scale needs an integer dtype"),
    (ColumnSpec("rad/s", dtype="i4", scale=-LSB), "scale must be positive and finite"),
    (ColumnSpec("rad/s", dtype="i4", scale=float("nan")), "scale must be positive and finite"),
    (ColumnSpec("rad/s", dtype="i4", scale="1e-6"), "scale must be a number"),  # type: ignore[arg-type]
])
def test_bad_scales_are_refused(spec, match):
    with pytest.raises(InvalidInputError, match=match):
        StreamSpec("imu", "U", {"gyro_x_rps": spec})


def test_plain_files_stay_version_2_and_read(tmp_path):
    """A file written without compression and without scaled columns is today's format."""
    data = _values()
    path = tmp_path / "plain.h5"
    spec = StreamSpec("imu", "U", {"gyro_x_rps": ColumnSpec("rad/s"),
                                   "accel_x_mps2": ColumnSpec("m/s^2")})
    with RecordingWriter(path, streams=[spec], compression=None) as w:
        w.append("imu", "U", data)
    with h5py.File(path, "r") as f:
        assert f.attrs["format_version"] == 2
        assert f["streams/imu/U/gyro_x_rps"].compression is None
        assert not f["streams/imu/U/gyro_x_rps"]._filters
    with open_recording(path) as rec:
        got = rec.read_stream("imu", "U")
    assert np.array_equal(got.columns["gyro_x_rps"], data["gyro_x_rps"])


def test_version_1_file_still_reads():
    path = Path(__file__).parents[1] / "data" / "p1_v1.h5"
    with open_recording(path) as rec:
        assert rec.format_version == 1
        imu = rec.read_stream("imu", rec.streams[0].unit, t_end_s=1.0)
    assert imu.columns["gyro_x_rps"].dtype == np.float64 and len(imu) > 0


def test_damaged_scale_is_refused_and_recovery_rebuilds_it(tmp_path):
    data = _values()
    path = tmp_path / "r.h5"
    with RecordingWriter(path, streams=[_spec()]) as w:
        w.append("imu", "U", data)
    with h5py.File(path, "r+") as f:
        g = f["streams/imu/U"]
        g.attrs["columns_json"] = g.attrs["columns_json"].replace(f"{LSB!r}", "-1.0")
    with pytest.raises(RecordingCorruptError, match=r"column 'gyro_x_rps' has scale -1.0"):
        open_recording(path)
    with h5py.File(path, "r+") as f:
        f["streams/imu/U"].attrs["columns_json"] = "[{"
    report = recover_recording(path)
    assert "columns_json rebuilt from the datasets" in report.summary()
    with open_recording(report.output) as rec:
        got = rec.read_stream("imu", "U")
    assert np.array_equal(got.columns["gyro_x_rps"], data["gyro_x_rps"])


def test_recovery_and_resume_keep_scales_and_filters(tmp_path):
    data = _values()
    path = tmp_path / "r.h5"
    with RecordingWriter(path, streams=[_spec()], compression="blosc-lz4") as w:
        w.append("imu", "U", {k: v[:3000] for k, v in data.items()})
    w = RecordingWriter.reopen(path)  # a resumed run appends counts of the same LSB
    w.append("imu", "U", {k: v[3000:] for k, v in data.items()})
    with pytest.raises(InvalidInputError, match="stores integer counts"):
        w.append("imu", "U", {"time_s": [9.0], "gyro_x_rps": [0.3 * LSB],
                              "accel_x_mps2": [0.0]})
    with h5py.File(path, "r") as f:  # reopened: written uncompressed until closed
        assert not f["streams/imu/U/gyro_x_rps"]._filters
    w.close()
    with h5py.File(path, "r") as f:  # closed with the compression it had: Blosc
        assert "32001" in f["streams/imu/U/gyro_x_rps"]._filters
    report = recover_recording(path)  # the copy gets the default compression
    with h5py.File(report.output, "r") as f:
        ds = f["streams/imu/U/gyro_x_rps"]
        assert ds.dtype == np.int32 and ds.attrs["scale"] == LSB and ds.compression == "gzip"
        assert f.attrs["format_version"] == 3
    with open_recording(report.output) as rec:
        got = rec.read_stream("imu", "U")
    assert np.array_equal(got.columns["gyro_x_rps"], data["gyro_x_rps"])
    assert np.array_equal(got.columns["accel_x_mps2"], data["accel_x_mps2"], equal_nan=True)


_LIVE_WRITER = textwrap.dedent("""
    import sys, time
    import numpy as np
    from imucalib.io import ColumnSpec, RecordingWriter, StreamSpec
    lsb = float(sys.argv[2])
    spec = StreamSpec("imu", "U", {"gyro_x_rps": ColumnSpec("rad/s", dtype="i4", scale=lsb)})
    with RecordingWriter(sys.argv[1], streams=[spec], flush_interval_s=float("inf"),
                         chunk_rows=512) as w:
        for b in range(1000):
            rows = np.arange(b * 300, (b + 1) * 300)
            w.append("imu", "U", {"time_s": rows / 1000.0, "gyro_x_rps": (rows - 5000) * lsb})
            w.flush()
            print(b, flush=True)
            if b >= 3:
                time.sleep(0.05)
""")


def test_live_reader_reads_a_compressed_scaled_stream(tmp_path):
    path = tmp_path / "live.h5"
    proc = subprocess.Popen([sys.executable, "-c", _LIVE_WRITER, str(path), repr(LSB)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        for _ in range(4):
            assert proc.stdout is not None and proc.stdout.readline(), proc.stderr
        lengths = []
        for _ in range(2):
            with open_recording(path) as rec:  # the writer is alive and appending
                assert rec.was_open_for_write
                # written uncompressed (compressed when closed): no chunk is rewritten elsewhere
                assert not rec._file["streams/imu/U/gyro_x_rps"]._filters
                got = rec.read_stream("imu", "U")
            n = len(got)
            assert n >= 1200 and n % 300 == 0
            rows = np.arange(n)
            assert np.array_equal(got.columns["gyro_x_rps"], (rows - 5000) * LSB)
            lengths.append(n)
            proc.stdout.readline()
            proc.stdout.readline()
        assert lengths[1] > lengths[0]
    finally:
        proc.kill()
        proc.wait()
        if proc.stdout is not None:
            proc.stdout.close()
        if proc.stderr is not None:
            proc.stderr.close()


def _twin_imu_columns(n: int) -> tuple[dict[str, np.ndarray], float, float, float]:
    """~n samples of a tactical twin IMU: a static minute, then turning at 50 °/s."""
    from imucalib.models import sample_imu_model
    from imucalib.sim import Site, TwinRig, single_imu_fixture
    from imucalib.sim.synth import SimImu
    from imucalib.sim.table import RateTableSpec, SimRateTable

    model = sample_imu_model("tactical", rng=3)
    table = SimRateTable(RateTableSpec.dual_axis_pitch_roll("ideal"))
    imu = SimImu("U", model)
    rig = TwinRig(site=Site(latitude_deg=45.0), fixture=single_imu_fixture(name="U"),
                  imus=[imu], table=table, rng=3)
    first = rig.generate(n / 2000.0).imu["U"]
    table.command_rate(0, math.radians(50.0), n / 2000.0)
    second = rig.generate(n / 1000.0).imu["U"]
    parts = (first, second)

    def cat(name: str) -> np.ndarray:
        return np.concatenate([getattr(p, name) for p in parts])

    gyro, accel = cat("gyro_rps"), cat("accel_mps2")
    cols = {"time_s": cat("time_s"), "device_time_s": cat("device_time_s"),
            "counter": cat("counter"), "temperature_degc": cat("temperature_degc"),
            "saturated": cat("saturated")}
    for j, axis in enumerate("xyz"):
        cols[f"gyro_{axis}_rps"] = gyro[:, j]
        cols[f"accel_{axis}_mps2"] = accel[:, j]
    g, a = model.gyro_output.effective_lsb, model.accel_output.effective_lsb
    assert g is not None and a is not None
    return cols, g, a, imu.temperature_resolution_degc


@pytest.mark.parametrize("flush_each_append", [False, True])
def test_twin_imu_stream_is_three_times_smaller_and_exact(tmp_path, flush_each_append):
    """≥3× smaller, also when every second of data is flushed, as a real-time station does
    (compressed chunks rewritten at each flush under SWMR would leave their old copies behind)."""
    n = 1 << 17  # 131 072 samples: two whole chunks, so the float64 file wastes no chunk space
    cols, g_lsb, a_lsb, t_lsb = _twin_imu_columns(n)
    before, after = tmp_path / "f64.h5", tmp_path / "compact.h5"
    with RecordingWriter(before, streams=[imu_stream_spec("U")], compression=None) as w:
        w.append("imu", "U", cols)
    compact = imu_stream_spec("U", gyro_lsb_rps=g_lsb, accel_lsb_mps2=a_lsb,
                              temperature_lsb_degc=t_lsb)
    with RecordingWriter(after, streams=[compact]) as w:
        for a in range(0, len(cols["time_s"]), 1000):
            w.append("imu", "U", {k: v[a:a + 1000] for k, v in cols.items()})
            if flush_each_append:
                w.flush()
    ratio = before.stat().st_size / after.stat().st_size
    assert ratio >= 3.0, f"only {ratio:.2f}× smaller"
    with open_recording(after) as rec:
        got = rec.read_stream("imu", "U")
    for name, values in cols.items():
        col = got.time_s if name == "time_s" else got.columns[name]
        assert np.array_equal(col, values), name


def test_the_twin_reports_its_lsbs_and_the_runner_stores_counts():
    from imucalib.procedures import generate_p1_plan
    from imucalib.station.runner import _stream_specs
    from imucalib.station.sim import SimStation

    for grade, counts in (("tactical", True), ("consumer", True), ("navigation", False)):
        plan = generate_p1_plan(grade=grade, repetitions=1, static_s=60.0, warm_up_s=60.0)
        assert plan.twin is not None
        station = SimStation(plan.twin)
        ident = station.imus[0].identify()
        model = station.rig.imus[ident.name].model
        assert ident.gyro_lsb_rps == model.gyro_output.effective_lsb
        assert ident.accel_lsb_mps2 == model.accel_output.effective_lsb
        assert (ident.gyro_lsb_rps is not None) == counts
        specs = {s.name: s for s in _stream_specs(station, [ident])}
        imu = specs[f"imu/{ident.name}"]
        assert imu.columns["gyro_x_rps"].dtype == ("i4" if counts else "f8"), grade
        assert imu.columns["temperature_degc"].scale == 1 / 256
        assert imu.columns["counter"].dtype == "i8" and imu.columns["time_s"].dtype == "f8"


def test_default_filters():
    assert DEFAULT_COMPRESSION == "gzip"  # every HDF5 reads it
    assert column_filter_kwargs(None) == {}
    assert column_filter_kwargs("gzip") == {"compression": "gzip", "compression_opts": 1,
                                            "shuffle": True}


def test_close_leaves_the_file_uncompressed_when_room_is_short(tmp_path, monkeypatch):
    from imucalib.io import recording as recording_module

    data = _values()
    path = tmp_path / "r.h5"
    w = RecordingWriter(path, streams=[_spec()])
    w.append("imu", "U", data)
    w.flush()
    monkeypatch.setattr(recording_module, "room_bytes",
                        lambda p, file_size_bytes=None: Path(p).stat().st_size + 1024)
    w.close()
    assert re.search(r"complete but was left uncompressed \(the copy needs up to .* is left",
                     w.compression_skipped)
    with h5py.File(path, "r") as f:
        assert not f["streams/imu/U/gyro_x_rps"]._filters
    with open_recording(path) as rec:
        got = rec.read_stream("imu", "U")
    assert np.array_equal(got.columns["gyro_x_rps"], data["gyro_x_rps"])
    assert not list(tmp_path.glob(".*partial"))


def test_compact_recording_round_trip_and_refusals(tmp_path):
    from imucalib.errors import RecordingOpenForWriteError
    from imucalib.io import compact_recording

    data = _values()
    path = tmp_path / "r.h5"
    with RecordingWriter(path, streams=[_spec()], compression="gzip") as w:
        w.append("imu", "U", data)
        i = w.begin_step("static", "s", 0.0, tags=("a",))
        w.update_step(i, t_end_s=1.0, status="done")
    with h5py.File(path, "r") as f:
        assert f["streams/imu/U/gyro_x_rps"].compression == "gzip"
    for compression in (None, "blosc-zstd", "lzf"):
        compact_recording(path, compression)
        with open_recording(path) as rec:
            got = rec.read_stream("imu", "U")
            assert rec.steps[0].tags == ("a",) and "recovered_from" not in rec.metadata
        assert np.array_equal(got.columns["gyro_x_rps"], data["gyro_x_rps"])
        assert np.array_equal(got.columns["accel_x_mps2"], data["accel_x_mps2"], equal_nan=True)
    with pytest.raises(InvalidInputError, match="`compression` must be one of"):
        compact_recording(path, "zip")
    live = tmp_path / "open.h5"
    w = RecordingWriter(live, streams=[_spec()])
    w.append("imu", "U", data)
    w.flush()
    try:
        with pytest.raises(RecordingOpenForWriteError):
            compact_recording(live, None)
    finally:
        w.close()


def test_older_files_never_gain_blosc(tmp_path):
    """A version 1 or 2 file stays readable by its readers: resumed or recovered, no Blosc."""
    import shutil

    from imucalib.io.recording import KEEP

    plain = tmp_path / "plain.h5"
    spec = StreamSpec("imu", "U", {"gyro_x_rps": ColumnSpec("rad/s")})
    with RecordingWriter(plain, streams=[spec], compression=None) as w:
        w.append("imu", "U", {"time_s": [0.0, 1.0], "gyro_x_rps": [1.0, 2.0]})
    with pytest.raises(InvalidInputError, match=r"format version 2, whose readers lack the Blosc"):
        RecordingWriter.reopen(plain, compression="blosc-lz4")
    with RecordingWriter.reopen(plain, compression=KEEP) as w:
        w.append("imu", "U", {"time_s": [2.0], "gyro_x_rps": [3.0]})
    with h5py.File(plain, "r") as f:
        assert f.attrs["format_version"] == 2 and not f["streams/imu/U/gyro_x_rps"]._filters
    v1 = tmp_path / "v1.h5"
    shutil.copyfile(Path(__file__).parents[1] / "data" / "p1_v1.h5", v1)
    for source in (plain, v1):
        report = recover_recording(source, compression="blosc-lz4")
        with h5py.File(report.output, "r") as f:
            assert f.attrs["format_version"] < 3
            assert all("32001" not in f[f"streams/imu/{u}/time_s"]._filters
                       for u in f["streams/imu"])
        with open_recording(report.output) as rec:
            assert len(rec.read_stream("imu", rec.streams[0].unit, t_end_s=1.0)) > 0


def test_a_run_says_when_its_file_was_left_uncompressed(tmp_path, monkeypatch):
    """The runner passes the writer's note on (RunSummary.storage_note), and the CLI prints it."""
    from imucalib.io import recover as recover_module
    from imucalib.procedures import generate_p1_plan
    from imucalib.station.runner import RunOptions, run_plan
    from imucalib.station.sim import SimStation

    plan = generate_p1_plan(name="note", grade="consumer", rates_dps=(-90.0, 0.0, 90.0),
                            held_out_rates_dps=(), revolutions=1, static_s=20.0, settle_s=2.0,
                            record_s=2.0, rate_settle_s=2.0, repetitions=1, warm_up_s=2.0,
                            sample_rate_hz=100.0, seed=3)
    assert plan.twin is not None
    def refuse(path, compression):
        raise RecordingError("the copy could not be written (test)")

    monkeypatch.setattr(recover_module, "compact_recording", refuse)  # imported at close
    summary = run_plan(plan, SimStation(plan.twin), tmp_path / "run.h5",
                       options=RunOptions(tick_s=2.0))
    assert summary.status == "done"
    assert "left uncompressed (the copy could not be written (test))" in summary.storage_note
    monkeypatch.undo()
    summary = run_plan(plan, SimStation(plan.twin), tmp_path / "run2.h5",
                       options=RunOptions(tick_s=2.0))
    assert summary.storage_note == ""
