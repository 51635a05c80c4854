"""Damaged Recordings for the validation tests (imported by path from tests/io and tests/cli).

:func:`write_small` writes a small valid Recording (two streams, a truth stream, three steps, two
events). :data:`DAMAGES` maps a name to a function that damages such a file in place, the error
class :func:`imucalib.io.open_recording` must raise and a regular expression its message must
match (``{path}`` stands for the file's path).
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from pathlib import Path

import h5py
import numpy as np

from imucalib.errors import RecordingCorruptError, RecordingError
from imucalib.io import FORMAT_VERSION, ColumnSpec, RecordingWriter, StreamSpec

IMU = StreamSpec("imu", "IMU-0001", {"gyro_x_rps": ColumnSpec("rad/s"),
                                     "accel_z_mps2": ColumnSpec("m/s^2"),
                                     "counter": ColumnSpec("counts", dtype="u4", quantity="raw")})
TABLE = StreamSpec("table", "main", {"angle_rad": ColumnSpec("rad"),
                                     "rate_rps": ColumnSpec("rad/s")})
TRUTH = StreamSpec("imu", "IMU-0001", {"rate_b_rps": ColumnSpec("rad/s")})
N_IMU, N_TABLE = 5000, 500
BAD_ROW = 1234
RECOVER = r"; run `imucalib recover {path}` to copy out what is valid$"


def write_small(path: Path) -> Path:
    """Write the small valid Recording every damage starts from."""
    t = np.arange(N_IMU) / 1000.0
    rng = np.random.default_rng(1)
    with RecordingWriter(path, streams=[IMU, TABLE], truth_streams=[TRUTH],
                         metadata={"plan_toml": 'name = "x"\n', "station_json": '{"site": "lab"}',
                                   "operator": "test", "latitude_deg": 48.1, "dry_run": False,
                                   "n_positions": 2, "environment_json": "{}"},  # > 8: dense
                         truth={"bias_rps": np.array([1e-4, 2e-4, -3e-4]), "model": "triad"},
                         chunk_rows=1024) as w:
        w.append("imu", "IMU-0001", {"time_s": t, "gyro_x_rps": rng.standard_normal(N_IMU),
                                     "accel_z_mps2": 9.8 + rng.standard_normal(N_IMU),
                                     "counter": np.arange(N_IMU, dtype=np.uint32)})
        tt = np.arange(N_TABLE) / 100.0
        w.append("table", "main", {"time_s": tt, "angle_rad": np.sin(tt), "rate_rps": np.cos(tt)})
        w.append_truth("imu", "IMU-0001", {"time_s": t, "rate_b_rps": np.zeros(N_IMU)})
        s0 = w.begin_step("static", "position 1", 0.0, commanded={"angle_deg": [0, 90]})
        w.update_step(s0, t_end_s=2.0, valid_start_s=0.5, valid_end_s=1.9, status="done")
        s1 = w.begin_step("rate", "rate +10 dps", 2.0, commanded={"rate_dps": 10})
        w.update_step(s1, t_end_s=4.0, valid_start_s=2.5, valid_end_s=3.9, status="done")
        w.begin_step("static", "position 2", 4.0)
        w.log_event(0.1, "info", "runner", "started")
        w.log_event(2.1, "warning", "guard", "rate error 0.2 %")
    return path


# --------------------------------------------------------------------------- damaging edits
def _edit(func: Callable[[h5py.File], None]) -> Callable[[Path], None]:
    def damage(path: Path) -> None:
        with h5py.File(path, "r+") as f:
            func(f)
    return damage


def _bytes(func: Callable[[bytearray, Path], None]) -> Callable[[Path], None]:
    def damage(path: Path) -> None:
        raw = bytearray(path.read_bytes())
        func(raw, path)
        path.write_bytes(bytes(raw))
    return damage


def _flip(raw: bytearray, offset: int, n: int = 4) -> None:
    raw[offset:offset + n] = bytes(b ^ 0xFF for b in raw[offset:offset + n])


def _header_address(path: Path, name: str) -> int:
    with h5py.File(path, "r") as f:
        return int(h5py.h5o.get_info(f[name].id).addr)


def _set_row(dataset: str, row: int, value: object) -> Callable[[Path], None]:
    def func(f: h5py.File) -> None:
        f[dataset][row] = value
    return _edit(func)


def _set_attr(obj: str, key: str, value: object) -> Callable[[Path], None]:
    def func(f: h5py.File) -> None:
        f[obj].attrs[key] = value
    return _edit(func)


def _delete(name: str) -> Callable[[Path], None]:
    def func(f: h5py.File) -> None:
        del f[name]
    return _edit(func)


def _commit(func: Callable[[list[str], np.ndarray], tuple[list[str], np.ndarray]]
            ) -> Callable[[Path], None]:
    def edit(f: h5py.File) -> None:
        entries, rows = func(json.loads(f["commit"].attrs["entries_json"]), f["commit/rows"][()])
        del f["commit/rows"]
        f["commit"].create_dataset("rows", data=np.asarray(rows, dtype=np.int64))
        f["commit"].attrs["entries_json"] = json.dumps(entries)
    return _edit(edit)


def _negative_count(entries: list[str], rows: np.ndarray) -> tuple[list[str], np.ndarray]:
    rows[entries.index("streams/imu/IMU-0001")] = -5
    return entries, rows


def _resize(name: str, n: int) -> Callable[[Path], None]:
    def func(f: h5py.File) -> None:
        f[name].resize((n,))
    return _edit(func)


def _columns_json(func: Callable[[list[dict[str, str]]], object]) -> Callable[[Path], None]:
    def edit(f: h5py.File) -> None:
        g = f["streams/table/main"]
        g.attrs["columns_json"] = json.dumps(func(json.loads(g.attrs["columns_json"])))
    return _edit(edit)


def _retype(f: h5py.File) -> None:
    g = f["streams/table/main"]
    del g["rate_rps"]
    g.create_dataset("rate_rps", data=np.zeros(N_TABLE, dtype=np.int32), maxshape=(None,))


def _zero_global_heap(raw: bytearray, path: Path) -> None:
    at = raw.find(b"GCOL")  # the first collection holds the root attributes
    raw[at + 16:at + 80] = bytes(64)  # its first object now has size 0: HDF5 loops forever


Damage = tuple[Callable[[Path], None], type[RecordingError], str]

DAMAGES: dict[str, Damage] = {
    # 1. missing groups
    "no-log": (_delete("log"), RecordingCorruptError,
               r"^{path} is damaged: the group /log is missing; expected the groups /streams, "
               r"/steps, /log and /commit of a recording" + RECOVER),
    "no-steps": (_delete("steps"), RecordingCorruptError,
                 r"^{path} is damaged: the group /steps is missing;"),
    "no-streams": (_delete("streams"), RecordingCorruptError, r"the group /streams is missing"),
    "no-commit": (_delete("commit"), RecordingCorruptError, r"the group /commit is missing"),
    # 2. a commanded state that is not JSON
    "commanded-not-json": (
        _set_row("steps/commanded", 1, b'{"rate_dps": 1'), RecordingCorruptError,
        r"^{path} is damaged: /steps/commanded row 1 is not JSON \('\{\"rate_dps\": 1': "
        r"Expecting ',' delimiter: line 1 column 15 \(char 14\)\); expected JSON text or an "
        r"empty string" + RECOVER),
    # 3. flipped metadata bytes (checksummed structures)
    "flipped-root-attribute-heap": (  # more than 8 root attributes live in a fractal heap
        _bytes(lambda raw, p: _flip(raw, raw.find(b"FRHP") + 8)), RecordingCorruptError,
        r"^{path} is damaged: HDF5 cannot read the root attributes \(.*incorrect metadata "
        r"checksum.*\); run `imucalib recover {path}` to copy out what is readable$"),
    "flipped-link-heap": (  # the second heap holds the links of /steps (more than 8 fields)
        _bytes(lambda raw, p: _flip(raw, raw.find(b"FRHP", raw.find(b"FRHP") + 4) + 8)),
        RecordingCorruptError,
        r"^{path} is damaged: HDF5 cannot read /steps \(.*incorrect metadata checksum.*\); run "
        r"`imucalib recover {path}` to copy out what is readable$"),
    "flipped-stream-header": (
        _bytes(lambda raw, p: _flip(raw, _header_address(p, "streams/imu/IMU-0001") + 8)),
        RecordingCorruptError,
        r"^{path} is damaged: HDF5 cannot read /streams/imu/IMU-0001 \(.*incorrect metadata "
        r"checksum.*\); run `imucalib recover {path}` to copy out what is readable$"),
    "flipped-root-header": (
        _bytes(lambda raw, p: _flip(raw, _header_address(p, "/") + 8)), RecordingCorruptError,
        r"^{path} is damaged: HDF5 cannot read its root group \(.*\); neither imucalib nor "
        r"`imucalib recover` can read this file: restore it from a copy$"),
    # 4. zeros in a global heap collection: HDF5 would loop forever
    "zeroed-global-heap": (
        _bytes(_zero_global_heap), RecordingCorruptError,
        r"^{path} is damaged: HDF5 did not finish reading its metadata within 1 s \(it was "
        r"reading the root attributes\) and was stopped; damaged metadata can make the HDF5 "
        r"library loop forever\. Neither imucalib nor `imucalib recover` can read this file: "
        r"restore it from a copy$"),
    # 5. time bases
    "time-nan": (_set_row("streams/imu/IMU-0001/time_s", BAD_ROW, np.nan), RecordingCorruptError,
                 r"^{path} is damaged: stream imu/IMU-0001 time_s row 1234 is nan; expected "
                 r"finite times from 0 to 1e9 s that never decrease; run `imucalib recover "
                 r"{path}` to copy out the rows before row 1234$"),
    "time-huge": (_set_row("streams/imu/IMU-0001/time_s", BAD_ROW, 1e308), RecordingCorruptError,
                  r"stream imu/IMU-0001 time_s row 1234 is 1e\+308, later than 1e9 s;"),
    "time-negative": (_set_row("streams/imu/IMU-0001/time_s", 0, -1.0), RecordingCorruptError,
                      r"stream imu/IMU-0001 time_s row 0 is -1\.0, negative;"),
    "time-decreasing": (_set_row("streams/table/main/time_s", 300, 1.0), RecordingCorruptError,
                        r"stream table/main time_s row 300 is 1\.0, before the previous time "
                        r"stamp 2\.99;"),
    "truth-time-inf": (_set_row("truth/streams/imu/IMU-0001/time_s", 7, np.inf),
                       RecordingCorruptError, r"truth stream imu/IMU-0001 time_s row 7 is inf;"),
    # 6. commit counts
    "commit-negative": (_commit(_negative_count), RecordingCorruptError,
                        r"^{path} is damaged: /commit/rows counts -5 rows for "
                        r"streams/imu/IMU-0001; expected a count ≥ 0" + RECOVER),
    "commit-too-few": (_commit(lambda e, r: (e, r[:-1])), RecordingCorruptError,
                       r"/commit/rows holds 4 counts for 5 entries in `entries_json`; expected "
                       r"one count per entry"),
    "commit-unknown-entry": (
        _commit(lambda e, r: ([*e, "streams/imu/IMU-9"], np.r_[r, 0])), RecordingCorruptError,
        r"/commit `entries_json` names 'streams/imu/IMU-9', which the file does not hold"),
    "commit-entries-not-json": (_set_attr("commit", "entries_json", "[streams"),
                                RecordingCorruptError,
                                r"/commit `entries_json` is not JSON \('\[streams': "),
    # 7. a column shorter than the committed rows
    "column-short": (_resize("streams/table/main/rate_rps", N_TABLE - 10), RecordingCorruptError,
                     r"^{path} is damaged: /streams/table/main/rate_rps holds 490 rows but 500 "
                     r"are committed; expected every column to hold the committed rows"
                     + RECOVER),
    # 8. layout
    "format-version-missing": (
        _edit(lambda f: f.attrs.__delitem__("format_version")), RecordingCorruptError,
        r"^{path} is damaged: its root has no `format_version` attribute; expected the int "
        + str(FORMAT_VERSION)),
    "format-version-str": (_set_attr("/", "format_version", "1"), RecordingCorruptError,
                           r"its `format_version` attribute is str '1'; expected a positive int"),
    "columns-json-not-json": (_set_attr("streams/table/main", "columns_json", "[{"),
                              RecordingCorruptError,
                              r"/streams/table/main `columns_json` is not JSON \('\[\{': "),
    "columns-json-missing": (_edit(lambda f: f["streams/table/main"].attrs.__delitem__(
        "columns_json")), RecordingCorruptError,
        r"/streams/table/main has no `columns_json` attribute"),
    "column-undeclared": (_columns_json(lambda c: c[:-1]), RecordingCorruptError,
                          r"/streams/table/main holds \['rate_rps'\], which `columns_json` does "
                          r"not declare"),
    "column-missing": (_delete("streams/table/main/rate_rps"), RecordingCorruptError,
                       r"/streams/table/main/rate_rps is missing; expected the columns "
                       r"\['time_s', 'angle_rad', 'rate_rps'\]"),
    "column-dtype": (_edit(_retype), RecordingCorruptError,
                     r"/streams/table/main/rate_rps holds i4; expected f8"),
    "time-not-first": (_columns_json(lambda c: c[::-1]), RecordingCorruptError,
                       r"`columns_json` starts with 'rate_rps' \(f8\); expected time_s \(f8\) "
                       r"first"),
    "step-field-missing": (_delete("steps/note"), RecordingCorruptError,
                           r"the field /steps/note is missing; expected the fields \['index', "),
    "step-status-unknown": (_set_row("steps/status", 0, b"finished"), RecordingCorruptError,
                            r"/steps/status row 0 is 'finished'; expected one of \['pending', "),
    "step-window-inf": (_set_row("steps/valid_end_s", 1, np.inf), RecordingCorruptError,
                        r"/steps/valid_end_s row 1 is inf; expected a finite time or NaN"),
    "step-index-wrong": (_set_row("steps/index", 2, 7), RecordingCorruptError,
                         r"/steps/index row 2 is 7; expected 2"),
    "log-level-unknown": (_set_row("log/level", 1, b"loud"), RecordingCorruptError,
                          r"/log/level row 1 is 'loud'; expected one of \['debug', "),
    "log-time-nan": (_set_row("log/time_s", 0, np.nan), RecordingCorruptError,
                     r"/log/time_s row 0 is nan; expected a finite time"),
    "truth-json": (_set_attr("truth", "model_json", "{tri"), RecordingCorruptError,
                   r"/truth `model_json` is not JSON \('\{tri': "),
}


def expected_message(name: str, path: Path) -> str:
    """The regular expression the message for damage `name` of `path` must match."""
    return DAMAGES[name][2].replace("{path}", re.escape(str(path)))
