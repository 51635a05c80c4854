"""How to read a real IMU log: the import specification and the one reader behind every command.

Contents
--------
:class:`ImportSpec`
    Which column is what, the units or counts-per-unit scale and offset, the time column or the
    sample rate, the delimiter and the rows before the header (docs/import.md, "Import
    specification").
:func:`load_import_spec`
    An :class:`ImportSpec` from a small TOML file (``--import spec.toml``).
:func:`read_imu_table`
    A log (one CSV/text file, or imu_tk's gyro and accelerometer files) → a DataFrame in SI
    indexed by ``time_s``, through :func:`~imucalib.io.csv_import.iter_imu_csv` (every check of
    that reader applies: the errors name the file, the column and the row).
:func:`iter_imu_table`
    The same log in chunks of at most ``chunk_rows`` rows, for logs larger than memory
    (docs/import.md, "Large files"); :func:`read_imu_table` joins these chunks.

Raw counts
----------
A ``gyro_unit`` (``accel_unit``) of ``counts`` says the columns hold raw counts; ``gyro_scale``
(``accel_scale``) is then required, in counts per °/s (per g), and the value is
(raw − offset) / scale. With a physical unit, a scale and offset may still be given: the value
is (raw − offset) / scale in that unit (e.g. ``gyro_unit = "rad/s"``, ``gyro_scale`` in counts
per rad/s).
"""

from __future__ import annotations

import math
import os
import tomllib
from collections.abc import Iterator
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from imucalib.conventions import ACCEL_COLUMNS, GYRO_COLUMNS, TIME_COLUMN
from imucalib.errors import InvalidInputError, UnitError
from imucalib.io.csv_import import (
    DEFAULT_CHUNK_ROWS,
    WHITESPACE,
    _read_header,
    concat_chunks,
    iter_imu_csv,
    named_unit,
    read_imu_csv,
)
from imucalib.io.csv_layouts import SHORT_NAMES, build_csv_mapping, normalize_column_map

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["COUNTS", "ImportSpec", "iter_imu_table", "load_import_spec", "read_imu_table"]

#: The unit of raw-count columns.
COUNTS = "counts"
#: The sample rates a log may be read at (``sample_rate_hz``): a sample every 1000 s to 1 MHz.
MIN_SAMPLE_RATE_HZ = 1e-3
MAX_SAMPLE_RATE_HZ = 1e6
#: The unit a counts-per-unit scale refers to when the column is in counts.
_COUNTS_BASE = {"gyro": "deg/s", "accel": "g"}


@dataclass(frozen=True)
class ImportSpec:
    r"""How to read one IMU log (module docstring; every field optional).

    Attributes
    ----------
    column_map : dict of str to str
        ``vendor=canonical`` or ``short=vendor`` items
        (:func:`~imucalib.io.csv_layouts.normalize_column_map`), e.g. ``{"gx": "GyroX"}``.
    units : dict of str to str
        Unit of single columns (canonical or short name → unit).
    gyro_unit, accel_unit : str, optional
        Unit of every gyro / accelerometer column: a unit (``deg/s``, ``rad/s``, ``g``,
        ``m/s^2`` …) or ``counts``.
    gyro_scale, accel_scale : float, optional
        Counts per unit (per °/s, per g for ``counts``).
    gyro_offset, accel_offset : float, optional
        Offset subtracted before the scale. [counts]
    time_column : str, optional
        The file's time column.
    time_unit : str, optional
        Its unit (``s``, ``ms``, ``us``, ``ns``).
    sample_rate_hz : float, optional
        The sample rate: the time of row k is k / rate when there is no time column; a time
        column present is then read as a sample counter.
    delimiter : str
        ``","``, ``";"``, ``"\t"``, ``"whitespace"`` … (default ``","``).
    skip_rows : int
        Lines before the header (a vendor's preamble).
    accel_file : Path, optional
        imu_tk's accelerometer file; the log given is then imu_tk's gyro file.
    """

    column_map: dict[str, str] = field(default_factory=dict)
    units: dict[str, str] = field(default_factory=dict)
    gyro_unit: str | None = None
    accel_unit: str | None = None
    gyro_scale: float | None = None
    accel_scale: float | None = None
    gyro_offset: float | None = None
    accel_offset: float | None = None
    time_column: str | None = None
    time_unit: str | None = None
    sample_rate_hz: float | None = None
    delimiter: str = ","
    skip_rows: int = 0
    accel_file: Path | None = None

    def merged(self, **overrides: Any) -> ImportSpec:
        """Return a copy with every override that is not None (the command line over a file).

        The column maps and units are merged item by item.
        """
        given = {k: v for k, v in overrides.items() if v is not None}
        for key in ("column_map", "units"):
            if key in given:
                given[key] = {**getattr(self, key), **given[key]}
        return replace(self, **given)


_FIELDS = {f.name for f in fields(ImportSpec)}
_FLOATS = ("gyro_scale", "accel_scale", "gyro_offset", "accel_offset", "sample_rate_hz")
_STRINGS = ("gyro_unit", "accel_unit", "time_column", "time_unit", "delimiter")


def load_import_spec(path: str | os.PathLike[str]) -> ImportSpec:
    """Read an import specification (TOML; docs/import.md, "Import specification").

    The keys are the fields of :class:`ImportSpec`; the column map may be written as a table
    ``[columns]`` (or ``column_map``) and the units as ``[units]``. A relative ``accel_file``
    is taken relative to the TOML file.

    Raises
    ------
    InvalidInputError
        The file cannot be read or parsed, a key is unknown, or a value has the wrong type.
    """
    p = Path(path)
    try:
        doc = tomllib.loads(p.read_text(encoding="utf-8"))
    except OSError as exc:
        raise InvalidInputError(f"cannot read the import file {p}: {exc.strerror or exc}") from exc
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise InvalidInputError(f"{p}: not a TOML import file: {exc}") from exc
    for key in ("columns", "column_map", "units"):
        if key in doc and not isinstance(doc[key], dict):
            raise InvalidInputError(f"{p}: `{key}` must be a table of names to strings (e.g. "
                                    f"`[{key}]` with `gx = \"GyroX\"`); got {_shown(doc[key])}")
    if "columns" in doc:
        doc["column_map"] = {**doc.pop("columns"), **doc.get("column_map", {})}
    unknown = sorted(set(doc) - _FIELDS)
    if unknown:
        raise InvalidInputError(f"{p}: unknown key(s) {unknown}; expected {sorted(_FIELDS)} "
                                "(and [columns])")
    out: dict[str, Any] = {}
    for key, value in doc.items():
        if key in ("column_map", "units"):
            if not (isinstance(value, dict) and all(isinstance(v, str) for v in value.values())):
                raise InvalidInputError(f"{p}: `{key}` must be a table of names to strings; got "
                                        f"{_shown(value)}")
            out[key] = dict(value)
        elif key in _FLOATS:
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise InvalidInputError(f"{p}: `{key}` must be a number; got {_shown(value)}")
            out[key] = float(value)
        elif key in _STRINGS:
            if not isinstance(value, str):
                raise InvalidInputError(f"{p}: `{key}` must be a string; got {_shown(value)}")
            out[key] = value
        elif key == "skip_rows":
            if isinstance(value, bool) or not isinstance(value, int) or value < 0:
                raise InvalidInputError(f"{p}: `skip_rows` must be an integer ≥ 0; got "
                                        f"{_shown(value)}")
            out[key] = value
        elif key == "accel_file":
            if not isinstance(value, str):
                raise InvalidInputError(f"{p}: `accel_file` must be a path; got {_shown(value)}")
            out[key] = p.parent / value
    return ImportSpec(**out)


def _shown(value: Any, limit: int = 60) -> str:
    """`value` as written in a message, cut at `limit` characters."""
    text = repr(value)
    return text if len(text) <= limit else text[:limit] + "…"


#: Characters that may not separate fields: they occur in numbers, or end a line or quote one.
_NOT_DELIMITERS = frozenset("0123456789.+-eE\"\r\n")


def check_delimiter(delimiter: object, option: str = "`delimiter`") -> str:
    """Return the field separator a spec's `delimiter` names (``"tab"`` → a tab).

    Raises
    ------
    InvalidInputError
        Not one character, ``"tab"`` or ``"whitespace"``, or a character of numbers.
    """
    if delimiter in ("\\t", "tab"):
        return "\t"
    if delimiter == WHITESPACE:
        return WHITESPACE
    if not isinstance(delimiter, str) or len(delimiter) != 1:
        raise InvalidInputError(f"{option} must be one character, 'tab' or {WHITESPACE!r}; got "
                                f"{_shown(delimiter)}")
    if delimiter in _NOT_DELIMITERS or delimiter.isalnum():
        raise InvalidInputError(f"{option} {delimiter!r} cannot separate fields (it occurs in "
                                "numbers or ends a line); expected ',', ';', 'tab', '|', ' ' or "
                                f"{WHITESPACE!r}")
    return delimiter


def _check_spec(spec: ImportSpec) -> None:
    for key in _FLOATS:
        value = getattr(spec, key)
        if value is not None and not math.isfinite(value):
            raise InvalidInputError(f"`{key}` must be finite; got {value}")
    for key in ("gyro_scale", "accel_scale", "sample_rate_hz"):
        value = getattr(spec, key)
        if value is not None and not value > 0:
            raise InvalidInputError(f"`{key}` must be > 0; got {value}")
    rate = spec.sample_rate_hz
    if rate is not None and not MIN_SAMPLE_RATE_HZ <= rate <= MAX_SAMPLE_RATE_HZ:
        raise InvalidInputError(f"`sample_rate_hz` must be between {MIN_SAMPLE_RATE_HZ:g} and "
                                f"{MAX_SAMPLE_RATE_HZ:g} Hz (an IMU's output rate); got {rate:g}")
    for kind in ("gyro", "accel"):
        if getattr(spec, f"{kind}_unit") == COUNTS and getattr(spec, f"{kind}_scale") is None:
            raise InvalidInputError(
                f"`{kind}_unit` is counts: give `--{kind}-scale`, the counts per "
                f"{_COUNTS_BASE[kind]} (the datasheet's sensitivity)")


def _unit(spec: ImportSpec, kind: str) -> str | None:
    unit: str | None = getattr(spec, f"{kind}_unit")
    return _COUNTS_BASE[kind] if unit == COUNTS else unit


def _scaling(spec: ImportSpec) -> tuple[dict[str, float], dict[str, float]]:
    scales: dict[str, float] = {}
    offsets: dict[str, float] = {}
    for kind, cols in (("gyro", GYRO_COLUMNS), ("accel", ACCEL_COLUMNS)):
        scale, offset = getattr(spec, f"{kind}_scale"), getattr(spec, f"{kind}_offset")
        for c in cols:
            if scale is not None:
                scales[c] = scale
            if offset is not None:
                offsets[c] = offset
    return scales, offsets


def _headerless(headers: list[str]) -> bool:
    try:
        [float(h) for h in headers]
    except ValueError:
        return False
    return True


def read_imu_table(path: str | os.PathLike[str], spec: ImportSpec | None = None, *,
                   chunk_rows: int = DEFAULT_CHUNK_ROWS) -> pd.DataFrame:
    """Read an IMU log into SI through its layout and `spec`: :func:`iter_imu_table`, joined.

    Parameters
    ----------
    path : str or Path
        The log: a CSV or text file with a header (its layout detected:
        :func:`~imucalib.io.csv_layouts.detect_layout`), or, with ``spec.accel_file`` or a
        first line of four numbers, imu_tk's gyro file (``time x y z`` rows).
    spec : ImportSpec, optional
        How to read it (default: the layout's own names and units).
    chunk_rows : int
        Rows parsed at a time; the result does not depend on it.

    Returns
    -------
    pandas.DataFrame
        Indexed by ``time_s`` [s], the columns in SI with canonical names;
        ``df.attrs["units"]`` and ``df.attrs["layout"]``.

    Raises
    ------
    InvalidInputError
        Any defect of the file (naming the column and row), of the spec, or an unknown unit
        (:class:`~imucalib.errors.UnitError`).
    """
    return concat_chunks(list(iter_imu_table(path, spec, chunk_rows=chunk_rows)))


def iter_imu_table(path: str | os.PathLike[str], spec: ImportSpec | None = None, *,
                   chunk_rows: int = DEFAULT_CHUNK_ROWS) -> Iterator[pd.DataFrame]:
    """Read an IMU log into SI in chunks of at most `chunk_rows` rows (bounded memory).

    The chunks joined are :func:`read_imu_table`'s frame, and each is checked as
    :func:`~imucalib.io.csv_import.iter_imu_csv` checks it: a defect names the column and the
    data row and line over the whole file, the time must not decrease across chunk boundaries,
    a sample-rate time base (or a sample counter read as time) continues from chunk to chunk,
    and a counts scale and offset apply to every chunk. The spec and the header are checked
    before this returns. imu_tk's two files (``spec.accel_file``), whose accelerometer may be
    interpolated at the gyro's times, are read whole and yielded as one chunk.

    Parameters
    ----------
    path, spec
        As :func:`read_imu_table`.
    chunk_rows : int
        Most rows per chunk (≥ 1).

    Yields
    ------
    pandas.DataFrame
        Consecutive rows, indexed by ``time_s`` [s]; ``df.attrs["units"]`` and
        ``df.attrs["layout"]``.

    Raises
    ------
    InvalidInputError
        As :func:`read_imu_table`; a defect of the rows is raised when its chunk is read.
    """
    spec = spec or ImportSpec()
    _check_spec(spec)
    p = Path(path)
    delimiter = check_delimiter(spec.delimiter, "--delimiter")
    headers = _read_header(p, spec.skip_rows, delimiter)
    if spec.accel_file is not None or (_headerless(headers) and len(headers) == 4
                                       and not spec.column_map):
        if isinstance(chunk_rows, bool) or not isinstance(chunk_rows, int) or chunk_rows < 1:
            raise InvalidInputError(f"`chunk_rows` must be an integer ≥ 1; got {chunk_rows!r}")
        return iter((_read_imu_tk(p, spec),))
    units = {SHORT_NAMES.get(k, k): v for k, v in spec.units.items()}
    user_map = normalize_column_map(spec.column_map)
    mapping = build_csv_mapping(headers, column_map=user_map,
                                units=units, gyro_unit=_unit(spec, "gyro"),
                                accel_unit=_unit(spec, "accel"), time_column=spec.time_column,
                                time_unit=spec.time_unit)
    only = mapping.only
    if only is None and mapping.column_map:  # read the mapped columns and the canonical ones
        canonical = {TIME_COLUMN, *GYRO_COLUMNS, *ACCEL_COLUMNS}
        only = tuple(h.strip() for h in headers
                     if h.strip() in mapping.column_map or h.strip() in canonical)
    scales, offsets = _scaling(spec)
    names = {mapping.column_map.get(h.strip(), h.strip()) for h in headers}
    counter = TIME_COLUMN in names and spec.sample_rate_hz is not None
    chunks = iter_imu_csv(p, column_map=mapping.column_map, units=mapping.units, only=only,
                          delimiter=delimiter, skip_rows=spec.skip_rows,
                          sample_rate_hz=spec.sample_rate_hz, scales=scales, offsets=offsets,
                          chunk_rows=chunk_rows)
    present = {h.strip() for h in headers}
    _check_mapped_units(p, {k: v for k, v in user_map.items() if k.strip() in present},
                        mapping.units)
    return _tagged(chunks, mapping.layout, spec.sample_rate_hz if counter else None)


def _check_mapped_units(p: Path, user_map: dict[str, str], known: dict[str, str]) -> None:
    """Refuse gyro or accelerometer columns a column map renames without saying their unit.

    A column renamed to ``gyro_x_rps`` is not thereby in rad/s: its unit must come from
    ``gyro_unit``/``accel_unit``, ``units``, the layout, or the column's own name
    (``AccX [g]``, ``gyr_x_dps``: :func:`~imucalib.io.csv_import.named_unit`).

    Raises
    ------
    UnitError
        Naming the columns and the option that gives their unit.
    """
    for kind, cols, option, example in (
            ("gyro", GYRO_COLUMNS, "--gyro-unit deg/s|rad/s|deg/h|counts", "gx=deg/s"),
            ("accelerometer", ACCEL_COLUMNS, "--accel-unit g|m/s^2|mg|counts", "ax=g")):
        bare = [vendor for vendor, canonical in user_map.items()
                if canonical in cols and canonical not in known and vendor.strip() != canonical
                and named_unit(vendor) is None]
        if bare:
            raise UnitError(
                f"{p}: the {kind} column(s) {bare} are mapped by the column map without a unit, "
                f"and their names carry none; give it with `{option}` (or `--units {example}`, "
                "`units` in the --import file, or a name such as `GyrX [deg/s]`)")


def _tagged(chunks: Iterator[pd.DataFrame], layout: str, counter_rate_hz: float | None
            ) -> Iterator[pd.DataFrame]:
    """Tag each chunk with its layout; make a sample-counter time column seconds.

    The counter is counted from the file's first count, at `counter_rate_hz`.
    """
    import pandas as pd

    first: float | None = None
    for df in chunks:
        if counter_rate_hz is not None:  # the time column is a sample counter
            t = np.asarray(df.index, dtype=np.float64)
            first = float(t[0]) if first is None else first
            df.index = pd.Index((t - first) / counter_rate_hz, name=TIME_COLUMN)
        df.attrs["layout"] = layout
        yield df


def _read_imu_tk(gyro_path: Path, spec: ImportSpec) -> pd.DataFrame:
    """imu_tk's two files: ``time x y z`` rows, blank-separated, no header."""
    import pandas as pd

    delimiter = (WHITESPACE if spec.delimiter == "," else
                 check_delimiter(spec.delimiter, "--delimiter"))
    scales, offsets = _scaling(spec)
    time_unit = spec.time_unit or "s"

    def one(path: Path, cols: tuple[str, ...], unit: str) -> pd.DataFrame:
        return read_imu_csv(path, names=(TIME_COLUMN, *cols),
                            units={TIME_COLUMN: time_unit, **dict.fromkeys(cols, unit)},
                            delimiter=delimiter, skip_rows=spec.skip_rows,
                            scales=scales, offsets=offsets)

    gyro = one(gyro_path, GYRO_COLUMNS, _unit(spec, "gyro") or "rad/s")
    if spec.accel_file is not None:
        accel = one(Path(spec.accel_file), ACCEL_COLUMNS, _unit(spec, "accel") or "m/s^2")
        tg = np.asarray(gyro.index, dtype=np.float64)
        ta = np.asarray(accel.index, dtype=np.float64)
        if ta.size == tg.size and np.allclose(ta, tg, rtol=0.0, atol=1e-9 * max(1.0, abs(tg[0]))):
            for c in ACCEL_COLUMNS:
                gyro[c] = accel[c].to_numpy()
        else:  # different time bases: the accelerometer interpolated at the gyro's times
            inside = (tg >= ta[0]) & (tg <= ta[-1])
            if inside.sum() < 2:
                raise InvalidInputError(
                    f"{gyro_path} and {spec.accel_file}: the gyro times ({tg[0]:.6g} … "
                    f"{tg[-1]:.6g} s) and the accelerometer times ({ta[0]:.6g} … {ta[-1]:.6g} s) "
                    "do not overlap")
            gyro = gyro.loc[inside].copy()
            for c in ACCEL_COLUMNS:
                gyro[c] = np.interp(tg[inside], ta, accel[c].to_numpy())
        gyro.attrs["units"] = {**gyro.attrs.get("units", {}), **accel.attrs.get("units", {})}
    if spec.sample_rate_hz is not None:
        t = np.asarray(gyro.index, dtype=np.float64)
        gyro.index = pd.Index((t - t[0]) / spec.sample_rate_hz, name=TIME_COLUMN)
    gyro.attrs["layout"] = "imu_tk"
    return gyro

