"""Layout constants, column/stream specifications and validators of the Recording format (private).

The format itself is documented in :mod:`imucalib.io.recording` and ``docs/recording-format.md``.
Everything the writer, the reader and recovery must agree on lives here, once.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Final

import h5py
import numpy as np
from numpy.typing import NDArray

from imucalib.conventions import TIME_COLUMN
from imucalib.errors import InvalidInputError, UnitError
from imucalib.units import parse_unit

__all__ = [
    "COMMIT_GROUP",
    "DEFAULT_CHUNK_ROWS",
    "EXTRA_UNITS",
    "FORMAT_NAME",
    "FORMAT_VERSION",
    "FORMAT_VERSION_PLAIN",
    "LOG_CHUNK_ROWS",
    "LOG_FIELDS",
    "LOG_GROUP",
    "LOG_LEVELS",
    "QUANTITIES",
    "RESERVED_METADATA",
    "STEPS_CHUNK_ROWS",
    "STEPS_GROUP",
    "STEP_FIELDS",
    "STEP_FIELDS_V1",
    "STEP_STATUSES",
    "STREAMS_GROUP",
    "TRUTH_GROUP",
    "TRUTH_STREAMS_GROUP",
    "ColumnSpec",
    "FieldSpec",
    "StreamSpec",
    "check_unit",
    "column_json",
    "decode_attr",
    "decode_counts",
    "dtype_code",
    "encode_counts",
    "encode_text",
    "json_dumps",
    "parse_string_list",
    "step_fields",
    "string_list_json",
]

FORMAT_NAME: Final = "imucalib-recording"
#: Version 2 added the step fields ``role``, ``tags`` and ``units``; version 3 added integer
#: columns with a ``scale`` (counts read as ``counts × scale`` in float64) and Blosc-compressed
#: columns. Files of versions 1 and 2 still read; a writer stamps 2 when it uses neither.
FORMAT_VERSION: Final = 3
#: The version of a file without scaled columns or plugin filters.
FORMAT_VERSION_PLAIN: Final = 2

#: Rows per chunk of a stream column: 64 Ki rows = 512 KiB of float64.
DEFAULT_CHUNK_ROWS: Final = 1 << 16
STEPS_CHUNK_ROWS: Final = 64
LOG_CHUNK_ROWS: Final = 256

STREAMS_GROUP: Final = "streams"
STEPS_GROUP: Final = "steps"
LOG_GROUP: Final = "log"
TRUTH_GROUP: Final = "truth"
TRUTH_STREAMS_GROUP: Final = "truth/streams"
COMMIT_GROUP: Final = "commit"

RESERVED_METADATA: Final = frozenset(
    {"format", "format_version", "created_utc", "software_version",
     "recovered_from", "recovered_utc"}
)
QUANTITIES: Final = ("si", "raw")
STEP_STATUSES: Final = ("pending", "running", "done", "invalid", "skipped", "aborted", "failed")
LOG_LEVELS: Final = ("debug", "info", "warning", "error", "critical")

#: Units accepted in addition to those :func:`imucalib.units.parse_unit` knows (which carry an SI
#: factor); these are quantities without a multiplicative SI conversion or beyond the motion units.
EXTRA_UNITS: Final = frozenset(
    {"degC", "°C", "K", "rad/s^2", "deg/s^2", "Pa", "hPa", "%RH", "V", "mV", "A", "mA", "W",
     "N", "kg", "bool"}
)

_NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.\-]{0,63}$")
_COLUMN_RE = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,62}$")
_KEY_RE = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,127}$")
_DTYPE_KINDS = "biuf"


@dataclass(frozen=True)
class FieldSpec:
    """One field of the ``/steps`` or ``/log`` table: float64, int64 or fixed-length UTF-8 text."""

    kind: str  # "f8", "i8" or "text"
    max_bytes: int = 0  # text only: capacity in UTF-8 bytes

    @property
    def dtype(self) -> np.dtype[Any]:
        """The HDF5/numpy dtype of the dataset."""
        if self.kind == "text":
            return h5py.string_dtype("utf-8", self.max_bytes)
        return np.dtype(self.kind)


#: The ``/steps`` fields of format version 1.
STEP_FIELDS_V1: Final[dict[str, FieldSpec]] = {
    "index": FieldSpec("i8"),
    "kind": FieldSpec("text", 64),
    "label": FieldSpec("text", 256),
    "commanded": FieldSpec("text", 8192),
    "t_start_s": FieldSpec("f8"),
    "t_end_s": FieldSpec("f8"),
    "valid_start_s": FieldSpec("f8"),
    "valid_end_s": FieldSpec("f8"),
    "status": FieldSpec("text", 32),
    "note": FieldSpec("text", 2048),
}

#: The ``/steps`` fields of the current format (version 2): version 1's, then
#: ``role`` (what the step is for in its procedure, e.g. ``"p1.accel-position"``; 128 characters
#: of any UTF-8), ``tags`` (a JSON list of strings) and ``units`` (a JSON list of the IMU unit
#: names the step concerns; ``[]`` for every IMU of the file).
STEP_FIELDS: Final[dict[str, FieldSpec]] = {
    **STEP_FIELDS_V1,
    "role": FieldSpec("text", 512),
    "tags": FieldSpec("text", 4096),
    "units": FieldSpec("text", 2048),
}


def step_fields(format_version: int) -> dict[str, FieldSpec]:
    """Return the ``/steps`` fields of a format version (1, or 2 and later)."""
    return STEP_FIELDS_V1 if format_version < 2 else STEP_FIELDS

LOG_FIELDS: Final[dict[str, FieldSpec]] = {
    "time_s": FieldSpec("f8"),
    "level": FieldSpec("text", 16),
    "source": FieldSpec("text", 128),
    "message": FieldSpec("text", 4096),
}


def check_name(value: object, what: str, pattern: re.Pattern[str] = _NAME_RE) -> str:
    """Return `value` if it is a valid device, unit, column or key name."""
    if not isinstance(value, str) or not pattern.match(value) or value in {".", ".."}:
        raise InvalidInputError(
            f"{what} must match {pattern.pattern} (letters, digits, '_', and for device/unit "
            f"names also '.' and '-'); got {value!r}"
        )
    return value


def check_column_name(value: object, what: str) -> str:
    """Return `value` if it is a valid column name (an identifier usable in MATLAB too)."""
    return check_name(value, what, _COLUMN_RE)


def check_key(value: object, what: str) -> str:
    """Return `value` if it is a valid metadata or truth key."""
    return check_name(value, what, _KEY_RE)


def check_unit(unit: object, where: str) -> str:
    """Return `unit` if it is a known unit string, else raise :class:`UnitError` naming `where`."""
    if not isinstance(unit, str) or not unit.strip():
        raise UnitError(f"{where}: unit must be a non-empty string (use '1' for dimensionless); "
                        f"got {unit!r}")
    if unit in EXTRA_UNITS:
        return unit
    try:
        parse_unit(unit)
    except UnitError as exc:
        raise UnitError(f"{where}: unknown unit {unit!r}; expected a unit that "
                        f"imucalib.units.parse_unit accepts or one of {sorted(EXTRA_UNITS)}"
                        ) from exc
    return unit


@dataclass(frozen=True)
class ColumnSpec:
    """Declaration of one column of a stream.

    Parameters
    ----------
    unit : str
        Unit string, e.g. ``"rad/s"``, ``"m/s^2"``, ``"s"``, ``"degC"``, ``"counts"``, ``"1"``.
        Checked by :class:`StreamSpec` against :func:`imucalib.units.parse_unit` and
        :data:`EXTRA_UNITS`.
    dtype : str
        Numpy dtype of the stored values (``"f8"``, ``"f4"``, ``"i8"``, ``"u4"``, ``"b1"``, …).
    quantity : {"si", "raw"}
        Whether the values are in SI (calibrated physical units) or raw device output.
    description : str
        Free text stored with the column.
    scale : float, optional
        For an integer `dtype` only: the column stores integer counts of `scale` (the LSB, in
        `unit`), and readers return ``counts × scale`` as float64. The writer is given the
        float64 values and refuses any that is not exactly ``k × scale`` for an integer ``k``
        of `dtype` (:func:`encode_counts`), so the round trip returns the very values written.
    """

    unit: str
    dtype: str = "f8"
    quantity: str = "si"
    description: str = ""
    scale: float | None = None

    @property
    def value_dtype(self) -> np.dtype[Any]:
        """The dtype of the values written and read: float64 for a scaled column."""
        return np.dtype("f8") if self.scale is not None else np.dtype(self.dtype)


def dtype_code(dt: np.dtype[Any]) -> str:
    """Short dtype code without byte order: ``"f8"``, ``"i4"``, ``"u2"``, ``"b1"``."""
    return f"{dt.kind}{dt.itemsize}"


def _check_column(spec: object, where: str) -> ColumnSpec:
    if not isinstance(spec, ColumnSpec):
        raise InvalidInputError(f"{where}: expected a ColumnSpec; got {type(spec).__name__}")
    check_unit(spec.unit, where)
    try:
        dt = np.dtype(spec.dtype)
    except TypeError as exc:
        raise InvalidInputError(f"{where}: unknown dtype {spec.dtype!r}") from exc
    if dt.kind not in _DTYPE_KINDS:
        raise InvalidInputError(f"{where}: dtype must be numeric or bool; got {spec.dtype!r}")
    if spec.quantity not in QUANTITIES:
        raise InvalidInputError(f"{where}: quantity must be one of {QUANTITIES}; "
                                f"got {spec.quantity!r}")
    encode_text(spec.description, f"{where} description")
    scale = check_scale(spec.scale, dt, where)
    return ColumnSpec(unit=spec.unit, dtype=dtype_code(dt), quantity=spec.quantity,
                      description=spec.description, scale=scale)


def check_scale(scale: object, dt: np.dtype[Any], where: str) -> float | None:
    """Return a column's scale as a float (None stays None), or raise InvalidInputError.

    A scale must be a positive, finite number and needs an integer dtype (``i`` or ``u``).
    """
    if scale is None:
        return None
    if isinstance(scale, bool) or not isinstance(scale, int | float | np.floating | np.integer):
        raise InvalidInputError(f"{where}: scale must be a number (the LSB) or None; "
                                f"got {scale!r}")
    value = float(scale)
    if not (math.isfinite(value) and value > 0):
        raise InvalidInputError(f"{where}: scale must be positive and finite; got {value!r}")
    if dt.kind not in "iu":
        raise InvalidInputError(f"{where}: a scale needs an integer dtype (counts); got "
                                f"{dtype_code(dt)}")
    return value


def column_json(name: str, spec: ColumnSpec) -> dict[str, Any]:
    """Return the ``columns_json`` item of a column (``scale`` only when it has one)."""
    item: dict[str, Any] = {"name": name, "unit": spec.unit, "dtype": spec.dtype,
                            "quantity": spec.quantity, "description": spec.description}
    if spec.scale is not None:
        item["scale"] = spec.scale
    return item


def encode_counts(values: Any, spec: ColumnSpec, where: str) -> NDArray[Any]:
    """Return the integer counts of a scaled column's float values, refusing any off the grid.

    Parameters
    ----------
    values : array_like
        The values in the column's unit (float64 after conversion).
    spec : ColumnSpec
        The column, with ``scale`` set and an integer dtype.
    where : str
        What is written, for messages.

    Returns
    -------
    ndarray
        ``rint(values / scale)`` in the column's dtype; ``counts × scale`` (in float64)
        reproduces every value (``-0.0`` reads back as ``0.0``, which compares equal).

    Raises
    ------
    InvalidInputError
        If a value is NaN or infinite, is not exactly an integer multiple of the scale, or its
        count does not fit the dtype; the message names the first such row.
    """
    assert spec.scale is not None
    v = as_column(values, np.dtype("f8"), where)
    dt = np.dtype(spec.dtype)
    with np.errstate(invalid="ignore", over="ignore"):
        k = np.rint(v / spec.scale)
        info = np.iinfo(dt)
        ok = (k * spec.scale == v) & (k >= info.min) & (k <= info.max)
    if not ok.all():
        i = int(np.argmin(ok))
        raise InvalidInputError(
            f"{where} stores integer counts of {spec.scale!r} {spec.unit} in {spec.dtype}; row "
            f"{i} of this append is {float(v[i])!r}, not such a multiple (or not finite, or out of "
            f"the {spec.dtype} range {info.min}…{info.max}); declare the column without a scale "
            "(float64) for values that are not the device's counts")
    return k.astype(dt)


def decode_counts(counts: NDArray[Any], scale: float | None) -> NDArray[Any]:
    """Return a column's values as read: ``counts × scale`` in float64, or `counts` unscaled."""
    if scale is None:
        return counts
    # one pass: each count converted to float64 (exact below 2^53), then the rounded product
    return np.multiply(counts, scale, dtype=np.float64)


@dataclass(frozen=True)
class StreamSpec:
    """Declaration of one stream, ``/streams/<device>/<unit>/``.

    Parameters
    ----------
    device : str
        Device kind, e.g. ``"imu"``, ``"table"``, ``"chamber"``, ``"centrifuge"``.
    unit : str
        Name of the physical unit, e.g. the serial ``"IMU-0001"`` or ``"main"``.
    columns : mapping of str to ColumnSpec
        The data columns. ``time_s`` (float64, ``"s"``) is added first when not given; when
        given it must be exactly that.

    Raises
    ------
    InvalidInputError
        For a bad name, dtype or quantity, naming the stream and column.
    UnitError
        For an unknown unit, naming the stream and column.
    """

    device: str
    unit: str
    columns: Mapping[str, ColumnSpec] = field(default_factory=dict)

    def __post_init__(self) -> None:
        check_name(self.device, "stream device")
        check_name(self.unit, f"unit name of stream {self.device!r}")
        if not isinstance(self.columns, Mapping):
            raise InvalidInputError(f"stream {self.name}: columns must be a mapping of name to "
                                    f"ColumnSpec; got {type(self.columns).__name__}")
        time_spec = ColumnSpec(unit="s", dtype="f8")
        cols: dict[str, ColumnSpec] = {TIME_COLUMN: time_spec}
        for name, spec in self.columns.items():
            where = f"stream {self.name}, column {name!r}"
            check_column_name(name, f"{where}: name")
            checked = _check_column(spec, where)
            if name == TIME_COLUMN:
                if (checked.unit, np.dtype(checked.dtype)) != ("s", np.dtype("f8")):
                    raise InvalidInputError(f"{where}: time_s must be float64 in 's'; got "
                                            f"{checked.dtype!r} in {checked.unit!r}")
                checked = ColumnSpec(unit="s", dtype="f8", description=checked.description)
            cols[name] = checked
        object.__setattr__(self, "columns", cols)

    @property
    def name(self) -> str:
        """``"<device>/<unit>"``."""
        return f"{self.device}/{self.unit}"


def encode_text(value: object, where: str, max_bytes: int | None = None) -> bytes:
    """UTF-8 encode a string field, refusing NUL characters and anything over `max_bytes`."""
    if not isinstance(value, str):
        raise InvalidInputError(f"{where} must be a string; got {type(value).__name__}")
    if "\x00" in value:
        raise InvalidInputError(f"{where} must not contain NUL characters")
    raw = value.encode("utf-8")
    if max_bytes is not None and len(raw) > max_bytes:
        raise InvalidInputError(f"{where} is {len(raw)} bytes in UTF-8; the field holds at most "
                                f"{max_bytes} (nothing is truncated: shorten it)")
    return raw


def decode_text(raw: bytes | str) -> str:
    """Decode a fixed-length UTF-8 field (trailing NUL padding already stripped by numpy)."""
    return raw if isinstance(raw, str) else raw.decode("utf-8", errors="replace")


def decode_attr(value: Any) -> Any:
    """Turn an h5py attribute value into a plain Python value."""
    if isinstance(value, bytes):
        return value.decode("utf-8", errors="replace")
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return [decode_attr(v) for v in value.tolist()] if value.dtype.kind in "OS" else value
    return value


def string_list_json(values: object, where: str, *, names: bool = False) -> str:
    """JSON text of a list of strings (UTF-8, not escaped), for the step fields ``tags``/``units``.

    Parameters
    ----------
    values : sequence of str
        The strings; a single ``str`` is refused (it is almost always a forgotten tuple).
    where : str
        What is checked, for messages.
    names : bool
        Each string must also be a valid unit name (:func:`check_name`).

    Raises
    ------
    InvalidInputError
        For a non-sequence, a non-string item, NUL characters or (with `names`) a bad name.
    """
    if isinstance(values, str | bytes) or not isinstance(values, Sequence):
        raise InvalidInputError(f"{where} must be a sequence of strings (e.g. a tuple); "
                                f"got {type(values).__name__} {values!r}")
    items = list(values)
    for k, item in enumerate(items):
        if not isinstance(item, str):
            raise InvalidInputError(f"{where}[{k}] must be a string; got {type(item).__name__}")
        encode_text(item, f"{where}[{k}]")
        if names:
            check_name(item, f"{where}[{k}]")
    return json.dumps(items, ensure_ascii=False) if items else "[]"


def parse_string_list(text: str) -> tuple[str, ...]:
    """Decode the JSON list of strings of a ``tags`` or ``units`` field (``""`` reads as empty).

    Raises
    ------
    ValueError
        If `text` is neither empty nor a JSON list of strings.
    """
    if not text:
        return ()
    value = json.loads(text)
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise ValueError("not a JSON list of strings")
    return tuple(value)


def _json_default(obj: Any) -> Any:
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    raise TypeError(f"cannot store a {type(obj).__name__} as JSON")


def json_dumps(value: Any, where: str) -> str:
    """JSON text of `value` (numpy arrays and scalars allowed), or an InvalidInputError."""
    try:
        return json.dumps(value, default=_json_default, allow_nan=True)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"{where}: cannot be stored as JSON ({exc}); use numbers, strings, "
                                "lists, dicts or numpy arrays") from exc


def check_metadata(metadata: Mapping[str, Any]) -> dict[str, str | int | float | bool]:
    """Validate root metadata: identifier keys; str/int/float/bool values; ``*_json`` is JSON."""
    if not isinstance(metadata, Mapping):
        raise InvalidInputError(f"`metadata` must be a mapping; got {type(metadata).__name__}")
    out: dict[str, str | int | float | bool] = {}
    for key, value in metadata.items():
        check_key(key, "metadata key")
        if key in RESERVED_METADATA:
            raise InvalidInputError(f"metadata key {key!r} is reserved (written by imucalib)")
        where = f"metadata[{key!r}]"
        if isinstance(value, np.generic):
            value = value.item()
        if key.endswith("_json") and not isinstance(value, str):
            raise InvalidInputError(f"{where} must be JSON text (a str); "
                                    f"got {type(value).__name__}")
        if isinstance(value, bool | float):
            out[key] = value
        elif isinstance(value, int):
            if not -(2**63) <= value < 2**63:
                raise InvalidInputError(f"{where} must fit in 64 bits; got {value}")
            out[key] = value
        elif isinstance(value, str):
            encode_text(value, where)
            if key.endswith("_json"):
                try:
                    json.loads(value)
                except ValueError as exc:
                    raise InvalidInputError(f"{where} must hold JSON text ({exc})") from exc
            out[key] = value
        else:
            raise InvalidInputError(f"{where} must be str, int, float or bool; got "
                                    f"{type(value).__name__}")
    return out


def as_column(values: Any, dtype: np.dtype[Any], where: str) -> NDArray[Any]:
    """Return a 1-D copy of `values` in `dtype`, refusing lossy integer conversions."""
    try:
        arr = np.asarray(values)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"{where} must be array-like; got {type(values).__name__}") from exc
    if arr.ndim != 1:
        raise InvalidInputError(f"{where} must be 1-D; got shape {arr.shape}")
    if arr.dtype == dtype:
        return arr.copy()
    if arr.dtype.kind not in _DTYPE_KINDS:
        if arr.size == 0:
            return np.empty(0, dtype=dtype)
        raise InvalidInputError(f"{where} must be numeric; got dtype {arr.dtype}")
    if dtype.kind in "iub" and arr.dtype.kind == "f" and arr.size:
        if not np.all(np.isfinite(arr)) or np.any(arr != np.round(arr)):
            raise InvalidInputError(f"{where} is an integer column ({dtype}); got non-integer "
                                    "or non-finite values")
    if dtype.kind in "iu" and arr.size and arr.dtype.kind != "b":
        info = np.iinfo(dtype)
        lo, hi = arr.min(), arr.max()
        if lo < info.min or hi > info.max:
            raise InvalidInputError(f"{where}: values [{lo}, {hi}] do not fit {dtype} "
                                    f"[{info.min}, {info.max}]")
    if (dtype.kind == "b" and arr.dtype.kind != "b" and arr.size
            and not np.all((arr == 0) | (arr == 1))):
        raise InvalidInputError(f"{where} is a bool column; got values other than 0 and 1")
    return arr.astype(dtype)


def check_time(value: Any, where: str) -> float:
    """Return a finite float time [s]."""
    try:
        out = float(value)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"{where} must be a number [s]; got {value!r}") from exc
    if not math.isfinite(out):
        raise InvalidInputError(f"{where} must be finite [s]; got {out}")
    return out


def check_optional_time(value: Any, where: str) -> float:
    """Return a float time [s]; NaN means "not set"; infinities are refused."""
    try:
        out = float(value)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"{where} must be a number [s] or NaN; got {value!r}") from exc
    if math.isinf(out):
        raise InvalidInputError(f"{where} must be finite or NaN [s]; got {out}")
    return out
