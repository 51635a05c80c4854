"""Recordings that every HDF5 tool opens: gzip by default, Blosc on request, hdf5plugin lazily.

A recording closed with the defaults must read in a plain h5py that has no ``hdf5plugin`` (as
MATLAB ``h5read``, HDFView, Octave or ``h5dump`` without the HDF5 Blosc plugin), be no larger
than with Blosc LZ4 on the twin's data, and ``hdf5plugin`` (0.2 s to import) must be imported
only for a file that needs it. The command line converts between codecs (``imucalib compact``)
and chooses one for a run (``run --compression``) or a recovery (``recover --compression``).
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import h5py
import numpy as np
import pytest
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.io import compact_recording, open_recording, recover_recording
from imucalib.io.compression import BLOSC_FILTER_ID, DEFAULT_COMPRESSION, compression_of
from imucalib.plan.equipment import ImuConfig, TableConfig
from imucalib.plan.schema import StaticStep
from imucalib.sim.scenario import Scenario
from imucalib.station.simulate import simulate_scenario

runner = CliRunner()

BAD_NAME = "--compression must be one of gzip, blosc-lz4, blosc-zstd, lzf, none; got 'zip'"

# every dataset of the file, read by an h5py in which `import hdf5plugin` fails
_PLAIN_H5PY = textwrap.dedent("""
    import sys
    sys.modules["hdf5plugin"] = None  # no plugin filter, as an HDF5 tool without the Blosc plugin
    import h5py
    names = []
    def read(name, obj):
        if isinstance(obj, h5py.Dataset):
            obj[()]
            names.append(name)
    with h5py.File(sys.argv[1], "r") as f:
        f.visititems(read)
    print(len(names), sum(n.startswith("streams/") for n in names))
""")

# open and read with imucalib: hdf5plugin is imported for a Blosc file only
_LAZY_PLUGIN = textwrap.dedent("""
    import sys
    from imucalib.io import open_recording
    def read(path):
        with open_recording(path) as rec:
            for s in rec.streams:
                rec.read_stream(s.device, s.unit)
    read(sys.argv[1])
    print("hdf5plugin" in sys.modules)
    read(sys.argv[2])
    print("hdf5plugin" in sys.modules)
""")


@pytest.fixture(scope="module")
def twin_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A twin scenario written with the defaults: a tactical IMU at 1 kHz storing counts, and
    a single-axis table, 70 s (more than one 65 536-row chunk of every IMU column)."""
    sc = Scenario(name="portable", seed=5, table=TableConfig(kind="single-axis"),
                  imus=(ImuConfig(name="A", sample_rate_hz=1000.0),),
                  steps=(StaticStep(kind="static", duration_s=70.0),))
    path = tmp_path_factory.mktemp("portable") / "twin.h5"
    simulate_scenario(sc, path)
    return path


def _stream_columns(path: Path) -> dict[str, h5py.Dataset]:
    out: dict[str, h5py.Dataset] = {}
    f = h5py.File(path, "r")
    f["streams"].visititems(lambda n, o: out.__setitem__(n, o)
                            if isinstance(o, h5py.Dataset) else None)
    return out


def _codecs(path: Path) -> set[str | None]:
    cols = _stream_columns(path)
    try:
        return {compression_of(ds) for ds in cols.values()}
    finally:
        next(iter(cols.values())).file.close()


def _stored_bytes(path: Path) -> int:
    """Bytes the stream columns take in the file (compressed chunks as stored)."""
    cols = _stream_columns(path)
    try:
        return sum(ds.id.get_storage_size() for ds in cols.values())
    finally:
        next(iter(cols.values())).file.close()


def _contents(path: Path) -> tuple[dict[str, np.ndarray], list[tuple[str, str]]]:
    """Every stream column's values as readers see them, and the steps."""
    values: dict[str, np.ndarray] = {}
    with open_recording(path) as rec:
        for s in rec.streams:
            data = rec.read_stream(s.device, s.unit)
            values[f"{s.device}/{s.unit}/time_s"] = data.time_s
            for name, col in data.columns.items():
                values[f"{s.device}/{s.unit}/{name}"] = col
        steps = [(st.label, st.status) for st in rec.steps]
    return values, steps


def _plain_h5py(path: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-c", _PLAIN_H5PY, str(path)], capture_output=True,
                          text=True, check=False, timeout=120)


def test_the_default_file_reads_in_h5py_without_the_plugin(twin_file, tmp_path):
    assert DEFAULT_COMPRESSION == "gzip"
    cols = _stream_columns(twin_file)
    try:
        assert len(cols) == 14  # 11 IMU columns, 3 of the table
        for name, ds in cols.items():
            plist = ds.id.get_create_plist()
            filters = [plist.get_filter(i)[0] for i in range(plist.get_nfilters())]
            assert filters == [h5py.h5z.FILTER_SHUFFLE, h5py.h5z.FILTER_DEFLATE], name
            assert ds.compression_opts == 1
    finally:
        next(iter(cols.values())).file.close()
    done = _plain_h5py(twin_file)
    assert done.returncode == 0, done.stderr
    n_all, n_streams = map(int, done.stdout.split())
    assert n_streams == 14 and n_all > n_streams  # steps, log, commit and truth too
    blosc = tmp_path / "blosc.h5"  # the control: the same file in Blosc does not read there
    shutil.copyfile(twin_file, blosc)
    compact_recording(blosc, "blosc-lz4")
    done = _plain_h5py(blosc)
    assert done.returncode != 0 and "OSError" in done.stderr  # HDF5 lacks the Blosc filter


def test_gzip_is_no_larger_than_blosc_lz4_on_twin_data(twin_file, tmp_path):
    gzip, blosc = tmp_path / "gzip.h5", tmp_path / "blosc.h5"
    for path, codec in ((gzip, "gzip"), (blosc, "blosc-lz4")):
        shutil.copyfile(twin_file, path)
        compact_recording(path, codec)
        assert _codecs(path) == {codec}
    assert _stored_bytes(gzip) <= _stored_bytes(blosc)
    assert gzip.stat().st_size <= blosc.stat().st_size


def test_hdf5plugin_is_imported_only_for_a_blosc_file(twin_file, tmp_path):
    blosc = tmp_path / "blosc.h5"
    shutil.copyfile(twin_file, blosc)
    compact_recording(blosc, "blosc-zstd")
    done = subprocess.run([sys.executable, "-c", _LAZY_PLUGIN, str(twin_file), str(blosc)],
                          capture_output=True, text=True, check=False, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["False", "True"]


def test_a_blosc_file_without_hdf5plugin_says_how_to_convert_it(twin_file, tmp_path):
    blosc = tmp_path / "blosc.h5"
    shutil.copyfile(twin_file, blosc)
    compact_recording(blosc, "blosc-lz4")
    code = ("import sys; sys.modules['hdf5plugin'] = None\n"
            "from imucalib.errors import RecordingError\n"
            "from imucalib.io import open_recording\n"
            "try:\n    open_recording(sys.argv[1])\n"
            "except RecordingError as exc:\n    print(exc)\n")
    done = subprocess.run([sys.executable, "-c", code, str(blosc)], capture_output=True,
                          text=True, check=False, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith(f"the Blosc compression (HDF5 filter {BLOSC_FILTER_ID}) needs "
                                  "the hdf5plugin package, which cannot be imported")
    assert "`imucalib compact FILE --compression gzip`" in done.stdout


def test_compact_command_round_trip(twin_file, tmp_path):
    path = tmp_path / "r.h5"
    shutil.copyfile(twin_file, path)
    before, steps = _contents(path)
    for codec, had in (("blosc-lz4", "gzip"), ("gzip", "blosc-lz4")):
        result = runner.invoke(app, ["compact", str(path), "--compression", codec])
        assert result.exit_code == 0, result.output
        assert f"compacted {path}: {had} → {codec}, " in " ".join(result.output.split())
        assert _codecs(path) == {codec}
        after, steps_after = _contents(path)
        assert after.keys() == before.keys() and steps_after == steps
        for key, values in before.items():
            assert after[key].dtype == values.dtype, key
            assert np.array_equal(after[key], values, equal_nan=True), key
    assert not list(tmp_path.glob(".*partial"))


def test_blosc_makes_a_version_2_file_version_3_and_is_refused_for_version_1(tmp_path):
    from imucalib.errors import InvalidInputError
    from imucalib.io import ColumnSpec, RecordingWriter, StreamSpec

    plain = tmp_path / "plain.h5"  # float64 columns, gzip: version 2
    spec = StreamSpec("imu", "U", {"gyro_x_rps": ColumnSpec("rad/s")})
    with RecordingWriter(plain, streams=[spec]) as w:
        w.append("imu", "U", {"time_s": [0.0, 1.0], "gyro_x_rps": [1.0, 2.0]})
    with open_recording(plain) as rec:
        assert rec.format_version == 2
    compact_recording(plain, "blosc-lz4")
    with open_recording(plain) as rec:  # as a writer stamps a Blosc file
        assert rec.format_version == 3
        assert rec.read_stream("imu", "U").columns["gyro_x_rps"].tolist() == [1.0, 2.0]
    v1 = tmp_path / "v1.h5"
    shutil.copyfile(Path(__file__).parents[1] / "data" / "p1_v1.h5", v1)
    size = v1.stat().st_size
    with pytest.raises(InvalidInputError, match="is of format version 1, whose step fields "
                                                "predate the Blosc filter"):
        compact_recording(v1, "blosc-zstd")
    assert v1.stat().st_size == size and not list(tmp_path.glob(".*partial"))


def test_recover_command_takes_a_compression(twin_file, tmp_path):
    out = tmp_path / "copy.h5"
    result = runner.invoke(app, ["recover", str(twin_file), "--out", str(out),
                                 "--compression", "none"])
    assert result.exit_code == 0, result.output
    assert _codecs(out) == {None}
    report = recover_recording(twin_file, tmp_path / "default.h5")
    assert _codecs(report.output) == {"gzip"}


def test_run_writes_the_compression_asked(tmp_path, p1_tools):
    plan = p1_tools.small_plan_file(tmp_path, "cli-codec")
    out = tmp_path / "run.h5"
    result = runner.invoke(app, ["run", str(plan), "--out", str(out), "--yes", "--no-live",
                                 "--no-record", "--compression", "blosc-lz4"])
    assert result.exit_code == 0, result.output
    assert _codecs(out) == {"blosc-lz4"}
    with h5py.File(out, "r") as f:
        assert str(BLOSC_FILTER_ID) in f["streams/table/main/time_s"]._filters
    with open_recording(out) as rec:
        assert all(s.status == "done" for s in rec.steps)


@pytest.mark.parametrize("args", [
    ["run", "PLAN", "--compression", "zip"],
    ["compact", "FILE", "--compression", "zip"],
    ["recover", "FILE", "--compression", "zip"],
])
def test_a_bad_compression_is_one_error_line(twin_file, tmp_path, args, p1_tools):
    names = {"PLAN": str(p1_tools.small_plan_file(tmp_path, "cli-codec")), "FILE": str(twin_file)}
    args = [names.get(a, a) for a in args]
    result = runner.invoke(app, args)
    assert result.exit_code == 2, result.output
    assert result.stderr == f"error: {BAD_NAME}\n"
    assert not list(tmp_path.glob("*.h5"))


def test_run_resume_refuses_a_compression(tmp_path):
    result = runner.invoke(app, ["run", "--resume", str(tmp_path / "r.h5"), "--compression",
                                 "gzip"])
    assert result.exit_code == 2
    assert result.stderr.startswith("error: --compression is for a new run; a resumed run "
                                    "closes its recording with the compression it had")
    assert result.stderr.count("\n") == 1
