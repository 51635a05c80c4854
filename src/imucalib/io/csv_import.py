"""Read IMU data from CSV: the exports of :mod:`imucalib.exports.streams` and plain vendor files.

Contents
--------
:func:`read_imu_csv`
    A CSV file → a DataFrame indexed by ``time_s`` with canonical column names and the units in
    ``df.attrs["units"]``.
:func:`iter_imu_csv`, :func:`concat_chunks`
    The same, in chunks of at most ``chunk_rows`` rows (a large log in bounded memory), and
    the join of those chunks (what :func:`read_imu_csv` returns).
:data:`MAX_ABS_TIME_S`, :data:`MAX_TIME_SPAN_S`
    The bounds on the time column.

Accepted headers
----------------
- ``name [unit]`` (what :func:`~imucalib.exports.streams.export_csv` writes): the unit is taken from
  the brackets; it must be one :func:`imucalib.units.parse_unit` knows, or one of the units
  without an SI factor that a Recording accepts (``degC``, ``bool``, ``K``, …);
- a bare canonical name (``gyro_x_rps``, ``accel_y_mps2``, ``time_s``): the unit its suffix
  names;
- a ``column_map`` renames vendor columns once, at ingest (``{"GyrX": "gyro_x_rps"}``), with
  ``units`` giving their units when the header does not (values are converted to SI).

The brackets give the unit the values are written in; the name gives the quantity. A name with
an SI suffix (``_s``, ``_rps``, ``_mps2``, and ``_degc``, ``_dps``, ``_g``) fixes the dimension:
``gyro_x_rps [deg/h]`` is the x gyro written in °/h (converted to rad/s), while
``gyro_x_rps [m/s^2]`` or ``time_s [furlong]`` is refused.

Checks at the door
------------------
Every defect is an :class:`~imucalib.errors.InvalidInputError` (a
:class:`~imucalib.errors.UnitError` for units) whose one-line message names the file, the
column and the data row (and file line) where relevant, what was expected and what was found:

- the file: missing, empty, binary (NUL bytes) or not UTF-8 text; a first line that is blank,
  over 64 KiB, or not a header of ``name`` / ``name [unit]`` fields; no data rows;
- the header: an unknown unit, a unit of the wrong dimension for the name, two columns for one
  quantity (``time_s`` next to ``time_s [ms]``), no ``time_s`` column;
- the rows: a row with more or fewer fields than the header, an empty cell, a non-numeric cell;
  NaN or ±inf in ``time_s`` or a gyro or accelerometer column (other columns may hold ``NaN``,
  the missing value the exports write, but not ±inf);
- the time: decreasing from one row to the next (equal consecutive times are allowed, as in a
  Recording), beyond ±:data:`MAX_ABS_TIME_S`, or spanning more than :data:`MAX_TIME_SPAN_S`;
- the values: a gyro beyond ±:data:`MAX_ABS_RATE_RPS` or an accelerometer beyond
  ±:data:`MAX_ABS_ACCEL_MPS2` after the conversion to SI (no IMU reads that much: raw counts
  read without their scale, or the wrong unit);
- a field longer than :data:`MAX_FIELD_CHARS` characters where a line is split into its fields
  (the header, the first data row, a row an error names). The ``csv`` module's own limit
  (131 072 characters) is raised to that bound, for the whole process, when a line is split.

The file is parsed once by pandas' C reader, :data:`DEFAULT_CHUNK_ROWS` rows at a time, and
checked with array operations: a 10⁶-row export (180 MB) reads in about the time pandas alone
takes; only the error path looks at single lines (to name the line of a bad row). The rows are
checked chunk by chunk with the same code whichever function reads them: a defect names the
data row and line over the whole file, and the time checks carry across chunk boundaries. When
a file spans several chunks, the count of like defects in a message covers the rows read so far
("in the first N data rows").
"""

from __future__ import annotations

import csv
import os
import re
from collections.abc import Collection, Iterator, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final

import numpy as np

from imucalib.conventions import ACCEL_COLUMNS, GYRO_COLUMNS, IMU_COLUMNS, TIME_COLUMN
from imucalib.errors import InvalidInputError, UnitError
from imucalib.io._schema import EXTRA_UNITS
from imucalib.units import parse_unit

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["DEFAULT_CHUNK_ROWS", "MAX_ABS_ACCEL_MPS2", "MAX_ABS_RATE_RPS", "MAX_ABS_TIME_S",
           "MAX_FIELD_CHARS", "MAX_TIME_SPAN_S", "WHITESPACE", "concat_chunks", "iter_imu_csv",
           "read_imu_csv"]

#: The `delimiter` of files whose fields are separated by runs of blanks (imu_tk's files).
WHITESPACE: Final = "whitespace"

#: Rows parsed at a time by :func:`iter_imu_csv` (about 100 MB of parsed columns for an IMU log).
DEFAULT_CHUNK_ROWS: Final = 1_000_000

#: Largest accepted |time_s|: about 317 years, so Unix-epoch times fit and float64 still resolves
#: 2 µs. [s]
MAX_ABS_TIME_S: Final = 1e10
#: Largest accepted last − first time of one file: 366 days. [s]
MAX_TIME_SPAN_S: Final = 366 * 86400.0
#: Largest accepted |gyro| once in SI: 10⁴ rad/s (about 573 000 °/s, some 30 times the widest
#: range of a MEMS or optical gyro). [rad/s]
MAX_ABS_RATE_RPS: Final = 1e4
#: Largest accepted |accelerometer| once in SI: 10⁷ m/s² (about 10⁶ g, ten times the range of a
#: shock accelerometer). [m/s²]
MAX_ABS_ACCEL_MPS2: Final = 1e7
#: Most characters of one field where a line is split by the csv module (the header, the first
#: data row, a row an error names); the module's own default is 131 072. [characters]
MAX_FIELD_CHARS: Final = 1 << 20

_HEADER = re.compile(r"^\s*(%?[A-Za-z][A-Za-z0-9_.]*)\s*(?:\[(.+)\])?\s*$")
_SI_SUFFIXES = {"_rps": "rad/s", "_mps2": "m/s^2", "_s": "s"}
_SUFFIX_UNITS = {"_rps": "rad/s", "_mps2": "m/s^2", "_s": "s", "_degc": "degC", "_dps": "deg/s",
                 "_g": "g"}
_TIME_UNITS = ("s", "ms", "us", "ns", "min", "h")
_RATE_UNITS = ("rad/s", "deg/s", "°/s", "dps", "deg/h", "°/h", "dph", "rpm")
_ACCEL_UNITS = ("m/s^2", "m/s²", "mps2", "g", "mg", "ug", "µg")
#: The dimension a name suffix fixes: (what it is, the units of that dimension).
_DIMENSIONS: dict[str, tuple[str, tuple[str, ...]]] = {
    "_rps": ("an angular rate", _RATE_UNITS), "_dps": ("an angular rate", _RATE_UNITS),
    "_mps2": ("an acceleration", _ACCEL_UNITS), "_g": ("an acceleration", _ACCEL_UNITS),
    "_degc": ("a temperature", ("degC", "°C")), "_s": ("a time", _TIME_UNITS),
}
_NO_FACTOR = frozenset(u.lower() for u in EXTRA_UNITS)
_MAX_HEADER_BYTES = 65536
_MUST_BE_FINITE = frozenset((TIME_COLUMN, *IMU_COLUMNS))
#: The SI bound of each IMU column, with what it is and the option that gives its unit.
_BOUNDS: dict[str, tuple[float, str, str]] = {
    **dict.fromkeys(GYRO_COLUMNS, (MAX_ABS_RATE_RPS, "a gyro", "gyro")),
    **dict.fromkeys(ACCEL_COLUMNS, (MAX_ABS_ACCEL_MPS2, "an accelerometer", "accel")),
}


def _unit_of(name: str) -> str:
    for suffix, unit in _SUFFIX_UNITS.items():
        if name.endswith(suffix):
            return unit
    return "1"


def _key(unit: str) -> str:
    return unit.strip().lower().replace(" ", "")


def _num(value: Any) -> str:
    x = float(value)
    return "NaN" if np.isnan(x) else repr(x)


def _short(text: str, limit: int = 60) -> str:
    return repr(text) if len(text) <= limit else repr(text[:limit]) + "…"


def named_unit(field: str) -> str | None:
    """Return the unit a column's own name carries, or None.

    ``name [unit]`` gives the unit in brackets; a name ending in a unit suffix (``_dps``,
    ``_rps``, ``_g``, ``_mps2``, ``_s``, ``_degc``; any case) the suffix's unit: ``acc_x[g]`` →
    ``g``, ``gyr_x_dps`` → ``deg/s``, ``GyroX`` → None.
    """
    m = _HEADER.match(field)
    if m is None:
        return None
    if m.group(2):
        return m.group(2).strip()
    return _suffix_unit(m.group(1).lower())


def _suffix_unit(name: str) -> str | None:
    return next((u for suffix, u in _SUFFIX_UNITS.items() if name.endswith(suffix)), None)


def _split(line: str, delimiter: str, where: str = "the line") -> list[str]:
    """Split one line: `delimiter` is one character, or ``"whitespace"``.

    Raises
    ------
    InvalidInputError
        A field longer than :data:`MAX_FIELD_CHARS`, or a line the csv module cannot split;
        `where` names the line.
    """
    if delimiter == WHITESPACE:
        return line.split()
    if csv.field_size_limit() < MAX_FIELD_CHARS:
        csv.field_size_limit(MAX_FIELD_CHARS)
    try:
        return next(csv.reader([line], delimiter=delimiter), [])
    except csv.Error as exc:
        if "field limit" in str(exc):
            raise InvalidInputError(f"{where} has a field longer than {MAX_FIELD_CHARS} "
                                    "characters, the most a field may hold; expected numbers "
                                    "(or short text in a column that is skipped)") from None
        raise InvalidInputError(f"{where} cannot be split into fields: {exc}") from None


def _read_header(p: Path, skip_rows: int = 0, delimiter: str = ",") -> list[str]:
    """Return the fields of the header line (after `skip_rows` lines), refusing non-CSV text."""
    try:
        with open(p, "rb") as fh:
            head = fh.read(_MAX_HEADER_BYTES + 1)
    except OSError as exc:
        raise InvalidInputError(f"cannot read CSV {p}: {exc.strerror or exc}") from exc
    if not head:
        raise InvalidInputError(f"{p} is empty: expected a header line (e.g. "
                                "`time_s,gyro_x_rps,gyro_y_rps,gyro_z_rps`) and rows of numbers")
    nul = head.find(b"\x00")
    if nul >= 0:
        raise InvalidInputError(f"{p} is not CSV text: it holds NUL bytes (the first at offset "
                                f"{nul}), as a binary file does")
    begin = 0
    for k in range(skip_rows):
        nl = head.find(b"\n", begin)
        if nl < 0:
            raise InvalidInputError(f"{p}: the file has {k + 1} line(s); the header was expected "
                                    f"after the {skip_rows} skipped row(s) (`skip_rows`)")
        begin = nl + 1
    head = head[begin:]
    end = head.find(b"\n")
    if end < 0 and len(head) > _MAX_HEADER_BYTES:
        raise InvalidInputError(f"{p}: the first line is longer than {_MAX_HEADER_BYTES} bytes; "
                                "expected a header of `name` or `name [unit]` fields")
    raw = head if end < 0 else head[:end]
    try:
        line = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InvalidInputError(f"{p} is not UTF-8 text: byte 0x{raw[exc.start]:02x} at offset "
                                f"{exc.start} cannot be decoded (a binary file, or text in "
                                "another encoding: save it as UTF-8)") from exc
    if not line.strip():
        raise InvalidInputError(f"{p}: line {skip_rows + 1} is blank; expected the header (e.g. "
                                "`time_s,gyro_x_rps,gyro_y_rps,gyro_z_rps`)")
    return _split(line.rstrip("\r"), delimiter, f"{p}: line {skip_rows + 1} (the header)")


def _columns(p: Path, headers: list[str], column_map: Mapping[str, str] | None,
             units: Mapping[str, str] | None, only: Collection[str] | None = None
             ) -> tuple[list[str | None], dict[str, str]]:
    """Return the canonical name of each header field (None: skipped) and each name's unit."""
    names: list[str | None] = []
    col_units: dict[str, str] = {}
    seen: dict[str, int] = {}
    given_names: list[str] = []
    for i, header in enumerate(headers):
        if only is not None and header.strip() not in only:
            names.append(None)
            given_names.append("")
            continue
        m = _HEADER.match(header)
        if m is None and column_map and header.strip() in column_map:
            m = _HEADER.match(column_map[header.strip()])  # a vendor name such as "Gyro X (°/s)"
            header = header.strip()
        if not header.strip():
            raise InvalidInputError(f"{p}: header field {i + 1} is empty; expected `name` or "
                                    "`name [unit]` (a trailing comma?)")
        if m is None:
            hint = (" (fields are separated by commas: give `--delimiter`)"
                    if ";" in header or "\t" in header else
                    " (a preamble before the header? give `--skip-rows`; a vendor name? map it "
                    "with `--column-map`)")
            raise InvalidInputError(f"{p}: header field {i + 1} {_short(header)} is not `name` or "
                                    f"`name [unit]` (a name starts with a letter){hint}")
        given = header if column_map and header in column_map else m.group(1)
        name = (column_map or {}).get(given, given)
        renamed = _suffix_unit(m.group(1).lower()) if name != given else None
        unit = (m.group(2) or (units or {}).get(name) or renamed or _unit_of(name)).strip()
        _check_unit(p, header, name, unit)
        if name in seen:
            j = seen[name]
            via = "both hold" if given == name == given_names[j] else "both map to"
            raise InvalidInputError(
                f"{p}: columns {_short(headers[j])} and {_short(header)} (header fields {j + 1} "
                f"and {i + 1}) {via} {name}; expected one column per quantity")
        seen[name] = i
        given_names.append(given)
        names.append(name)
        col_units[name] = unit
    return names, col_units


def _check_unit(p: Path, header: str, name: str, unit: str) -> None:
    """Refuse an unknown unit, or one of another dimension than the name's suffix."""
    key = _key(unit)
    known = key in _NO_FACTOR
    if not known:
        try:
            parse_unit(unit)
            known = True
        except UnitError:
            pass
    dim = next((d for suffix, d in _DIMENSIONS.items() if name.endswith(suffix)), None)
    if dim is not None and key not in {_key(u) for u in dim[1]}:
        what, allowed = dim
        problem = "an unknown unit" if not known else "a unit of another quantity,"
        raise UnitError(f"{p}: column {_short(header)} has {problem} {_short(unit)}; {name} is "
                        f"{what}, expected one of {', '.join(allowed)}")
    if not known:
        raise UnitError(f"{p}: column {_short(header)} has an unknown unit {_short(unit)}; "
                        "expected a "
                        "unit such as rad/s, deg/s, deg/h, m/s^2, g, s, ms, degC, counts or 1 "
                        "(imucalib.units.parse_unit lists them all)")


def _locate(p: Path, row: int, header_line: int = 1) -> tuple[int, str]:
    """Return the file line number (1-based) and text of data row `row` (0-based). Slow path."""
    seen = -1
    with open(p, encoding="utf-8-sig", errors="replace", newline="") as fh:
        for number, line in enumerate(fh, start=1):
            if number <= header_line or not line.strip():
                continue  # the header; blank lines are skipped, as pandas does
            seen += 1
            if seen == row:
                return number, line.rstrip("\r\n")
    return -1, ""


def _where(p: Path, row: int, header_line: int = 1) -> str:
    line, _ = _locate(p, row, header_line)
    return f"data row {row + 1}" + (f" (line {line})" if line > 0 else "")


def _parse(p: Path, n_fields: int, header_line: int = 1, delimiter: str = ",",
           has_header: bool = True, chunk_rows: int = DEFAULT_CHUNK_ROWS
           ) -> Iterator[pd.DataFrame]:
    """Parse the rows with pandas' C reader, `chunk_rows` at a time.

    Ragged rows and undecodable bytes are refused (pandas counts the line of a ragged row over
    the whole file).
    """
    import pandas as pd

    first, text = _locate(p, 0, header_line)
    if first < 0:
        raise InvalidInputError(f"{p}: no data rows after the header; expected at least one row "
                                "of numbers")
    n_first = len(_split(text, delimiter, f"{p}: line {first}"))
    if n_first > n_fields:  # pandas would silently take the extra field for an index
        raise InvalidInputError(f"{p}: line {first} has {n_first} fields; the header has "
                                f"{n_fields} (a ragged row)")
    try:
        sep = r"\s+" if delimiter == WHITESPACE else delimiter
        options: dict[str, Any] = {"names": list(range(n_fields)), "keep_default_na": False,
                                   "na_values": ["NaN", "nan"], "encoding": "utf-8-sig",
                                   "sep": sep, "chunksize": chunk_rows}
        if not has_header:  # header_line: the lines skipped
            reader = pd.read_csv(p, header=None, skiprows=header_line, **options)
        else:
            reader = pd.read_csv(p, header=0, skiprows=header_line - 1, **options)
        with reader:
            yield from reader
    except UnicodeDecodeError as exc:
        raise InvalidInputError(f"{p} is not UTF-8 text: byte 0x{exc.object[exc.start]:02x} "
                                "after the header cannot be decoded (a binary file, or text in "
                                "another encoding: save it as UTF-8)") from exc
    except pd.errors.ParserError as exc:
        m = re.search(r"Expected (\d+) fields in line (\d+), saw (\d+)", str(exc))
        if m is not None:
            raise InvalidInputError(f"{p}: line {m.group(2)} has {m.group(3)} fields; the header "
                                    f"has {m.group(1)} (a ragged row)") from exc
        raise InvalidInputError(f"cannot parse CSV {p}: {str(exc).strip()}") from exc
    except (OSError, ValueError) as exc:
        raise InvalidInputError(f"cannot read CSV {p}: {exc}") from exc


def _numeric(p: Path, df: pd.DataFrame, pos: int, name: str, n_fields: int,
             header_line: int = 1, delimiter: str = ",", row0: int = 0) -> Any:
    """Return column `pos` as numbers, or raise naming its first non-numeric cell.

    `row0` is the data row (0-based, over the whole file) of the first row of `df`.
    """
    import pandas as pd

    col = df[pos]
    if pd.api.types.is_numeric_dtype(col):  # float, int and bool
        return col
    num = pd.to_numeric(col, errors="coerce")
    bad = (num.isna() & col.notna()).to_numpy()
    if not bad.any():
        return num
    row = int(np.argmax(bad))
    value = col.iloc[row]
    row += row0
    line, text = _locate(p, row, header_line)
    where = f"data row {row + 1}" + (f" (line {line})" if line > 0 else "")
    if isinstance(value, str) and not value.strip():
        n_here = len(_split(text, delimiter, f"{p}: line {line}")) if text else n_fields
        if n_here < n_fields:
            raise InvalidInputError(f"{p}: line {line} has {n_here} fields; the header has "
                                    f"{n_fields} (a ragged row)")
        raise InvalidInputError(f"{p}: column {name!r} is empty at {where} (a number expected; "
                                "a missing value is written NaN)")
    shown = _short(value) if isinstance(value, str) else repr(value)
    raise InvalidInputError(f"{p}: column {name!r} holds a non-numeric value {shown} at "
                            f"{where} (numbers expected; a missing value is written NaN)")


def _check_finite(p: Path, name: str, values: np.ndarray[Any, Any], header_line: int = 1,
                  row0: int = 0, scope: str = "") -> None:
    """Refuse NaN/±inf where they are not allowed; `row0`, `scope`: as in :func:`_check_time`."""
    if values.dtype.kind != "f":
        return
    finite = np.isfinite(values)
    if finite.all():
        return
    bad = ~finite if name in _MUST_BE_FINITE else np.isinf(values)
    if not bad.any():
        return
    row = int(np.argmax(bad))
    rule = ("time_s and the gyro and accelerometer columns must be finite"
            if name in _MUST_BE_FINITE else "values must be finite numbers or NaN (missing)")
    raise InvalidInputError(f"{p}: column {name!r} holds {_num(values[row])} at "
                            f"{_where(p, row0 + row, header_line)}; "
                            f"{rule} ({int(bad.sum())} such cell(s){scope})")


def _check_range(p: Path, name: str, values: np.ndarray[Any, Any], unit: str,
                 header_line: int = 1, row0: int = 0, scope: str = "") -> None:
    """Refuse a gyro or accelerometer value beyond its bound (:data:`_BOUNDS`, in `unit`)."""
    if name not in _BOUNDS or values.dtype.kind not in "fiu" or not values.size:
        return
    bound_si, what, option = _BOUNDS[name]
    factor = 1.0 if _key(unit) in _NO_FACTOR else parse_unit(unit)
    bound = bound_si / factor
    with np.errstate(invalid="ignore"):
        big = np.abs(values.astype(np.float64)) > bound
    if not big.any():
        return
    row = int(np.argmax(big))
    raise InvalidInputError(
        f"{p}: column {name!r} holds {_num(values[row])} {unit} at "
        f"{_where(p, row0 + row, header_line)}; {what} reads at most ±{bound:.6g} {unit} "
        f"({int(big.sum())} such cell(s){scope}): raw counts? give `--{option}-unit counts` "
        f"and `--{option}-scale`; another unit? `--{option}-unit`")


def _check_time(p: Path, t: np.ndarray[Any, Any], header_line: int = 1, *, row0: int = 0,
                before: float | None = None, first: float | None = None, scope: str = ""
                ) -> None:
    """Refuse decreasing, too large or too long times.

    `t` holds data rows ``row0 …`` of the file; `before` is the time of the row before them and
    `first` the file's first time (None: `t` starts the file); `scope` says which rows the
    counts cover when they are not the whole file (a chunk, :func:`iter_imu_csv`).
    """
    ext = t if before is None else np.concatenate(([before], t))
    shift = row0 if before is None else row0 - 1  # ext[k] is data row shift + k
    with np.errstate(invalid="ignore"):  # inf − inf: the bound below names the time
        step = np.diff(ext)
    if np.any(step < 0):
        k = int(np.argmax(step < 0)) + 1
        raise InvalidInputError(
            f"{p}: {TIME_COLUMN} decreases at {_where(p, shift + k, header_line)}: {_num(ext[k])} "
            f"s after {_num(ext[k - 1])} s; times must not decrease "
            f"({int(np.sum(step < 0))} such step(s){scope})")
    big = np.abs(t) > MAX_ABS_TIME_S
    if big.any():
        i = int(np.argmax(big))
        raise InvalidInputError(
            f"{p}: {TIME_COLUMN} {_num(t[i])} s at {_where(p, row0 + i, header_line)} is beyond "
            f"±{MAX_ABS_TIME_S:g} s; "
            "expected seconds (give another unit in the header, e.g. `time_s [ms]`)")
    t0 = (t[0] if t.size else 0.0) if first is None else first
    if t.size and t[-1] - t0 > MAX_TIME_SPAN_S:
        raise InvalidInputError(
            f"{p}: {TIME_COLUMN} spans {t[-1] - t0:.6g} s (from {_num(t0)} to {_num(t[-1])}); "
            f"expected at most {MAX_TIME_SPAN_S:g} s (366 days) in one file")


def read_imu_csv(path: str | os.PathLike[str], *, column_map: Mapping[str, str] | None = None,
                 units: Mapping[str, str] | None = None, to_si: bool = True,
                 only: Collection[str] | None = None, delimiter: str = ",",
                 skip_rows: int = 0, sample_rate_hz: float | None = None,
                 scales: Mapping[str, float] | None = None,
                 offsets: Mapping[str, float] | None = None,
                 names: Collection[str] | None = None,
                 chunk_rows: int = DEFAULT_CHUNK_ROWS) -> pd.DataFrame:
    """Read a CSV file of IMU samples.

    Parameters
    ----------
    path : str or Path
        The file; its first line is the header.
    column_map : mapping, optional
        Vendor column name → canonical name.
    units : mapping, optional
        Canonical column name → unit, for columns whose header gives none.
    to_si : bool
        Convert every column with a known SI factor to SI (``deg/s`` → rad/s, ``g`` → m/s²);
        the canonical name must then carry the SI suffix.
    only : collection of str, optional
        Header fields (as written in the file) to read; the others are skipped unchecked (the
        text and bookkeeping fields of a ``rostopic echo -p`` export, :mod:`.csv_layouts`).
    delimiter : str
        The field separator: one character, or :data:`WHITESPACE` (runs of blanks).
    skip_rows : int
        Lines before the header (a vendor's preamble); they are not read.
    sample_rate_hz : float, optional
        With no time column: the sample rate, and the time of row k is k / `sample_rate_hz`.
    scales, offsets : mapping, optional
        Canonical column name → counts per unit and offset [counts]: the column's values become
        (raw − offset) / scale, in the column's unit, before the conversion to SI.
    names : sequence of str, optional
        For a file without a header line (imu_tk's): the name of each field; every line after
        the `skip_rows` is a data row.
    chunk_rows : int
        Rows parsed at a time (:func:`iter_imu_csv`); the result does not depend on it.

    Returns
    -------
    pandas.DataFrame
        Indexed by ``time_s`` [s]; ``df.attrs["units"]`` maps each column to its unit.

    Raises
    ------
    InvalidInputError
        For any defect the module docstring lists; the message names the file, the column and
        the row.
    UnitError
        An unknown unit in a header, or one of another dimension than the column's name.
    """
    chunks = list(iter_imu_csv(path, column_map=column_map, units=units, to_si=to_si, only=only,
                               delimiter=delimiter, skip_rows=skip_rows,
                               sample_rate_hz=sample_rate_hz, scales=scales, offsets=offsets,
                               names=names, chunk_rows=chunk_rows))
    return concat_chunks(chunks)


def concat_chunks(chunks: Sequence[pd.DataFrame]) -> pd.DataFrame:
    """Join the chunks of :func:`iter_imu_csv` into one frame (the first chunk's ``attrs``)."""
    if len(chunks) == 1:
        return chunks[0]
    import pandas as pd

    df = pd.concat(chunks)
    df.attrs = dict(chunks[0].attrs)
    return df


def iter_imu_csv(path: str | os.PathLike[str], *, column_map: Mapping[str, str] | None = None,
                 units: Mapping[str, str] | None = None, to_si: bool = True,
                 only: Collection[str] | None = None, delimiter: str = ",",
                 skip_rows: int = 0, sample_rate_hz: float | None = None,
                 scales: Mapping[str, float] | None = None,
                 offsets: Mapping[str, float] | None = None,
                 names: Collection[str] | None = None,
                 chunk_rows: int = DEFAULT_CHUNK_ROWS) -> Iterator[pd.DataFrame]:
    """Read a CSV file of IMU samples in chunks of at most `chunk_rows` rows.

    The parameters are those of :func:`read_imu_csv`, which joins these chunks. The file and
    header are checked before this returns; each chunk's rows are checked as it is read, with
    the checks of the module docstring: a defect names the data row and file line counted over
    the whole file, the time must not decrease across a chunk boundary either, its span is
    counted from the file's first time, and a sample-rate time base continues from chunk to
    chunk. Memory holds one chunk (and pandas' parser buffer) at a time.

    Yields
    ------
    pandas.DataFrame
        Consecutive rows, indexed by ``time_s`` [s]; ``df.attrs["units"]`` as
        :func:`read_imu_csv`.

    Raises
    ------
    InvalidInputError, UnitError
        As :func:`read_imu_csv`; a defect of the rows is raised when its chunk is read.
    """
    p = Path(path)
    if not (isinstance(skip_rows, int) and skip_rows >= 0):
        raise InvalidInputError(f"`skip_rows` must be an integer ≥ 0; got {skip_rows!r}")
    if delimiter != WHITESPACE and len(delimiter) != 1:
        raise InvalidInputError(f"`delimiter` must be one character or {WHITESPACE!r}; got "
                                f"{delimiter!r}")
    if sample_rate_hz is not None and not (np.isfinite(sample_rate_hz) and sample_rate_hz > 0):
        raise InvalidInputError(f"the sample rate must be a finite number > 0 Hz; got "
                                f"{sample_rate_hz}")
    if isinstance(chunk_rows, bool) or not isinstance(chunk_rows, int) or chunk_rows < 1:
        raise InvalidInputError(f"`chunk_rows` must be an integer ≥ 1; got {chunk_rows!r}")
    if names is None:
        hdr = skip_rows + 1
        headers = _read_header(p, skip_rows, delimiter)
    else:
        hdr = skip_rows
        _read_header(p, skip_rows, delimiter)  # the file checks (empty, binary, UTF-8)
        headers = list(names)
    canon, col_units = _columns(p, headers, column_map, units, only)
    if TIME_COLUMN not in canon and sample_rate_hz is None:
        found = [h.strip() for h in headers]
        raise InvalidInputError(
            f"{p}: no time column among the columns found {found}; name it with "
            f"`--time-column NAME` (or `column_map` to {TIME_COLUMN!r}), or give "
            "`--sample-rate-hz`; map the others with `--column-map gx=NAME,...` or an "
            "`--import` file (docs/import.md)")
    rows = _parse(p, len(canon), hdr, delimiter, names is None, chunk_rows)
    reader = _Chunks(p, canon, col_units, hdr, delimiter, to_si, sample_rate_hz, scales or {},
                     offsets or {}, chunk_rows)
    return reader.frames(rows)


class _Chunks:
    """The checks and conversions of each chunk, and what carries from one to the next."""

    def __init__(self, p: Path, canon: list[str | None], col_units: dict[str, str], hdr: int,
                 delimiter: str, to_si: bool, sample_rate_hz: float | None,
                 scales: Mapping[str, float], offsets: Mapping[str, float], chunk_rows: int
                 ) -> None:
        self.p, self.canon, self.col_units, self.hdr = p, canon, col_units, hdr
        self.delimiter, self.to_si, self.sample_rate_hz = delimiter, to_si, sample_rate_hz
        self.scales, self.offsets, self.chunk_rows = scales, offsets, chunk_rows
        self.row0 = 0  # data rows before the chunk
        self.last_t: float | None = None
        self.first_t: float | None = None

    def frames(self, rows: Iterator[pd.DataFrame]) -> Iterator[pd.DataFrame]:
        for raw in rows:
            if len(raw) == 0:
                continue
            yield self.frame(raw)
        if self.row0 == 0:
            raise InvalidInputError(f"{self.p}: no data rows after the header; expected at "
                                    "least one row of numbers")

    def frame(self, raw: pd.DataFrame) -> pd.DataFrame:
        import pandas as pd

        p, hdr, n = self.p, self.hdr, len(raw)
        whole = self.row0 == 0 and n < self.chunk_rows  # the chunk is the whole file
        scope = "" if whole else f" in the first {self.row0 + n} data rows"
        col_units = dict(self.col_units)
        data: dict[str, Any] = {}
        for pos, col in enumerate(self.canon):
            if col is None:
                continue
            values = _numeric(p, raw, pos, col, len(self.canon), hdr, self.delimiter,
                              self.row0).to_numpy()
            scale = self.scales.get(col)
            offset = self.offsets.get(col)
            if scale is not None or offset is not None:
                with np.errstate(over="ignore"):  # an overflow is refused below, column named
                    values = (values.astype(np.float64) - (offset or 0.0)) / (scale or 1.0)
            unit = col_units[col]
            factor = 1.0 if _key(unit) in _NO_FACTOR else parse_unit(unit)
            if self.to_si and factor != 1.0:
                si_unit = next((u for suffix, u in _SI_SUFFIXES.items() if col.endswith(suffix)),
                               None)
                if si_unit is None:
                    raise InvalidInputError(
                        f"{p}: column {col!r} is in {unit!r}; to convert it to SI give it a "
                        f"canonical SI name (ending in {list(_SI_SUFFIXES)}) with `column_map`")
                with np.errstate(over="ignore"):
                    values = values.astype(np.float64) * factor
                col_units[col] = si_unit
            _check_finite(p, col, values, hdr, self.row0, scope)
            _check_range(p, col, values, col_units[col], hdr, self.row0, scope)
            data[col] = values
        if TIME_COLUMN in data:
            t = np.asarray(data.pop(TIME_COLUMN), dtype=np.float64)
        else:
            with np.errstate(over="ignore"):  # a rate of 1e-320 Hz: refused below as too late
                t = (self.row0 + np.arange(n, dtype=np.float64)) / float(self.sample_rate_hz
                                                                         or 1.0)
        _check_time(p, t, hdr, row0=self.row0, before=self.last_t, first=self.first_t,
                    scope=scope)
        if self.first_t is None:
            self.first_t = float(t[0])
        self.last_t = float(t[-1])
        self.row0 += n
        df = pd.DataFrame(data, index=pd.Index(t, name=TIME_COLUMN))
        df.attrs["units"] = {c: col_units[c] for c in df.columns}
        return df
